"""A MeshLab-style filter suite on ``pymeshlab.MeshSet``: registry, typed parameters, .mlx scripts.

pymeshlab cannot register filters written in Python, so the package keeps its own registry and
runs its filters on a MeshSet the way pymeshlab runs its own::

    import pymeshlab
    from curvdetail import filters

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh("nose.obj")
    filters.apply(ms, "compute_curvature_detail")          # attributes + quality on layer 0
    filters.apply(ms, "apply_curvature_reconstruction", rows="free")
    filters.run_script(ms, "pipeline.mlx")                   # mixes pymeshlab's filters and ours
    filters.apply_native(ms, "meshing_isotropic_explicit_remeshing", targetlen=pymeshlab.PercentageValue(1))
    filters.save_script(ms, "recorded.mlx")                  # every step above, for `curvdetail run`

Every filter lives in its own module named as the filter and is declared with
`filter`; importing this package registers them all.
"""

import importlib

from .dispatch import apply
from .errors import FilterError, FilterParameterError, ScaleWarning, ScriptError, UnknownFilterError
from .mlx import run_script, save_script
from .parameters import BBoxLength, Parameter
from .recording import apply_native
from .registry import (FilterSpec, filter, get_filter, list_filters, print_filter_list,
                       print_filter_parameter_list)

#: Modules that declare filters, imported for their registration.
FILTER_MODULES = (
    "compute_curvature_detail",
    "apply_curvature_reconstruction",
    "generate_minimal_surface",
    "transfer_curvature_detail",
    "generate_curvature_remeshing",
    "get_curvature_reconstruction_error",
    "editing",
)

for _module in FILTER_MODULES:
    importlib.import_module(f"{__name__}.{_module}")
del _module

__all__ = [
    "BBoxLength", "FilterError", "FilterParameterError", "FilterSpec", "Parameter", "ScaleWarning", "ScriptError",
    "UnknownFilterError", "apply", "apply_native", "filter", "get_filter", "list_filters", "print_filter_list",
    "print_filter_parameter_list", "run_script", "save_script",
]
