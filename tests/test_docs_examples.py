"""The code of the README and of the site's pages runs as written, with the figures it quotes.

Each page runs in a scratch folder holding what the pages read: ``patch.obj`` (the bundled
terrain), ``tests/data`` and ``scripts/examples``."""

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


#: The site's pages whose code runs, in the order of its navigation.
PAGES = ["docs/index.md"] + [f"docs/tutorials/{name}.md" for name in
                             ("reconstruct", "minimal", "editing", "remeshing", "closed", "filters", "evaluate")]
#: Commands the pages show but the tests do not run: ``edit`` reads the deformation benchmark's
#: files (not shipped), ``evaluate`` starts a second Dask cluster after the page's Python one.
NOT_RUN = {"edit", "evaluate"}


def page_blocks(name):
    """``(kind, text)`` of every ```python and ```console block of a page, in order."""
    with open(os.path.join(ROOT, name), encoding="utf-8") as f:
        return re.findall(r"```(python|console)\n(.*?)```", f.read(), flags=re.S)


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES)
def test_site_page_code_runs_in_order(page, tmp_path, monkeypatch, capsys):
    # In a scratch folder with what the pages read: patch.obj (the bundled terrain), the test
    # meshes and the example scripts, so that nothing is written into the repository.
    from curvdetail.cli import main

    shutil.copy(os.path.join(ROOT, "curvdetail", "data", "terrainA_1k.obj"), tmp_path / "patch.obj")
    shutil.copytree(os.path.join(ROOT, "tests", "data"), tmp_path / "tests" / "data")
    shutil.copytree(os.path.join(ROOT, "scripts", "examples"), tmp_path / "scripts" / "examples")
    monkeypatch.chdir(tmp_path)
    scope, ran = {"__name__": "__docs__"}, 0
    for kind, text in page_blocks(page):
        if kind == "python":
            exec(compile(text, page, "exec"), scope)
            ran += 1
            continue
        for line in text.splitlines():
            argv = shlex.split(line.split(" #")[0])[2:] if line.startswith("$ curvdetail ") else []
            if argv and argv[0] not in NOT_RUN:
                assert main(argv) == 0, line
                ran += 1
    assert ran > 0
    capsys.readouterr()


def test_site_pages_quote_what_they_compute(tmp_path, monkeypatch):
    # the figures the getting-started example and the reconstruct tutorial state in comments
    shutil.copy(os.path.join(ROOT, "curvdetail", "data", "terrainA_1k.obj"), tmp_path / "patch.obj")
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(python_blocks("docs/tutorials/minimal.md")[0], scope)
    M, V, b = scope["M"], scope["V"], scope["b"]
    assert M.converged and np.array_equal(M[b], V[b])
    exec(python_blocks("docs/tutorials/editing.md")[0], scope)
    C, D, info = scope["C"], scope["D"], scope["info"]
    assert np.abs(C @ D - D).max() < 1e-9 * np.abs(D).max() and info.rank_deficient == 0


#: Two ways in, each followed top to bottom in one folder: the README alone, and the site's pages
#: in the order of its navigation; and the options of the ``curvdetail`` commands that take a
#: value (the values that are output files are marked True).
READING_ORDERS = [["README.md"],
                  PAGES + [f"docs/guide/{name}.md" for name in ("solvers", "editing", "remeshing", "filters", "evaluate")]]
VALUE_OPTIONS = {"--report": True, "--image": True, "--param": False, "--add": False, "--sel": False,
                 "--def": False, "--target-edge": False, "--method": False, "--transfer": False,
                 "--rows": False, "--location": False, "--parameterization": False, "--backend": False,
                 "--max-iterations": False, "--tol": False, "--step": False, "--handle-detail": False,
                 "--relations": False, "--laplacian": False, "--results": False, "--workers": False,
                 "--study": False, "--summary": False, "--cell-timeout": False, "--cell-memory": False,
                 "--scheduler": False}
FLAG_OPTIONS = {"--overwrite", "--example", "--quiet", "--no-evaluate", "--no-surface-check", "--fix-boundary",
                "--json", "--help"}


def documented_writes(order):
    """``(document, file, overwrite)`` for every file the docs' commands and Python examples
    write, in reading order: the ``curvdetail`` command lines of every fenced block (OUTPUT,
    ``--report``, ``--image``), ``write_mesh`` and pymeshlab's ``save_current_mesh``."""
    writes = []
    for name in order:
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


@pytest.mark.parametrize("order", READING_ORDERS, ids=["README", "site"])
def test_docs_commands_run_in_reading_order_never_write_a_file_an_earlier_one_made(order):
    # Followed top to bottom in one folder, a command whose OUTPUT an earlier step made stops with
    # 'exists; pass --overwrite'.
    writes = documented_writes(order)
    assert ("README.md", "report.json", True) in writes if order == ["README.md"] else len(writes) >= 15
    made, clashes = {}, []
    for name, path, overwrite in writes:
        if path in made and not overwrite:
            clashes.append(f"{name} writes {path}, which {made[path]} made")
        made.setdefault(path, name)
    assert clashes == []
