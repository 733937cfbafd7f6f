"""_file_counts: the vertex and face counts a mesh file declares, and the check against what
pymeshlab loaded."""

import numpy as np
import pytest

from curvdetail import _file_counts
from curvdetail._file_counts import check_loaded, declared_counts

OBJ = b"v 0 0 0\nvt 1 1\nv\t1 0 0\r\n  v 9 9 9\nvn 0 0 1\nv 0 1 0\nf 1 2 3\nf\t1 3 4\n  f 1 1 1\nv 1 1 1"


@pytest.mark.parametrize("chunk", [1, 2, 3, 5, 64])
def test_obj_lines_are_counted_across_chunk_boundaries(tmp_path, monkeypatch, chunk):
    path = tmp_path / "m.obj"
    path.write_bytes(OBJ)
    monkeypatch.setattr(_file_counts, "_CHUNK", chunk)
    # indented lines are neither vertices nor faces to pymeshlab
    assert declared_counts(str(path)) == (4, 2)


def test_off_and_ply_headers_give_both_counts(tmp_path):
    off = tmp_path / "m.off"
    off.write_text("# comment\nOFF\n5 7 0\n")
    assert declared_counts(off) == (5, 7)
    coff = tmp_path / "m.off"
    coff.write_text("COFF 4 2 0\n")
    assert declared_counts(coff) == (4, 2)
    ply = tmp_path / "m.ply"
    ply.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
                    b"element face 16\nproperty list uchar int vertex_indices\nend_header\n\x00\x01")
    assert declared_counts(ply) == (10, 16)
    assert declared_counts(tmp_path / "m.stl") == (None, None)


def test_check_loaded_accepts_a_complete_load_and_names_what_is_missing(tmp_path):
    path = tmp_path / "m.off"
    path.write_text("OFF\n4 2 0\n")
    F = np.array([[0, 1, 2], [1, 3, 2]])
    check_loaded(str(path), 4, F)                                  # complete: nothing raised
    check_loaded(str(path), 4, np.vstack([F, F]))                  # polygons triangulated: more is fine
    with pytest.raises(ValueError, match=r"has 4 vertices but pymeshlab loaded 3: 1 were dropped"):
        check_loaded(str(path), 3, F[:1])
    with pytest.raises(ValueError, match=r"has 2 faces but pymeshlab loaded 1 triangles"):
        check_loaded(str(path), 4, F[:1])
    with pytest.raises(KeyError, match=r"1 faces use vertex indices outside the file's 4 vertices "
                                       r"\(first: face 1, \[1, 4, 2\]"):
        check_loaded(str(path), 4, np.array([[0, 1, 2], [1, 4, 2]]), error=KeyError)
