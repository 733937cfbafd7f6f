"""The curvature-detail attributes of a layer, stamped with the vertex numbering they belong to.

pymeshlab keeps custom attributes through remeshing, decimation and subdivision but does not
interpolate them: new vertices get 0 and removed ones shift the rest. Detail read after such a
step belongs to another triangulation, and rebuilding from it quietly distorts the surface (a
remeshed nose moved by 10 % of its diagonal). So every writer of ``curvature_detail`` also
stores ``curvature_vertex_id`` = 0, 1, ..., n - 1 and ``curvature_vertex_ring`` (a key of each
vertex's triangles: valence and the sum of their corner ids, which edge flips change while
keeping the numbering), and the readers check that both still hold. Moving vertices keeps the
stamp: rebuilding moved geometry from stored detail is the editing use.
"""

import numpy as np

from .errors import FilterError
from .meshset import get_mesh, require_vertex_attribute, set_vertex_attribute, vertex_attribute

#: Custom attribute names written by compute_curvature_detail / transfer_curvature_detail.
NORMAL, DETAIL, AREA = "curvature_normal", "curvature_detail", "curvature_area"
#: The vertex numbering and the triangles the detail was stored with (doubles: exact for
#: any mesh pymeshlab holds; the ring key stays below 2^53 up to ~10^8 vertices).
VERTEX_ID, VERTEX_RING = "curvature_vertex_id", "curvature_vertex_ring"


def stamp(F, n):
    """``{VERTEX_ID: ..., VERTEX_RING: ...}`` of an ``n``-vertex layer with triangles ``F``."""
    corners = F.ravel()
    around = np.bincount(corners, weights=np.repeat(F.sum(axis=1).astype(np.float64), 3), minlength=n)
    valence = np.bincount(corners, minlength=n)
    return {VERTEX_ID: np.arange(n, dtype=np.float64), VERTEX_RING: 4096.0 * around + valence}


def store_detail(ms, mesh_id, F, D, K=None, A=None):
    """Store detail ``D`` (n, 3) (and optionally ``K`` (n, 3), ``A`` (n,)) of the layer with
    triangles ``F``, with the stamp."""
    set_vertex_attribute(ms, mesh_id, DETAIL, D)
    if K is not None:
        set_vertex_attribute(ms, mesh_id, NORMAL, K)
    if A is not None:
        set_vertex_attribute(ms, mesh_id, AREA, A)
    for name, values in stamp(F, D.shape[0]).items():
        set_vertex_attribute(ms, mesh_id, name, values)


def load_detail(ms, mesh_id, F):
    """The ``curvature_detail`` (n, 3) of the layer, whose triangles are ``F`` now; FilterError
    if it is missing or was stored for another numbering or other triangles. Detail without a
    stamp (a PLY from elsewhere) is taken as it is."""
    D = require_vertex_attribute(ms, mesh_id, DETAIL, "point",
                                 "run compute_curvature_detail or transfer_curvature_detail first.")
    now = stamp(F, D.shape[0])
    changed = np.zeros(D.shape[0], dtype=bool)
    for name in (VERTEX_ID, VERTEX_RING):
        stored = vertex_attribute(ms, mesh_id, name, "scalar")
        if stored is not None:
            changed |= stored != now[name]
    changed = np.flatnonzero(changed)
    if changed.size:
        raise FilterError(
            f"layer {mesh_id} ({get_mesh(ms, mesh_id).label()!r}): its {DETAIL!r} belongs to "
            f"another triangulation: {changed.size:,} of {D.shape[0]:,} vertices were added, "
            f"removed, renumbered or re-connected since it was stored (first: "
            f"{', '.join(map(str, changed[:3]))}; MeshLab's remeshing filters keep custom "
            "attributes but do not interpolate them). Run compute_curvature_detail again for "
            "the detail of the current surface, or transfer_curvature_detail from a layer "
            "that still holds the original.", value=DETAIL, count=int(changed.size), first=changed[:3].tolist())
    return D
