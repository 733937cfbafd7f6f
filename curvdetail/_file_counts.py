"""What a mesh file declares, to catch what pymeshlab's loader drops without a word.

pymeshlab's loader silently drops OBJ/OFF/PLY vertices with NaN or infinite coordinates (and the
faces using them, renumbering the rest), drops OBJ faces whose vertex indices are out of range
or repeated, and keeps OFF faces whose indices are out of range (its OFF loader then writes out
of bounds: such a file can crash the process later, before any check of ours can help; this
module reports the indices when it gets the chance). :func:`check_loaded` compares the
loaded mesh with the counts the file declares (OFF/PLY headers, a streamed count of OBJ ``v`` and
``f`` lines; never the whole file in memory) and with its own vertex count.
"""

import os

import numpy as np

_CHUNK = 1 << 20
_HEADER_LINES = 10_000


def _obj_counts(path):
    """Numbers of ``v`` and ``f`` lines of an OBJ file, counted in 1 MiB chunks. Like pymeshlab's
    loader, such a line starts at the beginning of a line with ``v`` / ``f`` and a space or tab
    (``vt``, ``vn``, ``vp`` and indented lines do not count)."""
    vertices = faces = 0
    tail = b"\n"
    with open(path, "rb") as f:
        while True:
            chunk = f.read(_CHUNK)
            if not chunk:
                return vertices, faces
            text = tail + chunk          # a match may straddle two chunks, never lie in tail alone
            vertices += text.count(b"\nv ") + text.count(b"\nv\t")
            faces += text.count(b"\nf ") + text.count(b"\nf\t")
            tail = text[-2:]


def _off_counts(path):
    """``(nv, nf)`` from an ASCII OFF header (``[ST][C][N][4]OFF`` then ``nv nf ne``, on the same
    line or the next one, comments allowed), or ``(None, None)`` if it is not of that form."""
    words = []
    with open(path, "rb") as f:
        for _ in range(_HEADER_LINES):
            line = f.readline()
            if not line:
                break
            words += line.split(b"#", 1)[0].decode("ascii", "replace").split()
            if len(words) >= 3:
                break
    if not words or not words[0].endswith("OFF") or "n" in words[0] or len(words) < 3:
        return None, None                # not OFF, nOFF (dimension first) or too short
    try:
        return int(words[1]), int(words[2])   # "OFF BINARY" is not an int: no check
    except ValueError:
        return None, None


def _ply_counts(path):
    """``N`` of ``element vertex N`` and ``element face N`` in a PLY header (ASCII or binary; only
    the header is read); None where absent."""
    found = {}
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            return None, None
        for _ in range(_HEADER_LINES):
            words = f.readline().split()
            if not words or words[0] == b"end_header":
                break
            if words[0] == b"element" and len(words) == 3 and words[2].isdigit():
                found[words[1]] = int(words[2])
    return found.get(b"vertex"), found.get(b"face")


_COUNTS = {".obj": _obj_counts, ".off": _off_counts, ".ply": _ply_counts}


def declared_counts(path):
    """``(vertices, faces)`` the file declares (OBJ, OFF, PLY), None where unknown."""
    counts = _COUNTS.get(os.path.splitext(os.fspath(path))[1].lower())
    return counts(path) if counts is not None else (None, None)


def check_loaded(path, n_vertices, F, error=ValueError):
    """Raise ``error`` if the loaded mesh (``n_vertices``, triangles ``F``) lost vertices or faces
    of ``path`` or holds face indices out of range; each message names the file, the counts, the
    likely cause and the fix."""
    F = np.asarray(F)
    if F.size and (F.min() < 0 or F.max() >= n_vertices):
        bad = np.flatnonzero((F < 0).any(axis=1) | (F >= n_vertices).any(axis=1))
        raise error(f"{path!r}: {bad.size} faces use vertex indices outside the file's {n_vertices} "
                    f"vertices (first: face {bad[0]}, {F[bad[0]].tolist()} 0-based); fix or remove "
                    "them in the file and read it again.")
    vertices, faces = declared_counts(path)
    if vertices is not None and vertices > n_vertices:     # more than declared: a misread count
        raise error(
            f"{path!r} has {vertices} vertices but pymeshlab loaded {n_vertices}: "
            f"{vertices - n_vertices} were dropped, most likely for non-finite (NaN or inf) "
            "coordinates, together with the faces using them, so the vertex order no longer "
            "matches the file. Fix or remove those vertices (and their faces) in the file and "
            "read it again.")
    # polygons are triangulated, so a complete load has at least as many triangles as faces
    if faces is not None and faces > F.shape[0]:
        raise error(
            f"{path!r} has {faces} faces but pymeshlab loaded {F.shape[0]} triangles: at least "
            f"{faces - F.shape[0]} were dropped, most likely for vertex indices out of range or "
            "repeated within a face. Fix or remove those faces in the file and read it again.")
