"""Adapters between a ``pymeshlab.MeshSet`` and the package's ``(V, F)`` arrays.

Filters read layers as arrays and write results back *in place* (same layer id, name, selection
and other attributes), as MeshLab's own filters do, or as a new layer that becomes current.

pymeshlab can add a custom attribute from an array but cannot overwrite one, nor set vertex
positions or quality from an array. Those writes therefore go through a fresh scratch custom
attribute (``curvdetail_scratch_<k>``) that pymeshlab's muparser filters
(``compute_new_custom_*_attribute_per_vertex``, ``compute_coord_by_function``,
``compute_scalar_by_function_per_vertex``) copy exactly (doubles, no rounding). Scratch attributes
stay on the mesh (pymeshlab cannot delete attributes) but are never saved to files.
"""

import contextlib
import itertools

import numpy as np

from ..curvature.errors import MeshError
from ..curvature.geometry import vertex_normals  # noqa: F401  (area-weighted, unit)
from .errors import FilterError

_scratch_ids = itertools.count()

#: ``{name: "point" | "scalar"}`` for every custom attribute a filter stored with
#: `set_vertex_attribute` or `add_layer`; saving to PLY keeps these.
WRITTEN_ATTRIBUTES = {}


def layer_id(ms, mesh_id=None, role="mesh"):
    """Return a valid layer id: ``mesh_id`` if the MeshSet has it, the current mesh if None.

    Raises FilterError when the MeshSet is empty or the id does not exist (lists the ids there)."""
    if ms.mesh_number() == 0:
        raise FilterError("the MeshSet holds no mesh; load one first (ms.load_new_mesh(path)).", parameter="ms",
                          count=0)
    if mesh_id is None:
        return int(ms.current_mesh_id())
    if not ms.mesh_id_exists(int(mesh_id)):
        ids = _existing_ids(ms)
        raise FilterError(f"{role} layer id {mesh_id} does not exist; the MeshSet holds layers "
                          f"{', '.join(map(str, ids))}.", parameter=role, value=mesh_id)
    return int(mesh_id)


def _existing_ids(ms):
    ids, k = [], 0
    while len(ids) < ms.mesh_number() and k < 100000:
        if ms.mesh_id_exists(k):
            ids.append(k)
        k += 1
    return ids


def get_mesh(ms, mesh_id):
    """The ``pymeshlab.Mesh`` of layer ``mesh_id`` (compacted if deletions left holes)."""
    mesh = ms.mesh(int(mesh_id))
    if not mesh.is_compact():
        mesh.compact()
    return mesh


def mesh_arrays(ms, mesh_id):
    """``(V, F)`` of a layer as float64 (n, 3) and int64 (m, 3) arrays.

    Raises MeshError if the layer is a point cloud (no triangles)."""
    mesh = get_mesh(ms, mesh_id)
    V = np.array(mesh.vertex_matrix(), dtype=np.float64)
    F = np.array(mesh.face_matrix(), dtype=np.int64)
    if F.shape[0] == 0:
        raise MeshError(f"layer {mesh_id} ({mesh.label()!r}) has {V.shape[0]} vertices but no "
                        "triangles; these filters need a triangle mesh.")
    return V, F


def selected_vertices(ms, mesh_id):
    """Indices of the selected vertices of a layer, increasing."""
    return np.flatnonzero(np.asarray(get_mesh(ms, mesh_id).vertex_selection_array(), dtype=bool))


def vertex_attribute(ms, mesh_id, name, kind):
    """A custom per-vertex attribute as an array ((n, 3) for ``kind="point"``, (n,) for
    ``"scalar"``), or None when the layer has none of that name."""
    mesh = get_mesh(ms, mesh_id)
    try:
        if kind == "point":
            return np.array(mesh.vertex_custom_point_attribute_matrix(name), dtype=np.float64)
        return np.array(mesh.vertex_custom_scalar_attribute_array(name), dtype=np.float64)
    except Exception:
        return None


#: How a missing attribute's error says to keep attributes through a file: pymeshlab's own
#: ``load_new_mesh`` and ``save_current_mesh`` read and write no custom attribute.
KEEP_ATTRIBUTES = ("if the layer came from a PLY file written with them, load it with "
                   "curvdetail.filters.files.load_meshset (pymeshlab's load_new_mesh drops custom attributes), "
                   "and save with curvdetail.filters.files.save_current_mesh (pymeshlab's save_current_mesh "
                   "does not write them)")


def require_vertex_attribute(ms, mesh_id, name, kind, hint):
    """Like `vertex_attribute` but raises FilterError (``value``: the attribute's name)
    naming the attribute, ``hint`` and how to keep attributes through a file
    (`KEEP_ATTRIBUTES`)."""
    values = vertex_attribute(ms, mesh_id, name, kind)
    if values is None:
        label = get_mesh(ms, mesh_id).label()
        raise FilterError(f"layer {mesh_id} ({label!r}) has no per-vertex {kind} attribute {name!r}",
                          value=name, hint=f"{hint.rstrip('.')}; {KEEP_ATTRIBUTES}")
    return values


@contextlib.contextmanager
def _current(ms, mesh_id):
    """Make ``mesh_id`` current for pymeshlab's current-mesh filters, then restore."""
    before = ms.current_mesh_id()
    ms.set_current_mesh(int(mesh_id))
    try:
        yield
    finally:
        if ms.mesh_id_exists(before):
            ms.set_current_mesh(before)


def _scratch(mesh, values):
    """Add ``values`` (n,) as a fresh scratch scalar attribute and return its name."""
    name = f"curvdetail_scratch_{next(_scratch_ids)}"
    mesh.add_vertex_custom_scalar_attribute(np.ascontiguousarray(values, dtype=np.float64), name)
    return name


def _as_columns(mesh, values, width, what):
    n = mesh.vertex_number()
    arr = np.asarray(values, dtype=np.float64)
    shape = (n, width) if width > 1 else (n,)
    if arr.shape != shape:
        raise MeshError(f"{what} has shape {arr.shape}; expected {shape} for this layer.", value=arr.shape)
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.isfinite(arr.reshape(n, -1)).all(axis=1))
        raise MeshError(f"{what} holds NaN or infinite values; refusing to store them.", count=int(bad.size),
                        first=bad[:3].tolist())
    return arr


def set_vertex_attribute(ms, mesh_id, name, values):
    """Store ``values`` as the custom per-vertex attribute ``name`` of a layer, creating it or
    overwriting it: (n, 3) -> point attribute, (n,) -> scalar attribute."""
    mesh = get_mesh(ms, mesh_id)
    arr = np.asarray(values, dtype=np.float64)
    kind = "point" if arr.ndim == 2 else "scalar"
    arr = _as_columns(mesh, arr, 3 if kind == "point" else 1, f"attribute {name!r}")
    WRITTEN_ATTRIBUTES[name] = kind
    if vertex_attribute(ms, mesh_id, name, kind) is None:
        if kind == "point":
            mesh.add_vertex_custom_point_attribute(np.ascontiguousarray(arr), name)
        else:
            mesh.add_vertex_custom_scalar_attribute(np.ascontiguousarray(arr), name)
        return
    with _current(ms, mesh_id):
        if kind == "point":
            sx, sy, sz = (_scratch(mesh, arr[:, k]) for k in range(3))
            ms.compute_new_custom_point_attribute_per_vertex(name=name, x_expr=sx, y_expr=sy, z_expr=sz)
        else:
            ms.compute_new_custom_scalar_attribute_per_vertex(name=name, expr=_scratch(mesh, arr))


def set_vertex_quality(ms, mesh_id, quality):
    """Set a layer's per-vertex quality in place, and its vertex colours from it
    (`colour_by_quality`); returns the colour range ``(lo, hi)``."""
    mesh = get_mesh(ms, mesh_id)
    q = _as_columns(mesh, quality, 1, "vertex quality")
    with _current(ms, mesh_id):
        ms.compute_scalar_by_function_per_vertex(q=_scratch(mesh, q), normalize=False, map=False,
                                                 onselected=False)
    return colour_by_quality(ms, mesh_id, q)


#: pymeshlab's name of the colour map of the vertex colours set from a quality (matplotlib's viridis).
COLOUR_MAP = "Viridis"


def colour_by_quality(ms, mesh_id, quality):
    """Colour a layer's vertices by its quality, which MeshLab shows on open and a PLY keeps:
    `COLOUR_MAP` over [0, max] for a quality of one sign (a distance), over [-m, m], m the
    largest magnitude, for a signed one (a mean curvature), so that 0 is the middle colour.
    Returns ``(lo, hi)``, in the quality's units."""
    q = np.asarray(quality, dtype=np.float64)
    top = float(np.abs(q).max(initial=0.0))
    lo, hi = (0.0, top) if q.size == 0 or q.min() >= 0 else (-top, top)
    with _current(ms, mesh_id):
        ms.compute_color_from_scalar_per_vertex(minval=lo, maxval=hi if hi > lo else lo + 1.0, perc=0.0,
                                                zerosym=False, colormap=COLOUR_MAP)
    return lo, hi


def set_vertex_positions(ms, mesh_id, X):
    """Move a layer's vertices to ``X`` (n, 3) in place (same layer, faces and attributes)."""
    mesh = get_mesh(ms, mesh_id)
    X = _as_columns(mesh, X, 3, "vertex positions")
    with _current(ms, mesh_id):
        sx, sy, sz = (_scratch(mesh, X[:, k]) for k in range(3))
        ms.compute_coord_by_function(x=sx, y=sy, z=sz, onselected=False)


def add_layer(ms, V, F, label, *, quality=None, attributes=None):
    """Add ``(V, F)`` as a new layer called ``label`` and make it current; return its id.

    ``quality`` (n,) becomes the vertex quality and the vertex colours (`colour_by_quality`);
    ``attributes`` maps names to (n, 3) point or
    (n,) scalar custom attributes."""
    import pymeshlab

    kwargs = {}
    if quality is not None:
        kwargs["v_scalar_array"] = np.ascontiguousarray(quality, dtype=np.float64)
    mesh = pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(V, dtype=np.float64),
                          face_matrix=np.ascontiguousarray(F, dtype=np.int32), **kwargs)
    ms.add_mesh(mesh, label)
    mid = int(ms.current_mesh_id())
    if quality is not None:
        colour_by_quality(ms, mid, quality)
    # attributes go onto the MeshSet's own copy: pymeshlab's add_mesh copies custom attributes in
    # a way its PLY exporter later crashes on (segmentation fault)
    for name, values in (attributes or {}).items():
        set_vertex_attribute(ms, mid, name, values)
    return mid
