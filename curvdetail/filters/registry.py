"""The filter registry: every filter is declared once, next to its code, with `filter`.

A filter is a function ``f(ms, *, p1, p2, ...) -> dict`` that reads a ``pymeshlab.MeshSet``,
calls the package's numeric code and writes custom attributes, vertex quality or a new layer.
Its declaration gives everything a user needs to call it without reading the code::

    from .parameters import Parameter
    from .registry import filter

    @filter(name="apply_curvature_reconstruction",
            category="Curvature detail",
            description="Rebuild the current mesh from ... (Zhejiang Univ. Sci. A 2006, Sec. 3).",
            parameters=[Parameter("rows", "str", "all", "residual rows in E_Q",
                                  choices=("all", "free"))])
    def apply_curvature_reconstruction(ms, *, rows):
        ...
        return {"max_displacement": ...}

and the module is imported by ``curvdetail/filters/__init__.py`` so that registration happens.
Users call it through `curvdetail.filters.apply`, which checks and completes the
parameters first.
"""

import difflib
import inspect
from dataclasses import dataclass

from .errors import UnknownFilterError

#: Name prefixes (pymeshlab's verb families); a filter name starts with one of them.
FAMILIES = ("compute_", "meshing_", "apply_", "generate_", "transfer_", "get_")

#: The reference cited in descriptions.
PAPER = ("Curvature detail representation of triangular surfaces, Zhejiang Univ. Sci. A 7(7):1210 "
         "(2006), doi 10.1631/jzus.2006.A1210")

_REGISTRY = {}


@dataclass(frozen=True)
class FilterSpec:
    """A registered filter: ``name``, ``category``, ``description``, ``parameters`` (a tuple of
    `Parameter`) and the ``function`` that runs it."""

    name: str
    category: str
    description: str
    parameters: tuple
    function: object

    def parameter(self, name):
        """The `Parameter` called ``name`` (KeyError if there is none)."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def parameter_names(self):
        return tuple(p.name for p in self.parameters)

    def defaults(self):
        """``{name: default}`` for every parameter."""
        return {p.name: p.default for p in self.parameters}

    def to_dict(self):
        """The filter as JSON-ready values (``json.dumps`` takes it): ``name``, ``category``,
        ``description`` (one line) and ``parameters`` (each `Parameter.to_dict`)."""
        return {"name": self.name, "category": self.category,
                "description": " ".join(self.description.split()),
                "parameters": [p.to_dict() for p in self.parameters]}


def filter(*, name, category, description, parameters=()):  # noqa: A001 (pymeshlab's word)
    """Declare and register a filter (decorator).

    Parameters
    ----------
    name : str
        snake_case, starting with a verb family (`FAMILIES`).
    category : str
        MeshLab menu-style category, e.g. ``"Curvature detail"``.
    description : str
        One paragraph, with the paper reference where it applies.
    parameters : list of Parameter
        In the order they are listed; each must match a keyword-only argument of the decorated
        function, and vice versa.

    Returns
    -------
    register : callable
        The decorator: it registers a `FilterSpec` under ``name`` (the description with
        its whitespace collapsed to single spaces), sets ``function.spec``, gives a function
        without a docstring one built from the declaration, and returns the same function. The
        decorated function keeps working as a plain function.

    Raises
    ------
    TypeError
        When the decorator is applied: ``name`` not snake_case or not starting with one of
        `FAMILIES`, already registered, an empty ``category`` or ``description``, a
        parameter declared twice, or declared parameters that differ from the function's
        keyword-only arguments.

    Examples
    --------
    >>> from curvdetail.filters import Parameter, filter, get_filter, registry
    >>> @filter(name="get_vertex_count", category="Example", description="Count the vertices.",
    ...         parameters=[Parameter("scale", "float", 1.0, "factor on the count")])
    ... def get_vertex_count(ms, *, scale):
    ...     return {"vertex_count": scale * ms.current_mesh().vertex_number()}
    >>> get_filter("get_vertex_count") is get_vertex_count.spec, get_vertex_count.spec.defaults()
    (True, {'scale': 1.0})
    >>> del registry._REGISTRY["get_vertex_count"]          # unregister the example again
    >>> filter(name="vertex_count", category="Example", description="d")(lambda ms: {})
    Traceback (most recent call last):
    ...
    TypeError: filter name 'vertex_count' must be snake_case and start with one of (...).
    """
    def register(function):
        if not name.startswith(FAMILIES) or name != name.lower() or " " in name:
            raise TypeError(f"filter name {name!r} must be snake_case and start with one of {FAMILIES}.")
        if name in _REGISTRY:
            raise TypeError(f"filter {name!r} is registered twice.")
        if not description or not description.strip() or not category or not category.strip():
            raise TypeError(f"filter {name!r} needs a category and a description.")
        params = tuple(parameters)
        names = [p.name for p in params]
        if len(set(names)) != len(names):
            raise TypeError(f"filter {name!r} declares a parameter twice: {names}.")
        sig = inspect.signature(function)
        kw = [p.name for p in sig.parameters.values() if p.kind is inspect.Parameter.KEYWORD_ONLY]
        if sorted(kw) != sorted(names):
            raise TypeError(f"filter {name!r}: declared parameters {names} do not match the "
                            f"function's keyword-only arguments {kw}.")
        spec = FilterSpec(name, category, " ".join(description.split()), params, function)
        _REGISTRY[name] = spec
        function.spec = spec
        if not function.__doc__:
            function.__doc__ = _docstring(spec)
        return function

    return register


def _docstring(spec):
    """A numpydoc docstring for a filter function, built from its declaration."""
    lines = [spec.description, "", "Run it with ``curvdetail.filters.apply(ms, "
             f"{spec.name!r}, ...)``, which checks and completes the parameters.", "",
             "Parameters", "----------", "ms : pymeshlab.MeshSet"]
    for p in spec.parameters:
        extra = f", one of {', '.join(map(repr, p.choices))}" if p.choices else ""
        lines += [f"{p.name} : {p.type_label}, default {p.default_label()}{extra}",
                  f"    {p.description}"]
    lines += ["", "Returns", "-------", "dict   the filter's figures"]
    return "\n".join(lines)


def list_filters():
    """Every registered filter's `FilterSpec`, sorted by name.

    Takes no parameters; importing `curvdetail.filters` registers the package's filters.

    Returns
    -------
    specs : list of FilterSpec
        A new list each call, sorted by ``name``

    Examples
    --------
    >>> from curvdetail.filters import list_filters
    >>> "compute_curvature_detail" in [f.name for f in list_filters()]
    True
    """
    return [_REGISTRY[k] for k in sorted(_REGISTRY)]


def close_matches(word, candidates, cutoff=0.5):
    """Up to three candidates that look like ``word`` (difflib, similarity >= ``cutoff``), for
    error messages."""
    return difflib.get_close_matches(word, list(candidates), n=3, cutoff=cutoff)


def get_filter(name):
    """The `FilterSpec` called ``name``, or UnknownFilterError listing the close matches.

    Parameters
    ----------
    name : str
        The filter's exact name, e.g. ``"compute_curvature_detail"``

    Returns
    -------
    spec : FilterSpec
        The registered declaration (name, category, description, parameters, function)

    Raises
    ------
    UnknownFilterError
        No filter of that name (also for a name that is not a string); the message lists up to three
        close matches or points to the list

    Examples
    --------
    >>> from curvdetail.filters import get_filter
    >>> get_filter("apply_curvature_reconstruction").defaults()["rows"]
    'all'
    >>> get_filter("compute_curvature_details")
    Traceback (most recent call last):
    ...
    curvdetail.filters.errors.UnknownFilterError: unknown filter ...; did you mean compute_curvature_detail...?
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        pass
    matches = close_matches(str(name), _REGISTRY)
    hint = (f"did you mean {', '.join(matches)}?" if matches
            else "see curvdetail.filters.print_filter_list() or `curvdetail list`.")
    raise UnknownFilterError(f"unknown filter {name!r}; {hint}", value=name)


def print_filter_list():
    """Print the filter names, as ``pymeshlab.print_filter_list()`` does.

    Takes no parameters and returns None: prints a header line, then each registered name on a
    line of its own, indented by a tab, sorted by name (as `list_filters`).

    Examples
    --------
    >>> from curvdetail.filters import print_filter_list
    >>> print_filter_list()                                # doctest: +NORMALIZE_WHITESPACE
    curvdetail.filters - list of filter names:
    ...
        compute_curvature_detail
    ...
    """
    print("curvdetail.filters - list of filter names:")
    for spec in list_filters():
        print(f"\t{spec.name}")


def print_filter_parameter_list(name):
    """Print a filter's parameters as ``name : type = default``, as
    ``pymeshlab.print_filter_parameter_list(name)`` does.

    Returns None: prints a header line, then one tab-indented line per parameter in declaration
    order (``None.`` for a filter without parameters).

    Parameters
    ----------
    name : str
        The filter's exact name

    Raises
    ------
    UnknownFilterError
        No filter of that name (as `get_filter`)

    Examples
    --------
    >>> from curvdetail.filters import print_filter_parameter_list
    >>> print_filter_parameter_list("apply_curvature_reconstruction")    # doctest: +NORMALIZE_WHITESPACE
    apply_curvature_reconstruction filter - list of parameter names:
        rows : str = 'all'
        fix_boundary : bool = True
    ...
    """
    spec = get_filter(name)
    print(f"{spec.name} filter - list of parameter names:")
    if not spec.parameters:
        print("\tNone.")
    for p in spec.parameters:
        print(f"\t{p.name} : {p.type_label} = {p.default_label()}")


def describe_filter(spec, width=96):
    """A filter as text for ``curvdetail list``: name, category, description, and each
    parameter with its type, default, choices or range and description."""
    import textwrap

    lines = [f"{spec.name}  [{spec.category}]"]
    lines += textwrap.wrap(spec.description, width, initial_indent="    ", subsequent_indent="    ")
    for p in spec.parameters:
        extra = ["required"] if p.required else []       # its default is refused
        if p.choices:
            extra.append(" | ".join(p.choices))
        if p.positive:
            extra.append("> 0")
        if p.min is not None:
            extra.append(f">= {p.min}")
        if p.max is not None:
            extra.append(f"<= {p.max}")
        suffix = f"  ({', '.join(extra)})" if extra else ""
        lines.append(f"    {p.name} : {p.type_label} = {p.default_label()}{suffix}")
        lines += textwrap.wrap(p.description, width, initial_indent="        ",
                               subsequent_indent="        ")
    return "\n".join(lines)
