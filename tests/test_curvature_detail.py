"""curvature_detail: D = L V = K A, extensive, rotation and scale behaviour."""

import doctest
import importlib

import numpy as np
import pytest

from curvdetail import cotan_laplacian, curvature_detail, mean_curvature_normal
from curvdetail.curvature.testing import icosphere


def test_equals_laplacian_times_positions(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    D = curvature_detail(V, F)
    # computed about the bounding box's centre: equal to L @ V up to rounding
    np.testing.assert_allclose(D, cotan_laplacian(V, F) @ V, rtol=0, atol=1e-12 * np.abs(D).max())


@pytest.mark.parametrize("offset", [1e6, 6.4e6])
def test_is_translation_invariant_far_from_the_origin(offset):
    # UTM / ECEF coordinates: L @ V summed terms of the coordinates' size to a result of the
    # detail's size; a 1 cm sphere 1e6 m out lost six digits of K
    V, F = icosphere(radius=0.01, subdivisions=4)
    shift = np.array([offset, 0.7 * offset, 0.3 * offset])
    far = V + shift                     # rounded to the coordinates' spacing ...
    near = far - shift                  # ... and back, exactly: the very same triangles
    D = curvature_detail(near, F)
    assert np.abs(curvature_detail(far, F) - D).max() < 1e-12 * np.abs(D).max()


def test_equals_mean_curvature_normal_times_area(load_mesh):
    V, F = load_mesh("spot.obj")
    K, A = mean_curvature_normal(V, F)
    D = curvature_detail(V, F)
    assert np.allclose(D, K * A[:, None], rtol=0, atol=1e-15 * np.abs(D).max() * 10)


def test_sums_to_zero_on_a_closed_surface(sphere):
    # the rows of L sum to zero and L is symmetric, so the columns do too: sum_i D_i = 0
    V, F = sphere
    D = curvature_detail(V, F)
    assert np.abs(D.sum(axis=0)).max() < 1e-12 * np.abs(D).sum()


def test_sphere_detail_is_two_over_r_times_area_outward(sphere):
    V, F = sphere
    D = curvature_detail(V, F)
    _, A = mean_curvature_normal(V, F)
    expected = (2.0 / 2.0) * A[:, None] * V / 2.0     # |K| = 2/R, direction V/R, R = 2
    # per-vertex K deviates from the radial direction by up to 4e-3 rad on this icosphere (and
    # from 2/R in length by 9e-6): rows agree to ~5e-3 of their length
    rel = np.linalg.norm(D - expected, axis=1) / np.linalg.norm(expected, axis=1)
    assert rel.max() < 1e-2


def test_rotates_with_the_mesh_and_scales_as_s(rng):
    V, F = icosphere(radius=1.0, subdivisions=2)
    V = V * [1.0, 0.7, 1.4] + 0.02 * rng.normal(size=V.shape)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    s, t = 0.3, np.array([10.0, 0.0, -4.0])
    D0 = curvature_detail(V, F)
    D1 = curvature_detail(s * V @ Q.T + t, F)
    assert np.allclose(D1, s * D0 @ Q.T, atol=1e-12 * np.abs(D0).max())


def test_is_extensive_under_refinement():
    # one subdivision quarters the vertex areas: the detail per vertex drops ~4x, K does not
    D2 = curvature_detail(*icosphere(subdivisions=2))
    D3 = curvature_detail(*icosphere(subdivisions=3))
    ratio = np.linalg.norm(D2, axis=1).mean() / np.linalg.norm(D3, axis=1).mean()
    assert 3.5 < ratio < 4.5


def test_docstring_example_runs():
    result = doctest.testmod(importlib.import_module("curvdetail.curvature.curvature_detail"))
    assert result.attempted > 0 and result.failed == 0, result
