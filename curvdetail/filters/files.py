"""Load mesh files into a MeshSet and save its current mesh with the filters' results.

PLY is read and written with plyfile (`curvdetail.io.ply`): double coordinates, the vertex
quality, colours and selection (in MeshLab's vertex flags), and every custom per-vertex
attribute a filter stored (``curvature_detail``, ``curvature_area``, ...; a point attribute as
the properties ``<name>_x``, ``<name>_y``, ``<name>_z``), so one step's output is the next one's
input. Other formats are loaded by pymeshlab (`curvdetail.io.mesh.load_new_mesh`) and
saved as `curvdetail.write_mesh` writes them: the geometry. Saves are atomic and replace
an existing file only with ``overwrite=True``.
"""

import os
import tempfile
import weakref

import numpy as np

from ..io.mesh import check_mesh_output, load_new_mesh, read_mesh, write_mesh_fields
from ..io.ply import write_ply
from .meshset import WRITTEN_ATTRIBUTES, get_mesh, set_vertex_attribute, vertex_attribute

#: MeshLab's vertex flag bit of a selected vertex (vcglib's ``SELECTED``).
SELECTED = 32
_RGBA = ("red", "green", "blue", "alpha")
#: The PLY vertex properties pymeshlab reads as the layer's own: the rest are custom attributes.
_OWN = ("quality", "flags") + _RGBA
#: The checks of an output path, before any work (the CLI's ``apply`` and ``run`` use it).
check_output_path = check_mesh_output

#: the absolute path each layer of a MeshSet made by `load_meshset` was read from, with a
#: digest of its geometry then (pymeshlab gives Python only the bare file name, ``Mesh.label()``)
_LOADED_FROM = weakref.WeakKeyDictionary()


def load_meshset(path, *more):
    """A new ``pymeshlab.MeshSet`` with the mesh file ``path`` as layer 0 and the files in
    ``more`` as layers 1, 2, ... (the last one current, as with ``load_new_mesh``).

    A PLY file's quality, colours, selection and other per-vertex properties come with it (the
    others as custom attributes). Raises as `curvdetail.read_mesh`.
    """
    import pymeshlab

    ms = pymeshlab.MeshSet()
    for p in (path, *more):
        p = os.fsdecode(p)
        if os.path.splitext(p)[1].lower() == ".ply":
            _add_ply_layer(ms, p)
        else:
            load_new_mesh(ms, p)
        _LOADED_FROM.setdefault(ms, {})[ms.current_mesh_id()] = (os.path.abspath(p),
                                                                  _geometry_digest(ms.current_mesh()))
    return ms


def _add_ply_layer(ms, path):
    """Add the PLY file ``path`` as a new current layer: read with plyfile, handed to pymeshlab
    as a plain binary PLY of its geometry, quality, colours and flags (pymeshlab marks a layer
    as having quality and colours only where its file has them; one made from arrays always
    does), its other vertex properties added as custom attributes."""
    V, F, fields = read_mesh(path, fields=True)
    own = {name: fields.pop(name) for name in _OWN if name in fields}
    if "flags" in own:              # the selection bit alone: pymeshlab drops vertices flagged deleted
        own["flags"] = (own["flags"].astype(np.int64) & SELECTED).astype(np.int32)
    with tempfile.TemporaryDirectory(prefix="curvdetail-") as folder:
        write_ply(os.path.join(folder, "layer.ply"), V, F, own)
        ms.load_new_mesh(os.path.join(folder, "layer.ply"))
    ms.current_mesh().set_label(os.path.basename(path))
    for name, values in fields.items():
        if values.dtype.kind in "fiu" and np.isfinite(values).all():
            set_vertex_attribute(ms, ms.current_mesh_id(), name, values)


def loaded_from(ms, mesh_id):
    """The absolute path of the file `load_meshset` read layer ``mesh_id`` of ``ms`` from,
    or None: a layer pymeshlab loaded itself, one made in memory, or one whose vertices or
    triangles changed since (a filter in a script smoothed it: the file is no longer its source)."""
    path, digest = _LOADED_FROM.get(ms, {}).get(mesh_id, (None, None))
    if path is None or _geometry_digest(ms.mesh(mesh_id)) != digest:
        return None
    return path


def _geometry_digest(mesh):
    """A digest of a pymeshlab mesh's vertex and face matrices (a few ms at 100k vertices)."""
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    for arr in (mesh.vertex_matrix(), mesh.face_matrix()):
        h.update(np.ascontiguousarray(arr).tobytes())
    return h.digest()


def _is_ply(path):
    return os.path.splitext(os.fsdecode(path))[1].lower() == ".ply"


def _attributes_on_current_mesh(ms):
    """``(name, kind)`` of every custom attribute a filter stored that the current mesh holds."""
    mid = ms.current_mesh_id()
    return [(name, kind) for name, kind in sorted(WRITTEN_ATTRIBUTES.items())
            if vertex_attribute(ms, mid, name, kind) is not None]


def attributes_lost_in(ms, path):
    """Names of the filters' custom attributes on the current mesh that ``path``'s format does
    not hold (all of them but for PLY), sorted."""
    return [] if _is_ply(path) else [name for name, _ in _attributes_on_current_mesh(ms)]


def vertex_colours_kept_in(ms, path):
    """Whether `save_current_mesh` writes the current mesh's vertex colours to ``path``:
    PLY, and colours other than the opaque white pymeshlab gives every mesh built from arrays."""
    mesh = ms.current_mesh()
    return _is_ply(path) and mesh.has_vertex_color() and not bool(np.all(mesh.vertex_color_matrix() == 1.0))


def save_current_mesh(ms, path, *, overwrite=False):
    """Atomically save the current mesh of ``ms``: to PLY with its quality, colours (see
    `vertex_colours_kept_in`), selection and custom attributes; to other formats its
    geometry, as `curvdetail.write_mesh` writes it. The layer is left as it is.

    Raises FileExistsError (``path`` exists, ``overwrite`` False), MeshError (``path`` cannot
    be written), MeshFileError (the write failed; nothing is left behind).
    """
    check_mesh_output(path, overwrite)
    mid = ms.current_mesh_id()
    mesh = get_mesh(ms, mid)
    fields = {}
    if _is_ply(path):
        if mesh.has_vertex_scalar():
            fields["quality"] = mesh.vertex_scalar_array()
        if vertex_colours_kept_in(ms, path):
            rgba = np.rint(mesh.vertex_color_matrix() * 255.0).astype(np.uint8)
            fields.update({c: rgba[:, k] for k, c in enumerate(_RGBA)})
        if mesh.selected_vertex_number():
            fields["flags"] = np.where(mesh.vertex_selection_array(), SELECTED, 0).astype(np.int32)
        for name, kind in _attributes_on_current_mesh(ms):
            fields[name] = vertex_attribute(ms, mid, name, kind)
    write_mesh_fields(path, mesh.vertex_matrix(), mesh.face_matrix(), fields, overwrite=overwrite)
