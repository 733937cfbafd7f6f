"""Array checks run once at the boundary of every public function, before any sparse
algebra: shapes, dtypes, finite values, index ranges, degenerate triangles. They raise
`MeshError` / `ConstraintError` (subclasses of ``ValueError``) that name the
problem, carry the facts as fields (``parameter``, ``count``, ``first``) and say the fix."""

import math
import numbers

import numpy as np

from .errors import ConstraintError, CurvdetailError, MeshError, counted, first_indices, them
from .geometry import bbox_diagonal, corner_cotangents, face_double_areas
from .topology import as_faces, non_manifold_edges, repeated_triangles

#: Largest coordinate magnitude taken: triangle areas (coordinates to the fourth) overflow from ~1e77.
MAX_COORDINATE = 1e75

#: Smallest bbox diagonal taken: a triangle passing the zero-area check then has a squared cross
#: product of at least 4e-28 diag^4 = 4e-268, clear of the subnormals.
MIN_DIAGONAL = 1e-60

#: A triangle whose area is below this fraction of the squared bbox diagonal is degenerate.
ZERO_AREA_RELATIVE = 1e-14
#: What to do about them (removing one leaves a slit in the surface).
ZERO_AREA_ADVICE = ("flip or collapse them away, e.g. with pymeshlab's meshing_remove_t_vertices(method=1) "
                    "for flat slivers (meshing_remove_null_faces drops exactly-zero triangles only, and "
                    "leaves a slit where each was)")


def as_vertices(V, name="V", dim=3, max_coordinate=MAX_COORDINATE):
    """Return ``V`` as a C-contiguous (n, dim) float64 array or raise MeshError (``dim=2``: planar
    positions, e.g. UVs; ``max_coordinate``: for callers that compute in a unit frame)."""
    try:
        arr = np.asarray(V)
    except Exception as exc:  # ragged lists and the like
        raise MeshError(f"{name} could not be read as an array ({exc}); pass an (n, {dim}) float array.",
                        parameter=name) from None
    if arr.dtype.kind not in "fiu":
        raise MeshError(f"{name} has dtype {arr.dtype}; pass an (n, {dim}) array of real numbers.", parameter=name)
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise MeshError(f"{name} has shape {arr.shape}; vertex positions must be an (n, {dim}) array.",
                        parameter=name)
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty (0 vertices); pass a mesh with at least one triangle.", parameter=name,
                        count=0)
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.isfinite(arr).all():      # one flat pass; the per-row search below only on failure
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        raise MeshError(
            f"{name}: {counted(bad.size, 'vertex', 'vertices', verb='have')} NaN or infinite coordinates "
            f"(first: {first_indices(bad)}); "
            f"remove or repair {them(bad.size)} before computing curvature.",
            parameter=name, count=int(bad.size), first=bad[:3].tolist())
    _check_magnitude(arr, name, MeshError, "scale the mesh down", max_coordinate)
    return arr


def _check_magnitude(arr, name, error, fix, limit=MAX_COORDINATE):
    """Refuse values beyond ``limit``, where the geometry's products overflow."""
    if arr.size and np.abs(arr).max() > limit:
        bad = np.flatnonzero((np.abs(arr) > limit).any(axis=1))
        raise error(f"{name}: {counted(bad.size, 'row', verb='reach')} {np.abs(arr).max():.3g} "
                    f"(first: {first_indices(bad)}); "
                    f"beyond {limit:.0e} the geometry overflows double precision: {fix}.",
                    parameter=name, count=int(bad.size), first=bad[:3].tolist())


def check_mesh(V, F, *, check_manifold=True, check_unreferenced=True):
    """Validate a triangle mesh and return ``(V, F)`` as new float64 / int64 arrays.

    Checks, in order: shapes and dtypes, emptiness, NaN/inf, coordinates beyond
    ``MAX_COORDINATE``, index range, repeated indices in a face, a bbox diagonal below
    ``MIN_DIAGONAL``, zero-area faces (below ``ZERO_AREA_RELATIVE`` times the squared diagonal),
    duplicate triangles and non-manifold edges (with ``check_manifold``), unreferenced vertices.

    Parameters
    ----------
    V : (n, 3) array of real numbers
        Vertex positions.
    F : (m, 3) array of integers
        Triangles (whole floats are taken).
    check_manifold : bool
        Refuse repeated triangles and edges shared by more than two triangles.
    check_unreferenced : bool
        Refuse vertices used by no triangle.

    Returns
    -------
    V : (n, 3) float64 array
        C-contiguous, never the input itself or a view of it.
    F : (m, 3) int64 array
        Likewise.

    Raises
    ------
    MeshError
        Naming the problem, with ``parameter``, ``count`` and ``first`` (the first indices).

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
    # float64 / int64 C inputs pass the conversions as themselves: copy them
    return tuple(out.copy() if isinstance(given, np.ndarray) and np.may_share_memory(out, given) else out
                 for out, given in zip(checked, (V, F)))


def checked_arrays(V, F, *, check_manifold=True, check_unreferenced=True):
    """`check_mesh` without its copy, for callers that only read the arrays."""
    return _check_mesh(V, F, check_manifold, check_unreferenced)[:2]


def _check_mesh(V, F, check_manifold, check_unreferenced, cotangents=False, zero_area=True):
    """``(V, F, cot)`` after every check; ``zero_area=False`` lets zero-area triangles pass."""
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    diag = bbox_diagonal(V)
    if diag == 0.0:
        raise MeshError(f"the mesh is 0 across (bbox diagonal): all {V.shape[0]} vertices lie at one point, so "
                        "every triangle has zero area; pass the mesh's real vertex positions.", parameter="V",
                        value=diag)
    if diag < MIN_DIAGONAL:
        raise MeshError(f"the mesh is {diag:.3g} across (bbox diagonal), below {MIN_DIAGONAL:.0e}: its triangle "
                        "areas (fourth powers of its lengths) underflow double precision and lose their digits; "
                        f"scale it up, e.g. to unit size (V / {diag:.3g}), and scale the results back.",
                        parameter="V", value=diag)
    cot = None
    with np.errstate(divide="ignore", invalid="ignore", under="ignore"):
        if cotangents:
            cot, _, dbl = corner_cotangents(V, F, lengths=False)
        else:
            dbl = face_double_areas(V, F)
    zero = np.flatnonzero(dbl <= 2.0 * ZERO_AREA_RELATIVE * diag ** 2)
    if zero.size and zero_area:
        raise MeshError(f"{counted(zero.size, 'triangle', verb='have')} zero area (first: {first_indices(zero)}; "
                        f"areas up to {ZERO_AREA_RELATIVE:g} of the bbox diagonal squared count); "
                        f"{ZERO_AREA_ADVICE.replace('them', them(zero.size), 1)}, "
                        "before computing curvature.", parameter="F", count=int(zero.size),
                        first=zero[:3].tolist())
    if check_manifold or cotangents:           # cotangents: the caller counts the edges itself, after this
        pairs = repeated_triangles(F, V.shape[0])
        if pairs is not None:
            shown = ", ".join(f"({i}, {j})" for i, j in pairs[:3])
            raise MeshError(f"F: {counted(pairs.shape[0], 'triangle', verb='repeat')} the three vertices of an "
                            f"earlier one (first pairs: {shown}): a repeated triangle counts its area and curvature "
                            "twice. Remove the duplicates, e.g. with pymeshlab's meshing_remove_duplicate_faces.",
                            parameter="F", count=int(pairs.shape[0]), first=pairs[:3, 1].tolist())
    if check_manifold:
        bad = non_manifold_edges(F)
        if bad.shape[0]:
            raise non_manifold_error(bad.shape[0], bad[:3])
    if check_unreferenced:
        check_referenced(V.shape[0], F)
    return V, F, cot


def check_referenced(n, F, name=None):
    """MeshError for vertices ``0 .. n - 1`` that no triangle of ``F`` uses; ``name``: the
    argument named first in the message, if any."""
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    unused = np.flatnonzero(~used)
    if unused.size:
        raise MeshError(
            f"{name + ': ' if name else ''}{counted(unused.size, 'vertex', 'vertices', verb='are')} not used by "
            f"any triangle (first: {first_indices(unused)}); "
            f"remove {them(unused.size)}, e.g. with pymeshlab's meshing_remove_unreferenced_vertices.",
            parameter=name or "V", count=int(unused.size), first=unused[:3].tolist())


def non_manifold_error(count, first):
    """The MeshError for ``count`` edges on three or more triangles, ``first``: a few (a, b)."""
    first = [(int(a), int(b)) for a, b in first]           # an iterator too: read it once
    pairs = ", ".join(f"({a}, {b})" for a, b in first)
    return MeshError(
        f"{counted(count, 'edge', verb='are')} shared by more than two triangles (first: {pairs}); "
        "the mesh is not manifold. Repair it, e.g. with pymeshlab's meshing_repair_non_manifold_edges.",
        parameter="F", count=int(count), first=first)


def as_index_set(indices, n, name):
    """Return ``indices`` as a duplicate-free int64 array in [0, n), in the order given, or raise
    ConstraintError (with ``parameter``, ``count`` and ``first``). Takes an int array or list,
    whole floats (3.0), a (k, 1) column, or an (n,) boolean mask (its true positions)."""
    def refuse(problem, count=None, first=None):
        return ConstraintError(f"{name}: {problem}", parameter=name, count=count, first=first)

    try:
        arr = np.asarray(indices)
    except Exception as exc:
        raise ConstraintError(f"{name} could not be read as an index array ({exc}).", parameter=name) from None
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise refuse(f"a boolean mask of shape {arr.shape}; it must have shape ({n},).")
        return np.flatnonzero(arr)
    if sum(d > 1 for d in arr.shape) > 1:      # an edge list (k, 2) or faces (m, 3)
        raise refuse(f"shape {arr.shape}; pass a 1-D array of vertex indices (a column (k, 1) is taken too), "
                     "e.g. np.unique(E) for the vertices of edges E.")
    arr = arr.reshape(-1)
    if arr.size and arr.dtype.kind not in "iuf":
        raise refuse(f"dtype {arr.dtype}; pass integer vertex indices.")
    if arr.dtype.kind == "f":
        error = non_whole_index_error(arr, name)
        if error is not None:
            raise error
    with np.errstate(invalid="ignore"):
        out = np.flatnonzero((arr < 0) | (arr >= n))
    if out.size:
        raise refuse(f"{counted(out.size, 'index', 'indices', verb='are')} outside [0, {n}) (first: "
                     f"{', '.join(f'{v:g}' for v in arr[out[:3]].tolist())}); indices are 0-based into V.",
                     int(out.size), arr[out[:3]].tolist())
    arr = arr.astype(np.int64)
    uniq, counts = np.unique(arr, return_counts=True)
    if uniq.size != arr.size:
        repeated = uniq[counts > 1]
        raise refuse(f"{counted(arr.size - uniq.size, 'index', 'indices', verb='are')} repeated (first: "
                     f"{first_indices(repeated)}); list each vertex once (a 0/1 mask: pass it as booleans).",
                     int(arr.size - uniq.size), repeated[:3].tolist())
    return arr


def non_whole_index_error(values, name, error=ConstraintError):
    """The ``error`` (a CurvdetailError class) for index values that are not whole numbers (3.5,
    NaN, inf), or None where every value is whole (3.0 is an index). ``values``: real numbers.

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
    message = (f"{name}: {counted(bad.size, 'value')} {what} (first: {float(arr[bad[0]])!r}, at position "
               f"{bad[0]}); vertex indices are whole numbers: pass integers (or whole floats such as 3.0), "
               "not positions or weights.")
    return error(message, parameter=name, count=int(bad.size), first=bad[:3].tolist())


def check_bool(value, name):
    """``bool(value)`` for True / False (numpy's too), else a ValueError (``"no"`` is no answer)."""
    if not isinstance(value, (bool, np.bool_)):
        raise CurvdetailError(f"{name}={value!r} must be True or False.", parameter=name, value=value)
    return bool(value)


def as_float(value):
    """``value`` as a float if it is a real number (numpy scalars and 0-d arrays included; too
    large for a double: inf), else None (bools and strings included)."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        return None
    try:
        return float(value)
    except OverflowError:              # a Python int beyond a double
        return math.inf


def as_count(value, name, minimum=1):
    """Return ``value`` as an int >= ``minimum`` (ints, whole floats, numpy scalars, 0-d arrays;
    not a bool or a string), or raise a ValueError naming the argument."""
    number = as_float(value)
    if number is None or not math.isfinite(number) or number != round(number):
        raise CurvdetailError(f"{name}={value!r} must be a whole number >= {minimum}.", parameter=name, value=value)
    if number < minimum:
        raise CurvdetailError(f"{name}={value!r} must be at least {minimum}.", parameter=name, value=value)
    value = value.item() if isinstance(value, np.ndarray) else value
    return int(value) if isinstance(value, numbers.Integral) else int(number)


def as_positive_number(value, name, hint=""):
    """Return ``value`` as a finite float > 0 (see `as_float`), or raise ValueError."""
    number = as_float(value)
    if number is None or not (math.isfinite(number) and number > 0):
        raise CurvdetailError(f"{name}={value!r} must be a positive number{hint}.", parameter=name, value=value)
    return number


def as_values(values, count, name, dim=3):
    """Return ``values`` as a (count, dim) float64 array of finite numbers within
    ``MAX_COORDINATE`` or raise ConstraintError (``parameter=name``)."""
    try:
        arr = np.asarray(values)
    except Exception as exc:
        raise ConstraintError(f"{name} could not be read as a float array ({exc}).", parameter=name) from None
    if arr.dtype.kind not in "fiu":            # complex would lose its imaginary part, bool mean 0/1
        raise ConstraintError(f"{name} has dtype {arr.dtype}; pass a ({count}, {dim}) array of real numbers.",
                              parameter=name)
    arr = arr.astype(np.float64, copy=False)
    if arr.shape != (count, dim):
        raise ConstraintError(f"{name} has shape {arr.shape}; expected ({count}, {dim}), one row per vertex.",
                              parameter=name)
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        raise ConstraintError(f"{name}: {counted(bad.size, 'row', verb='are')} NaN or infinite "
                              f"(first: {first_indices(bad)}).", parameter=name, count=int(bad.size),
                              first=bad[:3].tolist())
    _check_magnitude(arr, name, ConstraintError, "scale the problem down")
    return np.ascontiguousarray(arr)


def check_transformed_values(values, what, fix, error=ConstraintError):
    """Raise ``error`` if constraint values made by a user's transform (None: none) are not
    finite or beyond MAX_COORDINATE, naming ``what`` made them and ``fix``."""
    if values is not None and not np.all(np.abs(values) <= MAX_COORDINATE):
        raise error(f"{what} gives the handles values of {np.abs(values).max():.3g}, beyond {MAX_COORDINATE:.0e}, "
                    f"where the geometry overflows double precision; {fix}.")


def check_choice(value, name, choices, advice, error=None):
    """``value`` if it is a str among ``choices`` (not an array, which ``in`` compares element-wise),
    else ``error(f"{name}={shown}{advice}")`` (default: CurvdetailError with ``parameter``)."""
    if isinstance(value, str) and value in choices:
        return str(value)
    shown = repr(value) if isinstance(value, str) else f"{value!r} ({type(value).__name__}, not a single str)"
    if error is None:
        raise CurvdetailError(f"{name}={shown}{advice}", parameter=name, value=value)
    raise error(f"{name}={shown}{advice}", parameter=name, value=value)


def real_word(word):
    """``float(word)``, but a ValueError for Python's digit separators too (``1_0``)."""
    if "_" in word:
        raise ValueError(f"{word!r} is not a number")
    return float(word)


def affine_transform_problem(T):
    """What is wrong with the (4, 4) handle transform ``T`` for an edit, or None: a last row other
    than (0, 0, 0, 1), or a linear part that collapses a direction (singular value ratio < 1e-12)."""
    if not np.allclose(T[3], [0.0, 0.0, 0.0, 1.0], atol=1e-12):
        return f"the last row is {T[3].tolist()}; an affine transform has (0, 0, 0, 1) there"
    sigma = np.linalg.svd(T[:3, :3], compute_uv=False)
    if not sigma[0] > 0 or sigma[2] < 1e-12 * sigma[0]:
        return (f"its linear part is singular (singular values {sigma[0]:.3g} ... {sigma[2]:.3g}); it would "
                "collapse the handles onto a plane, a line or a point")
    return None
