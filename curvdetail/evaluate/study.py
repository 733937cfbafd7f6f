"""A study: mesh files x a grid of `remesh_experiment` configurations.

A study is one or more grids. A grid gives each option of the experiment as one value or a
list (``method``, ``target_edge``, ``transfer``, ``rows``, ``location``, ``parameterization``)
and may restrict itself to some of the study's meshes (``meshes``: file-name patterns such as
``"mannequin_*.obj"``); its cells are every mesh x every combination. ``baselines`` names the
figures to compare with: ``zero_detail`` and ``floor`` are measured in every cell anyway (the
zero-detail surface and the retriangulated surface itself), ``pointwise`` adds the paper's
configuration (pointwise transfer, all rows, harmonic-map location) to every grid.

A study file is TOML or JSON with the same keys: one grid at the top level, or a list of them
under ``grid`` (``[[grid]]`` tables in TOML), e.g. ``scripts/studies/fig3.toml``.
"""

import fnmatch
import glob
import hashlib
import itertools
import json
import os
import sys
from dataclasses import dataclass

from ..curvature.errors import CurvdetailError
from ..curvature.reconstruct import ROW_MODES
from ..io.mesh import MESH_FORMATS
from ..remesh.parameterize import METHODS as PARAMETERIZATIONS
from ..remesh.retriangulate import METHODS as RETRIANGULATIONS
from ..remesh.transfer import LOCATIONS
from ..remesh.transfer import METHODS as TRANSFERS

#: The options of a grid with their choices (``target_edge`` takes sizes, see `target_size`).
CHOICES = {"method": RETRIANGULATIONS, "transfer": TRANSFERS, "rows": ROW_MODES, "location": LOCATIONS,
           "parameterization": PARAMETERIZATIONS}
#: What a grid that leaves an option out runs (remesh_experiment's defaults).
DEFAULTS = {"method": ["isotropic"], "target_edge": ["1%"], "transfer": ["conservative"], "rows": ["free"],
            "location": ["closest"], "parameterization": ["harmonic"]}
#: The baselines a study may name; ``pointwise`` is a configuration, the others are figures of every cell.
BASELINES = {"zero_detail": None, "floor": None,
             "pointwise": {"transfer": ["pointwise"], "rows": ["all"], "location": ["uv"],
                           "parameterization": ["harmonic"]}}
#: The keys of a configuration, in the order of the table's columns.
CONFIG_KEYS = ("method", "target_edge", "transfer", "rows", "location", "parameterization")


class StudyError(CurvdetailError):
    """A study that cannot run: an unknown option or value, a mesh pattern or input that names
    nothing, an unreadable study file (``parameter`` and ``value`` name it)."""


def target_size(value):
    """A target edge size as the study writes it: ``"1%"`` (of the source's bbox diagonal) or a
    plain number (model units), normalized (``"0.50 %"`` -> ``"0.5%"``, ``0.01`` -> ``"0.01"``); StudyError if
    it is not a positive number."""
    text = str(value).strip()
    percent = text.endswith("%")
    try:
        number = float(text.removesuffix("%").strip())
    except ValueError:
        number = float("nan")
    if isinstance(value, bool) or not 0 < number < float("inf"):
        raise StudyError(f"target edge {value!r} is not a positive size", parameter="target_edge", value=value,
                         hint='write a percentage of the bbox diagonal, e.g. "1%"')
    return f"{number:g}%" if percent else f"{number:g}"


def experiment_target_edge(size):
    """The ``target_edge`` argument of `remesh_experiment` for a
    normalized size of `target_size`: ``"1%"`` as it is, a plain number in model units."""
    return size if size.endswith("%") else float(size)


@dataclass(frozen=True)
class Cell:
    """One run of a study: a mesh file and a configuration (``config``: `CONFIG_KEYS`).
    ``key`` identifies it across runs: a hash of the file's content and the configuration."""
    path: str
    name: str
    blake2b: str
    config: tuple

    @property
    def key(self):
        text = f"{self.blake2b or self.path}|{json.dumps(dict(self.config), sort_keys=True)}"
        return hashlib.blake2b(text.encode(), digest_size=10).hexdigest()

    def task(self):
        """The cell as a plain dict, as the worker gets it."""
        return {"path": self.path, "name": self.name, "blake2b": self.blake2b, "key": self.key, **dict(self.config)}


def file_hash(path):
    """blake2b (128 bits, hex) of a file's bytes, or None where it cannot be read."""
    h = hashlib.blake2b(digest_size=16)
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return None
    return h.hexdigest()


def find_meshes(inputs):
    """Absolute paths of the mesh files that ``inputs`` name: files, folders (their files with a
    mesh extension, not recursive) and glob patterns (``**`` recursive); each once, in order.
    StudyError where an input names nothing."""
    found = []
    for item in [inputs] if isinstance(inputs, (str, os.PathLike)) else inputs:
        item = os.fspath(item)
        if os.path.isdir(item):
            paths = [os.path.join(item, n) for n in sorted(os.listdir(item))
                     if os.path.splitext(n)[1].lower() in MESH_FORMATS]
        elif os.path.lexists(item):
            paths = [item]
        else:
            paths = sorted(p for p in glob.glob(item, recursive=True) if os.path.isfile(p))
        if not paths:
            raise StudyError(f"{item!r} names no mesh file", parameter="inputs", value=item,
                             hint=f"name files, folders of {', '.join(MESH_FORMATS)} files, or a glob pattern")
        found.extend(os.path.abspath(p) for p in paths)
    return list(dict.fromkeys(found))


def _values(grid, name, where):
    values = grid.get(name, DEFAULTS[name])
    values = values if isinstance(values, list) else [values]
    if not values:
        raise StudyError(f"{where}: {name} is an empty list", parameter=name, hint="give one value or more")
    if name == "target_edge":
        return [target_size(v) for v in values]
    bad = [v for v in values if v not in CHOICES[name]]
    if bad:
        raise StudyError(f"{where}: {name} {bad[0]!r} is not one of {', '.join(CHOICES[name])}", parameter=name,
                         value=bad[0])
    return values


class Study:
    """Grids of configurations, and the meshes each grid takes.

    Parameters
    ----------
    grids : list of dict
        Each: option -> value or list of values (`CHOICES`, ``target_edge`` sizes such as
        ``"1%"``), optional ``meshes`` (file-name patterns); a left-out option takes
        `DEFAULTS`.
    baselines : list of str
        Names of `BASELINES`.

    Raises
    ------
    StudyError
        An unknown key, option value or baseline (``e.parameter`` names it).

    Examples
    --------
    >>> study = Study([{"method": ["isotropic", "decimate"], "target_edge": ["1%", "2%"]}])
    >>> len(study.configurations())
    4
    """

    def __init__(self, grids, baselines=()):
        self.grids, self.baselines = [], list(baselines)
        for name in self.baselines:
            if name not in BASELINES:
                raise StudyError(f"baseline {name!r} is not one of {', '.join(BASELINES)}", parameter="baselines",
                                 value=name)
        extra = [dict(g, **BASELINES["pointwise"]) for g in grids] if "pointwise" in self.baselines else []
        for k, grid in enumerate(list(grids) + extra, start=1):
            where = f"grid {k}"
            if not isinstance(grid, dict):
                raise StudyError(f"{where} is not a table of options", parameter="grid", value=grid)
            unknown = sorted(set(grid) - set(DEFAULTS) - {"meshes"})
            if unknown:
                raise StudyError(f"{where}: unknown option {unknown[0]!r}", parameter=unknown[0],
                                 hint=f"use {', '.join(DEFAULTS)} or meshes")
            meshes = grid.get("meshes")
            self.grids.append({"meshes": None if meshes is None else list(_as_list(meshes)),
                               **{name: _values(grid, name, where) for name in DEFAULTS}})

    @classmethod
    def from_dict(cls, data):
        """A study from a study file's content: one grid at the top level, or ``grid``: a list."""
        data = dict(data)
        baselines = data.pop("baselines", [])
        grids = data.pop("grid", None)
        if grids is None:
            grids = [data]
        elif data:
            raise StudyError(f"study: {min(data)!r} beside a list of grids", parameter=min(data),
                             hint="put the option inside each [[grid]]")
        return cls([grids] if isinstance(grids, dict) else grids, _as_list(baselines))

    def configurations(self, grid=None):
        """The configurations of one grid (or of all, each once), as tuples of (key, value)."""
        out = []
        for g in self.grids if grid is None else [grid]:
            for values in itertools.product(*(g[k] for k in CONFIG_KEYS)):
                config = dict(zip(CONFIG_KEYS, values))
                if config["location"] != "uv":
                    config["parameterization"] = None       # no planar map
                out.append(tuple(config.items()))
        return list(dict.fromkeys(out))

    def cells(self, inputs):
        """The cells for the mesh files ``inputs`` names (`find_meshes`), each once; a
        grid's ``meshes`` patterns are matched against the files' names (StudyError where one
        matches none)."""
        paths = find_meshes(inputs)
        hashes = {p: file_hash(p) for p in paths}
        cells = []
        for k, grid in enumerate(self.grids, start=1):
            chosen = paths
            if grid["meshes"] is not None:
                for pattern in grid["meshes"]:
                    if not any(fnmatch.fnmatch(os.path.basename(p), pattern) for p in paths):
                        raise StudyError(f"grid {k}: mesh {pattern!r} matches none of the inputs", parameter="meshes",
                                         value=pattern, hint="add the file to INPUT or change the pattern")
                chosen = [p for p in paths if any(fnmatch.fnmatch(os.path.basename(p), pat)
                                                  for pat in grid["meshes"])]
            cells += [Cell(p, os.path.basename(p), hashes[p], c) for p in chosen for c in self.configurations(grid)]
        return list(dict.fromkeys(cells))


def _as_list(value):
    """A scalar or a list as a list."""
    return value if isinstance(value, list) else [value]


def load_study(path):
    """A `Study` from a TOML (``.toml``) or JSON file; StudyError where it cannot be read
    or parsed (``e.value`` is the file)."""
    path = os.fspath(path)
    try:
        if path.endswith(".toml"):
            if sys.version_info >= (3, 11):
                import tomllib
            else:
                import tomli as tomllib
            with open(path, "rb") as fh:
                data = tomllib.load(fh)
        else:
            with open(path, encoding="utf-8") as fh:
                data = json.load(fh)
    except (OSError, ValueError) as exc:
        raise StudyError(f"study file {path}: {exc}", parameter="study", value=path,
                         hint="name a readable TOML or JSON study file") from None
    if not isinstance(data, dict):
        raise StudyError(f"study file {path} does not hold a table of options", parameter="study", value=path)
    return Study.from_dict(data)
