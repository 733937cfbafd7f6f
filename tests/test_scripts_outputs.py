"""scripts/: every output file is refused, before any work, where it exists (unless the script's
--force; bench_reconstruct.py: --overwrite, or --merge for its JSON) or its folder cannot take it
(missing, not a folder, not writable), and a run's outputs are written together at its end
through curvdetail._output.atomic_outputs, so that a failed run or write leaves every old file
and no temporary one; the commands the docs show still run as written.

Only the cheap paths run: argument parsing, the refusals, --rebuild-markdown, and the scripts'
drivers with their measurements replaced by stubs. The public meshes (/work/shared) are not
needed: the mesh folder is pointed at one that does not exist, so a script that got past its
output check stops at its mesh check, in no time.
"""

import errno
import json
import os
import re
import shlex
import shutil
import sys

import numpy as np
import pytest

from conftest import load_script

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(ROOT, "scripts")


load = load_script


@pytest.fixture
def no_meshes(tmp_path, monkeypatch):
    """The scripts' mesh folder is one that does not exist (their mesh check exits at once)."""
    monkeypatch.syspath_prepend(SCRIPTS)
    import _meshes

    missing = str(tmp_path / "no-meshes")
    monkeypatch.setattr(_meshes, "MESHES", missing)
    monkeypatch.setenv("CURVDETAIL_MESHES", missing)
    return missing


def snapshot(folder):
    """``{relative path: bytes}`` of every file under ``folder`` (hidden ones too)."""
    out = {}
    for dirpath, _, names in os.walk(folder):
        for name in names:
            path = os.path.join(dirpath, name)
            with open(path, "rb") as fh:
                out[os.path.relpath(path, folder)] = fh.read()
    return out


def leftovers(folder):
    """Temporary files or kept-aside folders a write left under ``folder``."""
    return [os.path.join(d, n) for d, dirs, names in os.walk(folder) for n in names + dirs
            if n.startswith(".curvdetail-") or n.endswith(".tmp")]


def write(path, text):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


# --- _outputs.Run --------------------------------------------------------------------------------

def test_run_keeps_only_outputs_checked_before_the_work(tmp_path, monkeypatch):
    import argparse

    monkeypatch.syspath_prepend(SCRIPTS)
    import _outputs

    run = _outputs.Run(argparse.ArgumentParser(), [str(tmp_path / "a.txt")], False)
    with pytest.raises(ValueError, match="b.txt was not checked"):
        run.write_text(str(tmp_path / "b.txt"), "late")
    run.write_text(str(tmp_path / "a.txt"), "checked")
    run.commit()
    assert os.listdir(tmp_path) == ["a.txt"]


# --- bench_reconstruct.py -----------------------------------------------------------------------

def fake_result(case, *_):
    """What a bench_reconstruct case reports (the stub of its subprocess)."""
    from_size = {"10k": 10_000, "100k": 99_856, "1M": 1_000_000}
    return dict(case, n=from_size[case["size"]], backend="pardiso", unknowns=9_000, trials=1,
                factor_s=0.5, solve_s=0.1, resolve_s=0.02, total_s=0.6, max_error=1e-14,
                max_error_resolve=2e-14, peak_rss_gb=0.3, inputs_rss_gb=0.1, wall_s=1.0)


META = {"date": "2026-12-01 00:00 UTC", "cpus": 2, "cpu": "test CPU", "machine": "test machine",
        "numpy": "2", "scipy": "1"}
BENCH_DOC = "# Benchmarks\n\nbefore\n\n<!-- bench:begin -->\nold table\n<!-- bench:end -->\n\nafter\n"


@pytest.fixture
def bench_reconstruct(monkeypatch):
    """bench_reconstruct.py with its cases stubbed: ``(module, the cases it was asked to run)``."""
    module = load("bench_reconstruct")
    calls = []

    def run(case, timeout, mem_limit_gb=None):
        calls.append(case)
        return fake_result(case)

    monkeypatch.setattr(module, "run_in_subprocess", run)
    monkeypatch.setattr(module, "installed_methods", lambda: ["reconstruct", "pardiso", "splu", "spsolve"])
    return module, calls


def stored_results(tmp_path):
    path = tmp_path / "bench.json"
    case = {"surface": "grid", "size": "10k", "rows": "free", "method": "reconstruct"}
    path.write_text(json.dumps({"meta": META, "results": [fake_result(case)]}))
    return str(path)


def test_bench_reconstruct_rebuild_markdown_refuses_an_existing_file_without_overwrite(tmp_path, capsys):
    md = tmp_path / "bench.md"
    md.write_text(BENCH_DOC)
    module = load("bench_reconstruct")
    with pytest.raises(SystemExit) as exit_:
        module.main(["--rebuild-markdown", "--out", stored_results(tmp_path), "--markdown", str(md)])
    assert exit_.value.code == 2
    message = capsys.readouterr().err
    assert str(md) in message and "--overwrite" in message
    assert md.read_text() == BENCH_DOC


@pytest.mark.parametrize("stored", [None, "{not json", '{"meta": {}}'])
def test_bench_reconstruct_rebuild_markdown_without_usable_results_says_so(tmp_path, capsys, stored):
    # on a fresh checkout (no earlier run) it stopped with FileNotFoundError's traceback
    md = tmp_path / "bench.md"
    md.write_text(BENCH_DOC)
    out = tmp_path / "bench.json"
    if stored is not None:
        out.write_text(stored)
    module = load("bench_reconstruct")
    with pytest.raises(SystemExit) as exit_:
        module.main(["--rebuild-markdown", "--out", str(out), "--markdown", str(md), "--overwrite"])
    assert exit_.value.code == 2
    message = capsys.readouterr().err
    assert "--rebuild-markdown reads the results of earlier runs from --out" in message
    assert "run the benchmark first" in message
    assert md.read_text() == BENCH_DOC


def test_bench_reconstruct_rebuild_markdown_with_overwrite_rewrites_only_the_block(tmp_path):
    md = tmp_path / "bench.md"
    md.write_text(BENCH_DOC)
    module = load("bench_reconstruct")
    assert module.main(["--rebuild-markdown", "--out", stored_results(tmp_path), "--markdown", str(md),
                        "--overwrite"]) == 0
    text = md.read_text()
    assert text.startswith("# Benchmarks\n\nbefore\n\n<!-- bench:begin -->\n")
    assert text.endswith("<!-- bench:end -->\n\nafter\n")
    assert "old table" not in text and "| grid | 10,000 | free | **reconstruct** (pardiso) |" in text
    assert sorted(os.listdir(tmp_path)) == ["bench.json", "bench.md"]      # no temporary file left


def test_bench_reconstruct_refuses_an_existing_out_before_any_case_and_merge_updates_it(
        tmp_path, bench_reconstruct, capsys):
    module, calls = bench_reconstruct
    out = stored_results(tmp_path)
    before = open(out).read()
    args = ["--sizes", "10k", "--surfaces", "sphere", "--rows", "all", "--methods", "splu",
            "--out", out, "--markdown", ""]
    with pytest.raises(SystemExit) as exit_:
        module.main(args)
    assert exit_.value.code == 2 and calls == []                    # refused before any case ran
    message = capsys.readouterr().err
    assert out in message and "--overwrite" in message and "--merge" in message
    assert open(out).read() == before
    assert module.main(args + ["--merge"]) == 0                     # --merge is asked to update it
    kept = json.load(open(out))["results"]
    assert [(r["surface"], r["method"]) for r in kept] == [("grid", "reconstruct"), ("sphere", "splu")]
    assert leftovers(tmp_path) == []


def test_bench_reconstruct_force_runs_left_out_cases_but_does_not_replace_files(
        tmp_path, bench_reconstruct, capsys):
    module, calls = bench_reconstruct
    out = stored_results(tmp_path)
    before = open(out).read()
    with pytest.raises(SystemExit) as exit_:
        module.main(["--sizes", "10k", "--methods", "splu", "--out", out, "--markdown", "", "--force"])
    assert exit_.value.code == 2 and calls == []
    assert "--overwrite" in capsys.readouterr().err
    assert open(out).read() == before


def test_bench_reconstruct_refuses_one_file_named_for_out_and_markdown(tmp_path, capsys, monkeypatch,
                                                                       bench_reconstruct):
    monkeypatch.chdir(tmp_path)
    module, calls = bench_reconstruct
    with pytest.raises(SystemExit) as exit_:
        module.main(["--sizes", "10k", "--surfaces", "grid", "--rows", "free", "--methods", "splu",
                     "--out", "bench.json", "--markdown", "./bench.json"])
    assert exit_.value.code == 2 and calls == []
    assert "given for two outputs" in capsys.readouterr().err


def test_bench_reconstruct_refuses_a_markdown_folder_that_does_not_exist_before_any_case(
        tmp_path, bench_reconstruct, capsys):
    module, calls = bench_reconstruct
    md = os.path.join(str(tmp_path), "no-docs", "bench.md")
    with pytest.raises(SystemExit) as exit_:
        module.main(["--sizes", "10k", "--methods", "splu", "--out", str(tmp_path / "b.json"),
                     "--markdown", md])
    assert exit_.value.code == 2 and calls == []
    message = capsys.readouterr().err
    assert md in message and "mkdir -p" in message
    assert os.listdir(tmp_path) == []


def fail_rename_to(monkeypatch, path):
    """``os.replace`` or ``os.link`` onto ``path`` fails as on a full disk (every other rename or
    link works): a commit without overwrite links its file into place, one with it renames."""
    target = os.path.abspath(path)

    def failing(real):
        def move(src, dst, **kw):
            if os.path.abspath(dst) == target:
                raise OSError(errno.ENOSPC, "No space left on device")
            return real(src, dst, **kw)
        return move

    monkeypatch.setattr(os, "replace", failing(os.replace))
    monkeypatch.setattr(os, "link", failing(os.link))


def test_bench_reconstruct_run_of_one_group_writes_out_and_markdown_together(
        tmp_path, bench_reconstruct, monkeypatch):
    module, calls = bench_reconstruct
    out, md = stored_results(tmp_path), tmp_path / "bench.md"
    md.write_text(BENCH_DOC)
    before = snapshot(tmp_path)
    fail_rename_to(monkeypatch, md)
    with pytest.raises(OSError, match="bench.md"):
        module.main(["--sizes", "10k", "--surfaces", "sphere", "--rows", "free", "--methods", "splu",
                     "--out", out, "--markdown", str(md), "--overwrite"])
    assert calls                                                    # the work was done
    assert snapshot(tmp_path) == before                             # the JSON is not replaced either
    assert leftovers(tmp_path) == []


def test_bench_reconstruct_run_of_several_groups_keeps_the_groups_done_when_stopped(
        tmp_path, bench_reconstruct, monkeypatch):
    """The progress save of --out, kept on purpose: each group is committed once it is done."""
    module, calls = bench_reconstruct

    def run(case, timeout, mem_limit_gb=None):
        if case["surface"] == "sphere":
            raise KeyboardInterrupt
        calls.append(case)
        return fake_result(case)

    monkeypatch.setattr(module, "run_in_subprocess", run)
    out = tmp_path / "new" / "b.json"
    with pytest.raises(KeyboardInterrupt):
        module.main(["--sizes", "10k", "--surfaces", "grid,sphere", "--rows", "free", "--methods", "splu",
                     "--out", str(out), "--markdown", ""])
    assert [r["surface"] for r in json.load(open(out))["results"]] == ["grid"]
    assert leftovers(tmp_path) == []


def documented_commands(text, script):
    """The ``python scripts/SCRIPT ...`` command lines in ``text`` (continuations joined), as
    argument lists."""
    text = text.replace("\\\n", " ")
    found = re.findall(r"python scripts/" + re.escape(script) + r"([^`\n]*)", text)
    return [shlex.split(args, comments=True) for args in found]


def run_documented_in_order(module, commands, tree, changed_ok):
    """Run ``commands`` in order in ``tree``; each must succeed, and any file that existed
    before a command and changed must be allowed by that command (``changed_ok(path, args)``)."""
    for args in commands:
        before = snapshot(tree)
        assert module.main(list(args)) == 0, args
        after = snapshot(tree)
        replaced = [path for path in before if after.get(path) != before[path]]
        assert all(changed_ok(path, args) for path in replaced), (args, replaced)
        assert leftovers(tree) == []


def bench_reconstruct_may_replace(path, args):
    out = args[args.index("--out") + 1] if "--out" in args else "out/bench_reconstruct.json"
    return "--overwrite" in args or ("--merge" in args and os.path.normpath(path) == os.path.normpath(out))


@pytest.mark.parametrize("where", ["docs/benchmarks.md", "the script's docstring"])
def test_documented_bench_reconstruct_commands_run_as_written_from_a_fresh_checkout(
        where, tmp_path, monkeypatch, bench_reconstruct):
    """A fresh checkout has docs/benchmarks.md (committed) and no out/ (ignored): the commands
    shown run in order, and those that replace an existing file say so."""
    module, calls = bench_reconstruct
    shutil.copytree(os.path.join(ROOT, "docs"), tmp_path / "docs", ignore=shutil.ignore_patterns("*.png"))
    original = (tmp_path / "docs" / "benchmarks.md").read_text()
    monkeypatch.chdir(tmp_path)
    text = original if where == "docs/benchmarks.md" else module.__doc__
    commands = documented_commands(text, "bench_reconstruct.py")
    assert len(commands) >= 3
    run_documented_in_order(module, commands, str(tmp_path), bench_reconstruct_may_replace)
    assert calls
    refreshed = (tmp_path / "docs" / "benchmarks.md").read_text()
    begin, end = module.BEGIN, module.END
    assert refreshed[:refreshed.index(begin)] == original[:original.index(begin)]
    assert refreshed[refreshed.index(end):] == original[original.index(end):]
    assert "**reconstruct** (pardiso)" in refreshed


# --- bench_operations.py ------------------------------------------------------------------------

def test_bench_operations_failed_write_keeps_the_old_report_and_leaves_no_temporary_file(
        tmp_path, monkeypatch):
    module = load("bench_operations")
    out = tmp_path / "ops.json"
    out.write_text('{"old": true}\n')
    # a figure json cannot write: the report fails half-way through its file
    monkeypatch.setattr(module, "in_subprocess", lambda *a: {"seconds": 0.1, "engine": object()})
    with pytest.raises(TypeError):
        module.main(["--sizes", "10k", "--cases", "edge_measure", "--out", str(out), "--force"])
    assert out.read_text() == '{"old": true}\n'
    assert os.listdir(tmp_path) == ["ops.json"]


def test_bench_operations_refuses_an_out_folder_that_cannot_be_made_before_any_case(
        tmp_path, monkeypatch, capsys):
    module = load("bench_operations")
    calls = []
    monkeypatch.setattr(module, "in_subprocess", lambda *a: calls.append(a) or {"seconds": 0.1})
    (tmp_path / "results").write_text("a file, not a folder")
    out = str(tmp_path / "results" / "ops.json")
    with pytest.raises(SystemExit) as exit_:
        module.main(["--sizes", "10k", "--cases", "edge_measure", "--out", out])
    assert exit_.value.code == 2 and calls == []                    # found before the work
    message = capsys.readouterr().err
    assert out in message and "not a folder" in message


# --- the scripts on the public meshes: refusals before any work ---------------------------------

#: (script, arguments, an output file of that run, relative to the working folder)
REFUSALS = [
    ("bench_editing", [], "out/bench_editing.json"),
    ("bench_editing", ["--out", "b/e.json", "--skip-100k"], "b/e.json"),
    ("compare_deformation_benchmark", [], "out/compare/compare.md"),
    ("compare_deformation_benchmark", ["--out", "c"], "c/plane.png"),
    ("compare_deformation_benchmark", ["--docs", "docs"], "docs/editing_cactus.png"),
    ("reproduce_fig1", [], "out/fig1/fig1b.png"),
    ("reproduce_fig1", ["--out", "f"], "f/fig1.json"),
    ("reproduce_fig1", ["--docs", "docs"], "docs/editing_fig1.png"),
    ("reproduce_fig2", [], "out/fig2/fig2.json"),
    ("reproduce_fig2", ["--docs", "docs"], "docs/editing_fig2.png"),
    ("reproduce_table1", [], "out/table1/table1.md"),
    ("reproduce_table1", ["--out", "t", "--repeat", "3"], "t/table1.png"),
]
IDS = [f"{script}-{existing}" for script, _, existing in REFUSALS]


@pytest.mark.parametrize("script, args, existing", REFUSALS, ids=IDS)
def test_script_refuses_an_existing_output_before_any_work(script, args, existing, tmp_path, monkeypatch,
                                                           no_meshes, capsys):
    monkeypatch.chdir(tmp_path)
    write(existing, "old")
    before = snapshot(tmp_path)
    module = load(script)
    with pytest.raises(SystemExit) as exit_:
        module.main(args)
    assert exit_.value.code == 2                                    # a usage error, not the mesh check
    message = capsys.readouterr().err
    assert existing in message and "--force" in message
    assert snapshot(tmp_path) == before                             # not even a folder made
    assert sorted(os.listdir(tmp_path)) == sorted({existing.split("/")[0]})


@pytest.mark.parametrize("script, args, existing", REFUSALS, ids=IDS)
def test_script_with_force_gets_past_the_output_check(script, args, existing, tmp_path, monkeypatch,
                                                      no_meshes):
    monkeypatch.chdir(tmp_path)
    write(existing, "old")
    module = load(script)
    with pytest.raises(SystemExit) as exit_:
        module.main(args + ["--force"])
    assert "does not hold" in str(exit_.value.code)                 # stopped at the mesh check
    assert open(existing).read() == "old"


#: (script, arguments, the folder refused) where an output's folder is missing, not a folder or
#: cannot be made; "afile" is a file in the working folder
FOLDER_REFUSALS = [
    ("compare_deformation_benchmark", ["--docs", "no-docs"], "no-docs", "does not exist"),
    ("reproduce_fig1", ["--docs", "no-docs"], "no-docs", "does not exist"),
    ("reproduce_fig2", ["--docs", "no-docs"], "no-docs", "does not exist"),
    ("reproduce_fig2", ["--docs", "afile"], "afile", "not a folder"),
    ("reproduce_table1", ["--out", "afile/table1"], "afile", "not a folder"),
    ("bench_editing", ["--out", "afile/e.json"], "afile", "not a folder"),
]


@pytest.mark.parametrize("script, args, folder, why", FOLDER_REFUSALS,
                         ids=[f"{script}-{why}" for script, _, _, why in FOLDER_REFUSALS])
def test_script_refuses_an_output_folder_it_cannot_write_in_before_any_work(
        script, args, folder, why, tmp_path, monkeypatch, no_meshes, capsys):
    monkeypatch.chdir(tmp_path)
    write("afile", "a file")
    module = load(script)
    with pytest.raises(SystemExit) as exit_:
        module.main(args + ["--force"])
    assert exit_.value.code == 2                                    # a usage error, not the mesh check
    message = capsys.readouterr().err
    assert folder in message and why in message
    if why == "does not exist":
        assert f"mkdir -p {folder}" in message                      # the fix
    assert snapshot(tmp_path) == {"afile": b"a file"}               # no folder made


@pytest.mark.parametrize("args, why", [(["--docs", "locked"], "folder 'locked' is not writable"),
                                       (["--out", "locked/fig1"], "'locked/fig1' cannot be made")])
def test_script_refuses_an_output_folder_that_is_not_writable_before_any_work(
        args, why, tmp_path, monkeypatch, no_meshes, capsys):
    """The tests may run as root, who may write anywhere: os.access is made to deny the folder."""
    monkeypatch.chdir(tmp_path)
    os.mkdir("locked")
    locked, real = str(tmp_path / "locked"), os.access
    monkeypatch.setattr(os, "access",
                        lambda p, mode, **kw: os.path.abspath(p) != locked and real(p, mode, **kw))
    module = load("reproduce_fig1")
    with pytest.raises(SystemExit) as exit_:
        module.main(args)
    assert exit_.value.code == 2
    message = capsys.readouterr().err
    assert why in message and "make it writable or name another folder" in message
    assert os.listdir("locked") == []


def tiny_case(name, folder):
    """What compare_deformation_benchmark.run_case returns, on a 4 x 4 grid (the stub)."""
    from curvdetail.curvature.testing import grid

    V, F = grid(4, 4)
    status = np.zeros(V.shape[0], dtype=int)
    row = {"case": name, "vertices": 16, "n_fixed": 16, "n_free": 0, "n_handles": 0,
           "reference_moved_mean": 0.0, "reference_moved_max": 0.0}
    for mode in ("transform/one-ring", "transform/one+two-ring", "free/one-ring"):
        row[mode] = {"mean": 0.01, "max": 0.02, "first_solve_s": 0.1, "resolve_s": 0.001, "resolve_best_s": 0.001,
                     "editor": object()}                            # json cannot write this one
    return row, (V, F, status, {mode: V + 0.01 for mode in row if "/" in mode}, V)


def test_compare_deformation_benchmark_failed_run_writes_no_output_and_keeps_the_old_ones(
        tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(SCRIPTS)
    import _meshes

    (tmp_path / "meshes" / "deformation").mkdir(parents=True)
    monkeypatch.setattr(_meshes, "MESHES", str(tmp_path / "meshes"))
    module = load("compare_deformation_benchmark")
    monkeypatch.setattr(module, "CASES", ("bar",))                  # one picture: fast
    monkeypatch.setattr(module, "run_case", tiny_case)
    out = tmp_path / "out"
    with pytest.raises(TypeError):                                  # no earlier files
        module.main(["--out", str(out)])
    assert not out.exists()                     # not the picture made before the failure, nor the folder
    old = {"compare.json": "old json", "compare.md": "old table", "bar.png": "old picture"}
    for name, text in old.items():
        write(out / name, text)
    with pytest.raises(TypeError):
        module.main(["--out", str(out), "--force"])
    assert snapshot(out) == {name: text.encode() for name, text in old.items()}
    assert leftovers(tmp_path) == []


@pytest.fixture
def table1(monkeypatch):
    """reproduce_table1.py with its meshes and timings stubbed (4 x 4 grids, fixed figures)."""
    from curvdetail.curvature.testing import grid

    module = load("reproduce_table1")
    med = {"total": 0.01, "coefficients": 0.001, "curvature_stage": 0.002, "embedding": 0.003,
           "rest_check": 0.0001, "resolve": 0.0005, "total_min": 0.009}
    monkeypatch.setattr(module, "require", lambda *names: None)
    monkeypatch.setattr(module, "table1_meshes", lambda: {name: grid(4, 4) for name, *_ in module.PAPER})
    monkeypatch.setattr(module, "time_edit", lambda V, F, repeat: (dict(med), V + 0.01, None))
    return module


def fail_temporary_file_for(monkeypatch, suffix, folder):
    """The temporary file of an output ending in ``suffix`` in ``folder`` cannot be made (full disk)."""
    import tempfile

    real, folder = tempfile.mkstemp, os.path.abspath(folder)

    def mkstemp(*args, **kw):
        if kw.get("suffix") == suffix and os.path.abspath(kw.get("dir") or "") == folder:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(*args, **kw)

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)


@pytest.mark.parametrize("failure", ["temporary file", "rename"])
def test_reproduce_table1_output_that_cannot_be_written_leaves_every_old_file(failure, table1, tmp_path,
                                                                              monkeypatch):
    """The third output (table1.png) fails, before the renames (its temporary file cannot be made)
    or during them (its rename): the first two are not replaced either."""
    out = tmp_path / "table1"
    old = {"table1.json": "old json", "table1.md": "old table", "table1.png": "old picture"}
    for name, text in old.items():
        write(out / name, text)
    new = tmp_path / "new" / "table1"                               # a folder the run makes
    if failure == "temporary file":
        fail_temporary_file_for(monkeypatch, ".png", out)
        fail_temporary_file_for(monkeypatch, ".png", new)
    else:
        fail_rename_to(monkeypatch, out / "table1.png")
        fail_rename_to(monkeypatch, new / "table1.png")
    with pytest.raises(OSError, match="table1.png"):
        table1.main(["--out", str(out), "--repeat", "1", "--force"])
    assert snapshot(out) == {name: text.encode() for name, text in old.items()}
    with pytest.raises(OSError, match="table1.png"):
        table1.main(["--out", str(new), "--repeat", "1"])
    assert not (tmp_path / "new").exists()                          # the folders it made are removed
    assert leftovers(tmp_path) == []


def test_reproduce_table1_writes_its_three_outputs(table1, tmp_path):
    out = tmp_path / "a" / "table1"
    assert table1.main(["--out", str(out), "--repeat", "1"]) == 0
    assert sorted(os.listdir(out)) == ["table1.json", "table1.md", "table1.png"]
    assert (out / "table1.png").read_bytes().startswith(b"\x89PNG")
    report = json.load(open(out / "table1.json"))
    assert report["repeat"] == 1 and report["config"] == {"lift_fraction_of_diagonal": 0.1}
    assert 0 < report["peak_rss_gb"] < 1e3 and len(report["load_average"]) == 3 and report["utc"]
    assert [(row["vertices"], row["facets"]) for row in report["rows"]] == [(16, 18)] * 5


def test_reproduce_fig1_docs_composite_is_made_from_the_pictures_of_the_run(tmp_path, monkeypatch):
    """The pictures are kept in memory until the commit: the --docs composite reads them there."""
    from curvdetail.curvature.testing import grid

    module = load("reproduce_fig1")
    V, F = grid(4, 4)

    def edit(name):
        return lambda: (V, F, V + 0.01, {"model": name}, False)

    monkeypatch.setattr(module, "require", lambda *names: None)
    for name in ("elephant", "cactus", "devil"):
        monkeypatch.setattr(module, name, edit(name))
    os.mkdir(tmp_path / "docs")
    assert module.main(["--out", str(tmp_path / "out"), "--docs", str(tmp_path / "docs")]) == 0
    assert sorted(os.listdir(tmp_path / "out")) == ["fig1.json", "fig1a.png", "fig1b.png", "fig1c.png"]
    assert (tmp_path / "docs" / "editing_fig1.png").read_bytes().startswith(b"\x89PNG")
    assert leftovers(tmp_path) == []


def test_documented_compare_command_passes_the_flag_that_the_committed_pictures_need(
        tmp_path, monkeypatch, no_meshes, capsys):
    """docs/editing.md's command refreshes the committed docs/editing_NAME.png: it runs as
    written (up to the mesh check here), and without its --force it would be refused."""
    with open(os.path.join(ROOT, "docs", "editing.md"), encoding="utf-8") as fh:
        (args,) = documented_commands(fh.read(), "compare_deformation_benchmark.py")
    monkeypatch.chdir(tmp_path)
    for name in ("bar", "cactus", "cylinder", "plane"):
        write(f"docs/editing_{name}.png", "committed")
    module = load("compare_deformation_benchmark")
    with pytest.raises(SystemExit) as exit_:
        module.main(args)
    assert "does not hold" in str(exit_.value.code)
    with pytest.raises(SystemExit) as exit_:
        module.main([a for a in args if a != "--force"])
    assert exit_.value.code == 2 and "docs/editing_bar.png" in capsys.readouterr().err


def png_size(path):
    """``(width, height)`` in pixels, from the PNG header."""
    header = open(path, "rb").read(24)
    return int.from_bytes(header[16:20], "big"), int.from_bytes(header[20:24], "big")


def test_reproduce_fig1_docs_composite_keeps_each_picture_at_its_own_resolution(tmp_path, monkeypatch):
    # docs/editing_fig1.png was the three pictures squeezed into one row, 960 x 256 px at 80 dpi:
    # labels ~3 px tall. Now one row per sub-figure, each picture as rendered (100 dpi)
    from curvdetail.curvature.testing import grid

    module = load("reproduce_fig1")
    V, F = grid(4, 4)
    monkeypatch.setattr(module, "require", lambda *names: None)
    for name in ("elephant", "cactus", "devil"):
        monkeypatch.setattr(module, name, lambda name=name: (V, F, V + 0.01, {"model": name}, False))
    os.mkdir(tmp_path / "docs")
    assert module.main(["--out", str(tmp_path / "out"), "--docs", str(tmp_path / "docs")]) == 0
    sizes = [png_size(tmp_path / "out" / f"fig1{key}.png") for key in "abc"]
    width, height = png_size(tmp_path / "docs" / "editing_fig1.png")
    assert abs(width - max(w for w, _ in sizes)) <= 2 and abs(height - sum(h for _, h in sizes)) <= 3
    report = json.load(open(tmp_path / "out" / "fig1.json"))
    assert [edit["model"] for edit in report["edits"]] == ["elephant", "cactus", "devil"]
    assert 0 < report["peak_rss_gb"] < 1e3 and len(report["load_average"]) == 3 and report["utc"]


def devil_head(horns=True):
    """A z-up height field standing in for mannequin_devil (face towards -y, the boundary as its
    neck): a smooth dome whose crown (0, 0, 1) is higher than two sharp horns at (+-0.4, -0.4),
    tips at z = 0.96; the +x tip is vertex 1140, the -x tip 1116."""
    from curvdetail.curvature.testing import grid

    V, F = grid(61, 61, size=(2.0, 2.0))
    V[:, :2] -= 1.0
    x, y = V[:, 0], V[:, 1]
    V[:, 2] = 1.0 - 0.5 * (x ** 2 + y ** 2)
    if horns:
        for cx in (0.4, -0.4):
            V[:, 2] += 0.12 * np.exp(-((x - cx) ** 2 + (y + 0.4) ** 2) / (2 * 0.06 ** 2))
    return V, F


def test_reproduce_fig1_devil_scales_the_details_of_a_horn_not_of_the_crown(monkeypatch):
    # the tip was the highest vertex with y > 0.25 max y ("face towards +x"): on mannequin_devil
    # (face towards -y) the smooth crown, |K| 0.157 against a median of 0.65, so the reported
    # "horn length x0.88 / x1.42" was the head stretching; the real horn: x0.48 / x2.04
    module = load("reproduce_fig1")
    V, F = devil_head()
    monkeypatch.setattr(module, "read_mesh", lambda path: (V.copy(), F.copy()))
    _, _, X2, info, _ = module.devil()
    X05 = info["extra_panel"][0]
    diag = np.linalg.norm(np.ptp(V, axis=0))

    def length(X, tip):
        d = np.linalg.norm(V - V[tip], axis=1)
        ring = np.flatnonzero((d >= 0.05 * diag) & (d < 0.06 * diag))
        return np.linalg.norm(X[tip] - X[ring].mean(0)) / np.linalg.norm(V[tip] - V[ring].mean(0))

    assert length(X05, 1140) < 0.6 and length(X2, 1140) > 1.8                 # 0.51, 2.00
    assert abs(length(X05, 1116) - 1) < 0.1 and abs(length(X2, 1116) - 1) < 0.15   # 1.05, 0.91
    assert (info["tip"], info["other_tip"]) == (1140, 1116)
    assert info["detail_x2.0"]["horn_length_ratio"] == pytest.approx(length(X2, 1140))
    assert info["faces"] == F.shape[0] and info["config"]["detail_scales"] == [0.5, 2.0]


def test_reproduce_fig1_devil_without_a_sharp_tip_on_the_face_side_is_refused(monkeypatch):
    module = load("reproduce_fig1")
    V, F = devil_head(horns=False)
    monkeypatch.setattr(module, "read_mesh", lambda path: (V.copy(), F.copy()))
    with pytest.raises(ValueError, match="no sharp local z-maximum on the face side.*mannequin_devil.off"):
        module.devil()


def spot_as_the_cow():
    """tests/data/spot.obj (y up, head towards +z) turned and scaled to the cow's frame of
    reproduce_fig2.py (head towards +x, x up to 0.52): 260 vertices beyond x = 0.42 (its handles),
    the region beyond x = 0.18."""
    from curvdetail import read_mesh

    V, F = read_mesh(os.path.join(ROOT, "tests", "data", "spot.obj"))
    return 0.5 * V[:, [2, 1, 0]] * [1.0, 1.0, -1.0], F


def test_reproduce_fig2_cow_has_the_papers_edit_that_turns_only_the_handles_curvature_normals(monkeypatch):
    # every variant placed the handles (35-degree turn plus a move towards the reader); the
    # paper turns only the feature points' curvature normals and lets the embedding place them
    module = load("reproduce_fig2")
    V, F = spot_as_the_cow()
    monkeypatch.setattr(module, "read_mesh", lambda path: (V.copy(), F.copy()))
    V0, F0, status, meshes, out = module.cow()
    handles, fixed = status == 2, status == 0
    T = np.asarray(out["config"]["transform"])
    placed = V[handles] @ T[:3, :3].T + T[:3, 3]
    assert out["faces"] == F.shape[0] and out["config"]["turn_degrees"] == 35.0
    for relations in ("one-ring", "one+two-ring"):
        paper, moved = out[f"paper/transform/{relations}"], out[f"moved/transform/{relations}"]
        assert paper["position_constrained"] == 0 and moved["position_constrained"] == handles.sum()
        X = meshes[f"paper/transform/{relations}"]
        np.testing.assert_array_equal(X[fixed], V[fixed])
        assert paper["handle_centroid_move_fraction"] > 1e-3                   # the head did turn
        assert np.abs(X[handles] - placed).max() > 1e-3                       # not placed by T
        np.testing.assert_allclose(meshes[f"moved/transform/{relations}"][handles], placed, atol=1e-9)


def test_reproduce_fig2_terrain_json_keeps_the_boundary_detail_mode(monkeypatch):
    # "boundary_detail" was stored after the variable had become "deformed/one-ring"
    from curvdetail import read_mesh

    module = load("reproduce_fig2")
    V, F = read_mesh(os.path.join(ROOT, "tests", "data", "terrainA_1k.obj"))
    monkeypatch.setattr(module, "read_mesh", lambda path: (V.copy(), F.copy()))
    _, _, meshes, out = module.terrain()
    for sine in ("sine_y", "sine_z"):
        for mode, relations in (("deformed", "one-ring"), ("deformed", "one+two-ring"), ("rest", "one-ring")):
            case = out[f"{sine}_{mode}/{relations}"]
            assert (case["boundary_detail"], case["relations"]) == (mode, relations)
    assert out["faces"] == F.shape[0] and out["config"]["periods"] == 2


def test_compare_deformation_benchmark_reports_the_median_of_warm_re_solves(monkeypatch):
    # the re-solve time was one solve straight after the constructor
    from curvdetail.curvature.testing import grid

    module = load("compare_deformation_benchmark")
    V, F = grid(4, 4)
    status = np.ones(16, dtype=int)
    status[:4], status[-4:] = 0, 2
    clock = [0.0]
    durations = []

    class Editor:
        position_constrained = np.arange(12, 16)
        detail = np.zeros((16, 3))
        backend = {"curvature": "splu", "embedding": "splu"}
        rank_deficient = detail_islands = 0

        def solve(self, **values):
            clock[0] += durations.pop(0)
            return V

    def edit(V, F, status, T, **options):
        assert options["rcond"] == module.RCOND
        durations[:] = [1.0] + [0.5, 0.1, 0.3, 0.2, 0.4, 0.6, 0.7, 0.8, 0.9][:module.RESOLVES]
        return V.copy(), Editor()

    monkeypatch.setattr(module, "read_mesh", lambda path: (V.copy(), F.copy()))
    monkeypatch.setattr(module, "read_selection", lambda path, n: status)
    monkeypatch.setattr(module, "read_transform", lambda path: np.eye(4))
    monkeypatch.setattr(module, "edit_with_selection", edit)
    monkeypatch.setattr(module.time, "perf_counter", lambda: clock[0])
    row, _ = module.run_case("bar", "folder")
    times = [0.5, 0.1, 0.3, 0.2, 0.4, 0.6, 0.7, 0.8, 0.9][:module.RESOLVES]
    assert module.RESOLVES >= 5
    for variant in ("transform/one-ring", "transform/one+two-ring", "free/one-ring"):
        assert row[variant]["resolve_warmup_s"] == 1.0 and row[variant]["resolves"] == module.RESOLVES
        assert row[variant]["resolve_s"] == pytest.approx(np.median(times))                  # 0.4
        assert row[variant]["resolve_best_s"] == pytest.approx(0.1)
        assert row[variant]["backend"] == {"curvature": "splu", "embedding": "splu"}
    assert row["faces"] == F.shape[0] and row["files"]["reference"] == "bar-laplacian_editing.off"
    assert row["rcond"] == module.RCOND


@pytest.mark.parametrize("script, committed", [("reproduce_fig1", "docs/editing_fig1.png"),
                                               ("reproduce_fig2", "docs/editing_fig2.png"),
                                               ("reproduce_table1", None)])
def test_documented_reproduction_commands_run_as_written(script, committed, tmp_path, monkeypatch,
                                                          no_meshes, capsys):
    """docs/editing.md gives the one command that produced each figure or table: it runs as
    written (up to the mesh check here); one that refreshes a committed picture needs --force."""
    with open(os.path.join(ROOT, "docs", "editing.md"), encoding="utf-8") as fh:
        (args,) = documented_commands(fh.read(), script + ".py")
    monkeypatch.chdir(tmp_path)
    os.mkdir("docs")
    if committed:
        write(committed, "committed")
    module = load(script)
    with pytest.raises(SystemExit) as exit_:
        module.main(args)
    assert "does not hold" in str(exit_.value.code)
    if committed:
        with pytest.raises(SystemExit) as exit_:
            module.main([a for a in args if a != "--force"])
        assert exit_.value.code == 2 and committed in capsys.readouterr().err


# --- reproduce_fig3.py (ROOT is pointed at a scratch repository, the working folder) ------------

@pytest.fixture
def fig3(tmp_path, monkeypatch):
    """``(run, the scratch repository, its module)``: ``run(*args)`` runs reproduce_fig3.py with
    ``args`` in the scratch repository (and a mesh folder that exists and holds no mesh)."""
    module = load("reproduce_fig3")
    repo = tmp_path / "repo"
    repo.mkdir()
    monkeypatch.setattr(module, "ROOT", str(repo))
    monkeypatch.chdir(repo)
    (tmp_path / "meshes").mkdir()

    def run(*args):
        monkeypatch.setattr(sys, "argv", ["reproduce_fig3.py", "--meshes", str(tmp_path / "meshes"), *args])
        return module.main()

    return run, repo, module


DOCS_FILES = {"docs/fig3_table.md": "old tables\n", "docs/fig3.png": "old picture",
              "docs/remeshing.md": "text\n<!-- fig3-table -->\nold tables\n<!-- /fig3-table -->\nmore\n"}
README_TEXT = "intro\n<!-- fig3-readme-table -->\nold short table\n<!-- /fig3-readme-table -->\nrest\n"
FIG3_MESHES = ["mannequin_nose.obj", "mannequin_ear.obj", "elephant_trunk.obj", "terrainA_10k.obj",
               "camelhead.off", "mannequin_disk_1k.obj", "terrainA_100k.ply"]

#: (arguments, an output of that run that exists, relative to the scratch repository)
FIG3_REFUSALS = [([], "out/fig3/results.json"), ([], "out/fig3/fig3_table.md"), ([], "out/fig3/fig3.png"),
                 (["--out", "elsewhere"], "elsewhere/fig3.png"), (["--quick"], "out/fig3/table_quick.md"),
                 (["--docs", "docs"], "docs/fig3_table.md"), (["--docs", "docs"], "docs/fig3.png"),
                 (["--docs", "docs"], "docs/remeshing.md"), (["--readme", "README.md"], "README.md")]


@pytest.mark.parametrize("args, existing", FIG3_REFUSALS, ids=[e for _, e in FIG3_REFUSALS])
def test_reproduce_fig3_refuses_an_existing_output_without_force(args, existing, fig3, capsys):
    run, repo, _ = fig3
    os.makedirs("docs")
    write("README.md", README_TEXT)
    write(existing, DOCS_FILES.get(existing, README_TEXT if existing == "README.md" else "old"))
    before = snapshot(repo)
    with pytest.raises(SystemExit) as exit_:
        run(*args)
    assert exit_.value.code == 2                                    # a usage error, not the mesh check
    message = capsys.readouterr().err
    assert existing in message and "--force" in message
    assert snapshot(repo) == before


def test_reproduce_fig3_out_and_docs_hold_every_output_and_docs_is_optional(fig3, capsys):
    # the outputs went to the repository's out/fig3 and docs/ whatever was asked; now to --out,
    # and to docs/ only with --docs (as the other reproduction scripts)
    run, repo, _ = fig3
    for path, text in DOCS_FILES.items():
        write(path, text)
    with pytest.raises(SystemExit) as exit_:
        run("--out", "elsewhere")
    assert "does not hold" in str(exit_.value.code)                 # past the output check: the committed docs
    assert sorted(os.listdir(repo)) == ["docs"]                     # are no obstacle without --docs
    with pytest.raises(SystemExit) as exit_:
        run("--out", "elsewhere", "--docs", "no-docs")
    assert exit_.value.code == 2
    assert "no-docs" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        run("--quick", "--docs", "docs", "--force")                 # a subset never replaces the docs
    assert exit_.value.code == 2 and "--quick" in capsys.readouterr().err
    write("README.md", "no markers\n")
    with pytest.raises(SystemExit) as exit_:
        run("--readme", "README.md", "--force")
    assert exit_.value.code == 2 and "fig3-readme-table" in capsys.readouterr().err
    assert snapshot(repo) == {**{p: t.encode() for p, t in DOCS_FILES.items()}, "README.md": b"no markers\n"}


def test_reproduce_fig3_docs_remeshing_md_is_an_output_only_where_it_has_the_table_markers(fig3, capsys):
    run, repo, _ = fig3
    write("docs/remeshing.md", "no markers here\n")                 # not written: no obstacle
    with pytest.raises(SystemExit) as exit_:
        run("--docs", "docs")
    assert "does not hold" in str(exit_.value.code)
    assert (repo / "docs" / "remeshing.md").read_text() == "no markers here\n"


def fig3_stubs(module, monkeypatch, fail=()):
    """Cheap stand-ins for the meshes, the retriangulation and the experiment (a 4 x 4 grid whose
    reports give fixed figures and seconds); ``fail``: ``(mesh, transfer, rows, location)`` that
    raise. Returns the list of calls, ``(function, mesh name or None, keyword arguments)``."""
    from curvdetail.curvature.testing import grid

    V, F = grid(4, 4)
    V[:, 2] = 0.1 * V[:, 0] ** 2
    calls = []

    def read_mesh(path):
        if not os.path.isfile(path):
            raise FileNotFoundError(path)
        calls.append(("read_mesh", os.path.basename(path), {}))
        return V.copy(), F.copy()

    def retriangulate(V, F, *, method="isotropic", target_edge=0.01, iterations=10, max_surface_distance=None,
                      aggressiveness=7.0, surface_check=True):    # the library's defaults, which the JSON names
        calls.append(("retriangulate", None, dict(method=method, target_edge=target_edge, iterations=iterations,
                                                  max_surface_distance=max_surface_distance,
                                                  surface_check=surface_check)))
        return V.copy(), F.copy()

    def run_experiment(V, F, *, method="isotropic", target_edge=0.01, transfer="conservative", rows="free",
                       location="closest", parameterization=None, target=None, source_path=None):
        calls.append(("run_experiment", source_path, dict(method=method, target=target is not None)))
        if (source_path, transfer, rows, location) in fail:
            raise RuntimeError("stub failure")
        seconds = {"retriangulate": 0.0 if target is not None else 0.5, "parameterize": 0.0, "transfer": 0.25,
                   "reconstruct": 0.25, "evaluate": 1.0}
        report = {"source": {"path": source_path, "vertices": 16, "faces": 18, "bbox_diagonal": 1.5},
                  "target": {"vertices": 16, "faces": 18, "boundary_vertices": 12},
                  "options": {"method": "given" if target is not None else method,
                              "target_edge": None if target is not None else target_edge, "transfer": transfer,
                              "rows": rows, "location": location,
                              "parameterization": (parameterization or "harmonic") if location == "uv" else None},
                  "error": {"hausdorff_rms": 1e-4, "hausdorff_max": 1e-3},
                  "baseline_zero_detail": {"hausdorff_rms": 0.1, "hausdorff_max": 0.3},
                  "floor_retriangulated": {"hausdorff_rms": 1e-4, "hausdorff_max": 1e-3},
                  "improvement_over_zero_detail": 1000.0, "ratio_to_floor": 1.0,
                  "seconds": dict(seconds, total=sum(seconds.values()))}
        if location == "uv":
            report["parameterization"] = {"flipped_source": 0, "flipped_target": 0}
        return {"report": report, "X": V, "Ft": F, "Z": V, "distance": np.full(16, 1e-3)}

    for name, stub in (("read_mesh", read_mesh), ("retriangulate", retriangulate),
                       ("run_experiment", run_experiment)):
        monkeypatch.setattr(module, name, stub)
    return calls


@pytest.mark.parametrize("quick", [True, False])
def test_reproduce_fig3_refuses_a_missing_mesh_before_any_work(quick, fig3, tmp_path, monkeypatch):
    # --quick --meshes DIR with only the nose there: the nose ran, then a FileNotFoundError
    # traceback (exit status 1) after that work
    run, repo, module = fig3
    calls = fig3_stubs(module, monkeypatch)
    write(tmp_path / "meshes" / "mannequin_nose.obj", "")
    with pytest.raises(SystemExit) as exit_:
        run("--quick") if quick else run()
    message = str(exit_.value.code)                                 # sys.exit(message): status 1
    missing = FIG3_MESHES[1:-1] if quick else FIG3_MESHES[1:]      # --quick leaves out terrainA_100k
    assert "does not hold " + ", ".join(missing) + ";" in message and "--meshes" in message
    assert calls == [] and os.listdir(repo) == []


def test_reproduce_fig3_records_every_retriangulation_failure_and_peak_memory(fig3, tmp_path, monkeypatch,
                                                                               capsys):
    run, repo, module = fig3
    calls = fig3_stubs(module, monkeypatch, fail=[("camelhead.off", "pointwise", "all", "uv")])
    monkeypatch.setattr(module, "_figure", lambda inputs, path, force=False: write(path, ",".join(inputs)))
    for name in FIG3_MESHES:
        write(tmp_path / "meshes" / name, "")
    for path, text in DOCS_FILES.items():
        write(path, text)
    write("README.md", README_TEXT)
    assert run("--docs", "docs", "--readme", "README.md", "--force") == 1      # a configuration failed
    assert "camelhead.off RuntimeError: stub failure" in capsys.readouterr().err
    result = json.load(open(repo / "out" / "fig3" / "results.json"))
    assert result["status"] == "failed" and result["peak_rss_gb"] > 0
    assert result["failures"] == [{
        "source": "camelhead.off", "configuration": {"transfer": "pointwise", "rows": "all", "location": "uv"},
        "error": "RuntimeError: stub failure", "retriangulation": result["failures"][0]["retriangulation"]}]
    reports = result["reports"]
    assert len(reports) == 6 * 6 - 1 + 3 * 3 + 5
    shared = [r for r in reports if r["options"]["method"] == "given"]
    assert len(shared) == 6 * 6 - 1 + 3 * 3                          # the planar-domain ones too
    diagonal = np.sqrt(1.0 + 1.0 + 0.1 ** 2)                         # the stub grid's
    for r in shared:
        retri = r["retriangulation"]
        assert retri["seconds"] == r["seconds_retriangulate_shared"] >= 0
        assert {k: v for k, v in retri.items() if k not in ("seconds", "target_edge_length")} == {
            "method": "isotropic", "target_edge": 0.01, "iterations": 10, "max_surface_distance": None,
            "surface_check": True, "shared": True}
        assert retri["target_edge_length"] == pytest.approx(0.01 * diagonal)
    # what was recorded is what retriangulate was given: once per patch, and again for the planar domains
    given = [options for function, _, options in calls if function == "retriangulate"]
    assert given == [{"method": "isotropic", "target_edge": 0.01, "iterations": 10, "max_surface_distance": None,
                      "surface_check": True}] * (6 + 3)
    made = [r for r in reports if r["options"]["method"] != "given"]
    assert [(r["source"]["path"], r["retriangulation"]["method"], r["retriangulation"]["target_edge"],
             r["retriangulation"]["seconds"], r["retriangulation"]["shared"]) for r in made] == [
        ("mannequin_ear.obj", "decimate", 0.03, 0.5, False), ("camelhead.off", "decimate", 0.01, 0.5, False),
        ("terrainA_10k.obj", "decimate", 0.01, 0.5, False), ("terrainA_100k.ply", "isotropic", 0.01, 0.5, False),
        ("terrainA_100k.ply", "decimate", 0.01, 0.5, False)]
    assert made[0]["retriangulation"]["aggressiveness"] == 7.0 and made[3]["retriangulation"]["surface_check"]
    assert all("seconds_retriangulate_shared" not in r for r in made)
    peaks = [r["peak_rss_gb_so_far"] for r in reports]
    assert 0 < peaks[0] and peaks == sorted(peaks) and peaks[-1] <= result["peak_rss_gb"] + 1e-3
    # one run's tables, speed paragraph and short README table, in every copy
    table = (repo / "out" / "fig3" / "fig3_table.md").read_text()
    assert (repo / "docs" / "fig3_table.md").read_text() == table
    assert (repo / "docs" / "remeshing.md").read_text() == (
        "text\n<!-- fig3-table -->\n" + table + "<!-- /fig3-table -->\nmore\n")
    assert "| camelhead.off | 16 | 16 | isotropic | pointwise | all | uv | FAILED: stub failure |" in table
    terrain = next(line for line in table.splitlines() if line.startswith("| terrainA_10k | 16 | 16 | isotropic"))
    terrain_total = float(terrain.rstrip(" |").rsplit("/ ", 1)[1])
    assert terrain_total == pytest.approx(1.5, abs=0.01)           # the stub's 1.5 s and the retriangulation
    assert f"10k-vertex sources end to end {terrain_total:.1f} s (terrainA_10k)" in table
    assert "terrainA_100k 2.0 s (remeshing 0.5, transfer 0.2, reconstruct 0.25, evaluate 1.0)" in table
    assert f"Peak memory of the whole run (one process): {result['peak_rss_gb']:.2f} GB" in table
    readme = (repo / "README.md").read_text()
    block = readme[readme.index("<!-- fig3-readme-table -->\n"):readme.index("<!-- /fig3-readme-table -->")]
    assert readme.startswith("intro\n") and readme.endswith("<!-- /fig3-readme-table -->\nrest\n")
    assert result["started_utc"] in block
    assert [line.split(" | ")[0] for line in block.splitlines() if line.startswith("| ") and "---" not in line] == [
        "| patch", "| mannequin_nose", "| mannequin_ear", "| elephant_trunk", "| terrainA_10k", "| camelhead",
        "| mannequin_disk_1k", "| terrainA_100k"]
    assert (repo / "out" / "fig3" / "fig3.png").read_text() == (repo / "docs" / "fig3.png").read_text() == (
        "mannequin_nose.obj,mannequin_ear.obj,elephant_trunk.obj")


def test_reproduce_fig3_quick_table_has_only_the_sections_it_ran(fig3, tmp_path, monkeypatch):
    # --quick's table_quick.md had an "Every transfer configuration" section repeating the default
    # rows, and a "Decimation, and a 100k-vertex source" heading over decimation rows only
    run, repo, module = fig3
    fig3_stubs(module, monkeypatch)
    for name in FIG3_MESHES:
        write(tmp_path / "meshes" / name, "")
    assert run("--quick") == 0
    table = open(repo / "out" / "fig3" / "table_quick.md").read()
    headings = [line for line in table.splitlines() if line.startswith("### ")]
    assert headings == ["### Default configuration (isotropic 1 %, conservative transfer, free rows, "
                        "closest-point location)", "### Decimation (default transfer)"]
    rows = [line for line in table.splitlines() if line.startswith("| ") and not line.startswith("| patch")]
    assert len(rows) == 6 + len(module.EXTRA_RUNS)                  # each run once, no 100k source
    assert "terrainA_100k" not in table
    run("--force")                                                  # the full run keeps every section
    full = open(repo / "out" / "fig3" / "fig3_table.md").read()
    assert "### Every transfer configuration on the same targets" in full
    assert "### Decimation, and a 100k-vertex source (default transfer)" in full


def test_reproduce_fig3_as_a_program_leaves_numpy_floating_point_errors_reported(fig3, tmp_path, monkeypatch):
    # it ran np.seterr(all="ignore") for the whole process, hiding every floating-point warning;
    # no part of the run needs it (every configuration run with numpy's errors recorded: none)
    import runpy

    import curvdetail.remesh
    import curvdetail.remesh.experiment

    run, repo, module = fig3
    fig3_stubs(module, monkeypatch)              # the program imports them from the library
    monkeypatch.setattr(curvdetail, "read_mesh", module.read_mesh)
    monkeypatch.setattr(curvdetail.remesh, "retriangulate", module.retriangulate)
    monkeypatch.setattr(curvdetail.remesh.experiment, "run_experiment", module.run_experiment)
    for name in FIG3_MESHES:
        write(tmp_path / "meshes" / name, "")
    monkeypatch.setattr(sys, "argv", ["reproduce_fig3.py", "--meshes", str(tmp_path / "meshes"), "--quick",
                                      "--out", str(tmp_path / "out")])
    with np.errstate(all="warn"):                # restored afterwards whatever the program does
        with pytest.raises(SystemExit) as exit_:
            runpy.run_path(os.path.join(SCRIPTS, "reproduce_fig3.py"), run_name="__main__")
        assert np.geterr() == {"divide": "warn", "over": "warn", "under": "warn", "invalid": "warn"}
    assert exit_.value.code == 0 and sorted(os.listdir(tmp_path / "out")) == ["results.json", "table_quick.md"]


def test_reproduce_fig3_figure_that_fails_to_save_leaves_no_partial_picture(tmp_path, monkeypatch):
    """The figure is saved to a temporary file, its format given explicitly: a writer that fails
    half-way leaves no picture where there was none, and the old one where there was one."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from curvdetail.curvature.testing import grid

    formats, real = [], Figure.savefig

    def half_then_fail(fig, target, **options):
        formats.append(options.get("format"))
        real(fig, target, **options)
        raise RuntimeError("the writer failed after writing")

    monkeypatch.setattr(Figure, "savefig", half_then_fail)
    V, F = grid(3, 3)
    V[:, 2] = 0.1 * V[:, 0]
    report = {"error": {"hausdorff_rms": 1e-4, "hausdorff_max": 1e-3},
              "baseline_zero_detail": {"hausdorff_rms": 1e-2, "hausdorff_max": 1e-1},
              "target": {"vertices": 9}}
    inputs = {"nose.obj": (V, F, {"report": report, "X": V, "Ft": F, "distance": np.zeros(9), "Z": V})}
    module = load("reproduce_fig3")
    path = tmp_path / "fig3.png"
    with pytest.raises(RuntimeError):
        module._figure(inputs, str(path))
    assert os.listdir(tmp_path) == []
    path.write_bytes(b"old picture")
    with pytest.raises(RuntimeError):
        module._figure(inputs, str(path), True)
    assert path.read_bytes() == b"old picture"
    assert os.listdir(tmp_path) == ["fig3.png"]
    assert formats == ["png", "png"]


def test_reproduce_fig3_figure_shades_the_rebuilt_surface_light_with_a_colour_bar_in_percent(monkeypatch):
    # the rebuilt panels were viridis (dark purple at distance 0, the usual case), their scale
    # only in the titles: now the plain panels' light colour at 0 and a colour bar in %
    import matplotlib

    matplotlib.use("Agg")
    from curvdetail.curvature.testing import grid

    module = load("reproduce_fig3")
    V, F = grid(5, 5)
    V[:, 2] = 0.1 * V[:, 0] ** 2
    diagonal = np.linalg.norm(V.max(0) - V.min(0))
    distance = np.zeros(25)
    distance[0] = 0.004 * diagonal                                  # 0.4 % at one corner, 0 elsewhere
    report = {"error": {"hausdorff_rms": 1e-4, "hausdorff_max": 4e-3},
              "baseline_zero_detail": {"hausdorff_rms": 1e-2, "hausdorff_max": 1e-1}, "target": {"vertices": 25}}
    figures = []
    monkeypatch.setattr(module._outputs, "save_figure", lambda fig, path, force, **options: figures.append(fig))
    module._figure({"nose.obj": (V, F, {"report": report, "X": V, "Ft": F, "distance": distance, "Z": V})},
                   "not-written.png")
    source, rebuilt, zero = figures[0].axes[:3]
    [bar] = rebuilt.child_axes
    assert bar.get_xlabel() == "distance to the source, % of the bbox diagonal"
    assert bar.get_xlim() == pytest.approx((0.0, 0.4))
    colours = rebuilt.collections[0].get_facecolor()                 # in drawing (depth) order
    assert colours.shape == (F.shape[0], 4)
    # distance 0: the plain panels' light blue-grey (0.75, 0.78, 0.85), shaded (0.35 to 1); the
    # faces at the 0.4 % corner redder
    plain = np.isclose(colours[:, 0] / colours[:, 2], 0.75 / 0.85) & np.isclose(colours[:, 1] / colours[:, 2],
                                                                                0.78 / 0.85)
    corner = (F == 0).any(axis=1).sum()
    assert plain.sum() == F.shape[0] - corner and colours[plain, 2].min() > 0.85 * 0.35
    assert (colours[~plain, 0] > colours[~plain, 2]).all()


def test_documented_reproduce_fig3_command_refreshes_every_committed_file(fig3, tmp_path, monkeypatch):
    """docs/remeshing.md gives the command that wrote its tables, docs/fig3.png and README.md's
    table: it runs as written (with the work stubbed) and refreshes each of them."""
    with open(os.path.join(ROOT, "docs", "remeshing.md"), encoding="utf-8") as fh:
        (args,) = documented_commands(fh.read(), "reproduce_fig3.py")
    run, repo, module = fig3
    fig3_stubs(module, monkeypatch)
    monkeypatch.setattr(module, "_figure", lambda inputs, path, force=False: write(path, "new picture"))
    for name in FIG3_MESHES:
        write(tmp_path / "meshes" / name, "")
    for path, text in DOCS_FILES.items():
        write(path, text)
    write("README.md", README_TEXT)
    before = snapshot(repo)
    assert run(*args) == 0
    after = snapshot(repo)
    assert all(after[path] != before[path] for path in before)
    assert after["docs/fig3.png"] == after["out/fig3/fig3.png"] == b"new picture"
