"""The remeshing experiment of the paper's Fig. 3: retriangulate a surface (closed, holes, pieces), carry its
curvature detail to the new triangulation, rebuild it from that detail, and measure.

Depends on `curvdetail.curvature` (operators and solvers), pymeshlab (isotropic remeshing,
Hausdorff distance), libigl (closest points) and fast-simplification (decimation).
"""

from ._disk import (RETRIANGULATION_TOLERANCE, SURFACE_TOLERANCE, NotADiskError, RemeshError, check_disk,
                    check_retriangulation, check_surface, check_target_boundary)
from .closest_point import closest_points
from .evaluate import hausdorff, vertex_distance
from .experiment import WorseThanZeroDetailWarning, remesh_experiment
from .locate import interpolate, locate, spread
from .metric import source_metric
from .parameterize import flipped_triangles, harmonic_map, parameterize
from .retriangulate import LongRunWarning, retriangulate
from .transfer import edge_curvature_measure, transfer_curvature

__all__ = [
    "LongRunWarning", "NotADiskError", "RemeshError", "WorseThanZeroDetailWarning", "check_disk", "check_surface",
    "RETRIANGULATION_TOLERANCE", "SURFACE_TOLERANCE", "check_retriangulation", "check_target_boundary", "closest_points",
    "edge_curvature_measure", "flipped_triangles", "harmonic_map", "hausdorff", "interpolate", "locate",
    "parameterize", "remesh_experiment", "retriangulate", "source_metric", "spread", "transfer_curvature",
    "vertex_distance",
]
