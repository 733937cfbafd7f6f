"""Exceptions raised by the filter suite.

All derive from ``ValueError`` (as the core's ``MeshError`` and ``ConstraintError`` do), so the
CLI turns any of them into one ``curvdetail: error: ...`` line.
"""


class FilterError(ValueError):
    """A filter could not run: bad layer, missing attribute, or pymeshlab refused a step."""


class UnknownFilterError(FilterError):
    """No filter of that name is registered (the message lists the close matches)."""


class FilterParameterError(FilterError):
    """A parameter is unknown, of the wrong type or out of range (the message names it)."""


class ScriptError(FilterError):
    """A MeshLab filter script (.mlx) is malformed or one of its steps failed (names the step)."""
