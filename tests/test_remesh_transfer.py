"""Curvature detail carried to a retriangulation (curvdetail.remesh.transfer)."""

import numpy as np
import pytest

from curvdetail.curvature import curvature_detail, mixed_voronoi_area
from curvdetail.curvature.errors import ConstraintError, CurvdetailError, MeshError
from curvdetail.curvature.testing import grid, icosphere
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.curvature.topology import boundary_vertices
from curvdetail.remesh import (SURFACE_TOLERANCE, RemeshError, check_retriangulation, closest_points,
                               edge_curvature_measure, retriangulate, transfer_curvature)
from curvdetail.curvature import boundary_loop


def _cap(radius=2.0):
    V, F = icosphere(radius=radius, subdivisions=4)
    keep = V[:, 2] > 0.5 * radius
    faces = F[keep[F].all(axis=1)]
    used = np.unique(faces)
    remap = np.full(V.shape[0], -1)
    remap[used] = np.arange(used.size)
    return V[used], remap[faces]


def test_edge_measure_halves_give_the_vertex_detail(load_mesh):
    V, F = load_mesh("mannequin_ear.obj")
    E, c = edge_curvature_measure(V, F)
    D = np.zeros_like(V)
    np.add.at(D, E[:, 0], 0.5 * c)
    np.add.at(D, E[:, 1], 0.5 * c)
    assert np.abs(D - curvature_detail(V, F)).max() < 1e-14


def test_conservative_transfer_onto_the_same_mesh_is_exact(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    assert np.abs(transfer_curvature(V, F, V, F) - curvature_detail(V, F)).max() < 1e-14


def test_pointwise_transfer_onto_the_same_mesh_is_exact(load_mesh):
    # each target vertex is located on itself (one-hot barycentrics), so D_t = K(x_t) A_t = D
    V, F = load_mesh("mannequin_nose.obj")
    D = curvature_detail(V, F)
    assert np.abs(transfer_curvature(V, F, V, F, method="pointwise") - D).max() < 1e-12 * np.abs(D).max()


def test_conservative_transfer_keeps_the_total_detail(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    Vt, Ft = retriangulate(V, F, target_edge="3%")
    Ds = curvature_detail(V, F)
    scale = np.abs(Ds).sum()
    Dt = transfer_curvature(V, F, Vt, Ft, method="conservative")
    assert np.abs(Dt.sum(0) - Ds.sum(0)).max() <= 1e-12 * scale
    # the pointwise transfer does not conserve it (K A_t sums differently near the boundary)
    Dp = transfer_curvature(V, F, Vt, Ft, method="pointwise")
    assert np.abs(Dp.sum(0) - Ds.sum(0)).max() > 1e-3 * scale


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
@pytest.mark.parametrize("location", ["closest", "uv"])
def test_sphere_cap_detail_is_two_over_r_normal_on_the_target(method, location):
    R = 2.0
    V, F = _cap(R)
    Vt, Ft = retriangulate(V, F, target_edge="4%")
    uv = None
    if location == "uv":
        from curvdetail.remesh import parameterize

        UVs, UVt, _ = parameterize(V, F, Vt, Ft)
        uv = (UVs, UVt)
    Dt = transfer_curvature(V, F, Vt, Ft, method=method, location=location, uv=uv)
    K = Dt / mixed_voronoi_area(Vt, Ft)[:, None]
    interior = np.setdiff1d(np.arange(Vt.shape[0]), boundary_loop(Ft))
    # away from the boundary ring (its star catches the boundary's geodesic-curvature term)
    far = interior[Vt[interior, 2] > 0.6 * R]
    normal = Vt[far] / R
    # |K| = 2/R = 1 on the sphere, along the outward normal; the discrete K of the 2562-vertex
    # source is within ~2 % of it, the local transfer adds a few % per vertex
    assert np.median(np.abs((K[far] * normal).sum(1) - 2.0 / R)) < 0.05
    assert np.median(np.linalg.norm(K[far] - (K[far] * normal).sum(1)[:, None] * normal, axis=1)) < 0.05


def test_bad_options_are_refused(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, method="nearest")
    assert (e.value.parameter, e.value.value) == ("method", "nearest")
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, location="uv")
    assert e.value.parameter == "uv"
    # an array was compared with ``in`` element-wise: one entry passed as the option, two raised
    # numpy's "truth value ... is ambiguous"
    with pytest.raises(CurvdetailError, match="ndarray") as e:
        transfer_curvature(V, F, V, F, method=np.array(["pointwise", "conservative"]))
    assert e.value.parameter == "method"
    with pytest.raises(CurvdetailError, match="tuple") as e:
        transfer_curvature(V, F, V, F, location=("closest",))
    assert e.value.parameter == "location"


def _bad_mesh(kind):
    V, F = grid(5, 5)
    if kind == "nan vertex":
        V[3, 0] = np.nan
    elif kind == "zero area":
        V[F[7, 0]] = V[F[7, 1]]
    return {"nan vertex": (V, F), "zero area": (V, F), "(m, 4) F": (V, np.c_[F, F[:, :1]]),
            "negative index": (V, F - 1), "empty F": (V, F[:0]), "bool V": (V.astype(bool), F),
            "None V": (None, F), "index out of range": (V, F + 100), "float F": (V, F + 0.5)}[kind]


@pytest.mark.parametrize("kind, parameter, first", [
    ("nan vertex", "V", [3]), ("zero area", "F", [7, 19]), ("(m, 4) F", "F", None),   # 7 and its neighbour
    ("negative index", "F", [0, 16]), ("empty F", "F", None), ("bool V", "V", None), ("None V", "V", None),
    ("index out of range", "F", [0, 1, 2]), ("float F", "F", [0, 1, 2]),
])
def test_edge_measure_refuses_malformed_meshes_by_name(kind, parameter, first):
    # it had no checks: NaN came out silently for a NaN vertex or a zero-area triangle, (m, 4)
    # and negative indices were taken, other cases raised numpy errors
    with pytest.raises(MeshError) as e:
        edge_curvature_measure(*_bad_mesh(kind))
    assert (e.value.parameter, e.value.first) == (parameter, first)


@pytest.mark.parametrize("value", [0, -1, 2.5, "5", True, np.inf, 10 ** 30])
def test_samples_per_edge_must_be_a_sane_whole_number(value):
    # 0 and -1 were clamped to 1, 2.5 truncated, "5" and True accepted, 10**30 an OverflowError
    V, F = grid(5, 5)
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, samples_per_edge=value, metric="target")
    assert e.value.parameter == "samples_per_edge"
    if value == 10 ** 30:                               # 56 edges: 5.6e31 samples, beyond the limit
        assert e.value.value == 56 * 10 ** 30


def test_options_that_would_be_ignored_are_refused():
    V, F = grid(5, 5)
    uv = (V[:, :2], V[:, :2])
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, location="closest", uv=uv)
    assert e.value.parameter == "uv"
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, method="pointwise", samples_per_edge=3)
    assert e.value.parameter == "samples_per_edge"
    with pytest.raises(CurvdetailError) as e:            # the source's own detail is not on the edges
        transfer_curvature(V, F, V, F, samples_per_edge=3)
    assert e.value.parameter == "samples_per_edge"
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, method="pointwise", metric="source")
    assert e.value.parameter == "metric"
    with pytest.raises(CurvdetailError) as e:
        transfer_curvature(V, F, V, F, metric="intrinsic")
    assert (e.value.parameter, e.value.value) == ("metric", "intrinsic")


def test_malformed_uv_is_named_as_uv():
    # uv=5 raised a TypeError; a NaN in uv was reported as "points: ... rows are NaN"
    V, F = grid(5, 5)
    with pytest.raises(CurvdetailError, match=r"\bint\b") as e:
        transfer_curvature(V, F, V, F, location="uv", uv=5)
    assert e.value.parameter == "uv"
    UV = V[:, :2].copy()
    UV[4, 1] = np.nan
    with pytest.raises(MeshError) as e:
        transfer_curvature(V, F, V, F, location="uv", uv=(UV, V[:, :2]))
    assert (e.value.parameter, e.value.count, e.value.first) == ("uv[0] (UVs)", 1, [4])
    with pytest.raises(MeshError, match="<U") as e:
        transfer_curvature(V, F, V, F, location="uv", uv=(V[:, :2], V[:, :2].astype(str)))
    assert e.value.parameter == "uv[1] (UVt)"


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
@pytest.mark.parametrize("which", [0, 1])
def test_a_planar_map_that_squashes_a_triangle_is_named_as_the_maps_doing(method, which):
    # the mesh is fine (a curved grid); the map puts a vertex on the line through two of its
    # triangle's corners: before, "Fs: 1 triangles have zero area" with advice to repair the mesh
    V, F = grid(6, 6)
    V[:, 2] = 0.3 * V[:, 0] ** 2
    UV = [V[:, :2].copy(), V[:, :2].copy()]
    a, b, c = F[12]
    UV[which][c] = 0.5 * (UV[which][a] + UV[which][b])
    name = [r"uv\[0\] \(UVs\)", r"uv\[1\] \(UVt\)"][which]
    with pytest.raises(MeshError, match=rf"\b{name}.*location='closest'") as e:       # the map, the way out
        transfer_curvature(V, F, V, F, method=method, location="uv", uv=tuple(UV))
    assert (e.value.count, e.value.first) == (1, [12])
    # the same maps unsquashed transfer the detail exactly (the same triangulation)
    UV[which][c] = V[c, :2]
    D = transfer_curvature(V, F, V, F, method=method, location="uv", uv=tuple(UV))
    expected = curvature_detail(V, F)
    assert np.abs(D - expected).max() < 1e-12 * np.abs(expected).max()


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
def test_a_target_far_from_the_source_is_refused(load_mesh, method):
    # the closest point of a far target would silently give it the wrong detail
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(RemeshError) as e:
        transfer_curvature(V, F, V + [0.0, 0.0, 1000.0], F, method=method)
    assert e.value.count == boundary_vertices(F).size and e.value.value > 0.5
    d = bbox_diagonal(V)
    D = transfer_curvature(V, F, V + [0.0, 0.0, 1e-4 * d], F, method=method)   # a slight offset is fine
    # and gives the target the detail of the same surface: that of the identity transfer, up to
    # the sampling's sensitivity to the shift
    same = transfer_curvature(V, F, V, F, method=method)
    assert np.abs(D - same).max() < 0.1 * np.abs(same).max()


def _terrain_with_a_bump(load_mesh, height):
    """terrainA_1k ``(V, F)`` and a copy whose vertices within 15 % of the diagonal of its centre
    are raised by ``height`` x the diagonal, fading to 0 there (the boundary stays): ``(V, F, W, bumped)``."""
    V, F = load_mesh("terrainA_1k.obj")
    d = bbox_diagonal(V)
    centre = 0.5 * (V.min(0) + V.max(0))
    r = np.linalg.norm((V - centre)[:, :2], axis=1) / (0.15 * d)
    W = V.copy()
    W[:, 2] += height * d * np.clip(1 - r, 0, None) ** 2
    return V, F, W, np.flatnonzero(r < 1)


def test_a_disk_target_off_the_source_inside_its_boundary_is_refused_naming_the_vertices(load_mesh):
    # the boundary matches, the inside is another terrain: up to 10 % of the diagonal off
    V, F, W, bumped = _terrain_with_a_bump(load_mesh, 0.1)
    d = bbox_diagonal(V)
    off = np.flatnonzero(np.sqrt(closest_points(W, V, F)[0]) > SURFACE_TOLERANCE * d)
    assert 0 < off.size < bumped.size and np.isin(off, bumped).all()
    with pytest.raises(RemeshError) as e:
        transfer_curvature(V, F, W, F)
    assert e.value.count == off.size and e.value.first == off[:3].tolist()
    assert e.value.value == pytest.approx(0.1, rel=0.2)
    _, _, W, _ = _terrain_with_a_bump(load_mesh, 0.01)      # 1 %: a coarse retriangulation's error
    transfer_curvature(V, F, W, F)


def test_a_disk_target_whose_boundary_is_elsewhere_is_refused(load_mesh):
    # terrainA_1k onto the same patch with its heights mirrored: rebuilt 16.6 % off, exit 0, before
    V, F = load_mesh("terrainA_1k.obj")
    W = V.copy()
    W[:, 2] = V[:, 2].min() + V[:, 2].max() - V[:, 2]
    with pytest.raises(RemeshError) as e:
        transfer_curvature(V, F, W, F)
    assert e.value.count > 0 and set(e.value.first) <= set(boundary_vertices(F).tolist())


def test_a_closed_target_of_another_surface_is_refused():
    # a sphere of radius 1 onto one of radius 1.2: every vertex 0.2 off (5.8 % of the diagonal;
    # 1.1 would be 2.9 %, within SURFACE_TOLERANCE)
    V, F = icosphere(subdivisions=3)
    with pytest.raises(RemeshError) as e:
        transfer_curvature(V, F, 1.2 * V, F)
    assert e.value.count == V.shape[0] and e.value.first == [0, 1, 2]
    assert e.value.value == pytest.approx(0.2 / bbox_diagonal(V), rel=1e-2)     # the chords sag below 1


def test_a_closed_source_onto_a_disk_target_is_refused_by_its_loops():
    V, F = icosphere(subdivisions=3)
    Vt, Ft = _cap(radius=1.0)
    with pytest.raises(RemeshError) as e:
        transfer_curvature(V, F, Vt, Ft)
    assert e.value.count == 1 and e.value.first == [int(boundary_vertices(Ft).min())]   # its loop's first vertex


@pytest.mark.parametrize("closed", [True, False])
def test_a_true_retriangulation_passes(load_mesh, closed):
    # pymeshlab's isotropic remeshing, closed (a bumpy sphere) and a disk (the nose)
    if closed:
        V, F = icosphere(subdivisions=4)
        V *= 1 + 0.1 * np.sin(3 * V[:, [0]])
    else:
        V, F = load_mesh("mannequin_nose.obj")
    Vt, Ft = retriangulate(V, F, target_edge="3%")
    assert check_retriangulation(V, F, Vt, Ft) is None
    Dt = transfer_curvature(V, F, Vt, Ft)
    assert np.abs(Dt.sum(0) - curvature_detail(V, F).sum(0)).max() < 1e-12 * np.abs(Dt).sum()


def _located_on_grid():
    from curvdetail.remesh import locate

    V, F = grid(5, 5)
    face, bary, _ = locate(V[:6] + [0.01, 0.02, 0.0], V, F)
    return V, F, face, bary


@pytest.mark.parametrize("n", [127.7, None, "x", -1, 10 ** 12])        # 10**12: a dense result too large
def test_spread_refuses_a_vertex_count_that_is_not_a_count(n):
    from curvdetail.remesh import spread

    V, F, face, bary = _located_on_grid()
    with pytest.raises(CurvdetailError, match=f"^n={n!r}") as e:
        spread(np.ones(face.size), F, face, bary, n)
    assert e.value.parameter == "n"


def test_spread_refuses_a_vertex_count_below_the_mesh_fs():
    from curvdetail.remesh import spread

    V, F, face, bary = _located_on_grid()
    with pytest.raises(MeshError) as e:
        spread(np.ones(face.size), F, face, bary, 3)
    assert (e.value.parameter, e.value.value) == ("n", 3) and "25" in e.value.hint       # pass n >= 25


def test_spread_takes_numpy_and_whole_float_counts():
    from curvdetail.remesh import spread

    V, F, face, bary = _located_on_grid()
    assert spread(np.ones(face.size), F, face, bary, np.int64(25)).sum() == pytest.approx(face.size, abs=1e-12)
    assert spread(np.ones(face.size), F, face, bary, 30.0).shape == (30,)        # 1-D in, 1-D out
    assert spread(np.ones((face.size, 2)), F, face, bary, 30).shape == (30, 2)
    # no points at all: zeros (it was numpy's "cannot reshape array of size 0")
    assert np.array_equal(spread(np.ones(0), F, face[:0], bary[:0], 30), np.zeros(30))


@pytest.mark.parametrize("values, facts", [
    (np.array(["a"] * 25), {"value": (25,)}),
    (None, {"value": ()}),
    (np.ones(3), {"value": 3}),                                  # the values, not F, are blamed
    (np.r_[np.ones(24), np.nan], {"count": 1, "first": [24]}),
])
def test_interpolate_names_values_that_do_not_fit_the_mesh(values, facts):
    from curvdetail.remesh import interpolate

    V, F, face, bary = _located_on_grid()
    with pytest.raises(MeshError) as e:
        interpolate(values, F, face, bary)
    assert e.value.parameter == "values"
    assert {k: getattr(e.value, k) for k in facts} == facts


@pytest.mark.parametrize("scale", [100.0, 0.5, np.nan])          # outside [0, 1]; rows sum to 0.5; NaN
def test_interpolate_and_spread_refuse_coordinates_that_are_not_barycentric(scale):
    # they were taken silently: extrapolated values, and spread lost its conservation
    from curvdetail.remesh import interpolate, spread

    V, F, face, bary = _located_on_grid()
    for call in (lambda b: interpolate(V, F, face, b), lambda b: spread(np.ones(face.size), F, face, b, V.shape[0])):
        with pytest.raises(MeshError) as e:
            call(bary * scale)
        assert (e.value.parameter, e.value.count, e.value.first) == ("bary", 6, [0, 1, 2, 3, 4])


def test_coordinates_off_by_rounding_are_taken():
    from curvdetail.remesh import interpolate

    V, F, face, bary = _located_on_grid()
    nudged = bary + np.array([1e-9, -1e-9, 0.0])
    assert np.abs(interpolate(V, F, face, nudged) - interpolate(V, F, face, bary)).max() < 1e-8


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
def test_a_given_detail_equal_to_the_geometrys_changes_nothing(load_mesh, method):
    V, F = load_mesh("mannequin_nose.obj")
    Vt, Ft = retriangulate(V, F, target_edge="3%")
    own = transfer_curvature(V, F, Vt, Ft, method=method)
    given = transfer_curvature(V, F, Vt, Ft, method=method, detail=curvature_detail(V, F))
    assert np.abs(given - own).max() < 1e-12 * np.abs(own).max()       # measured 8e-15


def _moved_nose(load_mesh):
    """The nose ``(V, F)``, its detail ``D``, and ``Z``: its vertices moved to the zero-detail
    (harmonic) surface of its boundary, whose own detail is far from ``D``."""
    from curvdetail.curvature import boundary_vertices, reconstruct

    V, F = load_mesh("mannequin_nose.obj")
    b = boundary_vertices(F)
    return V, F, curvature_detail(V, F), reconstruct(V, F, np.zeros_like(V), b, V[b], rows="free")


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
def test_a_given_detail_onto_the_same_mesh_comes_back_exactly(load_mesh, method):
    # the moved geometry only locates: the detail carried is the one given, not Z's
    V, F, D, Z = _moved_nose(load_mesh)
    assert np.abs(curvature_detail(Z, F) - D).max() > 0.1 * np.abs(D).max()
    assert np.abs(transfer_curvature(Z, F, Z, F, method=method, detail=D) - D).max() < 1e-14


def test_a_given_detail_keeps_its_total_on_a_retriangulation(load_mesh):
    V, F, D, Z = _moved_nose(load_mesh)
    Zt, Ft = retriangulate(Z, F, target_edge="2%")
    Dt = transfer_curvature(Z, F, Zt, Ft, detail=D)
    assert np.abs(Dt.sum(0) - D.sum(0)).max() <= 1e-12 * np.abs(D).sum()


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
def test_a_moved_source_rebuilt_from_its_given_detail_comes_back(load_mesh, method):
    # the editing use: the nose's detail carried from its harmonic surface Z onto a
    # retriangulation of Z and rebuilt there lands near the nose (measured distance to it, of
    # the diagonal: RMS 1.5 % / 1.6 %, max 4.3 % / 4.7 % for conservative / pointwise), while
    # carrying Z's own detail gives Z back (RMS 5.7 %, max 16 %); L is the flat target's, so
    # not to solver precision (on the same mesh: RMS 2.6 %)
    from curvdetail.curvature import boundary_vertices, reconstruct
    from curvdetail.curvature.geometry import bbox_diagonal
    from curvdetail.remesh import vertex_distance

    V, F, D, Z = _moved_nose(load_mesh)
    Zt, Ft = retriangulate(Z, F, target_edge="2%")
    b = boundary_vertices(Ft)
    diagonal = bbox_diagonal(V)

    def rebuilt_distance(detail):
        Dt = transfer_curvature(Z, F, Zt, Ft, method=method, detail=detail)
        return vertex_distance(reconstruct(Zt, Ft, Dt, b, Zt[b], rows="free"), V, F) / diagonal

    given, own = rebuilt_distance(D), rebuilt_distance(None)
    assert np.sqrt(np.mean(given ** 2)) < 0.02 and given.max() < 0.06
    assert np.sqrt(np.mean(own ** 2)) > 0.05 and own.max() > 0.15


def test_a_malformed_detail_is_refused_by_name(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(ConstraintError, match=r"\(3, 3\).*\(640, 3\)") as e:
        transfer_curvature(V, F, V, F, detail=np.zeros((3, 3)))
    assert e.value.parameter.startswith("detail")
    D = curvature_detail(V, F)
    D[5, 1] = np.nan
    with pytest.raises(ConstraintError) as e:
        transfer_curvature(V, F, V, F, method="pointwise", detail=D)
    assert e.value.parameter.startswith("detail") and (e.value.count, e.value.first) == (1, [5])



def test_samples_on_one_sheet_stay_at_their_closest_points_where_the_target_is_uneven():
    # a target about 10 times finer near x = 0 than on average (uneven sampling, as scans have):
    # own_side's step toward a sample's own triangles crossed many target triangles there, and
    # moved 112 samples up to 10 times farther from the surface (the detail moved by 36 % of its max)
    from curvdetail.remesh.locate import locate, own_side
    from curvdetail.remesh.transfer import _edge_curvature_measure

    def lift(V):
        V[:, 2] = 0.05 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
        return V

    Vs, Fs = grid(8, 8)
    Vt, Ft = grid(60, 60)
    Vt[:, 0] **= 3
    Vs, Vt = lift(Vs), lift(Vt)
    E, _, _, inner = _edge_curvature_measure(Vs, Fs, normals=True)
    P = Vs[E].mean(axis=1)
    face, bary, dist = locate(P, Vt, Ft)
    closest = face.copy()
    assert own_side(P, inner, Vt, Ft, face, bary, dist) == 0
    assert np.array_equal(face, closest)
