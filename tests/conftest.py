"""Shared fixtures: analytic meshes with known answers and the bundled real meshes."""

import os

import numpy as np
import pytest

from curvdetail import read_mesh
from curvdetail.curvature.testing import cylinder, disk, grid, icosphere

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def data_path(name):
    return os.path.join(DATA, name)


def every_backend(exclude=()):
    """Every solver backend as a pytest parameter, skipped with a reason where it is not
    installed (CHOLMOD needs scikit-sparse, which CI does not install), so the report counts
    what did not run instead of leaving it out without a word."""
    from curvdetail import available_backends
    from curvdetail.curvature.sparse_solver import BACKENDS

    installed = available_backends()
    return [pytest.param(name, marks=pytest.mark.skipif(name not in installed, reason=f"solver backend {name!r} "
                                                        "not installed (pip install -e '.[cholmod]' for CHOLMOD)"))
            for name in BACKENDS if name not in exclude]


def jittered_grid(nx, ny, seed, *, jitter=0.2, heights=0.0):
    """A grid triangulation of the unit square whose interior vertices are moved by up to
    ``jitter`` of the spacing in x and y (at most 0.2: an affine image of a square grid jittered
    that much, so no triangle folds; about half the triangles come out obtuse), lifted by
    ``heights`` times a random smooth height field (0: flat). Returns ``(V, F, interior)``."""
    rng = np.random.default_rng(seed)
    V, F = grid(nx, ny)
    interior = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
    spacing = np.array([1.0 / (nx - 1), 1.0 / (ny - 1)])
    V[interior, :2] += rng.uniform(-jitter, jitter, (interior.size, 2)) * spacing
    a, b, c = rng.uniform(-1.0, 1.0, 3)
    V[:, 2] = heights * (a * np.sin(2.0 * V[:, 0] + b) + c * V[:, 0] * V[:, 1] ** 2)
    return V, F, interior


@pytest.fixture(scope="session")
def load_mesh():
    """``load_mesh(name) -> (V, F)`` for a file in tests/data (cached; returns copies)."""
    cache = {}

    def load(name):
        if name not in cache:
            cache[name] = read_mesh(data_path(name))
        V, F = cache[name]
        return V.copy(), F.copy()

    return load


@pytest.fixture
def sphere():
    """Icosphere of radius 2 (2562 vertices)."""
    return icosphere(radius=2.0, subdivisions=4)


@pytest.fixture
def plane_grid():
    """Flat 21 x 21 grid on the unit square."""
    return grid(21, 21)


@pytest.fixture
def open_cylinder():
    """Open cylinder, radius 0.5, height 2, 48 around x 21 along."""
    return cylinder(radius=0.5, height=2.0, n_around=48, n_along=21)


@pytest.fixture
def flat_disk():
    """Flat unit disk of 20 rings (1261 vertices)."""
    return disk(n_rings=20)


@pytest.fixture
def rng():
    return np.random.default_rng(20061210)


@pytest.fixture
def wavy_grid_with_a_sliver():
    """A builder: ``(V, F)`` of a 30 x 30 wavy grid with one valid but near-degenerate triangle
    of the given doubled area (times the squared bbox diagonal)."""
    from curvdetail.curvature._validate import bbox_diagonal
    from curvdetail.curvature.testing import grid

    def _build(double_area):
        """30 x 30 wavy grid whose vertex 465 is moved next to edge (434, 435), making a triangle of
        the given doubled area (times the squared diagonal): valid, but badly conditioned."""
        V, F = grid(30, 30)
        V[:, 2] = 0.1 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
        d = bbox_diagonal(V)
        a, b, v = 434, 435, 465
        mid, e = (V[a] + V[b]) / 2, V[b] - V[a]
        p = V[v] - mid
        p -= p @ e / (e @ e) * e
        V[v] = mid + p / np.linalg.norm(p) * double_area * d * d / np.linalg.norm(e)
        return V, F

    return _build


@pytest.fixture
def isotropic_calls(monkeypatch):
    """The keyword arguments of every ``meshing_isotropic_explicit_remeshing`` call, in order (a
    spy that still runs the filter)."""
    import pymeshlab

    calls, real = [], pymeshlab.MeshSet.meshing_isotropic_explicit_remeshing

    def spy(self, **kwargs):
        calls.append(kwargs)
        return real(self, **kwargs)

    monkeypatch.setattr(pymeshlab.MeshSet, "meshing_isotropic_explicit_remeshing", spy)
    return calls
