"""The Python examples of the README and docs/ run as written, with the figures they quote.

Paths in them are relative to the repository root (the bundled example, tests/data, the example
scripts), except the README's first example, which reads a ``patch.obj`` of the user's: it runs in
a scratch folder holding the bundled terrain under that name."""

import os
import re
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
    assert scope["figures"]["error"]["hausdorff_rms"] < 1e-3        # the terrain: ~0.014 %
    assert [s["filter"] for s in scope["steps"]][-1] == "get_curvature_reconstruction_error"
    assert "generate_curvature_remeshing" in capsys.readouterr().out


def test_filters_doc_examples_run_with_the_quoted_error(monkeypatch):
    monkeypatch.chdir(ROOT)
    printed = []
    scope = {"print": printed.append}
    exec(python_blocks("docs/filters.md")[0], scope)
    assert printed[0]["hausdorff_rms"] == pytest.approx(0.00022, abs=0.00002)   # as its comment says
    figures = {s["filter"]: s["figures"] for s in scope["steps"]}
    assert figures["generate_minimal_surface"]["converged"]


def test_remeshing_doc_example_runs_on_the_bundled_nose(monkeypatch):
    monkeypatch.chdir(ROOT)
    scope = {}
    exec(python_blocks("docs/remeshing.md")[0], scope)
    report = scope["report"]
    assert report["error"]["hausdorff_rms"] < 1e-3 < report["baseline_zero_detail"]["hausdorff_rms"]
    assert scope["Dt"].shape == scope["Vt"].shape and scope["Vt"].shape[0] < 640
