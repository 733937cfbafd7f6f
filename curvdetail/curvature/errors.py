"""Exceptions raised for malformed input, and the warning of a result that folded.

Every exception class derives from ``ValueError`` so that ``except ValueError`` keeps working for
callers who do not care about the details; the message always says what is wrong, how much,
where (the first offending indices) and what to do about it.
"""


class CurvdetailError(ValueError):
    """Base of the package's input errors: the message, and the facts as fields.

    ``parameter`` (the argument at fault, by its Python name), ``value`` (what was given),
    ``hint`` (what to do, in neutral words; appended to the message), ``count`` and ``first``
    (how many things are wrong and the first indices). A front end (the CLI, the filters) reads
    the fields and says it in its own terms; ``problem`` is the message without the hint.
    """

    def __init__(self, problem="", *, parameter=None, value=None, hint=None, count=None, first=None):
        super().__init__(f"{problem}; {hint}" if hint else problem)
        self.problem, self.parameter, self.value, self.hint = problem, parameter, value, hint
        self.count, self.first = count, first


class MeshError(CurvdetailError):
    """A mesh ``(V, F)`` is malformed: shapes, dtypes, non-finite values, bad indices,
    degenerate or non-manifold elements, unreferenced vertices, wrong topology."""


class ConstraintError(CurvdetailError):
    """A set of constrained (fixed) vertices or their values is malformed or insufficient."""


class UndeterminedEditError(ConstraintError):
    """The constraints of an edit leave part of it undetermined: a connected free region that no
    constraint reaches, or a curvature stage singular to working precision (see
    ``CurvatureEditor.rest_error``). ``problem`` is what was found and ``advice`` what to change
    in the editor's terms; callers with their own way of giving constraints (a selection file, a
    filter's parameters) raise it again with their own advice."""

    def __init__(self, problem, advice):
        super().__init__(f"{problem} {advice}")
        self.problem, self.advice = problem, advice


class FoldedTrianglesWarning(UserWarning):
    """Said when triangles of an edit's result fold over (their normals point against the rest
    shape's), e.g. by :func:`edit_boundary`: the edit ran, but the surface is not usable as it
    is. The message gives the count, the first folded triangles, how far the vertices moved and
    what to try; the same figures are in the function's ``info``. Turn it into an error with
    ``warnings.simplefilter("error", FoldedTrianglesWarning)``."""


def warn(message, category):
    """``warnings.warn`` naming the first caller outside curvdetail: the warning points at the
    user's line (and is shown once per such line, not once per process)."""
    import sys
    import warnings

    frame, level = sys._getframe(1), 2
    while frame is not None and frame.f_globals.get("__name__", "").startswith("curvdetail"):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)


def first_indices(indices, count=3):
    """Format the first few offending indices for an error message: ``'17, 402, 9311'``."""
    indices = [int(i) for i in list(indices)[:count]]
    return ", ".join(str(i) for i in indices)


#: The singular of the verbs the messages put after a count (the rest take an "s").
_SINGULAR_VERBS = {"are": "is", "have": "has", "were": "was", "reach": "reaches", "pass": "passes"}


def counted(count, noun, plural=None, verb=None):
    """A count with its noun (and the verb after it) in the right number, for a message:
    ``counted(1, "edge", verb="are")`` is ``'1 edge is'``, ``counted(3, "vertex", "vertices")``
    ``'3 vertices'``. ``plural`` defaults to ``noun + "s"``; ``verb`` is given in the plural
    (``"are"``, ``"have"``, ``"lie"``, ...).

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
