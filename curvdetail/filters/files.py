"""Load a mesh file into a MeshSet and save its current mesh with the filters' results.

Saving keeps what the format can hold: in PLY (binary, doubles) the vertex quality and every
custom per-vertex attribute the filters wrote (``curvature_normal``, ``curvature_detail``,
``curvature_area``, ...; pymeshlab's PLY exporter options ``__ca_vp__<name>`` /
``__ca_vs__<name>``), read back by :func:`load_meshset`, and a vertex selection (in the vertex
flags, as MeshLab saves it); OBJ, OFF and CTM hold the geometry and
the vertex colours (:data:`VERTEX_COLOUR_FORMATS`), STL the geometry only. Vertex normals and
colours are written only where the layer holds its own, not those pymeshlab computes or gives
every mesh (:func:`vertex_normals_kept`, :func:`vertex_colours_kept_in`). The file is written
from the MeshSet itself (pymeshlab crashes when a mesh with custom attributes is copied into
another MeshSet and its attributes exported), to a temporary file in the same folder and
renamed, so a failed save leaves nothing behind; an existing file is replaced only with
``overwrite=True``. .3ds is the exception: it is written from a copy
(:func:`curvdetail.io.save_mesh`, as :func:`curvdetail.write_mesh` writes it), since pymeshlab's
3DS writer fills what it leaves unset from uninitialised memory, and so differed from process to
process written from the layer itself.
"""

import os
import weakref

import numpy as np

from ..io.atomic import atomic_write
from ..io.mesh import MeshFileError, _save, check_coordinates, check_mesh_output, input_path, load_checked, save_mesh
from .meshset import WRITTEN_ATTRIBUTES, set_vertex_attribute, vertex_attribute
from .ply_attributes import read_ply_vertex_attributes

_HINT = "use .ply to keep quality and curvature attributes, or .obj, .off, .stl"

#: the absolute path each layer of a MeshSet made by :func:`load_meshset` was read from, with a
#: digest of its geometry then (pymeshlab keeps the path too, but gives Python only the bare
#: file name, ``Mesh.label()``)
_LOADED_FROM = weakref.WeakKeyDictionary()


def load_meshset(path, *more):
    """A new ``pymeshlab.MeshSet`` with the mesh file ``path`` as layer 0 and the files in
    ``more`` as layers 1, 2, ... (the last one loaded is current, as with pymeshlab's
    ``load_new_mesh``). The custom per-vertex attributes of PLY files (pymeshlab's loader drops
    them) are added back, and a CTM file's vertex colours and quality are set as the file holds
    them (pymeshlab reads the quality from the colour map; see
    :func:`curvdetail.io.load_checked`).

    Raises FileNotFoundError if a file does not exist, MeshFileError if pymeshlab cannot read it
    or dropped vertices or faces of an OBJ, OFF, PLY or STL file, or a face index is out of range
    (see :func:`curvdetail.read_mesh`)."""
    import pymeshlab

    paths = [input_path(p) for p in (path, *more)]
    ms = pymeshlab.MeshSet()
    for p in paths:
        n = load_checked(ms, p).vertex_number()
        _LOADED_FROM.setdefault(ms, {})[ms.current_mesh_id()] = (os.path.abspath(os.fsdecode(p)),
                                                                  _geometry_digest(ms.current_mesh()))
        for name, values in read_ply_vertex_attributes(p).items():
            if values.shape in ((n,), (n, 3)) and np.all(np.isfinite(values)):
                set_vertex_attribute(ms, ms.current_mesh_id(), name, values)
    return ms


def loaded_from(ms, mesh_id):
    """The absolute path of the file :func:`load_meshset` read layer ``mesh_id`` of ``ms`` from,
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


def check_output_path(path, overwrite=False):
    """Raise before any work if ``path`` cannot be written: it exists (and not ``overwrite``),
    it is a folder, its folder does not exist, or its extension names no mesh format pymeshlab
    writes (:func:`curvdetail.io.check_mesh_output`)."""
    return check_mesh_output(path, overwrite, hint=_HINT)


def save_options(ms, path):
    """pymeshlab ``save_current_mesh`` options that keep quality and our attributes in PLY, and
    the coordinates in CTM (its default compresses them to a grid). CTM keeps vertex colours but
    never the quality: a "Quality" map without a "Color" one crashes pymeshlab's CTM reader, and
    with one it reads the colours' red channel as the quality (:mod:`curvdetail._ctm_scan`;
    :func:`load_meshset` reads the map itself, MeshLab and pymeshlab do not)."""
    extension = os.path.splitext(os.fsdecode(path))[1].lower()      # a bytes one was b'.ply', never '.ply'
    if extension == ".ctm":
        return {"lossless": True, "save_vertex_quality": False,
                "save_vertex_color": vertex_colours_kept_in(ms, path)}     # not the white every built layer has
    if extension != ".ply":
        return {}
    mesh = ms.current_mesh()
    options = {"binary": True}
    if mesh.has_vertex_scalar():
        options["save_vertex_quality"] = True
    if mesh.selected_vertex_number():
        # the selection rides in the vertex flags, as MeshLab saves it: the fixed vertices of a
        # later apply_curvature_reconstruction (curvdetail apply ... then apply ...) were lost
        options["save_vertex_flag"] = True
    for name, kind in _attributes_on_current_mesh(ms):
        options[("__ca_vp__" if kind == "point" else "__ca_vs__") + name.lower()] = True
    return options


def _attributes_on_current_mesh(ms):
    """``(name, kind)`` of every custom attribute a filter wrote that the current mesh holds, sorted."""
    mid = ms.current_mesh_id()
    return [(name, kind) for name, kind in sorted(WRITTEN_ATTRIBUTES.items())
            if vertex_attribute(ms, mid, name, kind) is not None]


def attributes_lost_in(ms, path):
    """Names of the filters' custom attributes on the current mesh that ``path``'s format does
    not hold (all of them but for PLY), sorted."""
    if os.path.splitext(os.fsdecode(path))[1].lower() == ".ply":
        return []
    return [name for name, _ in _attributes_on_current_mesh(ms)]


#: Formats whose pymeshlab writer saves vertex colours (it has the ``save_vertex_color`` option, on
#: by default; pymeshlab 2025.7): :func:`save_current_mesh` keeps a layer's colours in these. The
#: other formats it writes (.stl, .3ds, .3mf, .dxf) hold none.
VERTEX_COLOUR_FORMATS = (".ply", ".obj", ".off", ".ctm", ".dae", ".wrl", ".x3d", ".json", ".idtf")


def vertex_colours_kept_in(ms, path):
    """Whether :func:`save_current_mesh` writes the current mesh's vertex colours to ``path``:
    the layer has vertex colours other than opaque white everywhere (pymeshlab gives every mesh
    made from arrays, e.g. a filter's new layer, white ones, which say nothing) and the format
    holds them (:data:`VERTEX_COLOUR_FORMATS`)."""
    mesh = ms.current_mesh()
    if os.path.splitext(os.fsdecode(path))[1].lower() not in VERTEX_COLOUR_FORMATS or not mesh.has_vertex_color():
        return False
    return not bool(np.all(mesh.vertex_color_matrix() == 1.0))


def vertex_normals_kept(ms):
    """Whether :func:`save_current_mesh` writes the current mesh's vertex normals (where the
    format holds them): they are not those pymeshlab derives from the geometry. pymeshlab gives
    every mesh normals, computed (the angle-weighted sum of its faces' normals) where a file had
    none and for a mesh made from arrays; written, they turned a plain OBJ into an OFF file
    headed NOFF, and they say nothing a reader cannot compute. Normals pointing as the computed
    ones do (any length) count as computed."""
    import pymeshlab

    mesh = ms.current_mesh()
    normals = mesh.vertex_normal_matrix()
    if normals.shape[0] == 0:
        return False
    computed = pymeshlab.Mesh(vertex_matrix=mesh.vertex_matrix(), face_matrix=mesh.face_matrix()).vertex_normal_matrix()
    return not np.allclose(_unit(normals), _unit(computed), rtol=0.0, atol=1e-6)


def _unit(vectors):
    length = np.linalg.norm(vectors, axis=1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros(vectors.shape), where=length > 0)


def save_current_mesh(ms, path, *, overwrite=False):
    """Atomically save the current mesh of ``ms`` (see the module docstring for what is kept).
    The layer itself is left as it is (.3ds: written from a copy, its faces given white where
    they have no colour, as :func:`curvdetail.io.save_mesh` does). Vertex normals and colours
    are written only where the layer really holds them (:func:`vertex_normals_kept`,
    :func:`vertex_colours_kept_in`), not those pymeshlab computes or gives every mesh.

    Raises FileExistsError, MeshFileError (unknown or points-only format, a folder, missing
    folder, a path that is not UTF-8, pymeshlab failed)."""
    path = check_output_path(path, overwrite)        # a str from here on: a bytes one compared as b'.ply'
    if os.path.splitext(path)[1].lower() == ".3ds":
        # from the layer itself the writer named the faces' material (no face colours) and set
        # their flags from uninitialised memory: the bytes differed from process to process.
        # 3DS holds no custom attributes, so the copy's (which crash an attribute export) stay unsaved.
        save_mesh(path, ms.current_mesh(), overwrite=overwrite)
        return
    options = save_options(ms, path)
    check_coordinates(path, ms.current_mesh().vertex_matrix(), **options)    # what the format cannot hold
    # turned off where the format has the option (pymeshlab refuses one it lacks): what every
    # mesh has, not the layer's own
    optional = {}
    if not vertex_normals_kept(ms):
        optional["save_vertex_normal"] = False
    if not vertex_colours_kept_in(ms, path):
        optional["save_vertex_color"] = False
    with atomic_write(path, overwrite=overwrite) as tmp:
        try:
            _save(ms, tmp, options, optional)
        except Exception as exc:
            detail = " ".join(str(exc).replace(tmp, path).split()) or type(exc).__name__
            raise MeshFileError(f"could not write {path!r}: {detail}") from None
