"""Lengths as the whole package takes them: a plain number is in model units, a percentage is of
the bounding-box diagonal (``"1%"``, ``"0.5 %"``, ``pymeshlab.PercentageValue(1)``).

The remeshing functions, the filters' length parameters, the command line's ``--target-edge``
and the ``.mlx`` scripts all read lengths through `as_bbox_length`; reports store both
forms with the unit in the key (``target_edge_model_units``, ``target_edge_percent_of_diagonal``).
"""

import math
import re
from dataclasses import dataclass

from ..curvature.checks import as_float
from ..curvature.errors import CurvdetailError

_PERCENT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*%\s*")


@dataclass(frozen=True)
class BBoxLength:
    """A length given as a percentage of a bounding-box diagonal (``percent=True``) or in model
    units.

    Examples
    --------
    >>> BBoxLength(2.0, True).resolve(15.0), BBoxLength(0.3, False).resolve(15.0)
    (0.3, 0.3)
    """

    value: float
    percent: bool

    def resolve(self, diagonal):
        """The length in model units for a mesh whose bounding-box diagonal is ``diagonal``."""
        return self.value / 100.0 * float(diagonal) if self.percent else self.value

    def fraction(self, diagonal):
        """The length as a fraction of ``diagonal`` (a percentage's own ``value / 100``, exactly)."""
        return self.value / 100.0 if self.percent else self.value / float(diagonal)

    def __str__(self):
        return f"{self.value!r}%" if self.percent else repr(self.value)


def as_bbox_length(value, name="length"):
    """``value`` as a `BBoxLength`: a real number is model units; ``"1%"``, ``"0.5 %"``,
    ``pymeshlab.PercentageValue(1)`` a percentage of the bbox diagonal; ``pymeshlab.PureValue``
    model units. Refuses anything else, and a length that is not positive and finite, with a
    CurvdetailError whose ``parameter`` is ``name``."""
    length = None
    if isinstance(value, BBoxLength):
        length = value
    elif type(value).__name__ in ("PercentageValue", "PureValue"):        # pymeshlab's, duck-typed
        length = BBoxLength(float(value.value()), type(value).__name__ == "PercentageValue")
    elif isinstance(value, str):
        match = _PERCENT.fullmatch(value)
        if match:
            length = BBoxLength(float(match.group(1)), True)
    elif as_float(value) is not None:
        length = BBoxLength(as_float(value), False)
    if length is None:
        raise CurvdetailError(f"{name}={value!r} is not a length", parameter=name, value=value,
                              hint='give a number in model units, or a percentage of the bbox diagonal '
                                   'such as "1%" or pymeshlab.PercentageValue(1)')
    if not (math.isfinite(length.value) and length.value > 0):
        raise CurvdetailError(f"{name}={value!r} is not a positive length", parameter=name, value=value,
                              hint='give a positive number in model units, or a percentage such as "1%"')
    return length


def as_length(value, diagonal, name="length"):
    """A length in model units from a number (model units) or a percentage of ``diagonal``.

    Parameters
    ----------
    value : float, str or pymeshlab.PercentageValue / PureValue
        ``0.3`` is 0.3 model units; ``"1%"``, ``"0.5 %"`` or ``PercentageValue(1)`` a
        percentage of the bounding-box diagonal.
    diagonal : float
        The mesh's bounding-box diagonal, in model units.
    name : str
        The parameter's name, for the error.

    Returns
    -------
    float   the length in model units

    Raises
    ------
    CurvdetailError
        Not a number or a percentage, or not positive and finite (``parameter`` is ``name``)

    Examples
    --------
    >>> as_length("2%", 15.0), as_length(0.3, 15.0)
    (0.3, 0.3)
    """
    return as_bbox_length(value, name).resolve(diagonal)


def length_figures(length, diagonal, name):
    """``{name_model_units, name_percent_of_diagonal}`` of a `BBoxLength`, for a report."""
    return {f"{name}_model_units": float(length.resolve(diagonal)),
            f"{name}_percent_of_diagonal": float(100.0 * length.fraction(diagonal))}

