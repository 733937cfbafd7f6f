"""The analytic test meshes (curvdetail.curvature.testing) are what the other tests take them for:
counts, exact positions, one piece, the boundary they claim, outward orientation."""

import numpy as np
import pytest

from curvdetail.curvature import boundary_vertices, check_mesh
from curvdetail.curvature.testing import cylinder, disk, grid, icosphere


def _euler(V, F):
    edges = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    return V.shape[0] - edges.shape[0] + F.shape[0]


def _normals(V, F):
    return np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])


def test_grid_counts_extent_and_upward_normals():
    V, F = grid(7, 4, size=(3.0, 2.0))
    check_mesh(V, F)
    assert V.shape == (28, 3) and F.shape == (2 * 6 * 3, 3)
    assert np.array_equal(V.min(0), [0, 0, 0]) and np.array_equal(V.max(0), [3.0, 2.0, 0])
    assert np.all(_normals(V, F)[:, 2] > 0) and _euler(V, F) == 1
    assert boundary_vertices(F).size == 2 * (7 + 4) - 4
    assert 0.5 * np.linalg.norm(_normals(V, F), axis=1).sum() == pytest.approx(6.0, rel=1e-14)


@pytest.mark.parametrize("subdivisions", [0, 2])
def test_icosphere_is_closed_on_its_radius_with_outward_normals(subdivisions):
    V, F = icosphere(radius=2.5, subdivisions=subdivisions)
    check_mesh(V, F)
    assert V.shape[0] == 10 * 4 ** subdivisions + 2 and F.shape[0] == 20 * 4 ** subdivisions
    assert np.allclose(np.linalg.norm(V, axis=1), 2.5, rtol=1e-15, atol=0)
    assert _euler(V, F) == 2 and boundary_vertices(F).size == 0
    centroids = V[F].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", _normals(V, F), centroids) > 0)


def test_cylinder_rings_lie_on_the_radius_between_its_two_boundary_circles():
    V, F = cylinder(radius=1.5, height=2.0, n_around=16, n_along=5, z0=1.0)
    check_mesh(V, F)
    assert V.shape[0] == 16 * 5 and F.shape[0] == 2 * 16 * 4
    assert np.allclose(np.hypot(V[:, 0], V[:, 1]), 1.5, rtol=1e-15)
    assert V[:, 2].min() == 1.0 and V[:, 2].max() == 3.0
    b = boundary_vertices(F)
    assert np.array_equal(np.sort(np.unique(V[b, 2])), [1.0, 3.0]) and b.size == 32
    assert _euler(V, F) == 0                                    # an annulus
    centroids = V[F].mean(axis=1)
    radial = centroids * [1.0, 1.0, 0.0]
    assert np.all(np.einsum("ij,ij->i", _normals(V, F), radial) > 0)


def test_disk_is_one_piece_with_its_outer_ring_as_boundary():
    V, F = disk(n_rings=6, radius=2.0)
    check_mesh(V, F)
    assert V.shape[0] == 1 + sum(6 * r for r in range(1, 7))
    assert _euler(V, F) == 1
    b = boundary_vertices(F)
    assert b.size == 36 and np.allclose(np.hypot(V[b, 0], V[b, 1]), 2.0, rtol=1e-15)
    assert np.all(V[:, 2] == 0) and np.all(_normals(V, F)[:, 2] > 0)
