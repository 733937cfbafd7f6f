"""MeshLab's own steps of a filter script: what MeshLab would misread in them, checked before
any step runs, and running one step through pymeshlab's script runner (its output kept off
the console, its failures said in words)."""

import contextlib
import functools
import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET

from .errors import ScriptError
from .registry import close_matches


@contextlib.contextmanager
def _quiet_output():
    """pymeshlab prints 'Reading filter with name ...' when it loads a script; its failures come
    back as exceptions, so its console output is kept from the console while a native step runs.
    Yields a list that holds the output (one str) once the block has ended."""
    saved, captured = [], []
    with tempfile.TemporaryFile() as sink:
        try:
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(AttributeError, OSError, ValueError):
                    stream.flush()
            for fd in (1, 2):                  # pymeshlab writes to the process's own descriptors
                with contextlib.suppress(OSError):
                    saved.append((fd, os.dup(fd)))
            for fd, _ in saved:
                os.dup2(sink.fileno(), fd)
            yield captured
        finally:
            _flush_c_streams()              # what pymeshlab's C++ side still buffers goes to the sink
            for fd, copy in saved:
                os.dup2(copy, fd)
                os.close(copy)
            sink.seek(0)
            captured.append(sink.read().decode("utf-8", "replace"))


def _flush_c_streams():
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):      # no C library to ask (not on a POSIX system)
        pass


#: How MeshLab reads a ``<Param>`` value of each type it checks: a bool is false only as the
#: exact text "false" ("0", "False" are true), an int or a float that does not parse is 0, and a
#: ``RichAbsPerc`` without both ``min`` and ``max`` attributes is ignored (measured with pymeshlab
#: 2023.12). So what it would read against the writer's meaning is refused before any step runs;
#: "True" or "1", read as true, pass.
_INTEGER = re.compile(r"\s*[+-]?\d+\s*")
_TRUE = ("true", "1", "yes", "on")
_NATIVE_CHECKS = {
    "RichBool": (lambda v: v == "false" or v.strip().lower() in _TRUE,
                 "'true' or 'false' (MeshLab reads any text but 'false' as true)"),
    "RichInt": (lambda v: bool(_INTEGER.fullmatch(v)), "a whole number (MeshLab reads other text as 0)"),
    "RichEnum": (lambda v: bool(_INTEGER.fullmatch(v)), "the index of the choice, a whole number"),
    "RichMesh": (lambda v: bool(_INTEGER.fullmatch(v)), "a layer index, a whole number"),
    "RichFloat": (lambda v: _finite(v), "a finite number with a decimal point (MeshLab reads other text as 0)"),
    "RichDynamicFloat": (lambda v: _finite(v), "a finite number with a decimal point"),
    "RichAbsPerc": (lambda v: _finite(v.removesuffix("%")),
                    "a finite number in model units, or a percentage of the bbox diagonal such as 2%"),
}


def _finite(text):
    if "_" in text:                     # Python's float reads 3_0 as 30, MeshLab's as 0
        return False
    try:
        return abs(float(text)) < float("inf")
    except ValueError:
        return False


def name_key(name):
    """A parameter name as MeshLab and pymeshlab both spell it: pymeshlab's Python names are
    MeshLab's in lower case, a Python keyword with "_" appended ('lambda' -> 'lambda_')."""
    return re.sub(r"[^a-z0-9]+", "", name.lower())


@functools.lru_cache(maxsize=None)
def _native_parameter_names(meshlab_name):
    """pymeshlab's Python names of a MeshLab filter's parameters, found through its rename table
    and a one-triangle MeshSet; None where either fails."""
    import numpy as np
    import pymeshlab

    python_name = _pymeshlab_renames().get(_snake(meshlab_name))
    if python_name is None:
        return None
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.eye(3), np.array([[0, 1, 2]], dtype=np.int32)))
    try:
        with _quiet_output():
            return frozenset(ms.filter_parameter_values(python_name))
    except Exception:
        return None


def check_native_parameters(element, where):
    """Refuse what MeshLab would misread in a native step's parameters without a word: values
    of the wrong kind for their type (see ``_NATIVE_CHECKS``), a parameter given twice, and
    names the filter does not have (checked in lower case against pymeshlab's names; MeshLab's
    own check, case-sensitive, runs with the step)."""
    names = _native_parameter_names(element.get("name"))
    keys = None if names is None else {name_key(n) for n in names}
    seen = set()
    for child in element:
        if child.tag != "Param":
            continue
        name, value, kind = child.get("name"), child.get("value"), child.get("type")
        if name is None:
            raise ScriptError(f"{where}: a <Param> lacks a name.")
        if name in seen:
            raise ScriptError(f"{where}: parameter {name!r} is given twice; keep one <Param name={name!r}>.",
                              parameter=name)
        seen.add(name)
        if keys is not None and name_key(name) not in keys:
            raise ScriptError(f"{where}: this MeshLab filter has no parameter {name!r} (pymeshlab ignores it "
                              f"without a word); its parameters, in pymeshlab's lower case: "
                              f"{', '.join(sorted(names))}.", parameter=name)
        check, meaning = _NATIVE_CHECKS.get(kind, (None, None))
        if check is not None and (value is None or not check(value if kind == "RichBool" else value.strip())):
            raise ScriptError(f"{where}: parameter {name!r} ({kind}) has value {value!r}; write {meaning}.",
                              parameter=name)
        if kind == "RichAbsPerc" and (child.get("min") is None or child.get("max") is None):
            raise ScriptError(f"{where}: parameter {name!r} (RichAbsPerc) needs min and max attributes, "
                              "as MeshLab writes them (e.g. min=\"0\" max=\"1\"); without them MeshLab "
                              "ignores its value.", parameter=name)


_IGNORED_PARAMETER = re.compile(r"Warning: parameter (\S*) not required by filter")


@functools.lru_cache(maxsize=1)
def _pymeshlab_renames():
    """pymeshlab's table of its old Python names (MeshLab's script names in snake case, e.g.
    ``remove_duplicate_vertices``) to its current ones (``meshing_remove_duplicate_vertices``);
    empty if it is not there."""
    import pymeshlab

    try:
        with open(os.path.join(os.path.dirname(pymeshlab.__file__), "keys.txt"), encoding="utf-8") as f:
            return dict(line.split()[:2] for line in f if len(line.split()) >= 2)
    except OSError:
        return {}


def _snake(meshlab_name):
    return re.sub(r"[^a-z0-9]+", "_", meshlab_name.lower()).strip("_")


def _creates_a_mesh(meshlab_name):
    """Whether a MeshLab filter (by its script name, e.g. "Sphere") makes a mesh from nothing:
    pymeshlab's ``create_*`` filters, found through the old-to-new name table it ships."""
    return _pymeshlab_renames().get(_snake(meshlab_name), "").startswith("create_")


#: MeshLab's own words for "I know no filter of this name" (its script runner says no more).
_UNKNOWN_STEP = "Something really bad happened"

_HOW_NAMES_ARE_WRITTEN = ("A step names MeshLab's filter with its capitals and spaces, as MeshLab writes "
                          "it (Filters > Show current filter script) or pymeshlab's "
                          "MeshSet.save_filter_script does.")


def _unknown_native_step(name):
    """Why MeshLab failed on a step called ``name`` without a reason: pymeshlab's Python name used in a script,
    MeshLab's name spelled with other capitals or spaces, or a close match (MeshLab's names
    in the words of pymeshlab's rename table, which holds the filters renamed since 2022)."""
    import pymeshlab

    renames = _pymeshlab_renames()
    if re.fullmatch(r"[a-z0-9_]+", name) and (name in renames.values() or hasattr(pymeshlab.MeshSet, name)):
        old = next((o for o, new in renames.items() if new == name), None)
        words = f" (its words, in lower case and without punctuation: {old.replace('_', ' ')!r})" if old else ""
        return (f"{name!r} is pymeshlab's Python name, not MeshLab's{words}. {_HOW_NAMES_ARE_WRITTEN}")
    key = _snake(name)
    if key in renames:
        return (f"MeshLab's name for this filter (pymeshlab's {renames[key]}) has these words, "
                f"{key.replace('_', ' ')!r}, with other capitals or punctuation (a colon, a comma, a "
                f"dash). {_HOW_NAMES_ARE_WRITTEN}")
    matches = close_matches(key, renames, cutoff=0.75)
    if matches:
        return (f"MeshLab has no filter called {name!r}; did you mean "
                f"{', '.join(repr(m.replace('_', ' ')) for m in matches)} (their words, in lower case "
                f"and without punctuation)? {_HOW_NAMES_ARE_WRITTEN}")
    return (f"pymeshlab failed without a reason ({_UNKNOWN_STEP!r}); the usual cause is a filter name "
            f"MeshLab does not know. {_HOW_NAMES_ARE_WRITTEN}")


def percentages_resolved(ms, element):
    """A copy of a native step whose ``RichAbsPerc`` values given as ``"2%"`` (MeshLab takes
    lengths in model units only) are resolved against the current mesh's bbox diagonal, with
    every digit (as `apply_native` resolves a ``PercentageValue``)."""
    import copy

    from ..curvature.geometry import bbox_diagonal
    element = copy.deepcopy(element)
    for p in element:
        value = (p.get("value") or "").strip()
        if p.get("type") == "RichAbsPerc" and value.endswith("%"):
            diagonal = bbox_diagonal(ms.current_mesh().vertex_matrix())
            p.set("value", repr(percent_length(value[:-1], diagonal)))
    return element


def far_lengths(ms, element):
    """``[(name, value, ratio)]`` of a native step's ``RichAbsPerc`` lengths in model units that
    are far from the current mesh's size: above ``FAR_LENGTH[1]`` or below ``FAR_LENGTH[0]`` of
    its bbox diagonal (``ratio``), likely sized for another mesh."""
    from ..curvature.geometry import bbox_diagonal

    far = []
    for p in element:
        value = (p.get("value") or "").strip()
        if p.get("type") == "RichAbsPerc" and not value.endswith("%") and ms.mesh_number():
            ratio = float(value) / bbox_diagonal(ms.current_mesh().vertex_matrix())
            if not FAR_LENGTH[0] <= ratio <= FAR_LENGTH[1]:
                far.append((p.get("name"), value, ratio))
    return far


def percent_length(percent, diagonal):
    """A percentage of ``diagonal`` in model units: one formula for recording
    (`apply_native`) and replay."""
    return float(percent) / 100.0 * float(diagonal)


#: Lengths in model units outside these fractions of the bbox diagonal get a note (a script's
#: TargetLen of 0.3, 2 % of the terrain it was written for, is 33 % of the nose's diagonal).
FAR_LENGTH = (1e-4, 0.1)


def run_native(ms, element, where):
    import pymeshlab

    element = percentages_resolved(ms, element)
    # pymeshlab's script runner crashes the process (segmentation fault) when a filter that needs
    # a mesh meets an empty MeshSet
    if ms.mesh_number() == 0 and not _creates_a_mesh(element.get("name")):
        raise ScriptError(f"{where}: the MeshSet holds no mesh, and this filter needs one; load a mesh "
                          "(or create one in an earlier step) first.")
    script = ET.Element("FilterScript")
    script.append(element)
    fd, tmp = tempfile.mkstemp(prefix="curvdetail-step-", suffix=".mlx")
    os.close(fd)
    try:
        with open(tmp, "w", encoding="utf-8") as out:
            out.write("<!DOCTYPE FilterScript>\n" + ET.tostring(script, encoding="unicode") + "\n")
        try:
            with _quiet_output() as output:
                ms.load_filter_script(tmp)
                ms.apply_filter_script()
        except pymeshlab.PyMeshLabException as exc:
            detail = " ".join(str(exc).split())
            reason = _unknown_native_step(element.get("name", "")) if _UNKNOWN_STEP in detail else \
                f"pymeshlab failed: {detail}"
            raise ScriptError(f"{where}: {reason}") from None
    finally:
        os.remove(tmp)
    ignored = _IGNORED_PARAMETER.findall(output[0])
    if ignored:      # a name right but for its capitals: MeshLab's check is case-sensitive
        raise ScriptError(f"{where}: pymeshlab ran this step without parameter(s) {', '.join(map(repr, ignored))}, "
                          "which the filter does not know under that spelling (MeshLab's names are "
                          "case-sensitive, e.g. 'TargetLen'); the MeshSet holds the step's result.")
