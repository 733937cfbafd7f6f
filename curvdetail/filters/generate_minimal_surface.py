"""Filter ``generate_minimal_surface``: the minimal surface spanned by the current mesh's boundary."""

import numpy as np

from ..curvature import minimal_surface
from ..curvature.minimal_surface import DEFAULT_TOL
from ..curvature.geometry import bbox_diagonal, face_double_areas
from ..curvature.topology import boundary_vertices
from ..curvature.errors import ConstraintError
from .apply_curvature_reconstruction import BACKEND_DESCRIPTION, BACKENDS
from .meshset import add_layer, get_mesh, layer_id, mesh_arrays
from .parameters import Parameter
from .registry import PAPER, filter


@filter(
    name="generate_minimal_surface",
    category="Curvature detail",
    description=f"""
        Generate the minimal surface spanned by the current mesh's boundary: zero curvature
        detail (D = 0) with the boundary vertices fixed, found by cotangent-harmonic steps with the
        weights recomputed from the current surface (Pinkall and Polthier 1993) until no vertex
        moves more than tol times the bounding-box diagonal of its piece normal to the surface in
        a step (vertices keep sliding within the surface on irregular meshes; that is not counted,
        and last_step is this normal step; step=full counts the whole displacement). It is the
        paper's validity check; its first step, the harmonic surface, is the remeshing
        experiment's zero-detail baseline. The result is added as a new
        layer (same triangles) and made current; its vertex quality is the distance each vertex
        moved. {PAPER}, the validity check of section "Base presentation".
    """,
    parameters=[
        Parameter("max_iterations", "int", 200, "Pinkall-Polthier steps at most", min=1),
        Parameter("tol", "float", DEFAULT_TOL,
                  "stop when no vertex moves more than tol x its piece's bbox diagonal in a step, as "
                  "step measures it (by default normal to the surface: tangential sliding is not "
                  "counted)", positive=True),
        Parameter("step", "str", "normal",
                  "what tol is compared with: the step normal to the surface or the full vertex "
                  "displacement, tangential sliding included",
                  choices=("normal", "full")),
        Parameter("backend", "str", "auto", BACKEND_DESCRIPTION, choices=BACKENDS),
    ],
)
def generate_minimal_surface(ms, *, max_iterations, tol, step, backend):
    mid = layer_id(ms)
    V, F = mesh_arrays(ms, mid)
    label = get_mesh(ms, mid).label()
    fixed = boundary_vertices(F)
    if fixed.size == 0:
        raise ConstraintError(f"layer {mid} ({label!r}) is closed: a minimal surface needs a "
                              "boundary to span.", count=0)
    if not tol > 0:
        raise ConstraintError(f"tol={tol} must be positive (a fraction of the bbox diagonal).")
    X = minimal_surface(V, F, fixed, max_iterations=max_iterations, tol=tol, step=step, backend=backend)
    moved = np.linalg.norm(X - V, axis=1)
    add_layer(ms, np.asarray(X), F, f"{label} minimal surface", quality=moved)
    return {
        "iterations": int(X.iterations),
        "converged": bool(X.converged),
        "last_step": float(X.last_step),
        "area_source": float(face_double_areas(V, F).sum() / 2.0),
        "area_minimal": float(face_double_areas(np.asarray(X), F).sum() / 2.0),
        "max_displacement_percent_of_diagonal": float(100 * moved.max() / bbox_diagonal(V)),
    }
