"""PLY files through plyfile: vertices, triangles and every per-vertex property as a plain array.

A per-vertex property is a field: a scalar property is an (n,) array; a point (three values per
vertex) is written as the three properties ``<name>_x``, ``<name>_y``, ``<name>_z`` and read back
as one (n, 3) array, as is a list property of three values per vertex (MeshLab's ``__ca_vp__``
export). `curvdetail.io.read_mesh` and `curvdetail.io.write_mesh` use these; the
arrays read here are not checked yet.
"""

import numpy as np

_FACE_LISTS = ("vertex_indices", "vertex_index")
_AXES = ("_x", "_y", "_z")
_PLY_TYPES = ("i1", "u1", "i2", "u2", "i4", "u4", "f4", "f8")


def read_ply(path):
    """Read a PLY file (ASCII or binary) with plyfile.

    Parameters
    ----------
    path : str
        The file.

    Returns
    -------
    V : (n, 3) float64 array
        The ``x``, ``y``, ``z`` vertex properties, in file order.
    F : (m, 3) array
        Triangles, of the file's index type; a polygon of k corners is cut into k - 2
        triangles fanned from its first corner (as pymeshlab cuts an OBJ file's polygons).
    fields : dict of str to array
        Every other vertex property: (n,) arrays, and (n, 3) arrays for the points (see the
        module docstring).

    Raises
    ------
    ValueError
        The file is not a PLY file plyfile reads (``plyfile.PlyParseError`` is a ValueError
        here too), has no ``vertex`` element with ``x``, ``y``, ``z``, or a face of fewer than
        three corners.
    """
    import plyfile

    try:                                # binary triangles are memory-mapped: no per-row Python
        ply = plyfile.PlyData.read(path, known_list_len={"face": dict.fromkeys(_FACE_LISTS, 3)})
    except plyfile.PlyElementParseError as exc:
        if exc.message != "unexpected list length":
            raise ValueError(str(exc)) from None
        ply = plyfile.PlyData.read(path)                # polygons: lists of any length
    except plyfile.PlyParseError as exc:
        raise ValueError(str(exc)) from None
    if "vertex" not in ply or not {"x", "y", "z"} <= set(ply["vertex"].data.dtype.names):
        raise ValueError("it has no vertex element with x, y, z properties")
    vertex = ply["vertex"].data
    V = np.column_stack([vertex[axis].astype(np.float64) for axis in "xyz"]) if len(vertex) else \
        np.zeros((0, 3))
    face = ply["face"].data if "face" in ply else np.zeros(0, dtype=[("vertex_indices", "i4", (3,))])
    lists = [name for name in _FACE_LISTS if name in face.dtype.names]
    if not lists:
        raise ValueError("its face element has no vertex_indices list")
    F = triangles(face[lists[0]])
    return V, F, _fields(vertex)


def triangles(faces):
    """(m, 3) triangles of ``faces``: an (m, 3) array, or an object array of index lists
    (polygons fanned from their first corner); ValueError for a face of fewer than 3 corners."""
    if faces.dtype != object:
        return faces.reshape(-1, 3)
    sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    if sizes.size and sizes.min() < 3:
        bad = np.flatnonzero(sizes < 3)
        raise ValueError(f"{bad.size} faces have fewer than 3 corners (first: face {bad[0]})")
    flat = np.concatenate(faces) if sizes.size else np.zeros(0, dtype=np.int64)
    starts = np.repeat(np.cumsum(sizes) - sizes, sizes - 2)          # one row per triangle
    step = np.arange(starts.size) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
    return np.column_stack([flat[starts], flat[starts + step + 1], flat[starts + step + 2]])


def _fields(vertex):
    """The vertex properties other than x, y, z as plain arrays, the points joined (n, 3)."""
    names = [name for name in vertex.dtype.names if name not in ("x", "y", "z")]
    fields = {}
    for name in names:
        column = vertex[name]
        if column.dtype == object:                      # a list property
            sizes = {len(row) for row in column}
            if sizes == {3}:
                fields[name] = np.stack(column).astype(np.float64)
        else:
            fields[name] = np.array(column)
    for name in [n[:-2] for n in names if n.endswith("_x")]:
        if all(name + axis in fields and fields[name + axis].ndim == 1 for axis in _AXES):
            fields[name] = np.column_stack([fields.pop(name + axis).astype(np.float64) for axis in _AXES])
    return fields


def write_ply(path, V, F, fields=None):
    """Write a binary little-endian PLY file: doubles for ``V``, int32 triangles.

    Parameters
    ----------
    path : str
        The file (written as it is: callers go through `curvdetail.io.atomic_write`).
    V : (n, 3) float64 array
    F : (m, 3) int array
    fields : dict of str to array, optional
        Per-vertex properties: (n,) arrays keep their dtype where PLY has it (``quality``:
        float64, ``red``: uint8, ``flags``: int32, ...), (n, 3) arrays become ``<name>_x``,
        ``<name>_y``, ``<name>_z`` doubles.
    """
    import plyfile

    V = np.asarray(V, dtype=np.float64)
    columns = [("x", V[:, 0]), ("y", V[:, 1]), ("z", V[:, 2])]
    for name, values in (fields or {}).items():
        values = np.asarray(values)
        if values.ndim == 2:
            columns += [(name + axis, values[:, k]) for k, axis in enumerate(_AXES)]
        else:
            columns.append((name, values))
    columns = [(name, values if values.dtype.str[1:] in _PLY_TYPES else values.astype(np.float64))
               for name, values in columns]
    vertex = np.empty(len(V), dtype=[(name, values.dtype.newbyteorder("<")) for name, values in columns])
    for name, values in columns:
        vertex[name] = values
    face = np.empty(len(F), dtype=[("n", "u1"), ("vertex_indices", "<i4", (3,))])
    face["n"], face["vertex_indices"] = 3, F
    # the header from plyfile; the body as numpy writes it (plyfile writes lists row by row: 2 s
    # per million triangles; these bytes are the same)
    triangles = plyfile.PlyElement("face", [plyfile.PlyListProperty("vertex_indices", "uint8", "int32")], len(F))
    header = plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex"), triangles], byte_order="<").header
    with open(path, "wb") as f:
        f.write(header.encode("ascii") + b"\n")
        f.write(vertex.tobytes())
        f.write(face.tobytes())
