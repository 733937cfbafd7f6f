"""mixed_voronoi_area: hand-computed cases (Voronoi and obtuse), tiling, sphere."""

import doctest
import importlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from curvdetail import mixed_voronoi_area
from curvdetail.curvature.testing import disk, icosphere

from conftest import jittered_grid

S3 = np.sqrt(3.0)


def _triangle_areas(V, F):
    return 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)


def test_right_triangle_uses_voronoi_regions():
    # Right angle at V0 is not obtuse, so each corner gets its Voronoi region
    # (|e_ij|^2 cot(opposite) + |e_ik|^2 cot(opposite)) / 8:
    # V0: (1 * cot45 + 1 * cot45) / 8 = 1/4; V1: (1 * cot45 + 2 * cot90) / 8 = 1/8; V2: 1/8.
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    A = mixed_voronoi_area(V, np.array([[0, 1, 2]]))
    assert np.allclose(A, [0.25, 0.125, 0.125], atol=1e-15)


def test_obtuse_triangle_gives_half_to_the_obtuse_corner():
    # (0,0,0), (4,0,0), (2,1,0): area 2, obtuse at V2 -> V2 gets 2/2 = 1, V0 and V1 get 2/4.
    V = np.array([[0.0, 0, 0], [4, 0, 0], [2, 1, 0]])
    A = mixed_voronoi_area(V, np.array([[0, 1, 2]]))
    assert np.allclose(A, [0.5, 0.5, 1.0], atol=1e-15)


def test_a_barely_obtuse_corner_already_takes_half():
    # 95 degrees at vertex 0: Meyer et al.'s rule switches at 90, not somewhere beyond it
    a = np.deg2rad(95.0)
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [np.cos(a), np.sin(a), 0.0]])
    area = 0.5 * np.sin(a)
    assert np.allclose(mixed_voronoi_area(V, np.array([[0, 1, 2]])), [area / 2, area / 4, area / 4],
                       rtol=1e-12)


def test_two_triangles_sum_their_corner_shares():
    # The folded square of test_cotan_laplacian: right triangle A = (0,1,2) gives 1/8, 1/4, 1/8;
    # equilateral B = (0,2,3) of side sqrt 2 (area sqrt(3)/2) gives a third, sqrt(3)/6, to each.
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1]])
    A = mixed_voronoi_area(V, np.array([[0, 1, 2], [0, 2, 3]]))
    third = S3 / 6
    assert np.allclose(A, [0.125 + third, 0.25, 0.125 + third, third], atol=1e-15)


def test_areas_tile_the_surface(load_mesh):
    V, F = load_mesh("mannequin_ear.obj")
    A = mixed_voronoi_area(V, F)
    assert np.all(A > 0)
    assert np.isclose(A.sum(), _triangle_areas(V, F).sum(), rtol=1e-12)


def test_sphere_areas_sum_to_four_pi_r_squared_within_the_polyhedral_error(sphere):
    # The icosphere is inscribed in the sphere of radius 2, so its area is below 4 pi R^2; with
    # 5120 triangles the deficit is 0.12 % (0.48 % with 1280), an O(h^2) polyhedral error.
    V, F = sphere
    A = mixed_voronoi_area(V, F)
    exact = 4 * np.pi * 2.0 ** 2
    assert np.isclose(A.sum(), _triangle_areas(V, F).sum(), rtol=1e-12)
    assert 0 < exact - A.sum() < 2e-3 * exact


def test_flat_disk_area_approaches_pi():
    # 20 rings: the inscribed polygon of 120 sides has area (120/2) sin(2 pi/120) = pi (1 - 4.6e-4)
    V, F = disk(n_rings=20)
    A = mixed_voronoi_area(V, F)
    assert np.isclose(A.sum(), 60 * np.sin(2 * np.pi / 120), rtol=1e-12)


def test_areas_scale_with_the_square_of_the_scale():
    V, F = icosphere(subdivisions=2)
    assert np.allclose(mixed_voronoi_area(2.5 * V, F), 6.25 * mixed_voronoi_area(V, F), rtol=1e-12)


def test_docstring_example_runs():
    mod = importlib.import_module("curvdetail.curvature.mixed_voronoi_area")

    result = doctest.testmod(mod)
    assert result.attempted > 0 and result.failed == 0, result


def _meyer_reference(V, F):
    """Meyer et al. 2002, Fig. 4, triangle by triangle in plain Python: the Voronoi share of each
    corner of a non-obtuse triangle, else half the area to the obtuse corner and a quarter to
    the others."""
    A = np.zeros(V.shape[0])
    for tri in F.tolist():
        P = V[tri]
        area = 0.5 * np.linalg.norm(np.cross(P[1] - P[0], P[2] - P[0]))
        cosines = []
        for k in range(3):
            u, w = P[(k + 1) % 3] - P[k], P[(k + 2) % 3] - P[k]
            cosines.append(np.dot(u, w) / (np.linalg.norm(u) * np.linalg.norm(w)))
        if min(cosines) < 0:                              # obtuse
            for k in range(3):
                A[tri[k]] += area / 2 if cosines[k] < 0 else area / 4
            continue
        for k in range(3):
            a, b, c = P[k], P[(k + 1) % 3], P[(k + 2) % 3]

            def cot(at, p, q):
                u, w = p - at, q - at
                return np.dot(u, w) / np.linalg.norm(np.cross(u, w))

            A[tri[k]] += (np.dot(b - a, b - a) * cot(c, a, b) + np.dot(c - a, c - a) * cot(b, a, c)) / 8
    return A


@settings(max_examples=40, derandomize=True, database=None, deadline=None)
@given(nx=st.integers(3, 8), ny=st.integers(3, 8), seed=st.integers(0, 2**32 - 1), heights=st.floats(0.0, 2.0))
def test_matches_a_triangle_by_triangle_reference_on_random_surfaces(nx, ny, seed, heights):
    # jittered grids: about half their triangles obtuse, lifted onto random height fields
    V, F, _ = jittered_grid(nx, ny, seed, heights=heights)
    A = mixed_voronoi_area(V, F)
    reference = _meyer_reference(V, F)
    assert np.abs(A - reference).max() <= 1e-13 * reference.max()
    assert A.sum() == pytest.approx(_triangle_areas(V, F).sum(), rel=1e-13)
