"""Typed filter parameters, as pymeshlab's: declaration, checking and parsing from text.

A `Parameter` has a ``name``, a ``type`` (one of `TYPES`), a ``default``, a
``description`` and, where they apply, ``choices`` (for ``str``) and ``min`` / ``max`` (for
``int``, ``float`` and ``PercentageValue``; ``positive=True`` asks for a value above 0).

Types, as pymeshlab names them:

``bool``, ``int``, ``float``, ``str``
    plain values; a ``str`` with ``choices`` is an enumeration (pymeshlab's RichEnum). A ``str``
    without choices also takes a list, tuple, range or array of numbers from Python, as the text
    of those numbers; ``shape`` (e.g. ``(4, 4)`` for a matrix) is the one multi-dimensional shape
    such an array may have, where the order of its axes matters. Without a ``shape`` the numbers
    are an index set, whose order does not matter: a single number (one index) and a set
    (sorted) are taken too; a matrix refuses both.
``PercentageValue``
    a length given either as a percentage of the bounding-box diagonal
    (``pymeshlab.PercentageValue(1.0)``, ``"1%"`` on the command line) or as an absolute value
    (``pymeshlab.PureValue(0.01)``, a plain number, ``"0.01"``). The filter receives a
    `BBoxLength` and calls ``.resolve(diagonal)``.
``mesh``
    a layer id of the MeshSet (pymeshlab shows these as ``int``); the default ``None`` means the
    current mesh.
"""

import math
import numbers
from dataclasses import dataclass

import numpy as np

from ..curvature.checks import as_float
from ..remesh.units import BBoxLength
from .errors import FilterParameterError

#: Largest magnitude of an int parameter or layer id (pymeshlab passes them as C++ ints).
INT_MAX = 2 ** 31 - 1


#: The parameter types a filter may declare.
TYPES = ("bool", "int", "float", "str", "PercentageValue", "mesh")


def _numbers_as_text(value):
    """A list, tuple or array of real numbers (``handles=[1, 2, 3]``, ``transform=np.eye(4)``)
    as the space-separated text the str parameters take (row by row, every digit kept); an
    empty one as the empty text; anything else unchanged."""
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = _object_array(value)
        if arr is None:
            return value
        if arr.size == 0:               # no numbers: the filter names an empty value as such
            return ""
        arr = arr.ravel()
        if all(isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)) for x in arr.tolist()):
            # numbers as Python writes them: numpy 2's repr of np.float64(1.0) is "np.float64(1.0)"
            return " ".join(str(int(x)) if isinstance(x, numbers.Integral) else repr(float(x))
                            for x in arr.tolist())
    return value


def _object_array(value):
    """``value`` as an object array with its nesting as shape, or None where numpy cannot make
    one (lists of arrays of different shapes)."""
    try:
        return np.asarray(value, dtype=object)
    except ValueError:
        return None


@dataclass(frozen=True)
class Parameter:
    """One typed filter parameter (see the module docstring for the types).

    Examples
    --------
    >>> p = Parameter("rows", "str", "all", "residual rows in E_Q", choices=("all", "free"))
    >>> p.check("free")
    'free'
    >>> Parameter("scale", "str", "", "2x2 matrix", shape=(2, 2)).check(np.eye(2))
    '1.0 0.0 0.0 1.0'
    """

    name: str
    type: str
    default: object
    description: str
    choices: tuple = None
    min: float = None
    max: float = None
    positive: bool = False
    #: a ``str`` of numbers only: the shape an array from Python must have where it has more than
    #: one axis, e.g. (4, 4) for a matrix read row by row (a flat sequence is counted by the
    #: filter); None flattens any array (an index set, where the order does not matter: a
    #: single number and a set are taken too)
    shape: tuple = None
    #: a function of the converted value that raises FilterParameterError where the filter would
    #: refuse the value whatever the mesh (a transform of 15 numbers), so that apply, a script's
    #: check and the command line refuse it before any work; its return value is ignored
    validate: object = None
    #: the filter cannot run without it (its default, e.g. no handles, is refused): a call, a
    #: script or a saved script that leaves it out is refused before any step runs
    required: bool = False

    def __post_init__(self):
        if self.type not in TYPES:
            raise TypeError(f"parameter {self.name!r}: type {self.type!r} is not one of {TYPES}.")
        if not self.description or not self.description.strip():
            raise TypeError(f"parameter {self.name!r} needs a description.")
        if self.choices is not None:
            object.__setattr__(self, "choices", tuple(self.choices))
        if self.shape is not None:
            if self.type != "str" or self.choices is not None:
                raise TypeError(f"parameter {self.name!r}: a shape applies to a str of numbers only.")
            object.__setattr__(self, "shape", tuple(int(k) for k in self.shape))
        if self.default is not None or self.type != "mesh":
            object.__setattr__(self, "default", self.check(self.default))

    def to_dict(self):
        """The parameter as JSON-ready values: ``name``, ``type``, ``default`` (a percentage as
        text, e.g. ``"1.0%"``), ``description``, and ``choices`` / ``min`` / ``max`` /
        ``positive`` / ``required`` where set."""
        out = {"name": self.name, "type": self.type,
               "default": str(self.default) if isinstance(self.default, BBoxLength) else self.default,
               "description": " ".join(self.description.split())}
        if self.choices is not None:
            out["choices"] = list(self.choices)
        for key in ("min", "max"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        if self.positive:
            out["positive"] = True
        if self.required:
            out["required"] = True
        return out

    # -- checking Python values -----------------------------------------------------------------

    def _fail(self, value, expected):
        return FilterParameterError(
            f"parameter {self.name!r} expects {expected}; got {value!r} ({type(value).__name__}).", parameter=self.name
        )

    def check(self, value):
        """Return ``value`` converted to this parameter's type, or raise FilterParameterError
        naming the parameter and the expected type (and the choices or range)."""
        value = self._convert(value)
        if self.validate is not None and value is not None:
            self.validate(value)
        return value

    def _convert(self, value):
        t = self.type
        if isinstance(value, np.ndarray) and value.ndim == 0 and \
                (t != "str" or (self.choices is not None and value.dtype.kind in "iu")):
            # a 0-d array as its numpy scalar, as pymeshlab takes it (an enum's index too; a text
            # parameter's array is read as its numbers below)
            value = value[()]
        if t == "bool":
            if isinstance(value, (bool, np.bool_)):
                return bool(value)
            raise self._fail(value, "a bool (True or False)")
        if t in ("int", "mesh"):
            if value is None and t == "mesh":
                return None
            if isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_)):
                if t == "mesh" and value < 0:
                    raise FilterParameterError(f"parameter {self.name!r} is {value}; a layer id is "
                                               "0 or more.", parameter=self.name)
                if abs(value) > INT_MAX:              # pymeshlab's C++ ints
                    raise FilterParameterError(f"parameter {self.name!r} is {value}; it must lie within "
                                               f"+-{INT_MAX}.", parameter=self.name)
                return self._range(int(value))
            raise self._fail(value, "an int" if t == "int" else "a layer id (int) of the MeshSet")
        if t == "float":
            if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
                return self._range(self._finite(as_float(value)))
            raise self._fail(value, "a float")
        if t == "str":
            if self.choices is not None and isinstance(value, numbers.Integral) \
                    and not isinstance(value, (bool, np.bool_)) and 0 <= value < len(self.choices):
                return self.choices[int(value)]           # an enum index, as pymeshlab takes it
            if self.choices is not None and isinstance(value, numbers.Integral) \
                    and not isinstance(value, (bool, np.bool_)):
                raise FilterParameterError(
                    f"parameter {self.name!r} is {value!r}; it must be one of {', '.join(self.choices)}, "
                    f"or its index, 0 to {len(self.choices) - 1}.", parameter=self.name)
            if self.choices is None:
                value = _numbers_as_text(self._check_numbers(self._as_sequence(value)))
            if not isinstance(value, str):
                raise self._fail(value, f"a str (one of {', '.join(self.choices)}, or its index)"
                                 if self.choices else "a str (from Python also a list or array of numbers)")
            if self.choices is not None:
                for c in self.choices:
                    if value.lower() == c.lower():
                        return c
                raise FilterParameterError(
                    f"parameter {self.name!r} is {value!r}; it must be one of {', '.join(self.choices)} "
                    f"(or its index, 0 to {len(self.choices) - 1}).", parameter=self.name
                )
            return value
        # PercentageValue
        if isinstance(value, BBoxLength):
            length = value
        elif type(value).__name__ == "PercentageValue":
            length = BBoxLength(float(value.value()), True)
        elif type(value).__name__ == "PureValue":
            length = BBoxLength(float(value.value()), False)
        elif isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
            length = BBoxLength(as_float(value), False)
        else:
            raise self._fail(value, "a PercentageValue: pymeshlab.PercentageValue(percent of the "
                             "bbox diagonal), pymeshlab.PureValue(absolute) or a number (absolute)")
        self._finite(length.value)
        self._range(length.value)
        return length

    def _as_sequence(self, value):
        """``value`` as a list where a ``str`` of numbers takes it as a sequence: a range; without
        a ``shape`` (an index set, whose order does not matter) also a single number, as one
        index, and a set, sorted. A matrix (``shape``) refuses a single number and a set (whose
        numbers have no order to read row by row) with the fix; anything else unchanged."""
        if isinstance(value, range):
            return list(value)
        single = isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))
        if not (single or isinstance(value, (set, frozenset))):
            return value
        if self.shape is not None:
            dims, count = "x".join(map(str, self.shape)), math.prod(self.shape)
            what = (f"a single number ({value!r})" if single else
                    f"a {type(value).__name__} of {len(value)} values, which has no order")
            raise FilterParameterError(
                f"parameter {self.name!r} is {what}; it must be a {dims} matrix: a {self.shape} array, or "
                f"its {count} numbers row by row as a list or as text.", parameter=self.name)
        if single:
            return [value]
        try:
            return sorted(value)
        except TypeError:                   # values that do not compare: refused as no numbers
            return value

    def _check_numbers(self, value):
        """``value`` unchanged, or FilterParameterError where a list, tuple or array would be read
        wrongly as numbers: a boolean mask (True/False are no indices), masked entries, or an
        array of another shape than ``shape`` (a 2x8 array was read as a 4x4 matrix)."""
        if not isinstance(value, (list, tuple, np.ndarray)):
            return value
        arr = _object_array(value)
        if arr is None or arr.size == 0:
            return value
        items = arr.ravel().tolist()
        if all(isinstance(x, (bool, np.bool_)) for x in items):
            fix = (f"pass a {self.shape} array of numbers" if self.shape is not None else
                   "pass the indices where the mask is true, np.flatnonzero(mask)")
            raise FilterParameterError(f"parameter {self.name!r} is a boolean mask ({arr.size} True/False "
                                       f"values); it takes numbers, not a mask: {fix}.", parameter=self.name)
        flags = [isinstance(x, (bool, np.bool_)) for x in items]
        if any(flags):                  # True/False among numbers: read as 1/0 otherwise
            raise FilterParameterError(
                f"parameter {self.name!r} has True/False among its numbers (first at position "
                f"{flags.index(True)}); pass numbers only (or, for indices, np.flatnonzero(mask) of a mask).",
                parameter=self.name)
        if np.ma.isMaskedArray(value) and np.ma.getmaskarray(value).any():
            raise FilterParameterError(
                f"parameter {self.name!r} has {int(np.ma.getmaskarray(value).sum())} masked entries, which "
                "would be read as numbers; pass the entries you mean, e.g. value.compressed().", parameter=self.name)
        if self.shape is not None and arr.ndim > 1 and arr.shape != self.shape and \
                all(isinstance(x, numbers.Real) for x in items):
            dims = "x".join(map(str, self.shape))
            raise FilterParameterError(
                f"parameter {self.name!r} is a {'x'.join(map(str, arr.shape))} array; it must be a {dims} "
                f"matrix: a {self.shape} array, or its {math.prod(self.shape)} numbers row by row as a "
                "flat list or as text.", parameter=self.name)
        return value

    def _finite(self, x):
        if not math.isfinite(x):
            raise FilterParameterError(f"parameter {self.name!r} is {x}; it must be a finite number.",
                                       parameter=self.name)
        return x

    def _range(self, x):
        if self.positive and not x > 0:
            raise FilterParameterError(f"parameter {self.name!r} is {x}; it must be greater than 0.",
                                       parameter=self.name)
        if self.min is not None and x < self.min:
            raise FilterParameterError(f"parameter {self.name!r} is {x}; it must be at least {self.min}.",
                                       parameter=self.name)
        if self.max is not None and x > self.max:
            raise FilterParameterError(f"parameter {self.name!r} is {x}; it must be at most {self.max}.",
                                       parameter=self.name)
        return x

    # -- parsing text (command line, .mlx) ------------------------------------------------------

    def parse(self, text):
        """Convert ``text`` (from the command line or an .mlx ``value``) and check it.

        ``bool``: true/false/1/0/yes/no; ``PercentageValue``: ``"1.5%"`` (percent of the bbox
        diagonal) or ``"0.01"`` (absolute); ``mesh``: a layer id, or ``""`` / ``"current"`` for
        the current mesh (how `format` writes None); ``str`` with choices: the choice,
        case-insensitive, or its 0-based index (how MeshLab writes a RichEnum).
        """
        s = str(text).strip()
        t = self.type
        try:
            if t == "bool":
                low = s.lower()
                if low in ("true", "1", "yes", "on"):
                    return True
                if low in ("false", "0", "no", "off"):
                    return False
                raise ValueError
            if t == "mesh" and s.lower() in ("", "current"):
                return self.check(None)
            if t in ("int", "mesh"):
                return self.check(int(s))
            if t == "float":
                return self.check(float(s))
            if t == "str":
                if self.choices is not None and s.isdecimal() and s.isascii() and s not in self.choices \
                        and int(s) < len(self.choices):
                    return self.choices[int(s)]
                return self.check(s)
            if s.endswith("%"):
                return self.check(BBoxLength(float(s[:-1]), True))
            return self.check(BBoxLength(float(s), False))
        except FilterParameterError:
            raise
        except ValueError:
            expected = {"bool": "true or false", "int": "an integer", "mesh": "a layer id (integer)",
                        "float": "a number", "str": "text",
                        "PercentageValue": "a number (absolute) or a percentage of the bbox "
                                           "diagonal such as 1%"}[t]
            raise FilterParameterError(f"parameter {self.name!r} expects {expected}; got {s!r}.",
                                       parameter=self.name) from None

    def format(self, value):
        """``value`` as text that `parse` reads back exactly."""
        if value is None:
            return ""
        if self.type == "bool":
            return "true" if value else "false"
        if self.type == "float":
            return repr(float(value))
        return str(value)

    @property
    def type_label(self):
        """The type as pymeshlab prints it (a layer id is an ``int``)."""
        return "int" if self.type == "mesh" else self.type

    def default_label(self):
        """The default as pymeshlab prints it (``'all'``, ``1%``, ``True``, ``current``)."""
        if self.type == "mesh" and self.default is None:
            return "current mesh"
        if self.type == "str":
            return repr(self.default)
        if self.type == "PercentageValue":
            return f"{self.default.value:g}{'%' if self.default.percent else ''}"
        return str(self.default)
