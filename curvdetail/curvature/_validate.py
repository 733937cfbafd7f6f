"""Input checks shared by the public functions of :mod:`curvdetail.curvature`.

They run at the boundary of each public function, before any sparse algebra, and raise
:class:`MeshError` / :class:`ConstraintError` with messages that name the problem, the count
and the first offending indices.
"""

import math
import numbers

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ._geometry import corner_cotangents
from .errors import ConstraintError, MeshError, counted, first_indices, them

#: Largest coordinate magnitude taken: triangle areas square the cross products of edge vectors
#: (coordinates squared), which overflow double precision from ~1e77 (mean_curvature_normal then
#: returned inf / NaN without a word).
MAX_COORDINATE = 1e75

#: Smallest bbox diagonal taken. Triangle areas square the cross products of edge vectors
#: (fourth powers of lengths): a triangle that passes the zero-area check (area above
#: ``ZERO_AREA_RELATIVE`` of the diagonal squared) then has a squared cross product of at least
#: 4e-28 diag^4 = 4e-268, clear of the subnormals below 2.2e-308. Smaller meshes lost digits
#: without a word (the nose scaled by 1e-78: K 1e-4 off, a reconstruction 5e-7) before whole
#: areas came out as zero.
MIN_DIAGONAL = 1e-60

# A triangle whose area is below this fraction of the squared bbox diagonal is degenerate:
# its cotangents overflow. 1e-14 leaves room for meshes of ~1e12 well-shaped triangles.
ZERO_AREA_RELATIVE = 1e-14
#: what to do about them: removing one leaves a slit in the surface where it was
ZERO_AREA_ADVICE = ("flip or collapse them away, e.g. with pymeshlab's meshing_remove_t_vertices(method=1) "
                    "for flat slivers (meshing_remove_null_faces drops exactly-zero triangles only, and "
                    "leaves a slit where each was)")


def as_vertices(V, name="V", dim=3, max_coordinate=MAX_COORDINATE):
    """Return ``V`` as a C-contiguous (n, dim) float64 array or raise MeshError (``dim=2``: planar
    positions, e.g. UVs; ``max_coordinate``: for callers that compute in a unit frame)."""
    try:
        arr = np.asarray(V)
    except Exception as exc:  # ragged lists and the like
        raise MeshError(f"{name} could not be read as an array ({exc}); pass an (n, {dim}) float array.") from None
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise MeshError(f"{name} has dtype {arr.dtype}; pass an (n, {dim}) array of real numbers.")
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise MeshError(f"{name} has shape {arr.shape}; vertex positions must be an (n, {dim}) array.")
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty (0 vertices); pass a mesh with at least one triangle.")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.isfinite(arr).all():      # one flat pass; the per-row search below only on failure
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        raise MeshError(
            f"{name}: {counted(bad.size, 'vertex', 'vertices', verb='have')} NaN or infinite coordinates "
            f"(first: {first_indices(bad)}); "
            f"remove or repair {them(bad.size)} before computing curvature."
        )
    _check_magnitude(arr, name, MeshError, "scale the mesh down", max_coordinate)
    return arr


def _check_magnitude(arr, name, error, fix, limit=MAX_COORDINATE):
    """Refuse values beyond ``limit``, where the geometry's products overflow."""
    if arr.size and np.abs(arr).max() > limit:
        bad = np.flatnonzero((np.abs(arr) > limit).any(axis=1))
        raise error(f"{name}: {counted(bad.size, 'row', verb='reach')} {np.abs(arr).max():.3g} "
                    f"(first: {first_indices(bad)}); "
                    f"beyond {limit:.0e} the geometry overflows double precision: {fix}.")


def as_faces(F, n_vertices, name="F"):
    """Return ``F`` as a C-contiguous (m, 3) int64 array with indices in range, or raise
    (``n_vertices=None``: only refuse negative indices, for functions of ``F`` alone)."""
    try:
        arr = np.asarray(F)
    except Exception as exc:
        raise MeshError(f"{name} could not be read as an array ({exc}); pass an (m, 3) int array.") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise MeshError(f"{name} has shape {arr.shape}; triangles must be an (m, 3) integer array.")
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty (0 triangles); pass a mesh with at least one triangle.")
    if np.issubdtype(arr.dtype, np.floating):
        if not np.all(np.isfinite(arr)) or np.any(arr != np.round(arr)):
            raise MeshError(f"{name} has non-integer entries; triangle indices must be integers.")
        if np.abs(arr).max() >= 2.0 ** 62:
            raise MeshError(f"{name} has entries of {np.abs(arr).max():.3g}; triangle indices must be "
                            "integers below the vertex count.")
    elif not np.issubdtype(arr.dtype, np.integer):
        raise MeshError(f"{name} has dtype {arr.dtype}; triangle indices must be integers.")
    elif arr.dtype == np.uint64 and arr.max() > np.iinfo(np.int64).max:
        raise MeshError(f"{name} has entries of {arr.max()}; triangle indices must be integers below the "
                        "vertex count.")
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    # two flat reductions; the per-triangle search only on failure (0.085 -> 0.035 s at 2M triangles)
    limit = np.iinfo(np.int64).max if n_vertices is None else n_vertices
    bad = np.empty(0, dtype=np.intp)
    if arr.min() < 0 or arr.max() >= limit:
        bad = np.flatnonzero(((arr < 0) | (arr >= limit)).any(axis=1))
    if bad.size:
        where = "negative vertex indices" if n_vertices is None else \
            f"vertex indices outside [0, {n_vertices})"
        raise MeshError(
            f"{name}: {counted(bad.size, 'triangle', verb='have')} {where} "
            f"(first: {first_indices(bad)}); indices are 0-based into V."
        )
    rep = np.flatnonzero((arr[:, 0] == arr[:, 1]) | (arr[:, 1] == arr[:, 2]) | (arr[:, 0] == arr[:, 2]))
    if rep.size:
        raise MeshError(
            f"{name}: {counted(rep.size, 'triangle', verb='repeat')} a vertex index (first: {first_indices(rep)}); "
            f"remove {them(rep.size)}, e.g. with pymeshlab's meshing_remove_null_faces."
        )
    return arr


def face_double_areas(V, F):
    """|(v1 - v0) x (v2 - v0)| per triangle, shape (m,)."""
    P0 = V[F[:, 0]]
    a, b = V[F[:, 1]] - P0, V[F[:, 2]] - P0
    cx = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    cy = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    cz = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return np.sqrt(cx * cx + cy * cy + cz * cz)


def bbox_diagonal(V):
    # reductions along the contiguous axis of V^T: ~7x faster than V.max(axis=0) on (n, 3)
    Vt = np.ascontiguousarray(np.asarray(V, dtype=np.float64).T)
    extent = Vt.max(axis=1) - Vt.min(axis=1)
    largest = float(np.abs(extent).max()) if extent.size else 0.0
    if not 0.0 < largest < np.inf:
        return largest
    # scaled by the largest extent: no square over- or underflows to a wrong diagonal (and numpy
    # 2.4's norm raises an underflow of a negligible component under the caller's errstate)
    with np.errstate(under="ignore"):
        return largest * float(np.sqrt(np.sum((extent / largest) ** 2)))


def centroid_diameter(V):
    """Twice the largest distance of a vertex from the vertices' centroid: a length of the
    bounding-box diagonal's size (equal to it for a box) that, unlike the diagonal, does not
    change when the mesh is rotated. For thresholds that must be rotation-invariant."""
    V = np.asarray(V, dtype=np.float64)
    if not V.shape[0]:
        return 0.0
    offsets = V - V.mean(axis=0)
    return float(2.0 * np.sqrt(np.einsum("ij,ij->i", offsets, offsets).max()))


def bbox_centre(V):
    """The centre of the axis-aligned bounding box, shape (3,) (zeros for no vertices)."""
    Vt = np.ascontiguousarray(np.asarray(V, dtype=np.float64).T)
    if not Vt.shape[1]:
        return np.zeros(Vt.shape[0])
    return 0.5 * (Vt.max(axis=1) + Vt.min(axis=1))


def check_mesh(V, F, *, check_manifold=True, check_unreferenced=True):
    """Validate a triangle mesh and return ``(V, F)`` as float64 / int64 arrays.

    Checks, in order: shapes and dtypes, emptiness, NaN/inf, coordinates beyond
    ``MAX_COORDINATE`` (1e75: the areas would overflow), index range, repeated indices in a face,
    a bbox diagonal below ``MIN_DIAGONAL`` (1e-60: the areas would underflow), zero-area faces
    (below ``ZERO_AREA_RELATIVE`` times the squared bbox diagonal), duplicate triangles (the
    same three vertices in any order; with ``check_manifold``), non-manifold edges (an edge in
    more than two triangles) and unreferenced vertices.

    Parameters
    ----------
    V : (n, 3) array of real numbers    vertex positions (integers are converted)
    F : (m, 3) array of integers        triangles (integral floats are accepted)
    check_manifold : bool               refuse duplicate triangles and edges shared by more than
                                        two triangles
    check_unreferenced : bool           refuse vertices used by no triangle

    Returns
    -------
    V : (n, 3) float64 C-contiguous array, a new one (never the input itself or a view of it)
    F : (m, 3) int64 C-contiguous array, likewise new

    Raises
    ------
    MeshError   naming the problem, how many elements have it, the first few indices and the fix

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]])
    >>> check_mesh(V, [[0, 1, 2]])
    Traceback (most recent call last):
    ...
    curvdetail.curvature.errors.MeshError: 1 vertex is not used by any triangle (first: 3); remove it, e.g. with pymeshlab's meshing_remove_unreferenced_vertices.
    >>> V, F = check_mesh(V[:3], [[0, 1, 2]])
    >>> V.dtype, F.dtype
    (dtype('float64'), dtype('int64'))
    """
    checked = _check_mesh(V, F, check_manifold, check_unreferenced)[:2]
    # float64 / int64 C inputs pass the conversions as themselves: copy, so that writing to the
    # result cannot change the caller's mesh (and a read-only or memmapped input comes back writable)
    return tuple(out.copy() if isinstance(given, np.ndarray) and np.may_share_memory(out, given) else out
                 for out, given in zip(checked, (V, F)))


def checked_arrays(V, F, *, check_manifold=True, check_unreferenced=True):
    """:func:`check_mesh` without its copy, for callers that only read the arrays (a float64 /
    int64 C input comes back as itself)."""
    return _check_mesh(V, F, check_manifold, check_unreferenced)[:2]


def _check_mesh(V, F, check_manifold, check_unreferenced, cotangents=False):
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    diag = bbox_diagonal(V)
    if diag < MIN_DIAGONAL:
        raise tiny_mesh_error(diag, V.shape[0])
    cot = None
    # zero areas are refused below; underflow: squares of a tiny cross-product component (a
    # triangle almost in a coordinate plane) are negligible next to the others, not an error
    with np.errstate(divide="ignore", invalid="ignore", under="ignore"):
        if cotangents:
            cot, _, dbl = corner_cotangents(V, F, lengths=False)
        else:
            dbl = face_double_areas(V, F)
    zero = np.flatnonzero(dbl <= 2.0 * ZERO_AREA_RELATIVE * diag ** 2)
    if zero.size:
        raise MeshError(f"{counted(zero.size, 'triangle', verb='have')} zero area (first: {first_indices(zero)}; "
                        f"areas up to {ZERO_AREA_RELATIVE:g} of the bbox diagonal squared count); "
                        f"{ZERO_AREA_ADVICE.replace('them', them(zero.size), 1)}, "
                        "before computing curvature.")
    if check_manifold or cotangents:           # cotangents: the caller counts the edges itself, after this
        duplicates = repeated_triangles(F, V.shape[0])
        if duplicates is not None:
            raise duplicate_triangles_error(duplicates)
    if check_manifold:
        bad = non_manifold_edges(F)
        if bad.shape[0]:
            raise non_manifold_error(bad.shape[0], bad[:3])
    if check_unreferenced:
        check_referenced(V.shape[0], F)
    return V, F, cot


def check_referenced(n, F, name=None):
    """MeshError for vertices ``0 .. n - 1`` that no triangle of ``F`` uses; ``name``: the
    argument the message starts with (``"Vs: ..."``), or none."""
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    unused = np.flatnonzero(~used)
    if unused.size:
        raise MeshError(
            f"{name + ': ' if name else ''}{counted(unused.size, 'vertex', 'vertices', verb='are')} not used by "
            f"any triangle (first: {first_indices(unused)}); "
            f"remove {them(unused.size)}, e.g. with pymeshlab's meshing_remove_unreferenced_vertices."
        )


def repeated_triangles(F, n):
    """Triangles with the vertices of an earlier one, in any order or orientation: None where
    there are none, else a (k, 2) array of pairs ``(first, repeat)``, ordered by ``repeat``, one
    per triangle that repeats an earlier one. ``n``: the number of vertices (indices below it).

    A duplicate inside a larger mesh makes an edge of three triangles (the non-manifold check
    would name it so, with the wrong fix); an isolated pair passes every other check and doubles
    the area. The faces are grouped by their smallest vertex with a sparse matrix whose column
    encodes the other two (SciPy's COO -> CSR conversion: a counting sort and sorts of a few
    entries a row, no sort of all faces): 1M-vertex grid (2M triangles) 0.04 s in its own face
    order, 0.075 s shuffled, against 0.15 s for sorting one key per face (the Laplacian's checks
    and assembly take ~0.2 / 0.35 s there; 2 busy cores, so +-0.03 s)."""
    m = F.shape[0]
    a, b, c = F[:, 0], F[:, 1], F[:, 2]
    low = np.minimum(np.minimum(a, b), c)
    high = np.maximum(np.maximum(a, b), c)
    if n <= 3_000_000_000:                     # the column mid * n + high fits an int64
        rest = a + b
        rest += c
        rest -= low
        rest -= high                           # the middle vertex
        rest *= n
        rest += high
        counts = sp.csr_matrix((np.ones(m, dtype=np.int32), (low, rest)), shape=(n, n * n))
        if counts.nnz == m:                    # no (low, mid, high) twice: the usual case
            return None
    # some triangle repeats: find which (np.unique sorts every row; error path only)
    _, first, inverse = np.unique(np.sort(F, axis=1), axis=0, return_index=True, return_inverse=True)
    repeat = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(m))
    if not repeat.size:
        return None
    return np.column_stack([first[inverse.reshape(-1)][repeat], repeat])


def duplicate_triangles_error(pairs):
    """The MeshError for :func:`repeated_triangles`' ``pairs`` (first, repeat)."""
    shown = ", ".join(f"({i}, {j})" for i, j in pairs[:3])
    return MeshError(f"F: {counted(pairs.shape[0], 'triangle', verb='repeat')} the three vertices of an earlier "
                     f"one (first pairs: {shown}): a repeated triangle counts its area and curvature twice. Remove the "
                     "duplicates, e.g. with pymeshlab's meshing_remove_duplicate_faces.")


def tiny_mesh_error(diag, n):
    """The MeshError for a mesh ``diag`` across (bbox diagonal), below ``MIN_DIAGONAL``, of ``n``
    vertices."""
    if diag == 0.0:
        return MeshError(f"the mesh is 0 across (bbox diagonal): all {n} vertices lie at one point, so every "
                         "triangle has zero area; pass the mesh's real vertex positions.")
    return MeshError(f"the mesh is {diag:.3g} across (bbox diagonal), below {MIN_DIAGONAL:.0e}: its triangle "
                     "areas (fourth powers of its lengths) underflow double precision and lose their digits; "
                     f"scale it up, e.g. to unit size (V / {diag:.3g}), and scale the results back.")


def non_manifold_error(count, first):
    """The MeshError for ``count`` edges on three or more triangles, ``first``: a few (a, b)."""
    pairs = ", ".join(f"({a}, {b})" for a, b in first)
    return MeshError(
        f"{counted(count, 'edge', verb='are')} shared by more than two triangles (first: {pairs}); "
        "the mesh is not manifold. Repair it, e.g. with pymeshlab's meshing_repair_non_manifold_edges."
    )


def undirected_edges(F):
    """All half-edges as sorted pairs, shape (3m, 2), in face order (edge k of face f at 3f+k,
    edge k joins corners k+1 and k+2, i.e. it is opposite corner k)."""
    E = np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1).reshape(-1, 2)
    return np.sort(E, axis=1)


def _edge_keys(F):
    """Key ``min * n + max`` of every half-edge's undirected edge, shape (3m,), in the order of
    :func:`undirected_edges`, and that ``n``."""
    n = int(F.max()) + 1
    b = F[:, [1, 2, 0]].ravel()          # half-edge 3f + k joins corners k+1 and k+2 of face f
    c = F[:, [2, 0, 1]].ravel()
    return np.minimum(b, c) * n + np.maximum(b, c), n


def non_manifold_edges(F):
    """Undirected edges used by more than two triangles, shape (k, 2), sorted."""
    keys, n = _edge_keys(F)
    keys.sort()
    # after sorting, an edge used three or more times has equal keys two places apart
    bad = np.unique(keys[2:][keys[2:] == keys[:-2]])
    return np.column_stack([bad // n, bad % n]) if bad.size else np.zeros((0, 2), dtype=F.dtype)


def boundary_edges(F):
    """Edges used by exactly one triangle, shape (k, 2), each oriented as in its triangle (so
    a consistently oriented disk's boundary runs counter-clockwise seen from its normals side).
    ``F`` is checked as in :func:`check_mesh` (shape, integer entries, no negative or repeated
    index in a triangle): MeshError otherwise.

    Parameters
    ----------
    F : (m, 3) int array   triangles (integral floats are accepted); no vertex positions are needed,
                           and indices need not be contiguous

    Returns
    -------
    E : (k, 2) int64 array   boundary edges as (from, to) in their triangle's winding, rows ordered
                             by the sorted pair (min, max); (0, 2) for a closed surface

    Raises
    ------
    MeshError   ``F`` not an (m, 3) integer array, empty, or with a negative or repeated index
                in a triangle

    Examples
    --------
    >>> import numpy as np
    >>> boundary_edges(np.array([[0, 1, 2], [0, 2, 3]]))     # a quad split along (0, 2)
    array([[0, 1],
           [3, 0],
           [1, 2],
           [2, 3]])
    """
    F = as_faces(F, None)
    ids, F = _compact_ids(F)
    D = np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1).reshape(-1, 2)
    keys, _ = _edge_keys(F)
    uniq, first, counts = np.unique(keys, return_index=True, return_counts=True)
    E = D[first[counts == 1]]
    return E if ids is None else ids[E]


def misoriented_edges(F):
    """Interior edges that run the same way in both their triangles, shape (k, 2) as (from, to),
    sorted: where the triangles are not consistently oriented. Empty for an oriented mesh.

    Examples
    --------
    >>> import numpy as np
    >>> misoriented_edges(np.array([[0, 1, 2], [0, 2, 3]])).tolist()    # (0, 2) against (2, 0)
    []
    >>> misoriented_edges(np.array([[0, 1, 2], [0, 3, 2]])).tolist()    # both run 2 -> 0
    [[2, 0]]
    """
    F = as_faces(F, None)
    ids, F = _compact_ids(F)
    keys, n = _edge_keys(F)
    directed = F[:, [1, 2, 0]].ravel() * n + F[:, [2, 0, 1]].ravel()
    order = np.argsort(keys, kind="stable")
    keys, directed = keys[order], directed[order]
    same = (keys[1:] == keys[:-1]) & (directed[1:] == directed[:-1])
    bad = np.unique(directed[1:][same])
    E = np.column_stack([bad // n, bad % n]).astype(F.dtype, copy=False)
    return E if ids is None else ids[E]


def check_oriented(F, what="the mesh", error=MeshError):
    """Raise ``error`` if triangles of ``F`` are wound against their neighbours (see
    :func:`misoriented_edges`). A reversed triangle at the boundary makes the boundary look
    pinched or split, and the fix is to orient the triangles, not to cut the mesh; the boundary
    checks call this on their error paths only (it sorts every half-edge)."""
    E = misoriented_edges(F)
    if E.shape[0]:
        pairs = ", ".join(f"({a}, {b})" for a, b in E[:3])
        raise error(f"{what} is not consistently oriented: {E.shape[0]} interior edges run the same way "
                    f"in both their triangles (first: {pairs}); orient the triangles consistently (e.g. "
                    "pymeshlab's meshing_re_orient_faces_coherently) and try again.")


def _compact_ids(F):
    """``(ids, F')`` with ``F = ids[F']`` and ``F'`` numbered ``0 .. len(ids) - 1``, where ``F``'s
    largest index is far above its number of corners (unchecked triangles, e.g. 2**32 - 1 as
    "no vertex": per-vertex arrays would take gigabytes and the edge keys ``min * n + max``
    overflow); ``(None, F)`` otherwise."""
    if F.size == 0 or int(F.max()) < 2 * F.size + 1024:
        return None, F
    ids, inverse = np.unique(F, return_inverse=True)
    return ids, inverse.reshape(F.shape)


def boundary_vertices(F):
    """Sorted indices of the vertices on a boundary edge; empty for a closed surface.

    A boundary edge is one used by exactly one triangle (as in :func:`boundary_edges`).

    Parameters
    ----------
    F : (m, 3) int array   triangles (integral floats are accepted), checked as in
                           :func:`boundary_edges`

    Returns
    -------
    b : (k,) int64 array   vertex indices in increasing order, each once

    Raises
    ------
    MeshError   ``F`` not an (m, 3) integer array, empty, or with a negative or repeated index
                in a triangle

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid, icosphere
    >>> boundary_vertices(grid(3, 3)[1])
    array([0, 1, 2, 3, 5, 6, 7, 8])
    >>> boundary_vertices(icosphere(subdivisions=1)[1]).size
    0
    """
    F = as_faces(F, None)
    ids, F = _compact_ids(F)
    # triangles per undirected edge by a sparse COO -> CSR pass (no sort of all half-edges:
    # 1M vertices 0.35 s against 1.0 s for np.unique of boundary_edges); cotan_laplacian's
    # _edge_pattern counts the same way, but the reconstruction tests check that its checks do
    # not count twice by disabling that one
    n = int(F.max()) + 1
    b, c = F[:, [1, 2, 0]].ravel(), F[:, [2, 0, 1]].ravel()
    counts = sp.csr_matrix((np.ones(b.size, dtype=np.int32), (np.minimum(b, c), np.maximum(b, c))), shape=(n, n))
    counts.sum_duplicates()
    once = counts.data == 1
    on_boundary = np.zeros(n, dtype=bool)
    on_boundary[np.repeat(np.arange(n), np.diff(counts.indptr))[once]] = True
    on_boundary[counts.indices[once]] = True
    return np.flatnonzero(on_boundary) if ids is None else ids[on_boundary]


def as_index_set(indices, n, name):
    """Return ``indices`` as a duplicate-free int64 array in [0, n), in the order given (a
    boolean mask gives its true positions in increasing order), or raise ConstraintError."""
    try:
        arr = np.asarray(indices)
    except Exception as exc:
        raise ConstraintError(f"{name} could not be read as an index array ({exc}).") from None
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise ConstraintError(f"{name} is a boolean mask of shape {arr.shape}; it must have shape ({n},).")
        return np.flatnonzero(arr)
    if sum(d > 1 for d in arr.shape) > 1:
        # an edge list (k, 2) or faces (m, 3): flattened, their shared vertices were called repeats
        raise ConstraintError(f"{name} has shape {arr.shape}; pass a 1-D array of vertex indices (a "
                              "column (k, 1) is taken too), e.g. np.unique(E) for the vertices of edges E.")
    arr = arr.reshape(-1)
    if arr.dtype == object and arr.size and all(isinstance(i, numbers.Integral) and not isinstance(i, bool)
                                                for i in arr):
        # Python ints (some beyond int64, or given as an object array): checked as they are
        out = np.flatnonzero([not 0 <= i < n for i in arr])
        if out.size:
            raise ConstraintError(f"{name}: {counted(out.size, 'index', 'indices', verb='are')} outside "
                                  f"[0, {n}) (first: "
                                  f"{', '.join(str(i) for i in arr[out[:3]])}); indices are 0-based into V.")
        arr = arr.astype(np.int64)
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        if not np.issubdtype(arr.dtype, np.floating):
            raise ConstraintError(f"{name} has dtype {arr.dtype}; pass integer vertex indices.")
        error = non_whole_index_error(arr, name)
        if error is not None:
            raise error
        if np.abs(arr).max() >= 2.0 ** 62:      # would not survive the cast to int64
            bad = np.flatnonzero((arr < 0) | (arr >= n))
            raise ConstraintError(f"{name}: {counted(bad.size, 'index', 'indices', verb='are')} outside "
                                  f"[0, {n}) (first: {arr[bad[0]]:.3g}); "
                                  "indices are 0-based into V.")
    elif arr.dtype == np.uint64 and arr.size and arr.max() > np.iinfo(np.int64).max:
        raise ConstraintError(f"{name}: indices up to {arr.max()} are outside [0, {n}); indices are 0-based into V.")
    arr = arr.astype(np.int64)
    out = np.flatnonzero((arr < 0) | (arr >= n))
    if out.size:
        raise ConstraintError(
            f"{name}: {counted(out.size, 'index', 'indices', verb='are')} outside [0, {n}) "
            f"(first: {first_indices(arr[out])}); "
            "indices are 0-based into V."
        )
    uniq, counts = np.unique(arr, return_counts=True)
    if uniq.size != arr.size:
        # a 0/1 mask of integers (mask.astype(int), a MeshLab selection) is the likely mistake
        mask = arr.size == n and uniq.size <= 2 and set(uniq.tolist()) <= {0, 1}
        hint = (f" It looks like a 0/1 mask of all {n} vertices: pass it as booleans "
                f"({name}=mask.astype(bool)) or as indices (np.flatnonzero(mask)).") if mask else ""
        raise ConstraintError(
            f"{name}: {counted(arr.size - uniq.size, 'index', 'indices', verb='are')} repeated "
            f"(first: {first_indices(uniq[counts > 1])}); "
            f"list each vertex once.{hint}"
        )
    return arr


def non_whole_index_error(values, name, error=ConstraintError):
    """The ``error`` for index values that are not whole numbers (3.5, NaN, inf), naming how many,
    the first and its position, and the fix; None where every value is whole (3.0 is an index,
    as pymeshlab's and libigl's float index arrays are). ``values``: real numbers, flattened.

    Examples
    --------
    >>> print(non_whole_index_error([3.0, 7.0], "handles"))
    None
    >>> print(non_whole_index_error([3.0, 7.5, np.nan], "handles"))
    handles: 2 values are not whole numbers (first: 7.5, at position 1); vertex indices are whole numbers: pass integers (or whole floats such as 3.0), not positions or weights.
    """
    arr = np.asarray(values, dtype=np.float64).reshape(-1)
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(~np.isfinite(arr) | (arr != np.round(arr)))
    if not bad.size:
        return None
    what = "is not a whole number" if bad.size == 1 else "are not whole numbers"
    return error(f"{name}: {counted(bad.size, 'value')} {what} (first: {float(arr[bad[0]])!r}, at position "
                 f"{bad[0]}); vertex indices are whole numbers: pass integers (or whole floats such as 3.0), "
                 "not positions or weights.")


def check_bool(value, name):
    """``bool(value)`` for True / False (numpy's too), else ValueError: ``"no"`` or ``0`` would
    otherwise count as an answer."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}={value!r} must be True or False.")
    return bool(value)


def as_float(value):
    """``value`` as a float if it is a real number (numpy scalars and 0-d arrays included; a
    number too large for a double becomes inf), else None (bools and strings included)."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        return None
    try:
        return float(value)
    except OverflowError:              # a Python int beyond a double
        return math.inf


def as_count(value, name, minimum=1):
    """Return ``value`` as an int >= ``minimum`` (a whole number: ints, whole floats, numpy
    scalars, 0-d arrays; not a bool or a string), or raise ValueError naming the argument."""
    number = as_float(value)
    if number is None or not math.isfinite(number) or number != round(number):
        raise ValueError(f"{name}={value!r} must be a whole number >= {minimum}.")
    if number < minimum:
        raise ValueError(f"{name}={value!r} must be at least {minimum}.")
    value = value.item() if isinstance(value, np.ndarray) else value
    return int(value) if isinstance(value, numbers.Integral) else int(number)


def as_positive_number(value, name, hint=""):
    """Return ``value`` as a finite float > 0 (see :func:`as_float`), or raise ValueError."""
    number = as_float(value)
    if number is None or not (math.isfinite(number) and number > 0):
        raise ValueError(f"{name}={value!r} must be a positive number{hint}.")
    return number


def as_values(values, count, name, dim=3):
    """Return ``values`` as a (count, dim) float64 array of finite numbers within
    ``MAX_COORDINATE`` or raise ConstraintError."""
    try:
        arr = np.asarray(values)
    except Exception as exc:
        raise ConstraintError(f"{name} could not be read as a float array ({exc}).") from None
    if arr.dtype.kind not in "fiu":            # complex would lose its imaginary part, bool mean 0/1
        raise ConstraintError(f"{name} has dtype {arr.dtype}; pass a ({count}, {dim}) array of real numbers.")
    arr = arr.astype(np.float64, copy=False)
    if arr.shape != (count, dim):
        raise ConstraintError(f"{name} has shape {arr.shape}; expected ({count}, {dim}), one row per vertex.")
    if not np.isfinite(arr).all():      # one flat pass; the per-row search below only on failure
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        raise ConstraintError(f"{name}: {counted(bad.size, 'row', verb='are')} NaN or infinite "
                              f"(first: {first_indices(bad)}).")
    _check_magnitude(arr, name, ConstraintError, "scale the problem down")
    return np.ascontiguousarray(arr)


def check_transformed_values(values, what, fix, error=ConstraintError):
    """Raise ``error`` if constraint values made by a user's transform (None: none) are not
    finite or beyond MAX_COORDINATE, naming ``what`` made them and ``fix``."""
    if values is not None and not np.all(np.abs(values) <= MAX_COORDINATE):
        raise error(f"{what} gives the handles values of {np.abs(values).max():.3g}, beyond {MAX_COORDINATE:.0e}, "
                    f"where the geometry overflows double precision; {fix}.")


def shown_choice(value):
    """How an option value that is not one of its choices is shown in a refusal: a str as its
    repr, anything else with its type, as not a single str (an array compared with ``in`` is
    compared element-wise: np.array(["all"]) passed as "all", two entries raised numpy's "truth
    value ... is ambiguous")."""
    return repr(value) if isinstance(value, str) else f"{value!r} ({type(value).__name__}, not a single str)"


def is_choice(value, choices):
    """Whether ``value`` is a str among ``choices`` (see :func:`shown_choice`)."""
    return isinstance(value, str) and value in choices


def check_choice(value, name, choices, advice, error=ValueError):
    """``value`` if it is a str among ``choices``, else ``error(f"{name}={shown}{advice}")``."""
    if is_choice(value, choices):
        return str(value)
    raise error(f"{name}={shown_choice(value)}{advice}")


def real_word(word):
    """``float(word)`` for a number written in a text file or parameter, but ValueError for
    Python's digit separators too (``1_0`` would be read as 10)."""
    if "_" in word:
        raise ValueError(f"{word!r} is not a number")
    return float(word)


def affine_transform_problem(T):
    """What is wrong with the (4, 4) handle transform ``T`` for an edit, or None: a last row other
    than (0, 0, 0, 1), or a linear part that collapses a direction (smallest over largest
    singular value below 1e-12: scale-free, so a uniform 1e-5 scaling passes and diag(1e6,
    1e6, 1e-12) does not)."""
    if not np.allclose(T[3], [0.0, 0.0, 0.0, 1.0], atol=1e-12):
        return f"the last row is {T[3].tolist()}; an affine transform has (0, 0, 0, 1) there"
    sigma = np.linalg.svd(T[:3, :3], compute_uv=False)
    if not sigma[0] > 0 or sigma[2] < 1e-12 * sigma[0]:
        return (f"its linear part is singular (singular values {sigma[0]:.3g} ... {sigma[2]:.3g}); it would "
                "collapse the handles onto a plane, a line or a point")
    return None


def vertex_components(F, n, adjacency=None):
    """Connected-component label per vertex, shape (n,), and the number of components.

    ``adjacency``: an (n, n) sparse matrix with the mesh's edge pattern (e.g. its cotangent
    Laplacian), used instead of building one from ``F``."""
    if adjacency is None:
        # two edges per triangle connect all three corners
        rows = np.concatenate([F[:, 0], F[:, 1]])
        cols = np.concatenate([F[:, 1], F[:, 2]])
        adjacency = sp.csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(n, n))
    count, labels = connected_components(adjacency, directed=False)
    return labels, count


def check_every_component_fixed(F, n, fixed, adjacency=None):
    """Raise ConstraintError if a connected component has no fixed vertex (the system is singular).
    ``adjacency``: see :func:`vertex_components`."""
    labels, count = vertex_components(F, n, adjacency)
    has = np.zeros(count, dtype=bool)
    has[labels[fixed]] = True
    missing = np.flatnonzero(~has)
    if missing.size:
        example = [int(np.flatnonzero(labels == c)[0]) for c in missing[:3]]
        raise ConstraintError(
            f"{missing.size} of {count} connected components have no fixed vertex (e.g. the pieces "
            f"containing vertex {', '.join(map(str, example))}); their position is undetermined. "
            "Fix at least one vertex in every piece, or split the mesh."
        )
