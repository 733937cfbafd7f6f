"""The paper's mathematics: operators, curvature detail, reconstruction, minimal surfaces.

numpy/scipy only. Every function takes ``(V, F)`` arrays and validates them at its boundary.
"""

from .anchors import anchor_vertices
from .checks import check_mesh
from .topology import boundary_edges, boundary_vertices
from .boundary_editing import boundary_loop, edit_boundary, sine_displacement
from .cotan_laplacian import cotan_laplacian
from .curvature_coefficients import CoefficientInfo, curvature_coefficients
from .curvature_detail import curvature_detail
from .curvature_editor import CurvatureEditor
from .errors import ConstraintError, MeshError
from .mean_curvature_normal import mean_curvature_normal
from .minimal_surface import minimal_surface
from .mixed_voronoi_area import mixed_voronoi_area
from .reconstruct import Reconstructor, reconstruct
from .rotation_editor import RotationAwareEditor
from .sparse_solver import SolverError, available_backends

__all__ = [
    "CoefficientInfo", "ConstraintError", "CurvatureEditor", "MeshError", "Reconstructor", "RotationAwareEditor",
    "SolverError", "anchor_vertices",
    "available_backends", "boundary_edges", "boundary_loop", "boundary_vertices", "check_mesh",
    "cotan_laplacian", "curvature_coefficients", "curvature_detail", "edit_boundary", "mean_curvature_normal",
    "minimal_surface", "mixed_voronoi_area", "reconstruct", "sine_displacement",
]
