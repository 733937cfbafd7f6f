"""scripts/bench_reconstruct.py and scripts/bench_operations.py: an option value outside what the
script can run is refused at once (argparse's exit status 2 and a message naming the option and
the values it takes), before any case runs and before any output is written.

Before, bench_reconstruct ran every case of ``--surfaces torus`` (each failing with a KeyError in
its subprocess) or of ``--methods foo`` ("not installed") and wrote a JSON of skipped cases with
exit status 0, labelled ``--rows some`` results as a row mode of their own, stopped with an
IndexError traceback after the work at ``--rounds 0``, ignored ``--trials 0`` and skipped every
case at ``--timeout -1``; bench_operations skipped every case at ``--timeout 0`` and wrote them.
Only argument parsing runs here: the cases are stubbed.
"""

import os

import pytest

from conftest import load_script

load = load_script


def refused(module, args, capsys):
    """Run ``module.main(args)`` expecting argparse's refusal; its stderr message."""
    with pytest.raises(SystemExit) as exit_:
        module.main(args)
    assert exit_.value.code == 2
    return capsys.readouterr().err


BENCH_RECONSTRUCT_BAD = [
    (["--surfaces", "torus"], ["--surfaces", "'torus'", "grid, sphere"]),
    (["--surfaces", "grid,"], None),                                   # a trailing comma is fine
    (["--rows", "some"], ["--rows", "'some'", "all, free"]),
    (["--methods", "foo"], ["--methods", "'foo'", "reconstruct", "spsolve"]),
    (["--methods", ""], ["--methods", "no method"]),
    (["--sizes", "5k"], ["--sizes", "'5k'", "10k, 100k, 1M"]),
    (["--sizes", ","], ["--sizes", "no size"]),
    (["--rounds", "0"], ["--rounds", "'0'", "at least 1"]),
    (["--trials", "0"], ["--trials", "'0'", "at least 1"]),
    (["--timeout", "-1"], ["--timeout", "'-1'", "positive"]),
    (["--mem-limit-gb", "0"], ["--mem-limit-gb", "'0'", "positive"]),
    (["--mem-limit-gb", "nan"], ["--mem-limit-gb", "'nan'", "positive"]),
]


@pytest.mark.parametrize("bad, words", BENCH_RECONSTRUCT_BAD, ids=[" ".join(b) for b, _ in BENCH_RECONSTRUCT_BAD])
def test_bench_reconstruct_refuses_a_bad_option_value_before_any_case(bad, words, tmp_path, monkeypatch, capsys):
    module = load("bench_reconstruct")
    calls = []

    def run(case, timeout, mem_limit_gb=None):
        calls.append(case)
        return dict(case, skipped="stub")

    monkeypatch.setattr(module, "run_in_subprocess", run)
    out = tmp_path / "bench.json"
    args = ["--sizes", "10k", "--surfaces", "grid", "--rows", "free", "--methods", "splu",
            "--out", str(out), "--markdown", ""]
    if words is None:           # a well-formed value runs as before
        assert module.main(args + bad) == 0
        assert [(c["surface"], c["rows"], c["method"]) for c in calls] == [("grid", "free", "splu")]
        return
    message = refused(module, args + bad, capsys)
    assert calls == [] and not out.exists()
    for word in words:
        assert word in message


@pytest.mark.parametrize("bad, words", [
    (["--timeout", "0"], ["--timeout", "'0'", "at least 1"]),
    (["--timeout", "-5"], ["--timeout", "'-5'", "at least 1"]),
    (["--sizes", "5k"], ["--sizes", "'5k'", "10k, 100k, 1M"]),
    (["--cases", "edge_measure,foo"], ["--cases", "'foo'", "edge_measure"]),
    (["--cases", ","], ["--cases", "none given"]),
])
def test_bench_operations_refuses_a_bad_option_value_before_any_case(bad, words, tmp_path, monkeypatch, capsys):
    module = load("bench_operations")
    calls = []
    monkeypatch.setattr(module, "in_subprocess", lambda *a: calls.append(a) or {"seconds": 0.1})
    out = tmp_path / "ops.json"
    message = refused(module, ["--sizes", "10k", "--cases", "edge_measure", "--out", str(out)] + bad, capsys)
    assert calls == [] and not out.exists()
    for word in words:
        assert word in message


def test_an_existing_output_is_refused_before_any_case_and_kept(tmp_path, capsys):
    out = tmp_path / "ops.json"
    out.write_text("keep")
    err = refused(load("bench_operations"), ["--out", str(out)], capsys)
    assert "--force" in err and out.read_text() == "keep"


def test_script_outputs_are_written_atomically_into_a_folder_made_for_them(tmp_path):
    files = load("_files")
    out = tmp_path / "new" / "r.json"
    files.write_json(out, {"a": 1}, False, end="\n")
    assert out.read_text() == '{"a": 1}\n' and os.listdir(out.parent) == ["r.json"]
    with pytest.raises(FileExistsError):
        files.write_json(out, {"a": 2}, False)
    files.write_json(out, {"a": 2}, True)
    assert out.read_text() == '{"a": 2}' and os.listdir(out.parent) == ["r.json"]
