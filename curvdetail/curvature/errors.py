"""Exceptions for malformed input (all ``ValueError`` subclasses) and the folded-result warning."""

import sys
import warnings


class CurvdetailError(ValueError):
    """Base of the package's input errors: the message and the facts as fields.

    ``parameter`` (the argument at fault), ``value`` (what was given), ``hint`` (what to do;
    appended to the message), ``count`` and ``first`` (how many things are wrong, the first
    indices); ``problem`` is the message without the hint.
    """

    def __init__(self, problem="", *, parameter=None, value=None, hint=None, count=None, first=None):
        super().__init__(f"{problem}; {hint}" if hint else problem)
        self.problem, self.parameter, self.value, self.hint = problem, parameter, value, hint
        self.count, self.first = count, first


class MeshError(CurvdetailError):
    """A mesh ``(V, F)`` is malformed (shapes, values, indices, degenerate elements, topology)."""


class ConstraintError(CurvdetailError):
    """A set of constrained (fixed) vertices or their values is malformed or insufficient."""


class UndeterminedEditError(ConstraintError):
    """An edit's constraints leave part of it undetermined; ``problem`` is what was found and
    ``advice`` what to change in the editor's terms (front ends give their own)."""

    def __init__(self, problem, advice, **fields):
        super().__init__(f"{problem} {advice}", **fields)
        self.problem, self.advice = problem, advice


class FoldedTrianglesWarning(UserWarning):
    """Triangles of an edit's result folded over (normals against the rest shape's): the edit ran,
    but the surface is not usable as it is."""


def warn(message, category):
    """``warnings.warn`` pointing at the first caller outside curvdetail (the user's line)."""
    frame, level = sys._getframe(1), 2
    while frame is not None and frame.f_globals.get("__name__", "").startswith("curvdetail"):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)


def first_indices(indices, count=3):
    """The first few offending indices for a message: ``'17, 402, 9311'``."""
    return ", ".join(str(int(i)) for i in list(indices)[:count])


#: The singular of the verbs the messages put after a count (the rest take an "s").
_SINGULAR_VERBS = {"are": "is", "have": "has", "were": "was", "reach": "reaches", "pass": "passes"}


def counted(count, noun, plural=None, verb=None):
    """A count with its noun (and verb, given in the plural) in the right number; ``plural``
    defaults to ``noun + "s"``.

    Examples
    --------
    >>> counted(1, "triangle", verb="have"), counted(2, "triangle", verb="have")
    ('1 triangle has', '2 triangles have')
    >>> counted(1, "vertex", "vertices", verb="lie")
    '1 vertex lies'
    """
    one = int(count) == 1
    text = f"{count} {noun if one else (plural or noun + 's')}"
    if verb is not None:
        text += " " + (_SINGULAR_VERBS.get(verb, verb + "s") if one else verb)
    return text


def them(count):
    """The pronoun for ``count`` things in a message: ``'it'`` for one, else ``'them'``."""
    return "it" if int(count) == 1 else "them"
