"""generate_curvature_remeshing: the experiment's layers and report, consistent with the filters."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import boundary_vertices
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.filters import apply
from curvdetail.filters.errors import FilterParameterError
from curvdetail.filters.meshset import vertex_attribute
from curvdetail.remesh import NotADiskError, transfer_curvature, vertex_distance

from conftest import triangle_brute_force, wavy_source_and_a_rebuild_beside_it

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


@pytest.fixture(scope="module")
def terrain_run():
    """terrainA_1k (1089 vertices) remeshed at 3 % of its diagonal, evaluated (about 2 s)."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(3.0))
    return ms, report


def test_adds_retriangulated_and_rebuilt_layers(terrain_run):
    ms, report = terrain_run
    assert report["layers"] == {"source": 0, "retriangulated": 1, "rebuilt": 2}
    assert ms.mesh_number() == 3 and ms.current_mesh_id() == 2
    assert ms.mesh(1).label() == "terrainA_1k.obj retriangulated"
    assert ms.mesh(2).label() == "terrainA_1k.obj rebuilt"
    assert report["target"]["vertices"] == ms.mesh(2).vertex_number() == ms.mesh(1).vertex_number()
    assert np.array_equal(ms.mesh(1).face_matrix(), ms.mesh(2).face_matrix())


def test_rebuilt_layer_carries_the_transferred_detail(terrain_run):
    ms, _ = terrain_run
    V, F = ms.mesh(0).vertex_matrix(), ms.mesh(0).face_matrix()
    Vt, Ft = ms.mesh(1).vertex_matrix(), ms.mesh(1).face_matrix()
    Dt = transfer_curvature(V, F, Vt, Ft, method="conservative", location="closest")
    assert np.array_equal(vertex_attribute(ms, 2, "curvature_detail", "point"), Dt)


def test_rebuilt_layer_equals_reconstruction_filter_on_the_retriangulation(terrain_run):
    # the experiment = transfer + apply_curvature_reconstruction on the retriangulated layer
    ms, _ = terrain_run
    check = pymeshlab.MeshSet()
    check.add_mesh(ms.mesh(0))
    check.add_mesh(ms.mesh(1))
    apply(check, "transfer_curvature_detail", sourcemesh=0, targetmesh=1)
    apply(check, "apply_curvature_reconstruction", rows="free")
    X = ms.mesh(2).vertex_matrix()
    assert np.abs(check.mesh(1).vertex_matrix() - X).max() < 1e-9 * bbox_diagonal(X)


def test_rebuilt_layers_stored_detail_rebuilds_that_layer(terrain_run, tmp_path):
    # the layer's detail is stamped with its own triangles: saved and loaded, moved back to the
    # retriangulated positions (same triangles) and rebuilt over the free rows, it gives the
    # rebuilt layer again (no "another triangulation")
    from curvdetail.filters.files import load_meshset, save_current_mesh
    from curvdetail.filters.meshset import set_vertex_positions

    ms, _ = terrain_run
    save_current_mesh(ms, str(tmp_path / "rebuilt.ply"))
    again = load_meshset(str(tmp_path / "rebuilt.ply"))
    set_vertex_positions(again, 0, ms.mesh(1).vertex_matrix())
    apply(again, "apply_curvature_reconstruction", rows="free")
    X = ms.mesh(2).vertex_matrix()
    assert np.abs(again.current_mesh().vertex_matrix() - X).max() < 1e-9 * bbox_diagonal(X)


def test_rebuilt_quality_is_the_distance_to_the_source(terrain_run):
    ms, _ = terrain_run
    d = vertex_distance(ms.mesh(2).vertex_matrix(), ms.mesh(0).vertex_matrix(), ms.mesh(0).face_matrix())
    assert np.array_equal(ms.mesh(2).vertex_scalar_array(), d)


def test_report_shows_detail_beats_the_zero_detail_baseline(terrain_run):
    # measured at 3 %: RMS 0.055 % (floor 0.053 %) against 1.3 % for the zero-detail surface
    _, report = terrain_run
    assert report["error"]["hausdorff_rms_percent_of_diagonal"] < report["baseline_zero_detail"]["hausdorff_rms_percent_of_diagonal"] / 10
    assert report["ratio_to_floor"] < 2.0
    assert set(report["seconds"]) >= {"retriangulate", "transfer", "reconstruct", "evaluate", "total"}


def test_absolute_target_edge_is_converted_to_a_fraction():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    diag = bbox_diagonal(ms.current_mesh().vertex_matrix())
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PureValue(0.025 * diag),
                   evaluate=False, add_baseline=True)
    assert report["options"]["target_edge_percent_of_diagonal"] == pytest.approx(2.5, rel=1e-6)   # PureValue is float32
    assert "error" not in report and report["layers"]["zero_detail"] == 2
    # the zero-detail baseline keeps the retriangulation's boundary
    b = boundary_vertices(ms.mesh(1).face_matrix())
    assert np.array_equal(ms.mesh(2).vertex_matrix()[b], ms.mesh(1).vertex_matrix()[b])


def test_closed_mesh_is_remeshed_with_one_anchor():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "spot.obj"))
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(3.0), evaluate=False)
    assert report["anchors"] == 1 and report["target"]["boundary_vertices"] == 0 and ms.mesh_number() == 3


def test_uv_location_on_a_closed_mesh_is_refused_as_not_a_disk():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "spot.obj"))
    with pytest.raises(NotADiskError):
        apply(ms, "generate_curvature_remeshing", location="uv", evaluate=False)
    assert ms.mesh_number() == 1


def test_a_parameterization_without_uv_location_is_refused_not_ignored():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    with pytest.raises(FilterParameterError, match="location='uv'") as e:            # the way to use it
        apply(ms, "generate_curvature_remeshing", parameterization="lscm", evaluate=False)
    assert e.value.parameter == "parameterization"
    assert ms.mesh_number() == 1


def test_the_baseline_layer_is_coloured_by_its_distance_to_the_source():
    # the distances run_experiment measured for the baseline's Hausdorff maximum, exact
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    V, F = ms.mesh(0).vertex_matrix(), ms.mesh(0).face_matrix()
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(3.0),
                   add_baseline=True)
    zero = ms.mesh(report["layers"]["zero_detail"])
    expected = vertex_distance(zero.vertex_matrix(), V, F)
    assert expected.max() > 0.05 * report["source"]["bbox_diagonal"]       # far from the source
    assert np.array_equal(zero.vertex_scalar_array(), expected)


@pytest.mark.parametrize("kwargs, expected", [({}, True), ({"surface_check": False}, False)])
def test_surface_check_is_passed_through_to_the_remesher(isotropic_calls, kwargs, expected):
    from curvdetail.remesh import retriangulate

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_ear.obj"))
    V, F = ms.mesh(0).vertex_matrix(), ms.mesh(0).face_matrix()
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(3.0),
                   evaluate=False, **kwargs)
    assert [call["checksurfdist"] for call in isotropic_calls] == [expected]
    assert report["options"]["surface_check"] is expected
    # the retriangulated layer is retriangulate's result with that option (the ear at 3 %
    # differs without the check: 644 vertices against 648)
    Vt, Ft = retriangulate(V, F, target_edge=f"{report['options']['target_edge_percent_of_diagonal']!r}%", **kwargs)
    assert np.array_equal(ms.mesh(report["layers"]["retriangulated"]).face_matrix(), Ft)


def test_surface_check_defaults_to_the_experiment_default():
    from curvdetail.filters import get_filter
    from curvdetail.remesh.experiment import DEFAULTS

    (param,) = [p for p in get_filter("generate_curvature_remeshing").parameters if p.name == "surface_check"]
    assert param.type == "bool" and param.default is DEFAULTS["surface_check"] is True
    assert "checksurfdist" in param.description


@pytest.mark.parametrize("value", ["no", 0, None])
def test_a_surface_check_that_is_not_a_bool_is_refused(isotropic_calls, value):
    from curvdetail.filters.errors import FilterParameterError

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    with pytest.raises(FilterParameterError) as e:
        apply(ms, "generate_curvature_remeshing", surface_check=value, evaluate=False)
    assert e.value.parameter == "surface_check"
    assert isotropic_calls == [] and ms.mesh_number() == 1


def test_a_big_target_is_said_beforehand_with_the_unit_of_a_plain_number(monkeypatch):
    # target_edge=0.01 is 0.01 model units: on the 15 km terrain ~1.3M vertices, 10 minutes
    # without a word before this warning
    import importlib
    import warnings

    from curvdetail.remesh import LongRunWarning

    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 100)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    # 1.0 model units on a terrain 15.3 units across: 6.55 % of its diagonal
    percent = 100.0 / bbox_diagonal(ms.current_mesh().vertex_matrix())
    assert round(percent, 2) == 6.55
    # the value, its share of the diagonal, and the option that speeds it up
    with pytest.warns(LongRunWarning, match=rf"target_edge=1\.0 \({percent:.3g} %.*surface_check=False"):
        apply(ms, "generate_curvature_remeshing", target_edge=1.0, evaluate=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", LongRunWarning)          # a smaller target: nothing said
        ms.set_current_mesh(0)
        apply(ms, "generate_curvature_remeshing", target_edge=1.3, evaluate=False)
        # a mesh the checks refuse (an edge in three triangles): the refusal alone, no "this takes
        # minutes" before it
        from curvdetail import MeshError
        from curvdetail.curvature.testing import disk

        V, F = disk(n_rings=12)
        fin = pymeshlab.MeshSet()
        fin.add_mesh(pymeshlab.Mesh(np.vstack([V, [[0.0, 0.0, 0.05]]]),
                                    np.vstack([F, [[F[0, 0], F[0, 1], V.shape[0]]]]).astype(np.int32)))
        with pytest.raises(MeshError) as refused:
            apply(fin, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(0.5), evaluate=False)
        assert refused.value.count == 1


def test_without_evaluation_the_rebuilt_layer_has_no_quality(tmp_path):
    # evaluate=false left pymeshlab's quality 0 on the rebuilt layer, and its PLY carried it as if
    # measured (the CLI's --no-evaluate writes none; the docs say quality = distance)
    from curvdetail.filters.files import load_meshset, save_current_mesh
    from curvdetail.remesh.experiment import run_experiment

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(3), evaluate=False,
                   add_baseline=True)
    rebuilt, zero = ms.mesh(report["layers"]["rebuilt"]), ms.mesh(report["layers"]["zero_detail"])
    assert ms.current_mesh_id() == report["layers"]["rebuilt"]
    assert not rebuilt.has_vertex_scalar() and not zero.has_vertex_scalar()
    assert rebuilt.label() == "mannequin_nose.obj rebuilt" and zero.label() == "mannequin_nose.obj zero detail"
    # the layers are the experiment's arrays exactly (they went through a binary PLY: doubles)
    result = run_experiment(ms.mesh(0).vertex_matrix(), ms.mesh(0).face_matrix(), target_edge="3%", evaluate=False)
    assert np.array_equal(rebuilt.vertex_matrix(), result["X"]) and np.array_equal(zero.vertex_matrix(), result["Z"])
    assert np.array_equal(rebuilt.face_matrix(), result["Ft"]) and np.array_equal(zero.face_matrix(), result["Ft"])
    assert np.array_equal(vertex_attribute(ms, report["layers"]["rebuilt"], "curvature_detail", "point"),
                          result["Dt"])
    save_current_mesh(ms, tmp_path / "rebuilt.ply")
    assert b"property double quality" not in (tmp_path / "rebuilt.ply").read_bytes().split(b"end_header")[0]
    again = load_meshset(tmp_path / "rebuilt.ply")
    assert not again.current_mesh().has_vertex_scalar()
    assert np.array_equal(vertex_attribute(again, 0, "curvature_detail", "point"), result["Dt"])


def test_a_rebuild_worse_than_zero_detail_is_said_by_the_filter():
    from curvdetail.curvature.testing import disk
    from curvdetail.remesh import WorseThanZeroDetailWarning

    V, F = disk(n_rings=8)                      # noise on a flat disk, see test_remesh_experiment.noisy_disk
    z = 0.02 * np.random.default_rng(1).standard_normal(V.shape[0])
    z[boundary_vertices(F)] = 0.0
    V[:, 2] = z
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)), "noisy")
    with pytest.warns(WorseThanZeroDetailWarning, match=r"transfer='conservative'") as caught:     # the fix
        report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(8),
                       transfer="pointwise")
    assert report["improvement_over_zero_detail"] < 0.5
    assert caught[0].filename == __file__


def test_layer_qualities_are_exact_beside_a_wavy_source(monkeypatch):
    # the rebuild forced beside a wavy source (as in test_remesh_experiment: the transfer patched
    # to give L(Vt) Y, Y the retriangulation with its interior flattened at z = 0.3 and spread
    # 1.4x past the source's edge): pymeshlab's closest-face grid, which gave the rebuilt layer's
    # quality, put 4 of its 500 vertices up to 0.49 % of the diagonal too far
    import warnings

    from curvdetail.remesh import WorseThanZeroDetailWarning

    V, F = wavy_source_and_a_rebuild_beside_it(monkeypatch)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)), "wavy")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", WorseThanZeroDetailWarning)       # it is worse: forced off
        report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(5),
                       add_baseline=True)
    d = bbox_diagonal(V)
    for name in ("rebuilt", "zero_detail"):
        layer = ms.mesh(report["layers"][name])
        exact = triangle_brute_force(layer.vertex_matrix(), V, F)
        np.testing.assert_allclose(layer.vertex_scalar_array(), exact, rtol=1e-12, atol=1e-15 * d)


def test_the_baseline_layers_vertices_are_searched_once(monkeypatch):
    # its quality is the distances the experiment measured for the baseline's Hausdorff maximum
    # (they were searched a second time for the layer, and the rebuilt ones twice: 5 x 640 +
    # 20,000 rows); every vertex set once, as in test_remesh_experiment's
    # test_each_vertex_set_is_searched_once
    import curvdetail.remesh.evaluate as evaluate
    from curvdetail.remesh.experiment import BASELINE_SAMPLES

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    m = ms.mesh(0).face_number()
    rows = []

    search = evaluate.SurfaceTree.distance

    def spy(tree, P):
        if tree.F.shape[0] == m:                           # against the source
            rows.append(P.shape[0])
        return search(tree, P)

    monkeypatch.setattr(evaluate.SurfaceTree, "distance", spy)
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(3.0),
                   add_baseline=True)
    p = report["target"]["vertices"]
    assert report["target"]["faces"] != m
    # the three vertex sets once each; face samples of the rebuilt and the retriangulated
    # surfaces (the exact engine's default count) and the baseline's
    n = int(np.clip(evaluate.SAMPLES_PER_FACE * report["target"]["faces"], evaluate.MIN_SAMPLES, evaluate.MAX_SAMPLES))
    assert rows.count(p) == 3 and sorted(r for r in rows if r != p) == sorted([n, n, BASELINE_SAMPLES]), rows


def test_report_names_the_source_file_by_its_absolute_path(tmp_path, monkeypatch):
    # as `curvdetail remesh --report` does (os.path.abspath of its input); it gave the bare file
    # name (pymeshlab's layer label), which names no file once the folder is not the current one
    import shutil

    from curvdetail.filters.files import load_meshset

    (tmp_path / "patches").mkdir()
    shutil.copy(os.path.join(DATA, "terrainA_1k.obj"), tmp_path / "patches")
    monkeypatch.chdir(tmp_path)
    ms = load_meshset(os.path.join("patches", "terrainA_1k.obj"))            # a relative path
    monkeypatch.chdir(DATA)                                                 # and elsewhere since
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(5), evaluate=False)
    assert report["source"]["path"] == str(tmp_path / "patches" / "terrainA_1k.obj")
    assert report["source"]["label"] == "terrainA_1k.obj"
    assert ms.mesh(0).label() == "terrainA_1k.obj"                          # the layer names are kept
    assert ms.mesh(report["layers"]["rebuilt"]).label() == "terrainA_1k.obj rebuilt"


def test_report_of_a_layer_pymeshlab_loaded_gives_its_label_not_a_path():
    # pymeshlab gives Python only the bare file name: not a path, so not reported as one
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(5), evaluate=False)
    assert report["source"]["path"] is None
    assert report["source"]["label"] == "terrainA_1k.obj"


def test_report_of_a_layer_made_in_memory_names_no_file():
    from curvdetail.curvature.testing import disk

    V, F = disk(n_rings=8)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)), "patch")
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(8), evaluate=False)
    assert report["source"]["path"] is None


def test_report_names_no_source_file_once_the_layer_changed_in_place():
    # a script that smooths the loaded layer and then remeshes it: the file is not the source
    from curvdetail.filters.files import load_meshset

    ms = load_meshset(os.path.join(DATA, "terrainA_1k.obj"))
    ms.apply_coord_laplacian_smoothing(stepsmoothnum=1, boundary=False, cotangentweight=True, selected=False)
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(5), evaluate=False)
    assert report["source"]["path"] is None and report["source"]["label"] == "terrainA_1k.obj"
