"""curvdetail: curvature detail representation of triangle meshes.

Store the detail of a surface as mean-curvature normals, rebuild it from them, edit it, and
carry it across a retriangulation (Zhejiang Univ. Sci. A 7(7):1210, 2006).
"""

from .curvature import (ConstraintError, MeshError, Reconstructor, SolverError, available_backends,
                        boundary_edges, boundary_vertices, check_mesh, cotan_laplacian,
                        curvature_detail, mean_curvature_normal, minimal_surface,
                        mixed_voronoi_area, reconstruct)
from .curvature import CurvatureEditor, curvature_coefficients, edit_boundary, sine_displacement
from .io import read_mesh, write_mesh

__version__ = "0.1.0"

__all__ = [
    "ConstraintError", "MeshError", "Reconstructor", "SolverError", "available_backends",
    "boundary_edges", "boundary_vertices", "check_mesh", "cotan_laplacian", "curvature_detail",
    "mean_curvature_normal", "minimal_surface", "mixed_voronoi_area", "read_mesh", "reconstruct",
    "write_mesh",
    # editing issue
    "CurvatureEditor", "curvature_coefficients", "edit_boundary", "sine_displacement",
]
