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


def _octahedron(height=1.0):
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, height], [0, 0, -height]], float)
    F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return V, F


def _icosahedron():
    t = (1 + 5 ** 0.5) / 2
    V = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
                  [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    return V, F


def test_a_closed_surface_is_viewed_along_its_least_spread_not_nan():
    # the normals of a closed surface sum to zero (or to rounding): the view frame was NaN, and
    # the picture three empty panels
    from curvdetail.remesh.figure import _view_frame

    for V, F in (_octahedron(), _icosahedron(), _octahedron(0.3)):
        assert np.allclose(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]).sum(0), 0.0, atol=1e-12)
        R = _view_frame(V, F)
        assert np.isfinite(R).all()
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.linalg.det(R) == pytest.approx(1.0)
    # an octahedron squashed along z spreads least along z: looked at from +z
    assert np.allclose(_view_frame(*_octahedron(0.3))[2], [0.0, 0.0, 1.0], atol=1e-12)


def test_the_picture_of_a_closed_surface_shows_all_three_panels(tmp_path):
    V, F = _octahedron(0.3)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    report = {"error": {"hausdorff_rms": 0.001, "hausdorff_max": 0.01},
              "baseline_zero_detail": {"hausdorff_rms": 0.1, "hausdorff_max": 0.2},
              "floor_retriangulated": {"hausdorff_rms": 0.0}, "options": {"transfer": "mean", "rows": "free"},
              "source": {"path": None, "vertices": 6, "bbox_diagonal": diag}, "target": {"vertices": 6}}
    path = tmp_path / "octahedron.png"
    save_figure(str(path), V, F, V, F, 0.8 * V, np.linspace(0.0, 0.01, 6), report)
    import matplotlib.image as mpimg

    img = mpimg.imread(str(path))
    thirds = np.array_split(np.arange(img.shape[1]), 3)
    drawn = [(np.abs(img[:, cols, :3] - 1.0).sum(-1) > 0.1).mean() for cols in thirds]
    assert min(drawn) > 0.08                     # each panel shows its octahedron (11-20 %; was 1-5 %: titles)
