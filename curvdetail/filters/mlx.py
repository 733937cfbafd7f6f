"""MeshLab filter scripts (.mlx): run them on a MeshSet, with our filters mixed in, and save ours.

The format is MeshLab's (and pymeshlab's ``save_filter_script``)::

    <!DOCTYPE FilterScript>
    <FilterScript>
     <filter name="Remeshing: Isotropic Explicit Remeshing">
      <Param name="Iterations" value="10" type="RichInt" .../>
      ...
     </filter>
     <filter name="transfer_curvature_detail">
      <Param name="sourcemesh" value="0" type="RichMesh" .../>
      <Param name="method" value="1" type="RichEnum" enum_val0="conservative" enum_val1="pointwise" .../>
     </filter>
    </FilterScript>

A ``<filter>`` whose name is one of ours (the snake_case name of
`list_filters`) runs through `apply` with
the ``<Param name= value=>`` pairs converted by the parameter types (an enum's value is its index,
as MeshLab writes it, read through the element's ``enum_val<i>`` where it has them, or its
text; a ``PercentageValue`` is absolute, as MeshLab writes it, or ``"1.5%"`` of the bbox
diagonal). Parameters missing from the script take their defaults. Any
other ``<filter>`` / ``<xmlfilter>`` (MeshLab GUI names) is handed to pymeshlab unchanged, one
at a time, through a temporary script and ``load_filter_script`` / ``apply_filter_script``.
"""

import os
import re
import xml.etree.ElementTree as ET

from ..io.atomic import atomic_write, check_output_path
from .dispatch import apply
from .errors import FilterError, ScriptError
from .parameters import BBoxLength
from .errors import ScaleWarning
from .native import check_native_parameters, far_lengths, run_native
from .recording import recorded_steps, step_element
from .registry import _REGISTRY, close_matches, get_filter

def _script_path(path):
    """``path`` as a str, or ScriptError if it is not a path (os.fspath raised a TypeError)."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise ScriptError(f"a filter script path is needed (a str or os.PathLike of a .mlx file); got "
                          f"{type(path).__name__}.")
    return os.fsdecode(path)


def _steps(path):
    path = _script_path(path)
    if os.path.isdir(path):       # not "not found": it exists, but is no script
        raise ScriptError(f"{path} is a folder; pass the path of a .mlx filter script (a file).")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"filter script not found: {path}")
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, LookupError, UnicodeError) as exc:   # LookupError: an unknown encoding
        raise ScriptError(f"{path} is not a MeshLab filter script: {exc}.") from None
    if root.tag != "FilterScript":
        raise ScriptError(f"{path}: the root element is <{root.tag}>; a MeshLab filter script has "
                          "<FilterScript>.")
    steps = []
    for k, element in enumerate(root, start=1):
        if element.tag not in ("filter", "xmlfilter"):
            named = f" name={element.get('name')!r}" if element.get("name") else ""
            raise ScriptError(f"{path}: step {k} is <{element.tag}{named}>; a step is <filter name=\"...\"> "
                              "(the tag in lower case, as MeshLab writes it).")
        if not element.get("name"):
            raise ScriptError(f"{path}: step {k} is <{element.tag}> without a name; expected "
                              "<filter name=\"...\">.")
        steps.append(element)
    return steps


def _our_parameters(spec, element, where):
    params = {}
    for child in element:
        if child.tag not in ("Param", "xmlparam"):
            continue
        name, value = child.get("name"), child.get("value")
        if name is None or value is None:
            raise ScriptError(f"{where}: a <{child.tag}> lacks a name or a value.")
        if name in params:
            raise ScriptError(f"{where}: parameter {name!r} is given twice; keep one <Param name={name!r}>.",
                              parameter=name)
        # an enum index means the script's own enum_val<i> where it lists them (MeshLab writes
        # both), so a script whose list is in another order still means what it says
        value = child.get(f"enum_val{value.strip()}", value) if child.get("type") == "RichEnum" else value
        try:
            params[name] = spec.parameter(name).parse(value)
        except KeyError:
            params[name] = value          # let apply() report it with the close matches
        except FilterError as exc:
            raise ScriptError(f"{where}: {exc}", parameter=getattr(exc, "parameter", None)) from None
    return params


def _refuse_a_near_miss(name, where):
    """A snake_case step name that is not ours but close to one of ours is a typo, not one of
    MeshLab's filters (whose script names are words with spaces): pymeshlab would only report
    'Something really bad happened'."""
    if re.fullmatch(r"[a-z0-9_]+", name):
        matches = close_matches(name, _REGISTRY)
        if matches:
            raise ScriptError(f"{where}: no filter is called {name!r}; did you mean {', '.join(matches)}?")


def run_script(ms, path, *, progress=None):
    """Run a MeshLab filter script (.mlx) on ``ms``, step by step, in order.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
        With the input mesh(es) loaded
    path : str or os.PathLike
    progress : callable or None
        Called as ``progress(step, total, name)`` before each step

    Returns
    -------
    list of dict   one per step: ``{"filter": name, "figures": dict}`` (pymeshlab's own filters
                   give no figures through a script: ``{}``)

    Raises
    ------
    FileNotFoundError
        The script does not exist
    ScriptError
        Not a MeshSet, ``path`` not a path or a folder, malformed XML (or an unknown encoding), a
        parameter given twice, a step name that is a typo of one of ours, a parameter of one of ours
        unknown or of the wrong type or range, a parameter of a MeshLab step that MeshLab would
        misread without a word (a bool other than 'true'/'false', a number that does not parse, a
        RichAbsPerc without min and max, a name the filter does not have): all these found before
        any step runs (`check_script`), except a MeshLab parameter name right but for its
        capitals, found after its step; then, as the steps run, a MeshLab filter that needs a mesh
        on an empty MeshSet, or a step failed (the message names the step number and filter, then
        the reason), or the last step left the MeshSet with no mesh

    Examples
    --------
    >>> import pymeshlab
    >>> from curvdetail.data import example_path
    >>> from curvdetail.filters import run_script, save_script
    >>> import tempfile, os
    >>> script = os.path.join(tempfile.mkdtemp(), "detail.mlx")
    >>> save_script(script, ["compute_curvature_detail"])
    >>> ms = pymeshlab.MeshSet(); ms.load_new_mesh(example_path())
    >>> [step["filter"] for step in run_script(ms, script)]
    ['compute_curvature_detail']
    """
    import pymeshlab

    if not isinstance(ms, pymeshlab.MeshSet):
        raise ScriptError(f"run_script needs a pymeshlab.MeshSet, got {type(ms).__name__}.")
    if progress is not None and not callable(progress):
        raise ScriptError(f"progress={progress!r} is not callable; pass a function (step, total, name) or None.")
    results = []
    steps = check_script(path)              # every step, before any of them changes the MeshSet
    for k, (element, where, params) in enumerate(steps, start=1):
        name = element.get("name")
        if progress is not None:
            progress(k, len(steps), name)
        _note_far_lengths(ms, where, element, params)
        if params is not None:
            try:
                figures = apply(ms, name, **params)
            except ValueError as exc:
                raise ScriptError(f"{where}: {exc}", parameter=getattr(exc, "parameter", None)) from None
        else:
            run_native(ms, element, where)
            figures = {}
        if ms.mesh_number() == 0 and k == len(steps):
            raise ScriptError(f"{where} deleted the last mesh: the script ends with none", parameter="script",
                              hint="remove that step, or create a mesh after it")
        results.append({"filter": name, "figures": figures})
    return results


def check_script(path):
    """Read a MeshLab filter script (.mlx) and check every step without running any: the
    checks of `run_script` that need no mesh, so that a typo in its last step is found
    before its first one has taken minutes.

    Of our filters: the name (a typo of one of ours gets the close matches), each parameter's
    name and value (parsed by its type, checked as `apply` checks
    it); of MeshLab's: what MeshLab would misread without a word (see `run_script`).
    What needs the meshes (layer ids that exist, attributes, a mesh for a native step) is
    checked as each step runs.

    Parameters
    ----------
    path : str or os.PathLike
        The script

    Returns
    -------
    list of (element, where, params)   per step, in order: its XML element, the words that name
                                       it in messages (``"s.mlx step 2 (name)"``) and, for one
                                       of our filters, its parameters as given, typed (None for
                                       one of MeshLab's)

    Raises
    ------
    FileNotFoundError, ScriptError   as `run_script`
    """
    from .dispatch import complete_parameters

    path = _script_path(path)
    checked = []
    for k, element in enumerate(_steps(path), start=1):
        name = element.get("name")
        where = f"{os.path.basename(path)} step {k} ({name})"
        params = None
        if name in _REGISTRY:
            params = _our_parameters(_REGISTRY[name], element, where)
            try:
                complete_parameters(_REGISTRY[name], params)
            except ValueError as exc:
                raise ScriptError(f"{where}: {exc}", parameter=getattr(exc, "parameter", None)) from None
        else:
            _refuse_a_near_miss(name, where)
            if element.tag == "filter":
                check_native_parameters(element, where)
        checked.append((element, where, params))
    return checked


def save_script(path, steps, *, overwrite=False):
    """Write a MeshLab filter script that `run_script` runs: the pipeline run on a MeshSet
    (``save_script(ms, path)``), or our filters named in a list (``save_script(path, steps)``).

    ``save_script(ms, path)`` writes every step run on ``ms`` from Python, in order: ours (run by
    `apply`) and pymeshlab's (run by
    `apply_native`, whose lengths and floats replay to the last digit,
    or on the MeshSet directly, as pymeshlab recorded them). ``curvdetail run`` replays it on the
    same input to the same result.

    Parameters
    ----------
    path : str or os.PathLike
        Destination (.mlx); written atomically (or the MeshSet, then ``steps`` is the destination)
    steps : list
        Each a filter name or ``(name, {parameter: value})``; every parameter is written (defaults
        for those not given), except a layer id left to the current mesh where that is its default
        (a layer id whose default is a layer, set to None, the current mesh, is written as
        ``value=""``)
    overwrite : bool
        Replace an existing file

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False
    FileNotFoundError
        The destination folder does not exist
    ScriptError
        ``steps`` is not a list of names or (name, parameters) pairs; a MeshSet on which no filter
        has run
    UnknownFilterError, FilterParameterError   as `apply`

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "rebuild.mlx")
    >>> save_script(path, ["compute_curvature_detail",
    ...                    ("apply_curvature_reconstruction", {"rows": "free"})])
    >>> "apply_curvature_reconstruction" in open(path).read()
    True
    """
    import pymeshlab

    from .dispatch import complete_parameters

    if isinstance(path, pymeshlab.MeshSet):
        ms, path = path, steps
        path = check_output_path(path, overwrite)
        elements = recorded_steps(ms)
        if not elements:
            raise ScriptError("no filter has run on this MeshSet", parameter="ms",
                              hint="run filters with curvdetail.filters.apply / apply_native first")
        return _write(path, elements, overwrite)
    path = check_output_path(path, overwrite)
    if isinstance(steps, str) or not isinstance(steps, (list, tuple)):
        raise ScriptError(f"steps must be a list of filter names or (name, parameters) pairs; got "
                          f"{type(steps).__name__}.")
    elements = []
    for k, step in enumerate(steps, start=1):
        if not isinstance(step, str) and not (isinstance(step, (list, tuple)) and len(step) == 2
                                              and isinstance(step[1], (dict, type(None)))):
            raise ScriptError(f"step {k} is {step!r}; give a filter name or a (name, {{parameter: value}}) pair.")
        name, params = (step, {}) if isinstance(step, str) else (step[0], dict(step[1] or {}))
        spec = get_filter(name)
        elements.append(step_element(spec, complete_parameters(spec, params)))
    _write(path, elements, overwrite)


def _write(path, elements, overwrite):
    root = ET.Element("FilterScript")
    root.extend(elements)
    ET.indent(root, space=" ")
    text = "<!DOCTYPE FilterScript>\n" + ET.tostring(root, encoding="unicode") + "\n"
    with atomic_write(path, overwrite=overwrite) as tmp:
        with open(tmp, "w", encoding="utf-8") as out:
            out.write(text)


def _note_far_lengths(ms, where, element, params):
    """A `ScaleWarning` for each length of a step given in model units far from the
    current mesh's size (see `FAR_LENGTH`): likely sized for another mesh."""
    from ..curvature.errors import warn
    from ..curvature.geometry import bbox_diagonal
    from .native import FAR_LENGTH

    if ms.mesh_number() == 0:
        return
    diagonal = bbox_diagonal(ms.current_mesh().vertex_matrix())
    if params is None:
        far = far_lengths(ms, element)
    else:
        far = [(name, repr(v.value), v.value / diagonal) for name, v in params.items()
               if isinstance(v, BBoxLength) and not v.percent
               and not FAR_LENGTH[0] <= v.value / diagonal <= FAR_LENGTH[1]]
    for name, value, ratio in far:
        warn(f"{where}: {name} {value} (model units) is {100 * ratio:.3g} % of the current mesh's bbox diagonal "
             f"({diagonal:.4g}); was it sized for another mesh? A percentage of the diagonal (value=\"2%\") "
             "suits any mesh.", ScaleWarning)
