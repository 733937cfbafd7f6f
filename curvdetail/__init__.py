"""curvdetail: curvature detail representation of triangle meshes.

Store the detail of a surface as mean-curvature normals, rebuild it from them, edit it, and
carry it across a retriangulation (Zhejiang Univ. Sci. A 7(7):1210, 2006).
"""

from .curvature import (ConstraintError, CurvatureEditor, MeshError, Reconstructor, SolverError, anchor_vertices,
                        available_backends, boundary_edges, boundary_vertices, check_mesh, cotan_laplacian,
                        curvature_coefficients, curvature_detail, edit_boundary, mean_curvature_normal,
                        minimal_surface, mixed_voronoi_area, reconstruct, sine_displacement,
                        RotationAwareEditor)
from .io import read_mesh, write_mesh

__version__ = "0.1.0"

__all__ = [
    "ConstraintError", "CurvatureEditor", "MeshError", "Reconstructor", "SolverError", "anchor_vertices",
    "available_backends",
    "boundary_edges", "boundary_vertices", "check_mesh", "cotan_laplacian", "curvature_coefficients",
    "curvature_detail", "edit_boundary", "mean_curvature_normal", "minimal_surface", "mixed_voronoi_area",
    "read_mesh", "reconstruct", "RotationAwareEditor", "sine_displacement", "write_mesh",
]
