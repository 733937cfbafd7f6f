"""Shared fixtures: analytic meshes with known answers and the bundled real meshes."""

import os

import numpy as np
import pytest

from curvdetail import read_mesh
from curvdetail.curvature.testing import cylinder, disk, grid, icosphere

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def data_path(name):
    return os.path.join(DATA, name)


class InexactSolves:
    """A factorization whose every solve comes back 1e-8 (relative) off: a stand-in for normal
    equations that lose cond^2 * eps, with an error that rounding on no machine can hide. The
    plain solve is then ~1e-8 off, and each corrected semi-normal step contracts the error by
    ~1e-8. (Asserting that the exact solves' plain error is large depended on the machine's
    rounding; "refined <= plain" does not hold by construction either: refine_least_squares
    does not keep the better iterate, and at the rounding floor a step may add rounding.)"""

    def __init__(self, factor):
        self.factor = factor

    def __getattr__(self, name):
        return getattr(self.factor, name)

    def solve(self, b):
        return self.factor.solve(b) * (1 + 1e-8)


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
    from curvdetail.curvature.geometry import bbox_diagonal
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


def square_with_one_long_side(n, m=12):
    """A planar unit-square patch ``(X (k, 2), F)`` whose bottom side is one edge and the other
    three ``n`` edges each, with an ``m`` x ``m`` grid of inner points, triangulated by Delaunay
    (triangles as scipy orders them): long triangles along the bottom beside small ones, where a
    search by the nearest few candidates goes wrong."""
    from scipy.spatial import Delaunay

    t = np.linspace(0.0, 1.0, n + 1)[:-1]
    ring = np.vstack([np.column_stack([np.ones(n), t]), np.column_stack([1 - t, np.ones(n)]),
                      np.column_stack([np.zeros(n), 1 - t]), [[0.0, 0.0]]])
    g = np.linspace(0.15, 0.85, m)
    X = np.vstack([ring, np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)])
    return X, Delaunay(X).simplices


def triangle_brute_force(P, V, F):
    """Distance from each point of ``P`` to the surface ``(V, F)``, every triangle measured: the
    distance to the triangle's plane where the projection falls inside it, else to the nearest
    of its three edges (checked on hand-computed points in test_remesh_evaluate)."""
    A, B, C = (V[F[:, i]][None] for i in range(3))                 # (1, m, d)
    Q = P[:, None, :]                                              # (k, 1, d)
    e0, e1, v = B - A, C - A, Q - A
    d00, d01, d11 = (e0 * e0).sum(-1), (e0 * e1).sum(-1), (e1 * e1).sum(-1)
    d20, d21 = (v * e0).sum(-1), (v * e1).sum(-1)
    s, t = d11 * d20 - d01 * d21, d00 * d21 - d01 * d20            # barycentrics times the determinant
    if P.shape[1] == 3:
        n = np.cross(e0, e1)
        plane = np.abs((v * n).sum(-1)) / np.linalg.norm(n, axis=-1)
    else:
        plane = np.zeros(s.shape)

    def segment(w, e):
        u = np.clip((w * e).sum(-1) / (e * e).sum(-1), 0.0, 1.0)
        return np.linalg.norm(w - u[..., None] * e, axis=-1)

    edge = np.minimum(np.minimum(segment(v, e0), segment(v, e1)), segment(Q - B, C - B))
    inside = (s >= 0) & (t >= 0) & (s + t <= d00 * d11 - d01 ** 2)
    return np.where(inside, np.minimum(plane, edge), edge).min(axis=1)


def wavy_source_and_a_rebuild_beside_it(monkeypatch):
    """A wavy 10 x 10 grid (heights +-0.5) as the source, and its rebuild forced beside it: the
    transfer patched to give ``L(Vt) Y``, so the rebuild is ``Y`` exactly, the retriangulation
    with its interior flattened at z = 0.3 (the source's height) and spread 1.4x about the
    centre, past the source's edge. There pymeshlab's closest-face grid (once locate's search)
    returned faces that were not the closest: 4 of the 500 vertices up to 0.49 % of the
    diagonal too far."""
    import curvdetail.remesh.experiment as experiment
    from curvdetail import boundary_vertices, cotan_laplacian
    from curvdetail.curvature.testing import grid

    V, F = grid(10, 10)
    V[:, 2] = 0.5 * np.sin(8 * V[:, 0]) * np.cos(6.4 * V[:, 1])

    def beside(Vs, Fs, Vt, Ft, **options):
        Y = Vt.copy()
        inner = np.setdiff1d(np.arange(Vt.shape[0]), boundary_vertices(Ft))
        Y[inner, :2] = (Y[inner, :2] - 0.5) * 1.4 + 0.5
        Y[inner, 2] = 0.3
        return cotan_laplacian(Vt, Ft) @ Y

    monkeypatch.setattr(experiment, "transfer_curvature", beside)
    return V, F


def squashing_target_triangle(parameterize):
    """``parameterize`` wrapped so that its target map puts one interior triangle's third corner on
    the line through the other two (what pymeshlab's float32 LSCM did to a camelhead triangle)."""
    from curvdetail.curvature import boundary_vertices

    def squashing(Vs, Fs, Vt, Ft, **kwargs):
        UVs, UVt, info = parameterize(Vs, Fs, Vt, Ft, **kwargs)
        interior = np.setdiff1d(np.arange(Vt.shape[0]), boundary_vertices(Ft))
        t = int(np.flatnonzero(np.isin(Ft, interior).all(1))[0])
        a, b, c = Ft[t]
        UVt = UVt.copy()
        UVt[c] = 0.25 * UVt[a] + 0.75 * UVt[b]
        return UVs, UVt, info
    return squashing


def load_script(name):
    """The script ``scripts/NAME.py`` as a fresh module (the scripts are not a package)."""
    import importlib.util

    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", name + ".py")
    spec = importlib.util.spec_from_file_location(f"script_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
