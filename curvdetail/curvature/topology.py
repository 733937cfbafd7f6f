"""Mesh topology from the triangles ``F`` (m, 3) alone: edges, boundary, pieces, manifoldness
and orientation."""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .errors import ConstraintError, MeshError, counted, first_indices, them


def as_faces(F, n_vertices, name="F"):
    """Return ``F`` as a C-contiguous (m, 3) int64 array with indices in range, or raise MeshError
    with ``parameter``, ``count`` and ``first`` (``n_vertices=None``: only refuse negative
    indices, for functions of ``F`` alone). Whole floats are taken as indices."""
    def refuse(problem, bad=None):
        return MeshError(problem, parameter=name, count=None if bad is None else int(bad.size),
                         first=None if bad is None else bad[:3].tolist())

    try:
        arr = np.asarray(F)
    except Exception as exc:
        raise refuse(f"{name} could not be read as an array ({exc}); pass an (m, 3) int array.") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise refuse(f"{name} has shape {arr.shape}; triangles must be an (m, 3) integer array.")
    if arr.shape[0] == 0:
        raise refuse(f"{name} is empty (0 triangles); pass a mesh with at least one triangle.")
    if arr.dtype.kind not in "iuf":
        raise refuse(f"{name} has dtype {arr.dtype}; triangle indices must be integers.")
    if arr.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero((arr != np.round(arr)).any(axis=1) | ~np.isfinite(arr).all(axis=1))
        if bad.size:
            raise refuse(f"{name} has non-integer entries (first triangles: {first_indices(bad)}); triangle "
                         "indices must be integers.", bad)
    limit = np.inf if n_vertices is None else n_vertices
    bad = np.flatnonzero(((arr < 0) | (arr >= limit)).any(axis=1))   # before the cast: no wrap-around
    if bad.size:
        where = "negative vertex indices" if n_vertices is None else f"vertex indices outside [0, {n_vertices})"
        raise refuse(f"{name}: {counted(bad.size, 'triangle', verb='have')} {where} (first: {first_indices(bad)}); "
                     "indices are 0-based into V.", bad)
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    rep = np.flatnonzero((arr[:, 0] == arr[:, 1]) | (arr[:, 1] == arr[:, 2]) | (arr[:, 0] == arr[:, 2]))
    if rep.size:
        raise refuse(f"{name}: {counted(rep.size, 'triangle', verb='repeat')} a vertex index (first: "
                     f"{first_indices(rep)}); remove {them(rep.size)}, e.g. with pymeshlab's meshing_remove_null_faces.",
                     rep)
    return arr


def repeated_triangles(F, n):
    """Triangles with the vertices of an earlier one, in any order or orientation: None where
    there are none, else a (k, 2) array of pairs ``(first, repeat)``, ordered by ``repeat``.
    ``n``: the number of vertices. The faces are counted per (smallest vertex, other two) in a
    sparse matrix (no sort of all faces); only a repeat sorts them."""
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
    _, first, inverse = np.unique(np.sort(F, axis=1), axis=0, return_index=True, return_inverse=True)
    repeat = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(m))
    if not repeat.size:
        return None
    return np.column_stack([first[inverse.reshape(-1)][repeat], repeat])


def edge_keys(F):
    """Key ``min * n + max`` of every half-edge's undirected edge, shape (3m,) (half-edge 3f + k
    is opposite corner k of face f), and that ``n``."""
    n = int(F.max()) + 1
    b = F[:, [1, 2, 0]].ravel()          # half-edge 3f + k joins corners k+1 and k+2 of face f
    c = F[:, [2, 0, 1]].ravel()
    return np.minimum(b, c) * n + np.maximum(b, c), n


def non_manifold_edges(F):
    """Undirected edges used by more than two triangles, shape (k, 2), sorted."""
    keys, n = edge_keys(F)
    keys.sort()
    # after sorting, an edge used three or more times has equal keys two places apart
    bad = np.unique(keys[2:][keys[2:] == keys[:-2]])
    return np.column_stack([bad // n, bad % n]) if bad.size else np.zeros((0, 2), dtype=F.dtype)


def boundary_edges(F):
    """Edges used by exactly one triangle, each oriented as in its triangle.

    Parameters
    ----------
    F : (m, 3) int array
        Triangles (whole floats are taken); indices need not be contiguous.

    Returns
    -------
    E : (k, 2) int64 array
        Boundary edges as (from, to) in their triangle's winding (counter-clockwise seen from the
        normals of a consistently oriented disk), rows ordered by (min, max); (0, 2) if closed.

    Raises
    ------
    MeshError
        If ``F`` is not an (m, 3) integer array, is empty, or has a negative or repeated index.

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
    keys, _ = edge_keys(F)
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
    keys, n = edge_keys(F)
    directed = F[:, [1, 2, 0]].ravel() * n + F[:, [2, 0, 1]].ravel()
    order = np.argsort(keys, kind="stable")
    keys, directed = keys[order], directed[order]
    same = (keys[1:] == keys[:-1]) & (directed[1:] == directed[:-1])
    bad = np.unique(directed[1:][same])
    E = np.column_stack([bad // n, bad % n]).astype(F.dtype, copy=False)
    return E if ids is None else ids[E]


def check_oriented(F, what="the mesh", error=MeshError):
    """Raise ``error`` if triangles of ``F`` are wound against their neighbours (see
    `misoriented_edges`), naming ``what``."""
    E = misoriented_edges(F)
    if E.shape[0]:
        pairs = ", ".join(f"({a}, {b})" for a, b in E[:3])
        raise error(f"{what} is not consistently oriented: {E.shape[0]} interior edges run the same way "
                    f"in both their triangles (first: {pairs}); orient the triangles consistently (e.g. "
                    "pymeshlab's meshing_re_orient_faces_coherently) and try again.", parameter="F",
                    count=int(E.shape[0]), first=[tuple(int(v) for v in e) for e in E[:3]])


def _compact_ids(F):
    """``(ids, F')`` with ``F = ids[F']`` and ``F'`` numbered ``0 .. len(ids) - 1`` where ``F``'s
    largest index is far above its number of corners (per-vertex arrays would be huge, edge keys
    overflow); ``(None, F)`` otherwise."""
    if F.size == 0 or int(F.max()) < 2 * F.size + 1024:
        return None, F
    ids, inverse = np.unique(F, return_inverse=True)
    return ids, inverse.reshape(F.shape)


def boundary_vertices(F):
    """Sorted indices of the vertices on an edge of exactly one triangle.

    Parameters
    ----------
    F : (m, 3) int array
        Triangles, as for `boundary_edges`.

    Returns
    -------
    b : (k,) int64 array
        Vertex indices, increasing, each once; empty for a closed surface.

    Raises
    ------
    MeshError
        As `boundary_edges`.

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
    # triangles per undirected edge by a sparse COO -> CSR pass (no sort of all half-edges)
    n = int(F.max()) + 1
    b, c = F[:, [1, 2, 0]].ravel(), F[:, [2, 0, 1]].ravel()
    counts = sp.csr_matrix((np.ones(b.size, dtype=np.int32), (np.minimum(b, c), np.maximum(b, c))), shape=(n, n))
    counts.sum_duplicates()
    once = counts.data == 1
    on_boundary = np.zeros(n, dtype=bool)
    on_boundary[np.repeat(np.arange(n), np.diff(counts.indptr))[once]] = True
    on_boundary[counts.indices[once]] = True
    return np.flatnonzero(on_boundary) if ids is None else ids[on_boundary]


def vertex_components(F, n, adjacency=None):
    """Connected-component label per vertex, shape (n,), and the number of components.
    ``adjacency``: an (n, n) sparse matrix with the mesh's edge pattern, if at hand."""
    if adjacency is None:                   # two edges per triangle connect all three corners
        rows = np.concatenate([F[:, 0], F[:, 1]])
        cols = np.concatenate([F[:, 1], F[:, 2]])
        adjacency = sp.csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(n, n))
    count, labels = connected_components(adjacency, directed=False)
    return labels, count


def check_every_component_fixed(F, n, fixed, adjacency=None):
    """Raise ConstraintError if a connected component has no fixed vertex (``first``: a vertex of
    each such piece). ``adjacency``: see `vertex_components`."""
    labels, count = vertex_components(F, n, adjacency)
    has = np.zeros(count, dtype=bool)
    has[labels[fixed]] = True
    missing = np.flatnonzero(~has)
    if missing.size:
        example = [int(np.flatnonzero(labels == c)[0]) for c in missing[:3]]
        raise ConstraintError(
            f"{missing.size} of {count} connected components have no fixed vertex (e.g. the pieces "
            f"containing vertex {', '.join(map(str, example))}); their position is undetermined. "
            "Fix at least one vertex in every piece, or split the mesh.", parameter="fixed",
            count=int(missing.size), first=example)
