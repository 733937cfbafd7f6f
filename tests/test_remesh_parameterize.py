"""Planar parameterization on one shared domain (curvdetail.remesh.parameterize)."""

import numpy as np
import pytest

from curvdetail.curvature.errors import CurvdetailError
from curvdetail.curvature.testing import disk
from curvdetail.remesh import flipped_triangles, harmonic_map, parameterize, retriangulate


def test_harmonic_map_of_a_flat_disk_is_a_rotation_of_it():
    # Linear functions are cotangent-harmonic on a planar mesh, and the boundary ring of disk()
    # is a regular polygon inscribed in the unit circle: arc length puts it at equal angles, so
    # the map is the identity up to the rotation that takes the anchor to angle 0.
    V, F = disk(n_rings=10)
    UV, _, info = parameterize(V, F)
    anchor = int(np.flatnonzero(np.isclose(np.linalg.norm(V[:, :2], axis=1), 1.0)).min())
    a = np.arctan2(V[anchor, 1], V[anchor, 0])
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    assert np.abs(UV - V[:, :2] @ R).max() < 1e-12
    assert info["flipped_source"] == 0


def test_target_boundary_lands_where_the_source_boundary_curve_is(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    Vt, Ft = retriangulate(V, F, target_edge="3%")
    UVs, UVt, info = parameterize(V, F, Vt, Ft)
    # both boundaries are placed by arc length on the same source polyline from the same anchor
    assert info["boundary_mismatch"] < 1e-12
    assert np.allclose(np.linalg.norm(UVt[np.abs(np.linalg.norm(UVt, axis=1) - 1) < 1e-9], axis=1), 1.0)
    assert info["flipped_source"] == 0 and info["flipped_target"] == 0


@pytest.mark.parametrize("method,tolerance", [("meshlab_harmonic", 0.02), ("lscm", 0.1)])
def test_meshlab_maps_are_aligned_to_the_source_domain(load_mesh, method, tolerance):
    V, F = load_mesh("mannequin_nose.obj")
    Vt, Ft = retriangulate(V, F, target_edge="3%")
    UVs, UVt, info = parameterize(V, F, Vt, Ft, method=method)
    size = np.linalg.norm(UVs.max(0) - UVs.min(0))
    # the two independent maps agree on the boundary after the similarity fit: the harmonic ones
    # within 2 % of the domain size (discretization); LSCM's free boundary depends on the
    # triangulation, so the two LSCM boundaries differ by up to ~5 % (measured 4.3 %)
    assert info["boundary_mismatch"] < tolerance * size
    assert UVs.shape == (V.shape[0], 2) and UVt.shape == (Vt.shape[0], 2)


def test_flipped_triangles_are_detected():
    UV = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 2]], float)
    F = np.array([[0, 1, 2], [1, 3, 2], [3, 4, 1]])   # the last is clockwise
    assert flipped_triangles(UV, F).tolist() == [2]


def test_flipped_triangles_refuses_uv_that_does_not_fit_f():
    from curvdetail.curvature.errors import MeshError

    V, F = disk(n_rings=4)
    with pytest.raises(MeshError, match=r"\[0, 3\)") as e:
        flipped_triangles(V[:3, :2], F)
    assert (e.value.parameter, e.value.count) == ("UV", 3)
    with pytest.raises(MeshError, match=rf"\({V.shape[0]}, 3\)") as e:
        flipped_triangles(V, F)
    assert e.value.parameter == "UV"


def test_flipped_triangles_refuses_nan_uv_instead_of_reporting_none_flipped():
    from curvdetail.curvature.errors import MeshError

    V, F = disk(n_rings=4)
    UV = V[:, :2].copy()
    UV[5] = np.nan                       # NaN <= 0 is False: every triangle passed as unflipped
    with pytest.raises(MeshError) as e:
        flipped_triangles(UV, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("UV", 1, [5])


def test_flipped_triangles_refuses_non_integer_faces():
    from curvdetail.curvature.errors import MeshError

    V, F = disk(n_rings=4)
    with pytest.raises(MeshError) as info:
        flipped_triangles(V[:, :2], F + 0.5)
    assert (info.value.parameter, info.value.count, info.value.first) == ("F", F.shape[0], [0, 1, 2])


def test_harmonic_map_without_pinned_vertices_is_refused_not_zeros():
    # with nothing pinned every constant solves it: it returned zeros silently
    from curvdetail.curvature.errors import ConstraintError

    V, F = disk(n_rings=4)
    with pytest.raises(ConstraintError) as e:
        harmonic_map(V, F, [], np.zeros((0, 2)))
    assert (e.value.parameter, e.value.count) == ("boundary", 0)
    with pytest.raises(ConstraintError, match=r"\(2, 3\).*\(2, 2\)") as e:
        harmonic_map(V, F, [0, 1], np.zeros((2, 3)))
    assert e.value.parameter == "boundary_uv"
    with pytest.raises(ConstraintError) as e:
        harmonic_map(V, F, [0, 1], [[0.0, 0.0], [np.nan, 1.0]])
    assert (e.value.parameter, e.value.count, e.value.first) == ("boundary_uv", 1, [1])


def test_a_target_half_given_is_refused_not_ignored():
    V, F = disk(n_rings=4)
    with pytest.raises(CurvdetailError) as e:
        parameterize(V, F, None, F)
    assert e.value.parameter == "Vt"                   # the one missing
    with pytest.raises(CurvdetailError) as e:
        parameterize(V, F, V)
    assert e.value.parameter == "Ft"


def test_source_boundary_is_placed_on_the_circle_by_arc_length(load_mesh):
    # the nose's boundary edges differ in length (0.4x ... 2.5x their mean): each boundary
    # vertex's angle on the circle is its arc-length fraction along the loop, not its index
    from curvdetail.curvature.boundary_editing import boundary_loop

    V, F = load_mesh("mannequin_nose.obj")
    loop = boundary_loop(F)
    UV, _, _ = parameterize(V, F)
    seg = np.linalg.norm(np.roll(V[loop], -1, axis=0) - V[loop], axis=1)
    assert seg.max() > 1.5 * seg.min()          # uneven spacing: arc length and index differ
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]]) / seg.sum()
    angle = np.arctan2(UV[loop, 1], UV[loop, 0])
    turn = np.mod(angle - angle[0], 2 * np.pi) / (2 * np.pi)      # fraction of a turn from loop[0]
    if turn[1] > 0.5:                   # the loop runs clockwise on the circle
        turn = np.mod(-turn, 1.0)
    assert np.abs(turn - s).max() < 1e-12


@pytest.mark.parametrize("method", ["conformal", np.array(["harmonic"]), ["lscm"]])
def test_a_method_that_is_not_a_parameterization_is_refused(method):
    # an array or list was compared with ``in`` element-wise (numpy's "truth value ... is ambiguous")
    V, F = disk(3)
    with pytest.raises(CurvdetailError, match="'conformal'" if isinstance(method, str) else "ndarray|list") as e:
        parameterize(V, F, method=method)
    assert e.value.parameter == "method"


def test_target_boundary_vertices_lie_on_the_source_domain_boundary():
    # disk(4) has 24 boundary vertices, its retriangulation 48: the target vertices between two
    # source boundary vertices belong on the source's boundary edge (a chord of the unit
    # circle) at their arc-length fraction. On the circle they lay up to 1 - cos(pi / 24) =
    # 0.0086 outside the source's domain, and boundary_mismatch said 0.
    from curvdetail.remesh import check_disk
    from curvdetail.remesh._disk import Polyline

    V, F = disk(n_rings=4)
    V[:, 2] = 0.2 * (1 - (V[:, :2] ** 2).sum(1))
    Vt, Ft = retriangulate(V, F, target_edge="4%")
    UVs, UVt, info = parameterize(V, F, Vt, Ft)
    _, _, loop = check_disk(V, F)
    _, _, loop_t = check_disk(Vt, Ft)
    assert loop_t.size > loop.size                       # vertices between the source's ones
    # in the domain: each target boundary vertex on the source's boundary polygon, at the same
    # arc-length fraction as in space (both exact: the polygon's points are exact lerps)
    dom = Polyline(np.column_stack([UVs[loop], np.zeros(loop.size)]))
    _, s_dom, d_dom = dom.project(np.column_stack([UVt[loop_t], np.zeros(loop_t.size)]))
    space = Polyline(V[loop])
    _, s_space, _ = space.project(Vt[loop_t])
    assert d_dom.max() < 1e-12
    # each source edge's fraction: s_dom / |edge in the domain| = s_space / |edge in space|
    seg = np.clip(np.searchsorted(space.s0, s_space, side="right") - 1, 0, loop.size - 1)
    chord = np.linalg.norm(UVs[loop[(seg + 1) % loop.size]] - UVs[loop[seg]], axis=1)
    frac_dom = (s_dom - dom.s0[seg]) / chord
    frac_space = (s_space - space.s0[seg]) / space.length[seg]
    assert np.abs(frac_dom - frac_space).max() < 1e-9
    assert info["boundary_mismatch"] < 1e-12 and info["flipped_target"] == 0


@pytest.mark.parametrize("move", [lambda V: V + [0.0, 0.0, 0.5], lambda V: 2.0 * V])
def test_a_target_whose_boundary_is_off_the_source_boundary_is_refused(move):
    # it was mapped as if its boundary lay where its projections land: the disk lifted by 0.5
    # got the source's own domain back, no flipped triangle and boundary_mismatch 0.0
    from curvdetail.remesh import RemeshError

    V, F = disk(n_rings=10)
    with pytest.raises(RemeshError, match=r"curvdetail\.remesh\.retriangulate") as e:      # what makes one
        parameterize(V, F, move(V), F)
    assert (e.value.count, e.value.first) == (60, [0, 1, 2])        # all 60 boundary vertices

    # on it to rounding (a float32 copy: 3e-8 of the diagonal) it is taken
    UVs, UVt, info = parameterize(V, F, V.astype(np.float32), F)
    assert np.abs(UVt - UVs).max() < 1e-6 and info["boundary_mismatch"] < 1e-6
