"""mean_curvature_normal: sphere, plane, cylinder, hand-computed case, rotation and scale."""

import doctest
import importlib

import numpy as np

from curvdetail import boundary_vertices, mean_curvature_normal
from curvdetail.curvature.testing import grid, icosphere


def test_sphere_has_magnitude_two_over_r(sphere):
    # icosphere of radius 2 (2562 vertices): |K| = 2/R = 1 up to an O(h^2) discretization error,
    # measured 8.7e-6 here (3.5e-5 with 642 vertices: a factor ~4 per halving of h)
    V, F = sphere
    K, _ = mean_curvature_normal(V, F)
    assert np.abs(np.linalg.norm(K, axis=1) - 1.0).max() < 1e-4


def test_sphere_normals_point_outward(sphere):
    V, F = sphere
    K, _ = mean_curvature_normal(V, F)
    cos = np.einsum("ij,ij->i", K, V) / (np.linalg.norm(K, axis=1) * np.linalg.norm(V, axis=1))
    assert cos.min() > 1 - 1e-4          # measured 1 - 9e-6


def test_plane_has_zero_curvature_inside_even_when_irregular(plane_grid, rng):
    # The cotangent Laplacian reproduces linear functions on any planar triangulation, so
    # interior K vanishes to rounding even after jittering the interior vertices in the plane.
    V, F = plane_grid
    inner = np.setdiff1d(np.arange(V.shape[0]), boundary_vertices(F))
    V[inner, :2] += rng.uniform(-0.01, 0.01, (inner.size, 2))   # grid spacing 0.05
    K, _ = mean_curvature_normal(V, F)
    assert np.abs(K[inner]).max() < 1e-10


def test_cylinder_has_magnitude_one_over_r_inside(open_cylinder):
    # radius 0.5: |K| = 2H = 1/r = 2 away from the two boundary circles, pointing away from the
    # axis with no z component. Rings of equal triangles make this exact to rounding (1e-13).
    V, F = open_cylinder
    inner = np.abs(V[:, 2]) < 1.0 - 1e-9
    K, _ = mean_curvature_normal(V, F)
    K, P = K[inner], V[inner]
    assert np.abs(np.linalg.norm(K, axis=1) - 2.0).max() < 1e-9
    radial = P[:, :2] / np.linalg.norm(P[:, :2], axis=1, keepdims=True)
    assert np.allclose(K[:, :2], 2.0 * radial, atol=1e-9)
    assert np.abs(K[:, 2]).max() < 1e-9


def test_two_triangle_fold_matches_hand_computation():
    # Folded square (see test_cotan_laplacian): row 3 of L is (-h, 0, -h, 2h), h = 1/(2 sqrt 3),
    # so (L V)_3 = 2h (0,1,1) - h (1,1,0) = h (-1, 1, 2); A_3 = sqrt(3)/6 = h. K_3 = (-1, 1, 2).
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1]])
    K, A = mean_curvature_normal(V, np.array([[0, 1, 2], [0, 2, 3]]))
    assert np.allclose(K[3], [-1.0, 1.0, 2.0], atol=1e-14)
    assert np.isclose(A[3], 1 / (2 * np.sqrt(3)), atol=1e-15)


def test_rotates_with_the_mesh_and_scales_as_one_over_s(rng):
    V, F = icosphere(radius=1.3, subdivisions=2)
    V = V * [1.0, 0.8, 1.2] + 0.02 * rng.normal(size=V.shape)    # no symmetry left to hide errors
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    s, t = 2.5, np.array([3.0, -1.0, 0.5])
    K0, A0 = mean_curvature_normal(V, F)
    K1, A1 = mean_curvature_normal(s * V @ Q.T + t, F)
    assert np.allclose(K1, (K0 @ Q.T) / s, atol=1e-12 * np.abs(K0).max())
    assert np.allclose(A1, s ** 2 * A0, rtol=1e-12)


def test_is_independent_of_density_on_the_sphere():
    # intensive: refining the mesh leaves |K| = 2/R (R = 0.5) to the discretization error
    for subdivisions in (2, 3):
        K, _ = mean_curvature_normal(*icosphere(radius=0.5, subdivisions=subdivisions))
        assert np.abs(np.linalg.norm(K, axis=1) - 4.0).max() < 4.0 * 1e-3


def test_flat_grid_interior_is_exactly_zero_at_regular_vertices():
    V, F = grid(5, 4)
    K, _ = mean_curvature_normal(V, F)
    inner = np.setdiff1d(np.arange(V.shape[0]), boundary_vertices(F))
    assert np.abs(K[inner]).max() < 1e-12


def test_docstring_example_runs():
    result = doctest.testmod(importlib.import_module("curvdetail.curvature.mean_curvature_normal"))
    assert result.attempted > 0 and result.failed == 0, result
