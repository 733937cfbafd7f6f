"""The curvature-detail attributes of a layer, stamped with the vertex numbering they belong to.

pymeshlab keeps custom attributes through remeshing, decimation and subdivision but does not
interpolate them: new vertices get 0 and removed ones shift the rest. Detail read after such a
step belongs to another triangulation, and rebuilding from it quietly distorts the surface (a
remeshed nose moved by 10 % of its diagonal). So every writer of ``curvature_detail`` also
stores ``curvature_vertex_id`` = 0, 1, ..., n - 1, and the readers check that it still is.
Moving vertices keeps the stamp: rebuilding moved geometry from stored detail is the editing use.
"""

import numpy as np

from .errors import FilterError
from .meshset import get_mesh, require_vertex_attribute, set_vertex_attribute, vertex_attribute

#: Custom attribute names written by compute_curvature_detail / transfer_curvature_detail.
NORMAL, DETAIL, AREA = "curvature_normal", "curvature_detail", "curvature_area"
#: The vertex numbering the detail was stored with (doubles: exact below 2^53 vertices).
VERTEX_ID = "curvature_vertex_id"


def stamp(n):
    """The ``VERTEX_ID`` values of an ``n``-vertex layer."""
    return np.arange(n, dtype=np.float64)


def store_detail(ms, mesh_id, D, K=None, A=None):
    """Store detail ``D`` (n, 3) (and optionally ``K`` (n, 3), ``A`` (n,)) with the stamp."""
    set_vertex_attribute(ms, mesh_id, DETAIL, D)
    if K is not None:
        set_vertex_attribute(ms, mesh_id, NORMAL, K)
    if A is not None:
        set_vertex_attribute(ms, mesh_id, AREA, A)
    set_vertex_attribute(ms, mesh_id, VERTEX_ID, stamp(D.shape[0]))


def load_detail(ms, mesh_id):
    """The layer's ``curvature_detail`` (n, 3); FilterError if it is missing or was stored for
    another vertex numbering. Detail without a stamp (a PLY from elsewhere) is taken as it is."""
    D = require_vertex_attribute(ms, mesh_id, DETAIL, "point",
                                 "run compute_curvature_detail or transfer_curvature_detail first.")
    ids = vertex_attribute(ms, mesh_id, VERTEX_ID, "scalar")
    if ids is not None:
        changed = np.flatnonzero(ids != stamp(ids.size))
        if changed.size:
            raise FilterError(
                f"layer {mesh_id} ({get_mesh(ms, mesh_id).label()!r}): its {DETAIL!r} belongs to "
                f"another triangulation: {changed.size:,} of {ids.size:,} vertices were added, "
                f"removed or renumbered since it was stored (first: "
                f"{', '.join(map(str, changed[:3]))}; MeshLab's remeshing filters keep custom "
                "attributes but do not interpolate them). Run compute_curvature_detail again for "
                "the detail of the current surface, or transfer_curvature_detail from a layer "
                "that still holds the original.")
    return D
