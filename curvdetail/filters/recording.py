"""A pipeline run on a MeshSet from Python, recorded as the steps of one MeshLab filter script.

pymeshlab records every filter it runs on a MeshSet (``ms.save_filter_script``), ours included
in the form of the internal steps they use to write attributes (``curvdetail_scratch_<k>``),
which no script can replay. So `apply` records each of our filters as
its own ``<filter>`` step, with the range of pymeshlab's history it covers, and
`apply_native` does the same for one of pymeshlab's filters, with the lengths and numbers
given as written (a ``PercentageValue`` as ``"1%"``, a float with every digit: pymeshlab's own
history keeps 6). `recorded_steps` puts them together with the steps run on the MeshSet
directly (``ms.meshing_...``), as pymeshlab recorded those.
"""

import os
import tempfile
import weakref
import xml.etree.ElementTree as ET

from .errors import FilterError

_RICH_TYPES = {"bool": "RichBool", "int": "RichInt", "float": "RichFloat", "str": "RichString",
               "PercentageValue": "RichAbsPerc", "mesh": "RichMesh"}

#: MeshSet -> [(start, end, element)]: a recorded step and the range of pymeshlab's history it covers
_RECORDS = weakref.WeakKeyDictionary()

#: What our internal steps write into pymeshlab's history (never a user's step).
_SCRATCH = "curvdetail_scratch_"


def param_element(p, value):
    """A ``<Param>`` of one of our filters' parameters, as MeshLab writes it (an enum as its index
    with the ``enum_val<i>`` names)."""
    attrs = {"name": p.name, "value": p.format(value), "type": _RICH_TYPES[p.type],
             "description": p.name, "tooltip": p.description}
    if p.type == "str" and p.choices is not None:
        attrs["type"] = "RichEnum"
        attrs["value"] = str(p.choices.index(value))
        attrs["enum_cardinality"] = str(len(p.choices))
        for i, c in enumerate(p.choices):
            attrs[f"enum_val{i}"] = c
    return ET.Element("Param", attrs)


def step_element(spec, values):
    """The ``<filter>`` step of one of our filters with its completed parameter ``values``; a
    layer id left to the current mesh, where that is its default, is left out."""
    element = ET.Element("filter", {"name": spec.name})
    for p in spec.parameters:
        if p.type == "mesh" and values[p.name] is None and p.default is None:
            continue
        element.append(param_element(p, values[p.name]))        # None (current) as value=""
    return element


def history(ms):
    """pymeshlab's record of the filters run on ``ms``: a list of ``<filter>`` elements."""
    fd, tmp = tempfile.mkstemp(prefix="curvdetail-history-", suffix=".mlx")
    os.close(fd)
    try:
        ms.save_filter_script(tmp)
        return list(ET.parse(tmp).getroot())
    finally:
        os.remove(tmp)


def record(ms, start, element):
    """Record ``element`` as the step that covers pymeshlab's history of ``ms`` from ``start``
    (its length before the step) to its length now."""
    _RECORDS.setdefault(ms, []).append((start, len(history(ms)), element))


def recorded_steps(ms):
    """Every step run on ``ms``, in order: ours and those of `apply_native` as recorded,
    the native filters run on it directly as pymeshlab recorded them (our internal steps left
    out)."""
    steps, done = [], 0
    full = history(ms)
    for start, end, element in _RECORDS.get(ms, []) + [(len(full), len(full), None)]:
        steps += [e for e in full[done:start] if not any(_SCRATCH in (p.get("value") or "") for p in e)]
        if element is not None:
            steps.append(element)
        done = end
    return steps


def apply_native(ms, name, **params):
    """Run pymeshlab's filter ``name`` (its Python name, e.g. ``"meshing_isotropic_explicit_remeshing"``)
    on ``ms`` and record it for `save_script`.

    As ``ms.apply_filter(name, **params)``, except that a ``pymeshlab.PercentageValue`` is
    resolved here against the current mesh's bbox diagonal (as a script's ``"1%"`` is when it is
    replayed, so both give the same length to the last digit) and written as a percentage; every
    float given is written with all its digits. Parameters left out are written as pymeshlab
    recorded them (6 significant digits): give the lengths a replay must repeat exactly.

    Returns
    -------
    dict   pymeshlab's figures (its ``get_*`` filters), else empty

    Raises
    ------
    FilterError
        Pymeshlab failed (its words)

    Examples
    --------
    >>> import pymeshlab
    >>> from curvdetail.data import example_path
    >>> ms = pymeshlab.MeshSet(); ms.load_new_mesh(example_path())
    >>> apply_native(ms, "meshing_isotropic_explicit_remeshing", targetlen=pymeshlab.PercentageValue(3))
    {}
    """
    import pymeshlab

    from ..curvature.geometry import bbox_diagonal
    from .native import name_key, percent_length

    call, written = {}, {}
    for key, value in params.items():
        kind = type(value).__name__
        if kind == "PercentageValue":
            diagonal = bbox_diagonal(ms.current_mesh().vertex_matrix())
            call[key] = pymeshlab.PureValue(percent_length(value.value(), diagonal))
            written[name_key(key)] = f"{float(value.value())!r}%"
        else:
            call[key] = value
            if kind == "PureValue" or isinstance(value, float):
                written[name_key(key)] = repr(float(value.value() if kind == "PureValue" else value))
    start = len(history(ms))
    try:
        figures = ms.apply_filter(name, **call)
    except pymeshlab.PyMeshLabException as exc:
        raise FilterError(f"{name}: pymeshlab failed: {' '.join(str(exc).split())}") from None
    added = history(ms)[start:]
    if len(added) == 1:
        for p in added[0]:
            if name_key(p.get("name", "")) in written:
                p.set("value", written[name_key(p.get("name"))])
        _RECORDS.setdefault(ms, []).append((start, start + 1, added[0]))
    return dict(figures or {})

