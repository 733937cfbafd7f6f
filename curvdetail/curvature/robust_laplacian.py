"""A cotangent Laplacian that tolerates degenerate triangles (Sharp & Crane 2020, mollification),
and the ``laplacian`` option of every public entry point that builds a Laplacian from a user's mesh.

The plain `cotan_laplacian` refuses triangles of zero area: their cotangents
are infinite. Scans have them (a vertex on the opposite edge: a "cap"; two vertices at one point:
a "needle"). The mollified Laplacian takes its cotangents from the edge lengths alone (an
intrinsic metric), each lengthened by the smallest ``delta`` that leaves every triangle's
triangle inequality a slack of ``eps`` x the mean edge length; ``delta`` is 0 on a mesh without
such slivers, where the result is the plain cotan Laplacian to rounding.
"""

import numpy as np
import scipy.sparse as sp

from .checks import MIN_DIAGONAL, ZERO_AREA_ADVICE, ZERO_AREA_RELATIVE, _check_mesh, as_faces, as_vertices, check_choice
from .cotan_laplacian import _assemble_upper, _symmetric_from_upper, checked_cotan_triangle, laplacian_product
from .errors import MeshError, counted, first_indices
from .geometry import bbox_diagonal, face_double_areas

#: Sharp & Crane's mollification factor: the least triangle-inequality slack, x the mean edge length.
MOLLIFY = 1e-6

#: The values of the ``laplacian`` option (see `choose_laplacian`).
LAPLACIANS = ("auto", "cotan", "robust")


def choose_laplacian(V, F, laplacian="auto"):
    """The Laplacian the option ``laplacian`` gives on ``(V, F)``, and why.

    The one rule behind the ``laplacian`` option of `reconstruct`, `Reconstructor`,
    `checked_laplacian`, ``remesh_experiment``, the filters and the CLI: "cotan" is the plain
    cotangent Laplacian, which refuses zero-area triangles; "robust" the mollified one
    (`robust_laplacian`); "auto" is "cotan" unless ``(V, F)`` has zero-area triangles (those
    `degenerate_triangles` names, which the plain checks refuse), then "robust".

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles.
    laplacian : {"auto", "cotan", "robust"}
        The option as given.

    Returns
    -------
    info : dict
        ``{"laplacian": "cotan" or "robust", "laplacian_reason": why}``, JSON-ready: the fields
        the reports carry.

    Raises
    ------
    CurvdetailError
        ``laplacian`` not one of `LAPLACIANS` (``parameter`` "laplacian").
    MeshError
        ``laplacian="cotan"`` on a mesh with zero-area triangles (``parameter`` "laplacian",
        ``count``, ``first``: the first triangles); malformed ``V`` or ``F``.

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]], float)   # vertex 2 on edge 0-1
    >>> choose_laplacian(V, [[0, 1, 2], [1, 0, 3]])["laplacian"]
    'robust'
    """
    laplacian = check_choice(laplacian, "laplacian", LAPLACIANS,
                             f" is not one of {', '.join(map(repr, LAPLACIANS))}.")
    if laplacian == "robust":
        return {"laplacian": "robust", "laplacian_reason": "asked for (laplacian='robust')"}
    try:
        zero = degenerate_triangles(V, F)
    except MeshError:                   # malformed: the plain checks say so, in their caller's words
        zero = np.zeros(0, dtype=np.int64)
    if not zero.size:
        return {"laplacian": "cotan", "laplacian_reason": f"laplacian={laplacian!r}: the plain cotangent "
                "Laplacian (no zero-area triangle)"}
    found = (f"{counted(zero.size, 'triangle', verb='have')} zero area (first: {first_indices(zero)}; "
             f"areas up to {ZERO_AREA_RELATIVE:g} of the bbox diagonal squared count)")
    if laplacian == "cotan":
        raise MeshError(f"{found}, which the plain cotangent Laplacian (laplacian='cotan') refuses",
                        parameter="laplacian", value="cotan", count=int(zero.size), first=zero[:3].tolist(),
                        hint="ask for 'auto' or 'robust' (the mollified Laplacian takes them), or "
                             + ZERO_AREA_ADVICE)
    return {"laplacian": "robust", "laplacian_reason": f"laplacian='auto': {found}, which the plain cotangent "
            "Laplacian refuses"}


def checked_laplacian(V, F, laplacian="auto"):
    """Every mesh check and the Laplacian ``laplacian`` gives (`choose_laplacian`), in one pass.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles (zero-area ones allowed where the Laplacian is the robust one).
    laplacian : {"auto", "cotan", "robust"}
        See `choose_laplacian`.

    Returns
    -------
    V : (n, 3) float64 array, F : (m, 3) int64 array
        The checked arrays.
    L : (n, n) scipy.sparse.csr_matrix
        Symmetric positive semi-definite, rows summing to zero: ``cotan_laplacian(V, F)`` bit for
        bit where it is the plain one. The detail is ``laplacian_product(L, V)``.
    info : dict
        ``{"laplacian", "laplacian_reason"}`` as `choose_laplacian` gives them; the reason of a
        mollified one also says the length added to every edge.

    Raises
    ------
    MeshError, CurvdetailError
        As `choose_laplacian`, and as `check_mesh` for every check but zero area (robust).

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]], float)
    >>> V, F, L, info = checked_laplacian(V, [[0, 1, 2], [1, 0, 3]])
    >>> info["laplacian"], bool(np.isfinite(L.data).all())
    ('robust', True)
    """
    V, F, U, diagonal, info = checked_laplacian_triangle(V, F, laplacian)
    return V, F, _symmetric_from_upper(U, diagonal), info


def checked_laplacian_triangle(V, F, laplacian="auto"):
    """`checked_laplacian` with ``L`` as its strict upper triangle and diagonal, as
    `checked_cotan_triangle` gives them: ``(V, F, U, diagonal, info)``."""
    info = choose_laplacian(V, F, laplacian)
    if info["laplacian"] == "cotan":
        return (*checked_cotan_triangle(V, F), info)
    return _robust_triangle(V, F, info)


def _robust_triangle(V, F, info):
    """`checked_laplacian_triangle` for the robust Laplacian: every check but zero area."""
    V, F, _ = _check_mesh(V, F, check_manifold=True, check_unreferenced=True, zero_area=False)
    cot, _, delta = _mollified(V, F, MOLLIFY)
    U, diagonal = _assemble_upper(V, F, cot, check_manifold=False)
    info = {**info, "laplacian_reason": f"{info['laplacian_reason']}; mollified (every edge + {delta:.3g})"}
    return V, F, U, diagonal, info


def source_detail(V, F, laplacian="auto"):
    """The detail of a mesh to carry over to another triangulation, by the Laplacian
    `choose_laplacian` gives, and the triangles to locate points on: ``(F_located, D, info)``.

    Where the plain Laplacian applies, ``F_located`` is ``F`` and ``D`` None (the caller takes the
    plain detail, as `transfer_curvature` does by itself). Where the robust one does, ``D`` is
    ``L V`` of the mollified Laplacian and ``F_located`` is ``F`` with its zero-area caps flipped
    away (`flip_caps`: the same surface, point for point), where closest points are defined; a
    needle (two vertices at one point) stays, and the caller's mesh checks name it. Used by
    ``remesh_experiment`` and the ``transfer_curvature_detail`` filter.

    Returns
    -------
    F_located : (m, 3) int array
    D : (n, 3) float array or None
    info : dict
        As `choose_laplacian`'s, the reason also counting the triangles re-cut.
    """
    info = choose_laplacian(V, F, laplacian)
    if info["laplacian"] == "cotan":
        return F, None, info
    V, F, U, diagonal, info = _robust_triangle(V, F, info)
    flipped = flip_caps(V, F)
    D = laplacian_product(_symmetric_from_upper(U, diagonal), V)
    recut = int((flipped != F).any(axis=1).sum())
    info["laplacian_reason"] += (f"; {recut} triangles re-cut for locating points, by flipping the caps' long "
                                 "edges (the same surface)")
    return flipped, D, info


def robust_laplacian(V, F, eps=MOLLIFY):
    """The mollified intrinsic cotangent Laplacian ``L`` and its lumped mass ``M``.

    Same convention as `cotan_laplacian`: symmetric positive semi-definite,
    ``(L X)_i = 1/2 sum_j (cot a_ij + cot b_ij)(x_i - x_j)``, rows summing to zero, the cotangents
    those of the triangles with edge lengths ``l + delta`` (``delta`` as in the module's text).
    A sum of one positive semi-definite energy per triangle, so PSD whatever the mesh.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions
    F : (m, 3) int array
        Triangles (zero-area ones allowed)
    eps : float
        Least triangle-inequality slack, x the mean edge length

    Returns
    -------
    L : (n, n) scipy.sparse.csr_matrix
        The Laplacian
    M : (n, n) scipy.sparse.dia_matrix
        Lumped (barycentric) mass: a third of each intrinsic triangle area to each of its corners
    delta : float
        The length added to every edge (0 on a clean mesh)

    Raises
    ------
    MeshError
        Malformed ``V`` or ``F`` (shapes, dtypes, NaN, indices)

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]], float)   # vertex 2 on edge 0-1
    >>> L, M, delta = robust_laplacian(V, [[0, 1, 2], [1, 0, 3]])
    >>> bool(np.isfinite(L.data).all() and delta > 0 and abs(L.sum(axis=1)).max() < 1e-6)
    True
    """
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    cot, area, delta = _mollified(V, F, eps)
    L = _symmetric_from_upper(*_assemble_upper(V, F, cot, check_manifold=False)).tocsr()
    mass = np.bincount(F.ravel(), weights=np.repeat(area / 3.0, 3), minlength=V.shape[0])
    return L, sp.diags(mass), delta


def _mollified(V, F, eps):
    """``(cot, area, delta)``: the cotangent of each corner (m, 3) and the area of each triangle
    (m,) of the intrinsic triangles with edge lengths ``l + delta``."""
    # l[:, k]: the length of the edge opposite corner k
    lengths = np.linalg.norm(V[F[:, [2, 0, 1]]] - V[F[:, [1, 2, 0]]], axis=2)
    slack = lengths.sum(axis=1, keepdims=True) - 2.0 * lengths          # l_j + l_k - l_i, per corner i
    delta = float(max(0.0, eps * lengths.mean() - slack.min()))
    a = lengths + delta
    s = a.sum(axis=1, keepdims=True)
    area = 0.25 * np.sqrt(s[:, 0] * np.prod(s - 2.0 * a, axis=1))      # Heron
    sq = a ** 2
    cot = (sq.sum(axis=1, keepdims=True) - 2.0 * sq) / (4.0 * area[:, None])   # (b^2 + c^2 - a^2) / 4A
    return cot, area, delta


def degenerate_triangles(V, F):
    """Indices of the triangles of ``(V, F)`` the plain checks call zero-area (twice the area at
    most ``2 ZERO_AREA_RELATIVE`` x the bbox diagonal squared), as an int64 array; none on a mesh
    too small across for any (the plain checks refuse it as such)."""
    V, F = as_vertices(V), as_faces(F, np.shape(V)[0])
    d = bbox_diagonal(V)
    if d < MIN_DIAGONAL:                # every triangle: the plain checks say why (no extent)
        return np.zeros(0, dtype=np.int64)
    with np.errstate(under="ignore"):   # a squared component of 1e-170: negligible, as in check_mesh
        return np.flatnonzero(face_double_areas(V, F) <= 2.0 * ZERO_AREA_RELATIVE * d ** 2)


def flip_caps(V, F, rounds=8):
    """``F`` with the longest edge of each zero-area triangle flipped, where it has a second
    triangle and the flipped edge is not an edge already.

    A zero-area "cap" has its third vertex on its longest edge: flipping that edge splits the
    neighbouring triangle at that vertex, the same surface (point for point) without the cap (the
    intrinsic Delaunay flip of an edge facing a 180 degree angle). A "needle" (two vertices at one
    point) stays. Repeated up to ``rounds`` times, for caps next to caps.

    Parameters
    ----------
    V : (n, 3) float array, F : (m, 3) int array
        A consistently oriented manifold mesh

    Returns
    -------
    F : (m, 3) int64 array
        A new array, same triangle count and vertices

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]], float)
    >>> flip_caps(V, [[0, 1, 2], [1, 0, 3]]).tolist()
    [[0, 3, 2], [3, 1, 2]]
    """
    V = as_vertices(V)
    F = as_faces(F, V.shape[0]).copy()
    n = V.shape[0]
    for _ in range(rounds):
        bad = degenerate_triangles(V, F)
        keys = (F * n + F[:, [1, 2, 0]]).ravel()        # half-edge F[f, c] -> F[f, c+1]
        order = np.argsort(keys)
        flipped, touched = 0, set()
        for f in bad:
            if f in touched:
                continue
            tri = F[f]
            edge_len = np.linalg.norm(V[tri[[1, 2, 0]]] - V[tri], axis=1)
            c = int(np.argmax(edge_len))                # edge tri[c] -> tri[c+1], opposite tri[c+2]
            p, q, k = tri[c], tri[(c + 1) % 3], tri[(c + 2) % 3]
            at = np.searchsorted(keys, q * n + p, sorter=order)
            if at == keys.size or keys[order[at]] != q * n + p:
                continue                                # a boundary edge: nothing to flip with
            g = order[at] // 3
            if g in touched:
                continue
            l = F[g][(order[at] % 3 + 2) % 3]            # the apex of the other triangle
            there = np.searchsorted(keys, [k * n + l, l * n + k], sorter=order).clip(max=keys.size - 1)
            if (keys[order[there]] == [k * n + l, l * n + k]).any():
                continue                                # edge k-l exists: the flip would double it
            F[f], F[g] = (p, l, k), (l, q, k)
            touched.update((f, g))
            flipped += 1
        if not flipped:
            break
    return F
