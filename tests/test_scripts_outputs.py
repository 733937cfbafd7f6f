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
import importlib.util
import json
import os
import re
import shlex
import shutil
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(ROOT, "scripts")


def load(name):
    """The script ``scripts/NAME.py`` as a fresh module (the scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(f"script_{name}", os.path.join(SCRIPTS, name + ".py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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
    """``os.replace`` onto ``path`` fails as on a full disk (every other rename works)."""
    real, target = os.replace, os.path.abspath(path)

    def replace(src, dst, **kw):
        if os.path.abspath(dst) == target:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(src, dst, **kw)

    monkeypatch.setattr(os, "replace", replace)


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
        row[mode] = {"mean": 0.01, "max": 0.02, "first_solve_s": 0.1, "resolve_s": 0.001,
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
    assert json.load(open(out / "table1.json"))["repeat"] == 1


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


# --- reproduce_fig3.py (fixed paths under the repository: ROOT is pointed at a scratch tree) ----

@pytest.fixture
def fig3(tmp_path, monkeypatch):
    """``(run, the scratch repository)``: ``run(*args)`` runs reproduce_fig3.py with ``args``
    (and a mesh folder that exists and holds no mesh)."""
    module = load("reproduce_fig3")
    monkeypatch.setattr(module, "ROOT", str(tmp_path / "repo"))
    (tmp_path / "meshes").mkdir()

    def run(*args):
        monkeypatch.setattr(sys, "argv", ["reproduce_fig3.py", "--meshes", str(tmp_path / "meshes"), *args])
        return module.main()

    return run, tmp_path / "repo"


DOCS_FILES = {"docs/fig3_table.md": "old tables\n", "docs/fig3.png": "old picture",
              "docs/remeshing.md": "text\n<!-- fig3-table -->\nold tables\n<!-- /fig3-table -->\nmore\n"}


@pytest.mark.parametrize("existing", ["docs/fig3_table.md", "docs/fig3.png", "out/fig3/results.json"])
def test_reproduce_fig3_full_run_refuses_an_existing_output_without_force(existing, fig3, capsys):
    run, repo = fig3
    write(repo / existing, DOCS_FILES.get(existing, "old"))
    with pytest.raises(SystemExit) as exit_:
        run()
    assert exit_.value.code == 2
    message = capsys.readouterr().err
    assert os.path.join(str(repo), existing) in message and "--force" in message
    assert snapshot(repo) == {existing: DOCS_FILES.get(existing, "old").encode()}


def test_reproduce_fig3_full_run_refuses_a_checkout_without_docs_before_any_work(fig3, capsys):
    run, repo = fig3
    with pytest.raises(SystemExit) as exit_:
        run()
    assert exit_.value.code == 2
    message = capsys.readouterr().err
    assert os.path.join(str(repo), "docs") in message and "mkdir -p" in message
    assert not repo.exists()


def test_reproduce_fig3_refuses_docs_remeshing_md_only_where_it_has_the_table_markers(fig3, capsys):
    run, repo = fig3
    write(repo / "docs" / "remeshing.md", DOCS_FILES["docs/remeshing.md"])
    with pytest.raises(SystemExit) as exit_:
        run()
    assert exit_.value.code == 2 and "remeshing.md" in capsys.readouterr().err
    write(repo / "docs" / "remeshing.md", "no markers here\n")     # not written: no obstacle
    with pytest.raises(FileNotFoundError, match="mannequin_nose"):  # the first mesh: work began
        run()
    assert (repo / "docs" / "remeshing.md").read_text() == "no markers here\n"


def test_reproduce_fig3_with_force_gets_past_the_output_check(fig3):
    run, repo = fig3
    for path, text in DOCS_FILES.items():
        write(repo / path, text)
    with pytest.raises(FileNotFoundError, match="mannequin_nose"):  # the first mesh: work began
        run("--force")
    assert snapshot(repo) == {path: text.encode() for path, text in DOCS_FILES.items()}


def test_reproduce_fig3_quick_leaves_docs_alone_and_refuses_only_its_own_files(fig3, capsys):
    run, repo = fig3
    for path, text in DOCS_FILES.items():
        write(repo / path, text)
    write(repo / "out" / "fig3" / "table_quick.md", "old quick")
    with pytest.raises(SystemExit) as exit_:
        run("--quick")
    assert exit_.value.code == 2 and "table_quick.md" in capsys.readouterr().err
    os.remove(repo / "out" / "fig3" / "table_quick.md")
    with pytest.raises(FileNotFoundError, match="mannequin_nose"):  # the committed docs/ are no obstacle
        run("--quick")


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
