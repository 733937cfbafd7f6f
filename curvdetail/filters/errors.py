"""Exceptions raised by the filter suite.

All derive from `curvdetail.curvature.errors.CurvdetailError` (a ``ValueError``), so they
carry ``parameter``, ``value`` and ``hint`` as fields: a front end (the CLI) names the
parameter in its own terms.
"""

from ..curvature.errors import CurvdetailError


class FilterError(CurvdetailError):
    """A filter could not run: bad layer, missing attribute, or pymeshlab refused a step."""


class UnknownFilterError(FilterError):
    """No filter of that name is registered (the message lists the close matches)."""


class FilterParameterError(FilterError):
    """A parameter is unknown, of the wrong type or out of range (``e.parameter`` names it)."""


class ScriptError(FilterError):
    """A MeshLab filter script (.mlx) is malformed or one of its steps failed (names the step)."""


class ScaleWarning(UserWarning):
    """Said by `run_script` (``curvdetail run`` says it as a note) when a
    script gives a length in model units far from the mesh's size: likely sized for another mesh
    (the message names the ratio to the bbox diagonal). Write such lengths as percentages."""
