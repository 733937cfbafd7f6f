"""detail_attributes: stored curvature detail carries the vertex numbering it belongs to, and
detail of another triangulation is refused instead of rebuilt from."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import boundary_vertices, curvature_detail, reconstruct
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.filters import FilterError, apply

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def meshset(name):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, name))
    return ms


def _remeshed(ms):
    # every parameter passed: pymeshlab keeps earlier calls' values in one process
    ms.meshing_isotropic_explicit_remeshing(
        iterations=3, adaptive=False, selectedonly=False, targetlen=pymeshlab.PercentageValue(1.5),
        featuredeg=30.0, checksurfdist=True, maxsurfdist=pymeshlab.PercentageValue(1.5), splitflag=True,
        collapseflag=True, swapflag=True, smoothflag=True, reprojectflag=True)


@pytest.mark.parametrize("step", ["remesh", "subdivide", "remove_vertex", "flip_edges"])
def test_detail_of_another_triangulation_is_refused_not_rebuilt(step):
    # MeshLab keeps custom attributes through these steps without interpolating them: new
    # vertices read 0 and the remeshed nose, rebuilt from that, moved by 10 % of its diagonal
    ms = meshset("mannequin_nose.obj")
    apply(ms, "compute_curvature_detail")
    if step == "remesh":
        _remeshed(ms)
    elif step == "subdivide":
        ms.meshing_surface_subdivision_midpoint(iterations=1, threshold=pymeshlab.PercentageValue(0.0),
                                                selected=False)
    elif step == "remove_vertex":
        ms.compute_selection_by_condition_per_vertex(condselect="(vi == 100)")
        ms.meshing_remove_selected_vertices()
    else:                   # same vertices, same numbering, other triangles (nose moved 1.3 %)
        ms.meshing_edge_flip_by_planar_optimization(selection=False, pthreshold=1.0, planartype="area/max side",
                                                    iterations=1)
    n = ms.current_mesh().vertex_number()
    with pytest.raises(FilterError, match=rf"\b{n:,}\b.*\bcompute_curvature_detail\b") as e:   # the fix's filter
        apply(ms, "apply_curvature_reconstruction")
    assert e.value.value == "curvature_detail" and 0 < e.value.count <= n and len(e.value.first) >= 1


def test_detail_survives_moved_vertices_and_a_ply_round_trip(tmp_path):
    # the stamp follows the numbering, not the geometry; and it is saved with the detail
    from curvdetail.filters.files import load_meshset, save_current_mesh

    ms = meshset("mannequin_nose.obj")
    V = ms.current_mesh().vertex_matrix().copy()
    apply(ms, "compute_curvature_detail")
    ms.compute_coord_by_function(x="x", y="y", z="z + 0.01 * x", onselected=False)
    save_current_mesh(ms, str(tmp_path / "d.ply"))
    ms2 = load_meshset(str(tmp_path / "d.ply"))
    apply(ms2, "apply_curvature_reconstruction")
    # the boundary was moved with the rest; the interior follows its detail
    F = ms2.current_mesh().face_matrix()
    b = boundary_vertices(F)
    W = V.copy()
    W[:, 2] += 0.01 * V[:, 0]
    X = ms2.current_mesh().vertex_matrix()
    assert np.allclose(X[b], W[b], rtol=0, atol=1e-12)
    # the interior is the core rebuild of the moved geometry from the detail of the unmoved one,
    # with the filter's default rows="all" (measured: 0.0; the moved surface itself is 3.9e-4
    # of the diagonal away, rows="free" 2.1e-4)
    interior = np.setdiff1d(np.arange(V.shape[0]), b)
    expected = reconstruct(W, F, curvature_detail(V, F), b, W[b], rows="all")
    assert np.abs(X[interior] - expected[interior]).max() < 1e-9 * bbox_diagonal(W)
    with pytest.raises(FilterError) as e:
        _remeshed(ms2)
        apply(ms2, "apply_curvature_reconstruction")
    assert e.value.value == "curvature_detail" and e.value.count > 0
