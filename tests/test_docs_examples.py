"""The Python examples of the README and docs/ run as written, with the figures they quote.

Paths in them are relative to the repository root (the bundled example, tests/data, the example
scripts), except the README's first example, which reads a ``patch.obj`` of the user's: it runs in
a scratch folder holding the bundled terrain under that name."""

import os
import re
import shlex
import shutil

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def python_blocks(name):
    """The ```python blocks of a markdown file, in order."""
    with open(os.path.join(ROOT, name), encoding="utf-8") as f:
        return re.findall(r"```python\n(.*?)```", f.read(), flags=re.S)


def block_under(name, heading):
    """The first ```python block after ``heading`` in a markdown file."""
    with open(os.path.join(ROOT, name), encoding="utf-8") as f:
        text = f.read()
    start = text.index(heading)
    return re.search(r"```python\n(.*?)```", text[start:], flags=re.S).group(1)


def test_readme_python_example_rebuilds_the_patch_to_solver_precision(tmp_path, monkeypatch):
    shutil.copy(os.path.join(ROOT, "curvdetail", "data", "terrainA_1k.obj"), tmp_path / "patch.obj")
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(block_under("README.md", "## Python"), scope)
    V, X, M, b = scope["V"], scope["X"], scope["M"], scope["b"]
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    assert np.abs(X - V).max() < 1e-12 * diagonal                  # "~1e-14"
    assert np.array_equal(M[b], V[b])
    assert sorted(os.listdir(tmp_path)) == ["patch.obj", "rebuilt.ply"]


def test_readme_filter_example_runs_the_remeshing_and_the_script(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    scope = {}
    exec(block_under("README.md", "## MeshLab-style filters"), scope)
    assert scope["figures"]["error"]["hausdorff_rms_percent_of_diagonal"] < 0.1        # the terrain: ~0.014 %
    assert [s["filter"] for s in scope["steps"]][-1] == "get_curvature_reconstruction_error"
    assert "generate_curvature_remeshing" in capsys.readouterr().out


def test_filters_doc_examples_run_with_the_quoted_error(monkeypatch):
    monkeypatch.chdir(ROOT)
    printed = []
    scope = {"print": printed.append}
    exec(python_blocks("docs/filters.md")[0], scope)
    assert printed[0]["hausdorff_rms_percent_of_diagonal"] == pytest.approx(0.022, abs=0.002)   # as its comment says
    figures = {s["filter"]: s["figures"] for s in scope["steps"]}
    assert figures["generate_minimal_surface"]["converged"]


def test_remeshing_doc_example_runs_on_the_bundled_nose(monkeypatch):
    monkeypatch.chdir(ROOT)
    scope = {}
    exec(python_blocks("docs/remeshing.md")[0], scope)
    report = scope["report"]
    assert report["error"]["hausdorff_rms_percent_of_diagonal"] < 0.1 < report["baseline_zero_detail"]["hausdorff_rms_percent_of_diagonal"]
    assert scope["Dt"].shape == scope["Vt"].shape and scope["Vt"].shape[0] < 640


#: The documents in the order the README sends a new user through them, and the options of the
#: ``curvdetail`` commands that take a value (the values that are output files are marked True).
READING_ORDER = ["README.md", "docs/filters.md", "docs/remeshing.md", "docs/editing.md", "docs/benchmarks.md"]
VALUE_OPTIONS = {"--report": True, "--image": True, "--param": False, "--add": False, "--sel": False,
                 "--def": False, "--target-edge": False, "--method": False, "--transfer": False,
                 "--rows": False, "--location": False, "--parameterization": False, "--backend": False,
                 "--max-iterations": False, "--tol": False, "--step": False, "--handle-detail": False,
                 "--relations": False}
FLAG_OPTIONS = {"--overwrite", "--example", "--quiet", "--no-evaluate", "--no-surface-check", "--fix-boundary",
                "--json", "--help"}


def documented_writes():
    """``(document, file, overwrite)`` for every file the docs' commands and Python examples
    write, in reading order: the ``curvdetail`` command lines of every fenced block (OUTPUT,
    ``--report``, ``--image``), ``write_mesh`` and pymeshlab's ``save_current_mesh``."""
    writes = []
    for name in READING_ORDER:
        with open(os.path.join(ROOT, name), encoding="utf-8") as f:
            blocks = re.findall(r"```[a-z]*\n(.*?)```", f.read(), flags=re.S)
        for block in blocks:
            for line in block.replace("\\\n", " ").splitlines():
                calls = re.findall(r"""(?:write_mesh|save_current_mesh)\(\s*["']([^"']+)["']([^)]*)""", line)
                writes += [(name, path, "overwrite=True" in rest) for path, rest in calls]
                for command in line.split(" #")[0].split("&&"):
                    writes += command_writes(name, command.strip().removeprefix("$ "))
    return writes


def command_writes(name, command):
    """``documented_writes`` of one shell command (nothing unless it is a ``curvdetail`` one)."""
    if not command.startswith("curvdetail "):
        return []
    words = shlex.split(re.sub(r"\[[^\]]*\]", " ", command))  # a synopsis' [--option VALUE]
    positional, outputs, i = [], [], 2
    while i < len(words):
        if words[i] in VALUE_OPTIONS:
            if VALUE_OPTIONS[words[i]]:
                outputs.append(words[i + 1])
            i += 2
            continue
        assert words[i] in FLAG_OPTIONS or not words[i].startswith("-"), f"{name}: {command}: {words[i]}?"
        if not words[i].startswith("-"):
            positional.append(words[i])
        i += 1
    if words[1] in {"remesh", "reconstruct", "minimal", "edit", "apply", "run"} and positional:
        outputs.append(positional[-1])
    return [(name, path, "--overwrite" in words) for path in outputs]


def test_docs_commands_run_in_reading_order_never_write_a_file_an_earlier_one_made():
    # Followed top to bottom in one folder, a command whose OUTPUT an earlier step made stops with
    # 'exists; pass --overwrite' (the README's reconstruct wrote the rebuilt.ply of its Python
    # example; docs/filters.md the rebuilt.ply, remeshed.ply and out.ply of the README's).
    writes = documented_writes()
    assert len(writes) >= 15 and ("README.md", "report.json", True) in writes
    made, clashes = {}, []
    for name, path, overwrite in writes:
        if path in made and not overwrite:
            clashes.append(f"{name} writes {path}, which {made[path]} made")
        made.setdefault(path, name)
    assert clashes == []
