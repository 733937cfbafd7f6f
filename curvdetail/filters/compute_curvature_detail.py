"""Filter ``compute_curvature_detail``: the paper's curvature detail as per-vertex attributes."""

import numpy as np

from ..curvature.topology import boundary_vertices, check_oriented
from ..curvature.cotan_laplacian import laplacian_product
from ..curvature.mixed_voronoi_area import mixed_voronoi_area
from ..curvature.robust_laplacian import LAPLACIANS, checked_laplacian, robust_laplacian
from .parameters import Parameter
from .detail_attributes import AREA, DETAIL, NORMAL, store_detail  # noqa: F401  (names re-exported)
from .meshset import layer_id, mesh_arrays, set_vertex_quality, vertex_normals
from .registry import PAPER, filter

LAPLACIAN_DESCRIPTION = ("the mesh's Laplacian: 'cotan' (refuses zero-area triangles), 'robust' (mollified "
                         "intrinsic cotan) or 'auto' (cotan unless the mesh has zero-area triangles); the "
                         "returned 'laplacian' says which ran")


def signed_mean_curvature(V, F, K):
    """``H = 0.5 K . n`` with ``n`` the unit area-weighted vertex normal, shape (n,).

    With consistently oriented triangles whose normals point outwards, ``H > 0`` on a sphere
    (``H = 1/R``), the sign pymeshlab's curvature filter uses."""
    return 0.5 * np.einsum("ij,ij->i", K, vertex_normals(V, F))


@filter(
    name="compute_curvature_detail",
    category="Curvature detail",
    description=f"""
        Compute the curvature detail representation of the current mesh: per vertex the mean
        curvature normal K = (L V)_i / A_i (custom point attribute 'curvature_normal', intensive,
        K = 2 H n, |K| = 2/R on a sphere), the curvature detail D = L V = K A (point attribute
        'curvature_detail', extensive; what the reconstruction filters rebuild from) and the mixed
        Voronoi area A (Meyer et al. 2002; scalar attribute 'curvature_area'). L is the cotangent
        Laplacian. The vertex quality is set to the signed mean curvature H = K.n / 2 (n: the
        area-weighted vertex normal; H > 0 on a sphere with outward normals) so that MeshLab can
        colour it. Returns the range and the 10/90 percentiles of H over the interior vertices,
        like pymeshlab's compute_scalar_by_discrete_curvature_per_vertex (boundary vertices carry
        the boundary's geodesic curvature in K and are left out of the figures, which are None
        where every vertex lies on the boundary). H's sign needs
        consistently oriented triangles: others are refused (meshing_re_orient_faces_coherently
        orients them). Zero-area triangles (scans) take the mollified Laplacian (laplacian 'auto' or
        'robust'; A is then its lumped mass); the returned 'laplacian' says which ran. {PAPER},
        section "Curvature detail representation".
    """,
    parameters=[Parameter("laplacian", "str", "auto", LAPLACIAN_DESCRIPTION, choices=LAPLACIANS)],
)
def compute_curvature_detail(ms, *, laplacian):
    mid = layer_id(ms)
    V, F, L, info = checked_laplacian(*mesh_arrays(ms, mid), laplacian)
    D = laplacian_product(L, V)         # = curvature_detail(V, F) bit for bit with the plain L
    # H's sign comes from the vertex normals: with reversed triangles it was +-H at random
    check_oriented(F, "the current mesh")
    A = mixed_voronoi_area(V, F) if info["laplacian"] == "cotan" else robust_laplacian(V, F)[1].diagonal()
    K = D / A[:, None]                  # = mean_curvature_normal(V, F)[0], bit for bit; L built once
    H = signed_mean_curvature(V, F, K)
    store_detail(ms, mid, F, D, K, A)
    set_vertex_quality(ms, mid, H)
    boundary = boundary_vertices(F)
    interior = np.ones(V.shape[0], dtype=bool)
    interior[boundary] = False
    h = H[interior]
    # no interior vertex (a strip): no figures of H, rather than the boundary's geodesic curvature
    low, high, p10, p90 = ([float(x) for x in (h.min(), h.max(), *np.percentile(h, [10, 90]))]
                           if h.size else [None] * 4)
    return {
        "curv_range_min": low,
        "curv_range_max": high,
        "10_percentile": p10,
        "90_percentile": p90,
        "surface_area": float(A.sum()),
        "interior_vertices": int(interior.sum()),
        "boundary_vertices": int(boundary.size),
        **info,
    }
