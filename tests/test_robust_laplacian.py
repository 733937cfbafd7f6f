"""The mollified Laplacian (curvature.robust_laplacian) and the experiment's ``laplacian`` option."""

import json
import os

import numpy as np
import pymeshlab
import pytest

from curvdetail.cli import main
from curvdetail.curvature.cotan_laplacian import cotan_laplacian
from curvdetail.curvature.errors import CurvdetailError, MeshError
from curvdetail.curvature.geometry import bbox_diagonal, face_double_areas
from curvdetail.curvature.robust_laplacian import degenerate_triangles, flip_caps, robust_laplacian
from curvdetail.curvature.testing import icosphere
from curvdetail.filters import apply
from curvdetail.filters.errors import FilterParameterError
from curvdetail.io.mesh import write_mesh
from curvdetail.remesh.experiment import RMS, remesh_experiment


def bumpy_sphere():
    V, F = icosphere(subdivisions=3)
    return V * (1 + 0.1 * np.sin(3 * V[:, [0]]) * np.cos(2 * V[:, [1]])), F


def capped_sphere():
    """The bumpy sphere with triangle 10 made a zero-area cap: its third vertex on its opposite edge."""
    V, F = bumpy_sphere()
    i, j, k = F[10]
    V[k] = 0.5 * (V[i] + V[j])
    return V, F


def test_equals_the_cotan_laplacian_on_a_clean_mesh():
    # no triangle has a slack below eps x the mean edge: nothing is mollified (delta = 0), and the
    # cotangents from the lengths agree with the ones from the positions to rounding (1e-12 relative)
    V, F = bumpy_sphere()
    L, M, delta = robust_laplacian(V, F)
    L0 = cotan_laplacian(V, F)
    assert delta == 0.0
    assert abs(L - L0).max() <= 1e-12 * abs(L0).max()
    assert M.diagonal().sum() == pytest.approx(face_double_areas(V, F).sum() / 2, rel=1e-12)


def test_is_symmetric_psd_with_zero_row_sums_on_a_zero_area_cap():
    V, F = capped_sphere()
    assert degenerate_triangles(V, F).tolist() == [10]
    with pytest.raises(MeshError):
        cotan_laplacian(V, F)
    L, M, delta = robust_laplacian(V, F)
    A = L.toarray()
    assert delta > 0 and np.isfinite(A).all()
    assert np.abs(A - A.T).max() == 0
    assert np.abs(A.sum(axis=1)).max() <= 1e-10 * np.abs(A).max()
    assert np.linalg.eigvalsh(A).min() >= -1e-10 * np.abs(A).max()
    assert (M.diagonal() > 0).all()


def test_flipping_caps_keeps_the_surface_and_removes_the_zero_area_triangle():
    V, F = capped_sphere()
    G = flip_caps(V, F)
    assert degenerate_triangles(V, G).size == 0
    assert (G != F).any(axis=1).sum() == 2                           # the cap and its neighbour
    assert face_double_areas(V, G).sum() == pytest.approx(face_double_areas(V, F).sum(), rel=1e-12)


def test_auto_falls_back_to_robust_on_a_cap_and_reports_it():
    V, F = capped_sphere()
    with pytest.raises(MeshError) as refused:
        remesh_experiment(V, F, target_edge="4%", laplacian="cotan")
    assert refused.value.parameter == "laplacian" and refused.value.count == 1 and refused.value.first == [10]
    (X, Ft), report = remesh_experiment(V, F, target_edge="4%")
    assert report["laplacian"] == "robust" and report["options"]["laplacian"] == "auto"
    assert "1 triangle has zero area (first: 10" in report["laplacian_reason"]
    assert np.isfinite(X).all()
    # the rebuilt surface is as close to the source as the clean sphere's (within 10 %)
    _, clean = remesh_experiment(*bumpy_sphere(), target_edge="4%")
    assert clean["laplacian"] == "cotan"
    # a study's table says which ran
    from curvdetail.evaluate.cell import report_columns

    assert (report_columns(report)["laplacian"], report_columns(clean)["laplacian"]) == ("robust", "cotan")
    assert report["error"][RMS] < 1.1 * clean["error"][RMS]


def test_robust_on_a_clean_mesh_gives_the_cotan_rebuild():
    V, F = bumpy_sphere()
    (X, _), report = remesh_experiment(V, F, target_edge="4%", laplacian="robust", evaluate=False)
    (X0, _), report0 = remesh_experiment(V, F, target_edge="4%", laplacian="cotan", evaluate=False)
    assert report["laplacian"] == "robust" and report0["laplacian"] == "cotan"
    assert np.abs(X - X0).max() < 1e-9


@pytest.mark.parametrize("value", ["mollified", None, 1])
def test_an_unknown_laplacian_is_refused_by_name(value):
    with pytest.raises(CurvdetailError) as refused:
        remesh_experiment(*bumpy_sphere(), laplacian=value)
    assert refused.value.parameter == "laplacian"


def test_the_filter_passes_the_option_and_refuses_a_bad_one():
    V, F = capped_sphere()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    report = apply(ms, "generate_curvature_remeshing", target_edge=pymeshlab.PercentageValue(4.0), evaluate=False)
    assert report["laplacian"] == "robust"
    with pytest.raises(FilterParameterError, match="'laplacian'"):
        apply(ms, "generate_curvature_remeshing", laplacian="mollified", evaluate=False)


def test_the_cli_takes_laplacian_and_the_report_says_which(tmp_path, capsys):
    src = tmp_path / "capped.obj"
    write_mesh(str(src), *capped_sphere())
    rep = tmp_path / "r.json"
    rc = main(["remesh", str(src), str(tmp_path / "o.ply"), "--target-edge", "4%", "--laplacian", "auto",
               "--no-evaluate", "--report", str(rep), "--quiet"])
    assert rc == 0
    assert json.loads(rep.read_text())["laplacian"] == "robust"
    with pytest.raises(SystemExit) as refused:
        main(["remesh", str(src), str(tmp_path / "p.ply"), "--laplacian", "mollified"])
    assert refused.value.code == 2 and "--laplacian" in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "p.ply")


def test_the_scan_script_makes_the_holes_and_caps_it_says():
    from conftest import load_script
    from curvdetail.remesh import check_surface

    V, F = load_script("reproduce_scan").scan_like(3000, holes=3, caps=5)
    assert degenerate_triangles(V, F).size == 5
    assert len(check_surface(V, flip_caps(V, F))[2]) == 3


# --- the laplacian= option of reconstruct, the filters and the CLI (one rule: choose_laplacian) ---

def _robust_detail(V, F):
    from curvdetail.curvature.cotan_laplacian import laplacian_product
    from curvdetail.curvature.robust_laplacian import checked_laplacian

    _, _, L, info = checked_laplacian(V, F)
    return laplacian_product(L, V), info


def test_reconstruct_rebuilds_a_capped_sphere_with_auto_and_says_so():
    # its own robust detail with one anchor: the same surface back to solver precision (1e-12 of
    # the diagonal, the plain reconstruction's round-trip bound)
    from curvdetail.curvature.reconstruct import reconstruct

    V, F = capped_sphere()
    D, info = _robust_detail(V, F)
    assert info["laplacian"] == "robust"
    for rows in ("all", "free"):
        X, used = reconstruct(V, F, D, [0], V[[0]], rows=rows, return_info=True)
        assert used["laplacian"] == "robust" and "first: 10" in used["laplacian_reason"]
        assert np.abs(X - V).max() < 1e-12 * bbox_diagonal(V)


def test_reconstruct_with_cotan_refuses_the_cap_by_parameter_and_triangle():
    from curvdetail.curvature.reconstruct import Reconstructor

    V, F = capped_sphere()
    with pytest.raises(MeshError) as refused:
        Reconstructor(V, F, [0], laplacian="cotan")
    assert refused.value.parameter == "laplacian" and refused.value.count == 1 and refused.value.first == [10]


def test_auto_on_a_clean_mesh_is_the_plain_laplacian_bit_for_bit():
    from curvdetail.curvature import curvature_detail
    from curvdetail.curvature.reconstruct import reconstruct
    from curvdetail.curvature.robust_laplacian import checked_laplacian

    V, F = bumpy_sphere()
    _, _, L, info = checked_laplacian(V, F)
    L0 = cotan_laplacian(V, F)
    assert info["laplacian"] == "cotan"
    assert np.array_equal(L.indptr, L0.indptr) and np.array_equal(L.indices, L0.indices)
    assert np.array_equal(L.data, L0.data)
    D = curvature_detail(V, F)
    for rows in ("all", "free"):
        X, used = reconstruct(V, F, D, [0], V[[0]], rows=rows, return_info=True)
        assert used["laplacian"] == "cotan"
        assert np.array_equal(X, reconstruct(V, F, D, [0], V[[0]], rows=rows, laplacian="cotan"))


def test_the_filters_rebuild_a_capped_sphere_and_report_the_robust_laplacian():
    V, F = capped_sphere()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    assert apply(ms, "compute_curvature_detail")["laplacian"] == "robust"
    figures = apply(ms, "apply_curvature_reconstruction")
    assert figures["laplacian"] == "robust" and figures["anchors"] == 1
    assert np.abs(ms.current_mesh().vertex_matrix() - V).max() < 1e-12 * bbox_diagonal(V)
    with pytest.raises(MeshError) as refused:
        apply(ms, "apply_curvature_reconstruction", laplacian="cotan")
    assert refused.value.parameter == "laplacian" and refused.value.first == [10]


def test_the_transfer_filter_carries_a_capped_sources_robust_detail():
    # onto the same surface with the cap flipped away: the detail carried is the robust one, its
    # total kept by the conservative transfer
    V, F = capped_sphere()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.add_mesh(pymeshlab.Mesh(V, flip_caps(V, F)))
    figures = apply(ms, "transfer_curvature_detail", sourcemesh=0, targetmesh=1)
    assert figures["laplacian"] == "robust" and figures["detail_source"] == "computed"
    D, _ = _robust_detail(V, F)
    assert np.allclose(figures["detail_total_source"], D.sum(axis=0), rtol=0, atol=1e-14)
    assert figures["detail_total_gap"] < 1e-12
    with pytest.raises(MeshError) as refused:
        apply(ms, "transfer_curvature_detail", sourcemesh=0, targetmesh=1, laplacian="cotan")
    assert refused.value.parameter == "laplacian" and refused.value.first == [10]


def test_the_cli_reconstructs_a_capped_sphere_and_names_the_option_when_refused(tmp_path, capsys):
    from curvdetail.io.mesh import read_mesh

    V, F = capped_sphere()
    src = tmp_path / "capped.obj"
    write_mesh(str(src), V, F)
    assert main(["reconstruct", str(src), str(tmp_path / "o.ply")]) == 0
    out = capsys.readouterr()
    assert "laplacian=robust" in out.out and "first: 10" in out.err
    X, _ = read_mesh(str(tmp_path / "o.ply"))
    assert np.abs(X - V).max() < 1e-6 * bbox_diagonal(V)          # the PLY stores float32
    assert main(["reconstruct", str(src), str(tmp_path / "p.ply"), "--laplacian", "cotan"]) == 1
    err = capsys.readouterr().err
    assert "--laplacian" in err and "first: 10" in err
    assert not os.path.exists(tmp_path / "p.ply")
