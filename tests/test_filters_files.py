"""Loading into a MeshSet and saving the current mesh: PLY keeps quality and attributes exactly."""

import os

import numpy as np
import pytest

from curvdetail.filters import apply, files
from curvdetail.filters.files import check_output_path, load_meshset, save_current_mesh
from curvdetail.filters.meshset import vertex_attribute
from curvdetail.io.mesh import MeshFileError

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
NOSE = os.path.join(DATA, "mannequin_nose.obj")
ATTRIBUTES = (("curvature_normal", "point"), ("curvature_detail", "point"), ("curvature_area", "scalar"))


def test_ply_round_trip_keeps_positions_quality_and_attributes_exactly(tmp_path):
    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "d.ply")
    back = load_meshset(tmp_path / "d.ply")
    assert np.array_equal(back.current_mesh().vertex_matrix(), ms.current_mesh().vertex_matrix())
    assert np.array_equal(back.current_mesh().vertex_scalar_array(), ms.current_mesh().vertex_scalar_array())
    for name, kind in ATTRIBUTES:
        assert np.array_equal(vertex_attribute(back, 0, name, kind), vertex_attribute(ms, 0, name, kind))


def test_a_vertex_selection_is_kept_in_ply_and_serves_the_next_step(tmp_path):
    # the selection (MeshLab keeps it in the vertex flags) was dropped: a step saved between
    # curvdetail apply calls lost the vertices a later reconstruction keeps fixed
    ms = load_meshset(NOSE)
    V = ms.current_mesh().vertex_matrix()
    ms.compute_selection_by_condition_per_vertex(condselect="(x < 0)")
    selected = ms.current_mesh().vertex_selection_array().copy()
    assert 0 < selected.sum() < selected.size
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "d.ply")
    back = load_meshset(tmp_path / "d.ply")
    assert np.array_equal(back.current_mesh().vertex_selection_array(), selected)
    # the next step keeps the selected vertices where they are and rebuilds the rest exactly
    apply(back, "apply_curvature_reconstruction", fix_boundary=False)
    X = back.current_mesh().vertex_matrix()
    assert np.array_equal(X[selected], V[selected])
    assert np.abs(X - V).max() < 1e-9 * np.linalg.norm(np.ptp(V, axis=0))
    # a mesh with nothing selected writes no flags
    plain = load_meshset(NOSE)
    save_current_mesh(plain, tmp_path / "p.ply")
    with open(tmp_path / "p.ply", "rb") as fh:
        assert b"property int flags" not in fh.read(2000).split(b"end_header")[0]


def test_scratch_attributes_are_not_saved(tmp_path):
    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")                 # sets quality through a scratch attribute
    save_current_mesh(ms, tmp_path / "d.ply")
    header = (tmp_path / "d.ply").read_bytes().split(b"end_header")[0]
    assert b"curvature_detail" in header and b"scratch" not in header


def test_obj_output_holds_the_geometry(tmp_path):
    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "d.obj")
    back = load_meshset(tmp_path / "d.obj")
    assert np.allclose(back.current_mesh().vertex_matrix(), ms.current_mesh().vertex_matrix(), atol=1e-6)


def test_existing_output_is_kept_unless_overwrite(tmp_path):
    out = tmp_path / "d.ply"
    out.write_text("keep me")
    ms = load_meshset(NOSE)
    with pytest.raises(FileExistsError, match=r"d.ply exists; pass overwrite=True to replace it\.$"):
        save_current_mesh(ms, out)
    assert out.read_text() == "keep me"
    save_current_mesh(ms, out, overwrite=True)
    assert out.read_bytes().startswith(b"ply")


def test_an_existing_script_is_refused_in_pythons_words(tmp_path):
    # save_script said "--overwrite (overwrite=True)": the command line's option, no use in Python
    from curvdetail.filters import save_script

    path = tmp_path / "p.mlx"
    path.write_text("keep me")
    with pytest.raises(FileExistsError, match=r"p.mlx exists; pass overwrite=True to replace it\.$"):
        save_script(path, ["compute_curvature_detail"])
    assert path.read_text() == "keep me"
    save_script(path, ["compute_curvature_detail"], overwrite=True)
    assert "compute_curvature_detail" in path.read_text()


def test_failed_save_leaves_no_file(tmp_path, monkeypatch):
    ms = load_meshset(NOSE)
    # pymeshlab refuses the write (here: an option it does not have) after the checks passed
    monkeypatch.setattr(files, "save_options", lambda ms, path: {"no_such_option": True})
    with pytest.raises(MeshFileError, match=r"could not write .*d\.ply': .*no_such_option"):
        save_current_mesh(ms, tmp_path / "d.ply")
    assert os.listdir(tmp_path) == []


def test_unknown_and_point_formats_are_refused_before_saving(tmp_path):
    ms = load_meshset(NOSE)
    with pytest.raises(MeshFileError, match="pymeshlab does not write .unknownformat meshes"):
        save_current_mesh(ms, tmp_path / "d.unknownformat")
    with pytest.raises(MeshFileError, match=".xyz files hold points only"):
        check_output_path(tmp_path / "d.xyz")
    assert os.listdir(tmp_path) == []


def test_output_checks_happen_before_work(tmp_path):
    with pytest.raises(MeshFileError, match="does not exist"):
        check_output_path(tmp_path / "no" / "d.ply")
    with pytest.raises(MeshFileError, match="no file extension"):
        check_output_path(tmp_path / "d")


def test_missing_and_unreadable_inputs_are_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="mesh file not found"):
        load_meshset(tmp_path / "none.obj")
    bad = tmp_path / "bad.ply"
    bad.write_text("not a ply")
    with pytest.raises(MeshFileError, match="could not read"):
        load_meshset(bad)


def test_file_with_a_nan_vertex_is_refused_not_renumbered(tmp_path, capsys):
    # pymeshlab's loader drops the NaN vertex 1 and renumbers the faces; load_meshset (and so
    # `curvdetail apply`) refuses the file as read_mesh does
    from curvdetail.cli import main

    path = tmp_path / "bad.obj"
    path.write_text("v 0 0 0\nv nan 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 3 4\nf 3 5 4\n")
    with pytest.raises(MeshFileError, match=r"has 5 vertices but pymeshlab loaded 4.*non-finite"):
        load_meshset(NOSE, path)
    assert main(["apply", "compute_curvature_detail", str(path), str(tmp_path / "out.ply")]) == 1
    assert "has 5 vertices but pymeshlab loaded 4" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["bad.obj"]


def test_filter_saves_refuse_coordinates_the_format_cannot_hold(tmp_path):
    # the filters' save path wrote OBJ's 16 decimals of a 1e-20 mesh as zeros without a word
    import pymeshlab

    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(subdivisions=1)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V * 1e-20, F.astype(np.int32)))
    with pytest.raises(MeshFileError, match="OBJ coordinates with 16 decimals"):
        save_current_mesh(ms, tmp_path / "m.obj")
    assert not os.listdir(tmp_path)
    save_current_mesh(ms, tmp_path / "m.ply")                       # binary doubles: exact
    loaded = load_meshset(tmp_path / "m.ply")
    assert np.array_equal(loaded.current_mesh().vertex_matrix(), V * 1e-20)


def test_filter_saves_write_ctm_lossless(tmp_path):
    # pymeshlab's CTM default compresses the coordinates to a grid (2e-5 of a unit sphere lost)
    import pymeshlab

    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(subdivisions=2)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    save_current_mesh(ms, tmp_path / "m.ctm")
    loaded = load_meshset(tmp_path / "m.ctm")
    W = loaded.current_mesh().vertex_matrix()
    assert W.shape == V.shape and np.abs(W - V.astype(np.float32)).max() == 0.0


def test_a_ctm_save_holds_the_geometry_only_and_reads_back(tmp_path):
    # a mesh with a quality (here the reconstruction filter's) saved as CTM wrote a lone "Quality"
    # map, on which pymeshlab's CTM reader crashes the process: the geometry only now
    import subprocess
    import sys

    from curvdetail._ctm_scan import ctm_problem

    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    apply(ms, "apply_curvature_reconstruction")
    assert ms.current_mesh().has_vertex_scalar()
    out = tmp_path / "out.ctm"
    save_current_mesh(ms, out)
    assert ctm_problem(str(out)) is None
    code = f"import curvdetail; V, F = curvdetail.read_mesh({str(out)!r}); print(V.shape[0], F.shape[0])"
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert child.returncode == 0, child.stderr
    assert child.stdout.split() == [str(ms.current_mesh().vertex_number()), str(ms.current_mesh().face_number())]


def test_a_ctm_save_keeps_vertex_colours(tmp_path):
    # the geometry-only CTM options dropped the colours too; only the quality must go
    import pymeshlab

    from curvdetail._ctm_scan import ctm_problem

    ms = load_meshset(NOSE)
    n = ms.current_mesh().vertex_number()
    colours = np.tile([0.2, 0.4, 0.6, 1.0], (n, 1))
    m = ms.current_mesh()
    ms.add_mesh(pymeshlab.Mesh(m.vertex_matrix(), m.face_matrix(), v_color_matrix=colours), "coloured")
    out = tmp_path / "coloured.ctm"
    save_current_mesh(ms, out)
    assert ctm_problem(str(out)) is None
    assert b"Color" in out.read_bytes() and b"Quality" not in out.read_bytes()


def test_a_ctm_files_colours_and_quality_are_loaded_and_kept_in_ply(tmp_path):
    # pymeshlab read a CTM file's quality from its colour map and marked the layer as holding
    # neither: a PLY save then dropped both. Written here by pymeshlab itself (lossless: MG1)
    import pymeshlab

    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(subdivisions=2)
    quality = 10 + 3.7 * V[:, 2]                                       # not a colour
    random_colours = np.c_[np.random.default_rng(3).random((len(V), 3)), np.ones(len(V))]
    written = pymeshlab.MeshSet()
    written.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32), v_scalar_array=quality, v_color_matrix=random_colours))
    colours = written.current_mesh().vertex_color_matrix()             # 8 bits, as pymeshlab holds them
    written.save_current_mesh(str(tmp_path / "m.ctm"), lossless=True)
    ms = load_meshset(tmp_path / "m.ctm")
    mesh = ms.current_mesh()
    assert mesh.has_vertex_scalar() and mesh.has_vertex_color()
    assert np.array_equal(mesh.vertex_scalar_array(), quality.astype(np.float32))
    # 8-bit colours, truncated on reading: at most one step off
    assert np.abs(mesh.vertex_color_matrix() - colours).max() <= 1 / 255 + 1e-9
    save_current_mesh(ms, tmp_path / "m.ply")
    loaded = load_meshset(tmp_path / "m.ply")                        # kept: its meshes are views into it
    back = loaded.current_mesh()
    assert np.array_equal(back.vertex_scalar_array(), mesh.vertex_scalar_array())
    assert np.array_equal(back.vertex_color_matrix(), mesh.vertex_color_matrix())


_3DS_SAVE = """
import hashlib, sys
import numpy as np
from curvdetail.filters import apply
from curvdetail.filters.files import load_meshset, save_current_mesh
from curvdetail.filters.meshset import vertex_attribute

def layer_digest(ms):
    m = ms.current_mesh()
    h = hashlib.blake2b()
    for arrays in ([m.vertex_matrix(), m.face_matrix(), m.vertex_scalar_array()],
                   [m.face_color_matrix()] if m.has_face_color() else [],
                   [vertex_attribute(ms, 0, name, kind) for name, kind in
                    (("curvature_detail", "point"), ("curvature_area", "scalar"))]):
        for a in arrays:
            h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr((ms.mesh_number(), ms.current_mesh_id(), m.label(), m.has_face_color(), m.has_vertex_color(),
                   m.has_vertex_scalar())).encode())
    return h.hexdigest()

ms = load_meshset(sys.argv[1])
apply(ms, "compute_curvature_detail")                    # quality and custom attributes on the layer
before = layer_digest(ms)
save_current_mesh(ms, sys.argv[2])
print(before == layer_digest(ms), ms.current_mesh().has_face_color())
"""


def test_a_3ds_save_is_the_same_in_every_process_and_leaves_the_layer_alone(tmp_path):
    # written from the layer itself, pymeshlab's 3DS writer named the faces' material (the layer
    # has no face colours) and set their flags from uninitialised memory: the bytes differed
    # from process to process (as from run to run). Two processes, the second with malloc
    # filling its memory (as memory recycled in a long run is)
    import subprocess
    import sys

    from curvdetail import read_mesh

    outputs = [tmp_path / "a.3ds", tmp_path / "b.3ds"]
    for out, env in zip(outputs, [{}, {"MALLOC_PERTURB_": "165"}]):
        done = subprocess.run([sys.executable, "-c", _3DS_SAVE, NOSE, str(out)], capture_output=True, text=True,
                              timeout=120, env={**os.environ, **env})
        assert done.returncode == 0, done.stderr[-2000:]
        assert done.stdout.split() == ["True", "False"]             # the layer as it was, no face colours added
    assert outputs[0].read_bytes() == outputs[1].read_bytes()
    V, F = read_mesh(NOSE)
    W, G = read_mesh(outputs[0])
    assert np.array_equal(W, V.astype(np.float32)) and np.array_equal(G, F)


@pytest.mark.parametrize("extension", [".3ds", ".3mf", ".ctm", ".dae", ".dxf", ".idtf", ".json", ".obj", ".off", ".ply",
                                       ".stl", ".wrl", ".x3d"])
def test_the_vertex_colour_formats_are_those_whose_writer_saves_vertex_colours(tmp_path, extension):
    # every mesh format pymeshlab writes (the Nexus and U3D writers are never run): the writer
    # has the save_vertex_color option exactly where the table says the colours are kept
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.eye(3), np.array([[0, 1, 2]], dtype=np.int32),
                               v_color_matrix=np.tile([0.2, 0.4, 0.6, 1.0], (3, 1))))
    try:
        ms.save_current_mesh(str(tmp_path / ("m" + extension)), save_vertex_color=True)
        has_option = True
    except pymeshlab.PyMeshLabException as exc:
        assert "Parameter save_vertex_color not found" in str(exc), str(exc)
        has_option = False
    assert has_option == (extension in files.VERTEX_COLOUR_FORMATS)
    assert files.vertex_colours_kept_in(ms, "m" + extension) == has_option


def test_a_bytes_path_keeps_what_a_str_path_keeps(tmp_path):
    # b'.ply' != '.ply': the custom attributes and the quality were silently left out
    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "s.ply")
    save_current_mesh(ms, os.fsencode(tmp_path / "b.ply"))
    assert (tmp_path / "b.ply").read_bytes() == (tmp_path / "s.ply").read_bytes()
    assert files.attributes_lost_in(ms, b"x.ply") == [] and files.save_options(ms, b"x.ply") == \
        files.save_options(ms, "x.ply")


def test_a_path_that_is_not_utf8_is_refused_with_the_fix(tmp_path):
    # pymeshlab's own TypeError ("incompatible function arguments") went through
    folder = os.path.join(os.fsencode(tmp_path), b"lat\xe9")
    os.mkdir(folder)
    ms = load_meshset(NOSE)
    for path in (os.path.join(folder, b"d.ply"), os.fsdecode(os.path.join(folder, b"d.obj"))):
        with pytest.raises(MeshFileError, match=r"not UTF-8 .* pymeshlab takes paths as UTF-8 text only; rename"):
            save_current_mesh(ms, path)
    assert os.listdir(folder) == []


def _off_header(path):
    return path.read_text().split("\n", 1)[0]


def test_computed_normals_and_default_colours_are_not_saved(tmp_path):
    # an OBJ without normals was saved to OFF as NOFF (the normals pymeshlab computes on load),
    # a layer made from arrays as NCOFF (those and the white colours every such mesh gets)
    import pymeshlab
    from curvdetail.curvature.testing import icosphere

    ms = load_meshset(NOSE)
    save_current_mesh(ms, tmp_path / "n.off")
    V, F = icosphere(subdivisions=1)
    made = pymeshlab.MeshSet()
    made.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    save_current_mesh(made, tmp_path / "m.off")
    save_current_mesh(made, tmp_path / "m.obj")
    assert _off_header(tmp_path / "n.off") == _off_header(tmp_path / "m.off") == "OFF"
    rows = (tmp_path / "m.off").read_text().split("\n")
    assert rows[1].split() == [str(len(V)), str(len(F)), "0"] and len(rows[2].split()) == 3
    assert "vn " not in (tmp_path / "m.obj").read_text()
    back = load_meshset(tmp_path / "m.off")
    assert np.allclose(back.current_mesh().vertex_matrix(), V, atol=1e-15)


def test_a_layers_own_normals_and_colours_are_saved(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]])
    normals = np.array([[0.6, 0, 0.8], [0, 0.6, 0.8], [0, 0, 1], [0.8, 0, 0.6]])
    (tmp_path / "vn.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in V)
                                      + "".join(f"vn {x} {y} {z}\n" for x, y, z in normals)
                                      + "f 1//1 2//2 3//3\nf 2//2 4//4 3//3\n")
    (tmp_path / "c.off").write_text("COFF\n4 2 0\n" + "".join(f"{x} {y} {z} {10 * k} 20 30 255\n"
                                                              for k, (x, y, z) in enumerate(V))
                                    + "3 0 1 2\n3 1 3 2\n")
    ms = load_meshset(tmp_path / "vn.obj")
    save_current_mesh(ms, tmp_path / "vn.off")
    assert _off_header(tmp_path / "vn.off") == "NOFF"
    back = load_meshset(tmp_path / "vn.off")                       # kept: its meshes are views into it
    assert np.allclose(back.current_mesh().vertex_normal_matrix(), normals)
    ms = load_meshset(tmp_path / "c.off")
    save_current_mesh(ms, tmp_path / "c2.off")
    assert _off_header(tmp_path / "c2.off") == "COFF"
    back = load_meshset(tmp_path / "c2.off")
    assert np.allclose(back.current_mesh().vertex_color_matrix() * 255, [[10 * k, 20, 30, 255] for k in range(4)])
