"""A mixed pipeline run from Python, recorded as one .mlx and replayed by `curvdetail run`."""

import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pymeshlab
import pytest

from curvdetail.curvature.testing import grid
from curvdetail.data import example_path
from curvdetail.filters import ScaleWarning, ScriptError, apply, apply_native, run_script, save_script
from curvdetail.filters.files import load_meshset

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _pipeline(ms):
    """pymeshlab's filters and ours, as a user mixes them: a copy, remeshed at 3 % of the
    diagonal, the source's detail carried over and rebuilt, a selection made directly."""
    ms.generate_copy_of_current_mesh()                                      # pymeshlab, directly
    apply_native(ms, "meshing_isotropic_explicit_remeshing", iterations=6,
                 targetlen=pymeshlab.PercentageValue(3), maxsurfdist=pymeshlab.PercentageValue(1.5))
    apply(ms, "transfer_curvature_detail", sourcemesh=0, targetmesh=1)
    apply(ms, "apply_curvature_reconstruction", rows="free")


@pytest.mark.slow
def test_a_recorded_mixed_pipeline_replays_bit_for_bit(tmp_path):
    # the recording process and a fresh `curvdetail run` give the same mesh to the last bit
    ms = load_meshset(example_path())
    _pipeline(ms)
    script = tmp_path / "recorded.mlx"
    save_script(ms, script)
    text = script.read_text()
    assert "curvdetail_scratch" not in text and 'value="3.0%"' in text
    names = [line.split('"')[1] for line in text.splitlines() if line.startswith(" <filter")]
    assert names == ["Duplicate Current layer", "Remeshing: Isotropic Explicit Remeshing",
                     "transfer_curvature_detail", "apply_curvature_reconstruction"]
    out = tmp_path / "replayed.ply"
    done = subprocess.run([sys.executable, "-m", "curvdetail", "run", str(script), example_path(), str(out)],
                          capture_output=True, text=True, cwd=ROOT, env={**os.environ, "PYTHONPATH": ROOT})
    assert done.returncode == 0, done.stderr
    back = load_meshset(out)
    assert np.array_equal(back.current_mesh().vertex_matrix(), ms.current_mesh().vertex_matrix())
    assert np.array_equal(back.current_mesh().face_matrix(), ms.current_mesh().face_matrix())


def test_a_meshset_without_filters_has_nothing_to_save(tmp_path):
    ms = load_meshset(example_path())
    with pytest.raises(ScriptError) as refused:
        save_script(ms, tmp_path / "empty.mlx")
    assert refused.value.parameter == "ms" and not (tmp_path / "empty.mlx").exists()


def test_a_length_sized_for_another_mesh_gets_a_note_naming_the_ratio(tmp_path):
    # TargetLen 0.3 is 2 % of the terrain's diagonal (15.27) but 30 % of a unit square's (1.41)
    text = (ROOT + "/scripts/examples/remesh_transfer_rebuild.mlx")
    with open(text, encoding="utf-8") as f:
        script = f.read().replace('value="2%"', 'value="0.3"')
    (tmp_path / "absolute.mlx").write_text(script)
    V, F = grid(21, 21)
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    with pytest.warns(ScaleWarning) as said:
        run_script(ms, tmp_path / "absolute.mlx")
    ratio = 0.3 / np.linalg.norm(np.ptp(V, axis=0))
    assert f"{100 * ratio:.3g} %" in str(said[0].message) and "TargetLen" in str(said[0].message)


def test_the_bundled_script_in_percent_gives_no_note_on_any_patch(tmp_path):
    V, F = grid(21, 21)
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ScaleWarning)
        steps = run_script(ms, ROOT + "/scripts/examples/remesh_transfer_rebuild.mlx")
    assert steps[-1]["figures"]["hausdorff_rms_percent_of_diagonal"] < 1.0
    assert json.dumps(steps[-1]["figures"])


def test_curvdetail_run_says_the_ratio_as_a_note(tmp_path, capsys):
    from curvdetail.cli import main
    from curvdetail.io import write_mesh

    with open(ROOT + "/scripts/examples/remesh_transfer_rebuild.mlx", encoding="utf-8") as f:
        (tmp_path / "absolute.mlx").write_text(f.read().replace('value="2%"', 'value="0.3"'))
    V, F = grid(21, 21)
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0])
    write_mesh(tmp_path / "square.obj", V, F)
    assert main(["run", str(tmp_path / "absolute.mlx"), str(tmp_path / "square.obj"), str(tmp_path / "o.ply")]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1 and "TargetLen 0.3" in notes[0] and f"{100 * 0.3 / np.linalg.norm(np.ptp(V, axis=0)):.3g} %" in notes[0]
