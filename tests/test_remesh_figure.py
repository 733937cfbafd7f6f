"""The experiment picture (curvdetail.remesh.figure)."""

import numpy as np
import pytest

from curvdetail.curvature.testing import disk
from curvdetail.remesh.experiment import run_experiment
from curvdetail.remesh.figure import save_figure


@pytest.fixture(scope="module")
def result():
    V, F = disk(n_rings=10)
    V[:, 2] = 0.2 * np.exp(-3.0 * (V[:, :2] ** 2).sum(1))
    return V, F, run_experiment(V, F, target_edge=0.06)


def test_figure_is_a_png_of_three_panels(tmp_path, result):
    V, F, r = result
    path = tmp_path / "f.png"
    save_figure(str(path), V, F, r["X"], r["Ft"], r["Z"], r["distance"], r["report"])
    import matplotlib.image as mpimg

    img = mpimg.imread(str(path))
    # three panels side by side: much wider than tall
    assert img.shape[1] > 2 * img.shape[0]
    rgb = img[..., :3]
    thirds = np.array_split(np.arange(img.shape[1]), 3)
    drawn = [(np.abs(rgb[:, cols] - 1.0).sum(-1) > 0.1).mean() for cols in thirds]
    # vivid pixels: the error colour map; the source and zero-detail panels are shaded grey
    vivid = [(np.ptp(rgb[:, cols], axis=-1) > 0.25).mean() for cols in thirds]
    assert min(drawn) > 0.1                      # every panel shows its mesh (~24 % of its area)
    assert vivid[1] > 0.05 and vivid[0] < 0.005 and vivid[2] < 0.005


def test_figure_refuses_to_overwrite(tmp_path, result):
    V, F, r = result
    path = tmp_path / "f.png"
    path.write_bytes(b"keep")
    with pytest.raises(FileExistsError):
        save_figure(str(path), V, F, r["X"], r["Ft"], r["Z"], r["distance"], r["report"])
    assert path.read_bytes() == b"keep"


def test_an_unmeasured_report_or_mismatched_distances_are_refused_by_name(tmp_path, result):
    # a report of evaluate=False raised KeyError('error'); its distance None a TypeError from
    # len(); distances for another mesh came out as an IndexError inside the drawing
    V, F, r = result
    path = tmp_path / "f.png"
    unmeasured = {k: v for k, v in r["report"].items() if k not in ("error", "baseline_zero_detail",
                                                                    "floor_retriangulated")}
    with pytest.raises(ValueError, match="report has no error, baseline_zero_detail, floor_retriangulated"):
        save_figure(str(path), V, F, r["X"], r["Ft"], r["Z"], None, unmeasured)
    with pytest.raises(ValueError, match=r"distance is None for \d+ rebuilt vertices"):
        save_figure(str(path), V, F, r["X"], r["Ft"], r["Z"], None, r["report"])
    with pytest.raises(ValueError, match=r"distance has shape \(3,\) for \d+ rebuilt vertices"):
        save_figure(str(path), V, F, r["X"], r["Ft"], r["Z"], r["distance"][:3], r["report"])
    assert not path.exists()
