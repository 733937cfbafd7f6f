"""Read the custom per-vertex attributes of a PLY file (pymeshlab's loader drops them).

pymeshlab's PLY exporter writes a custom scalar attribute as ``property double <name>`` and a
custom point attribute as ``property list uchar double <name>`` (always 3 items) on the vertex
element; its importer reads positions, normals, colours and quality but not these. This module
reads them back so that ``curvdetail apply compute_curvature_detail a.obj b.ply`` followed by
``curvdetail apply apply_curvature_reconstruction b.ply c.ply`` works.
"""

import itertools
import os

import numpy as np

from .._file_counts import _whole

_SCALARS = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
            "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
            "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}

#: Vertex properties pymeshlab itself reads (not custom attributes).
STANDARD = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "quality", "radius",
            "s", "t", "u", "v", "texture_u", "texture_v", "flags", "confidence", "intensity"}


def _header(f):
    if f.readline().strip() != b"ply":
        return None
    fmt, elements = None, []
    while True:
        line = f.readline()
        if not line:
            return None
        words = line.decode("ascii", "replace").split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "end_header":
            return fmt, elements
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            # counts as pymeshlab's reader and the file scan read them ("3.0" is 3); others were refused
            count = _whole(words[2].encode("ascii", "replace")) if len(words) >= 3 else None
            if count is None or count < 0:
                return None
            elements.append((words[1], count, []))
        elif words[0] == "property" and elements:
            if words[1] == "list":
                elements[-1][2].append((words[4], "list", _SCALARS.get(words[2]), _SCALARS.get(words[3])))
            else:
                elements[-1][2].append((words[2], "scalar", None, _SCALARS.get(words[1])))


def read_ply_vertex_attributes(path):
    """``{name: (n,) or (n, k) float64 array}`` for the non-standard vertex properties of a PLY
    file (custom scalar and point attributes); ``{}`` for other files, for a vertex element that
    is not first, or for list properties whose length varies (not pymeshlab's attributes)."""
    path = os.fspath(path)
    if os.path.splitext(path)[1].lower() != ".ply":
        return {}
    with open(path, "rb") as f:
        head = _header(f)
        if head is None:
            return {}
        fmt, elements = head
        if not elements or elements[0][0] != "vertex":
            return {}
        _, n, props = elements[0]
        if any(p[3] is None or (p[1] == "list" and p[2] is None) for p in props):
            return {}
        custom = [p[0] for p in props if p[0] not in STANDARD]
        if not custom or n == 0:
            return {}
        if fmt == "ascii":
            return _from_ascii(list(itertools.islice(f, n)), n, props, custom)
        if fmt not in ("binary_little_endian", "binary_big_endian"):
            return {}
        order = "<" if fmt == "binary_little_endian" else ">"
        start = f.tell()
        first = f.read(4096)
        fields, offset = [], 0
        for name, kind, count_t, item_t in props:
            if kind == "list":
                size = np.dtype(count_t).itemsize
                count = int(np.frombuffer(first[offset:offset + size], dtype=order + count_t)[0])
                fields.append((f"{name}__count", order + count_t))
                fields.append((name, order + item_t, (count,)))
                offset += size + count * np.dtype(item_t).itemsize
            else:
                fields.append((name, order + item_t))
                offset += np.dtype(item_t).itemsize
        f.seek(start)
        dtype = np.dtype(fields)
        data = np.frombuffer(f.read(dtype.itemsize * n), dtype=dtype, count=n)
    out = {}
    for name, kind, _, _ in props:
        if name not in custom:
            continue
        if kind == "list":
            if not np.all(data[f"{name}__count"] == data[name].shape[1]):
                return {}
            out[name] = np.array(data[name], dtype=np.float64)
        else:
            out[name] = np.array(data[name], dtype=np.float64)
    return out


def _from_ascii(lines, n, props, custom):
    """The custom attributes from the vertex lines of an ASCII PLY file, parsed as one block:
    every line must hold the same number of values (pymeshlab's lists always have 3 items)."""
    if len(lines) < n:
        return {}
    try:
        values = np.loadtxt(lines, dtype=np.float64, ndmin=2, comments=None)
    except (ValueError, IndexError):                     # rows of different lengths, not numbers
        return {}
    if values.shape[0] != n:                             # blank lines among the vertices
        return {}
    out, k = {}, 0
    for name, kind, _, _ in props:
        if kind == "list":
            if k >= values.shape[1] or np.any(values[:, k] != values[0, k]):
                return {}
            count = int(values[0, k])
            columns, k = slice(k + 1, k + 1 + count), k + 1 + count
        else:
            columns, k = k, k + 1
        if name in custom:
            out[name] = values[:, columns].copy()
    return out if k == values.shape[1] else {}
