"""Point location with barycentric coordinates (curvdetail.remesh.locate)."""

import numpy as np
import pytest

from curvdetail.curvature.errors import MeshError
from curvdetail.remesh import interpolate, locate, spread


def _points_on_faces(V, F, rng, k=2000):
    face = rng.integers(0, F.shape[0], k)
    bary = rng.dirichlet([1.0, 1.0, 1.0], k)
    return face, bary, interpolate(V, F, face, bary)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
def test_located_barycentrics_reproduce_points_on_the_surface(load_mesh, rng, engine):
    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng)
    face, bary, dist = locate(P, V, F, engine=engine)
    # a point on the surface is found at distance 0 and rebuilt from its face to rounding
    assert np.abs(interpolate(V, F, face, bary) - P).max() < 1e-12
    assert dist.max() < 1e-12
    assert np.all(bary >= 0) and np.allclose(bary.sum(1), 1.0)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
def test_planar_location_finds_the_containing_triangle(flat_disk, rng, engine):
    V, F = flat_disk
    face0, bary0, P = _points_on_faces(V[:, :2], F, rng)
    face, bary, dist = locate(P, V[:, :2], F, engine=engine)
    assert np.abs(interpolate(V[:, :2], F, face, bary) - P).max() < 1e-12
    assert np.all(dist < 1e-12)


def test_points_off_the_surface_get_the_exact_closest_point(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng, k=200)
    P = P + rng.normal(scale=0.01, size=P.shape)
    _, _, dist = locate(P, V, F)
    # brute force over every triangle (Ericson's closest point, same code path, all candidates)
    from curvdetail.remesh.locate import _closest_barycentric

    _, d_all = _closest_barycentric(P[:, None, :], V[F][None])
    assert np.allclose(dist, d_all.min(axis=1), atol=1e-14)


def test_point_outside_a_planar_domain_falls_back_to_the_nearest_triangle():
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    F = np.array([[0, 1, 2]])
    face, bary, dist = locate(np.array([[1.0, 1.0]]), V, F)
    # nearest point of the hypotenuse to (1, 1) is its midpoint, at distance sqrt(2)/2
    assert face.tolist() == [0]
    assert np.allclose(bary, [[0.0, 0.5, 0.5]])
    assert np.allclose(dist, [np.sqrt(0.5)])


def test_spread_is_the_adjoint_of_interpolate_and_conserves_the_total(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    face, bary, _ = _points_on_faces(V, F, rng)
    f = rng.normal(size=V.shape[0])
    g = rng.normal(size=face.size)
    assert np.dot(interpolate(f, F, face, bary), g) == pytest.approx(np.dot(f, spread(g, F, face, bary, V.shape[0])[:, 0]))
    assert spread(g, F, face, bary, V.shape[0]).sum() == pytest.approx(g.sum(), abs=1e-12)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
@pytest.mark.parametrize("dim", [2, 3])
def test_nan_points_are_refused_naming_them_not_a_crash(flat_disk, engine, dim):
    # pymeshlab's nearest-face grid used to die with a segmentation fault on a NaN point
    V, F = flat_disk
    P = V[:4, :dim].copy()
    P[2, 0] = np.nan
    with pytest.raises(MeshError, match=r"points: 1 rows are NaN or infinite \(first: 2\)"):
        locate(P, V[:, :dim], F, engine=engine)


def test_triangle_indices_outside_v_are_refused(flat_disk):
    V, F = flat_disk
    G = F.copy()
    G[5, 1] = V.shape[0]
    with pytest.raises(MeshError, match=r"1 triangles have vertex indices outside .*first: 5"):
        locate(V[:3], V, G)


def test_interpolate_and_spread_refuse_located_points_that_do_not_fit(flat_disk):
    # they used to fail with numpy's IndexError from deep inside the indexing
    V, F = flat_disk
    face, bary, _ = locate(V[:5], V, F)
    with pytest.raises(MeshError, match=r"spread: 1 face indices are outside"):
        spread(np.ones(5), F, np.r_[face[:4], F.shape[0]], bary, V.shape[0])
    with pytest.raises(MeshError, match="vertex indices outside"):
        spread(np.ones(5), F, face, bary, 3)
    with pytest.raises(MeshError, match="4 values for 5 located points"):
        spread(np.ones(4), F, face, bary, V.shape[0])
    with pytest.raises(MeshError, match="vertex indices outside"):
        interpolate(np.ones(3), F, face, bary)
