"""Filter ``apply_curvature_reconstruction``: rebuild a mesh from its stored curvature detail."""

import numpy as np

from ..curvature import anchor_vertices, reconstruct
from ..curvature.robust_laplacian import LAPLACIANS, choose_laplacian, flip_caps
from ..curvature.geometry import bbox_diagonal
from ..curvature.topology import boundary_vertices
from ..curvature.sparse_solver import AUTO_RULE, BACKENDS as _SOLVERS
from .compute_curvature_detail import LAPLACIAN_DESCRIPTION
from .detail_attributes import load_detail
from .meshset import layer_id, mesh_arrays, selected_vertices, set_vertex_positions, set_vertex_quality
from .parameters import Parameter
from .registry import PAPER, filter

BACKENDS = ("auto",) + _SOLVERS
BACKEND_DESCRIPTION = "sparse solver backend; " + AUTO_RULE


@filter(
    name="apply_curvature_reconstruction",
    category="Curvature detail",
    description=f"""
        Rebuild the current mesh's vertex positions from its 'curvature_detail' attribute (the
        paper's embedding, energy E_Q = sum_i |(L X)_i - D_i|^2, L the cotangent Laplacian of the
        current geometry), keeping the boundary vertices and the selected vertices fixed. The
        attribute comes from compute_curvature_detail (then the mesh is reproduced to solver
        precision) or from transfer_curvature_detail (a retriangulation rebuilt from another
        mesh's curvature). Vertices move in place; the vertex quality is set to the distance each
        vertex moved. A connected piece with no fixed vertex (a closed surface, or every piece when
        nothing is fixed) gets one anchor, its flattest vertex (curvdetail.anchor_vertices). Zero-area
        triangles (scans) take the mollified Laplacian (laplacian 'auto' or 'robust'); the returned
        'laplacian' says which ran. {PAPER}, sections "Base presentation" (E_Q) and "Embedding".
    """,
    parameters=[
        Parameter("rows", "str", "all",
                  "residual rows in E_Q: 'all' vertices (the paper; least squares) or 'free' "
                  "vertices only (the square system L_ff X_f = D_f - L_fc X_c)",
                  choices=("all", "free")),
        Parameter("fix_boundary", "bool", True, "keep the boundary vertices where they are"),
        Parameter("fix_selected", "bool", True, "keep the selected vertices where they are"),
        Parameter("backend", "str", "auto", BACKEND_DESCRIPTION, choices=BACKENDS),
        Parameter("laplacian", "str", "auto", LAPLACIAN_DESCRIPTION, choices=LAPLACIANS),
    ],
)
def apply_curvature_reconstruction(ms, *, rows, fix_boundary, fix_selected, backend, laplacian):
    mid = layer_id(ms)
    V, F = mesh_arrays(ms, mid)
    D = load_detail(ms, mid, F)
    parts = []
    if fix_boundary:
        parts.append(boundary_vertices(F))
    if fix_selected:
        parts.append(selected_vertices(ms, mid))
    given = np.unique(np.concatenate(parts)) if parts else np.zeros(0, dtype=np.int64)
    # anchors are placed on the same surface with its zero-area caps flipped away, where areas are defined
    located = F if choose_laplacian(V, F, laplacian)["laplacian"] == "cotan" else flip_caps(V, F)
    fixed = anchor_vertices(V, located, detail=D, fixed=given)
    X, info = reconstruct(V, F, D, fixed, V[fixed], rows=rows, backend=backend, laplacian=laplacian,
                          return_info=True)
    moved = np.linalg.norm(X - V, axis=1)
    set_vertex_positions(ms, mid, X)
    set_vertex_quality(ms, mid, moved)
    diag = bbox_diagonal(V)
    return {
        "max_displacement_percent_of_diagonal": float(100 * moved.max() / diag),
        "rms_displacement_percent_of_diagonal": float(100 * np.sqrt(np.mean(moved ** 2)) / diag),
        "fixed_vertices": int(fixed.size),
        "anchors": int(fixed.size - given.size),
        "free_vertices": int(V.shape[0] - fixed.size),
        "rows": rows,
        **info,
    }
