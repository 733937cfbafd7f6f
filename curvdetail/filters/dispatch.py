"""``apply(ms, name, **params)``: run a registered filter on a MeshSet, as pymeshlab's
``ms.apply_filter(name, **params)`` does."""

from .errors import FilterError, FilterParameterError
from .meshset import layer_id
from .recording import history, record, step_element
from .registry import close_matches, get_filter


def complete_parameters(spec, params):
    """Check ``params`` against a filter's declaration and fill in the defaults.

    Raises FilterParameterError for an unknown parameter (listing the close matches), a required
    one left out, or a value of the wrong type or out of range (naming the parameter and the
    expected type)."""
    names = spec.parameter_names
    for key in params:
        if key not in names:
            matches = close_matches(key, names)
            hint = (f"did you mean {', '.join(matches)}?" if matches else
                    f"its parameters are: {', '.join(names) if names else 'none'}")
            raise FilterParameterError(f"filter {spec.name!r} has no parameter {key!r}", value=key, hint=hint)
    values = {p.name: (p.check(params[p.name]) if p.name in params else p.default)
              for p in spec.parameters}
    missing = [p for p in spec.parameters if p.required and p.name not in params]
    if missing:                        # after the given values' checks: what was written wrong first
        p = missing[0]
        raise FilterParameterError(f"filter {spec.name!r} needs parameter {p.name!r}: "
                                   f"{' '.join(p.description.split())}", parameter=p.name,
                                   hint="it has no default that works")
    return values


def apply(ms, name, **params):
    """Run the filter ``name`` on ``ms`` and return its figures.

    The filter works on the current mesh, or on the layers named by its layer-id parameters
    (``sourcemesh``, ``targetmesh``, ...). Parameters left out take their defaults (never values
    from an earlier call). A filter that creates a mesh adds it as a new layer and makes it
    current, as pymeshlab's ``generate_*`` filters do. The step is recorded on ``ms`` for
    `save_script` (with every parameter, the defaults included).

    Parameters
    ----------
    ms : pymeshlab.MeshSet
    name : str
        A registered filter (see `list_filters`)
    **params         the filter's parameters by name

    Returns
    -------
    dict   the filter's figures (numbers, strings, lists), as pymeshlab's ``get_*`` filters return

    Raises
    ------
    UnknownFilterError
        No filter of that name (the message lists the close matches)
    FilterParameterError
        Unknown parameter, wrong type, out of range or not a choice
    FilterError
        An empty MeshSet, a missing layer or attribute, or pymeshlab failed
    MeshError, ConstraintError   the mesh or the constraints do not suit the filter

    Examples
    --------
    >>> import pymeshlab
    >>> from curvdetail.data import example_path
    >>> from curvdetail.filters import apply
    >>> ms = pymeshlab.MeshSet()
    >>> ms.load_new_mesh(example_path())
    >>> figures = apply(ms, "compute_curvature_detail")
    >>> figures["curv_range_min"] <= figures["curv_range_max"]
    True
    """
    import pymeshlab

    spec = get_filter(name)
    if not isinstance(ms, pymeshlab.MeshSet):
        raise FilterError(f"apply({name!r}) needs a pymeshlab.MeshSet, got {type(ms).__name__}.", parameter="ms")
    values = complete_parameters(spec, params)
    layer_id(ms)                                   # an empty MeshSet fails here, clearly
    for p in spec.parameters:
        if p.type == "mesh" and values[p.name] is not None:
            layer_id(ms, values[p.name], role=p.name)
    start = len(history(ms))
    try:
        result = spec.function(ms, **values)
    except pymeshlab.PyMeshLabException as exc:
        raise FilterError(f"{name}: pymeshlab failed: {str(exc).strip()}") from None
    record(ms, start, step_element(spec, values))
    return dict(result or {})
