"""The one mesh renderer (curvdetail.plot): panels, the camera, the remeshing figure."""

import matplotlib.image as mpimg
import numpy as np
import pytest

from curvdetail.curvature.testing import disk, grid
from curvdetail.plot import camera, draw_mesh, save_panels, save_remeshing_figure, top_view, view_direction
from curvdetail.remesh.experiment import run_experiment


def _drawn(img):
    """Fraction of pixels that are not the white background."""
    return (np.abs(img[..., :3] - 1.0).sum(-1) > 0.1).mean()


def _vivid(img):
    """Fraction of strongly coloured pixels (the colour map; grey shading has a spread under 0.1)."""
    return (np.ptp(img[..., :3], axis=-1) > 0.25).mean()


@pytest.fixture(scope="module")
def result():
    V, F = disk(n_rings=10)
    V[:, 2] = 0.2 * np.exp(-3.0 * (V[:, :2] ** 2).sum(1))
    return V, F, run_experiment(V, F, target_edge="6%")


def test_panels_are_a_png_of_the_size_asked_showing_every_mesh(tmp_path):
    V, F = grid(8, 8)
    V[:, 2] = 0.3 * V[:, 0] * V[:, 1]
    path = tmp_path / "p.png"
    save_panels(path, [(V, F, "grey"), (V, F, "coloured", V[:, 2])], elev=30, azim=-60, panel_size=2.5, dpi=80,
                title="two panels")
    img = mpimg.imread(str(path))
    assert img.shape[:2] == (200, 400)                      # 2.5 in x 80 dpi, two panels wide
    halves = np.array_split(np.arange(img.shape[1]), 2)
    assert min(_drawn(img[:, cols]) for cols in halves) > 0.05
    assert _vivid(img[:, halves[0]]) < 0.005 < 0.05 < _vivid(img[:, halves[1]])


def test_panels_refuse_to_overwrite_and_leave_no_file_on_failure(tmp_path):
    V, F = grid(3, 3)
    path = tmp_path / "p.png"
    path.write_bytes(b"keep")
    with pytest.raises(FileExistsError):
        save_panels(path, [(V, F, "a")])
    assert path.read_bytes() == b"keep"
    with pytest.raises(IndexError):
        save_panels(tmp_path / "q.png", [(V, F + 100, "bad")])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png"]


def test_draw_mesh_colour_scale_spans_the_values():
    from matplotlib.figure import Figure

    V, F = grid(4, 4)
    ax = Figure().subplots()
    assert draw_mesh(ax, V, F) is None
    mappable = draw_mesh(ax, V, F, values=np.linspace(-2.0, 3.0, V.shape[0]))
    assert (mappable.norm.vmin, mappable.norm.vmax) == (-2.0, 3.0)


def test_camera_is_a_rotation_looking_down_from_elevation_90():
    R = camera(35.0, -60.0)
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(view_direction(90.0, 10.0), [0.0, 0.0, 1.0], atol=1e-12)
    assert np.allclose(view_direction(0.0, -90.0)[2], 0.0, atol=1e-12)


def _octahedron(height=1.0):
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, height], [0, 0, -height]], float)
    F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return V, F


def test_top_view_turns_a_patch_normal_to_z_and_a_closed_surface_along_its_least_spread():
    V, F = grid(5, 5)
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, 0.6, -0.8], [0.0, 0.8, 0.6]])
    assert np.allclose(top_view(V @ tilt.T, F)[2], tilt[:, 2], atol=1e-12)
    # the normals of a closed surface sum to zero: the frame was NaN, the picture empty
    R = top_view(*_octahedron(0.3))
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(R[2], [0.0, 0.0, 1.0], atol=1e-12)


def test_remeshing_figure_shows_three_panels_the_rebuilt_one_coloured(tmp_path, result):
    V, F, r = result
    path = tmp_path / "f.png"
    save_remeshing_figure(path, V, F, r["X"], r["Ft"], r["Z"], r["distance"], r["report"], dpi=50)
    img = mpimg.imread(str(path))
    assert img.shape[:2] == (200, 600)
    thirds = [img[:, cols] for cols in np.array_split(np.arange(img.shape[1]), 3)]
    assert min(_drawn(t) for t in thirds) > 0.1
    assert _vivid(thirds[1]) > 0.05 and _vivid(thirds[0]) < 0.005 and _vivid(thirds[2]) < 0.005


def test_remeshing_figure_refuses_an_unmeasured_report_or_mismatched_distances(tmp_path, result):
    V, F, r = result
    path = tmp_path / "f.png"
    unmeasured = {k: v for k, v in r["report"].items() if k != "error"}
    for distance, report in ((r["distance"], unmeasured), (None, r["report"]), (r["distance"][:3], r["report"])):
        with pytest.raises(ValueError):
            save_remeshing_figure(path, V, F, r["X"], r["Ft"], r["Z"], distance, report)
    assert not path.exists()


def test_the_remeshing_figure_of_a_closed_surface_shows_all_three_panels(tmp_path):
    V, F = _octahedron(0.3)
    report = {"error": {"hausdorff_rms_percent_of_diagonal": 0.001, "hausdorff_max_percent_of_diagonal": 0.01},
              "baseline_zero_detail": {"hausdorff_rms_percent_of_diagonal": 0.1, "hausdorff_max_percent_of_diagonal": 0.2},
              "floor_retriangulated": {"hausdorff_rms_percent_of_diagonal": 0.0}, "options": {"transfer": "mean", "rows": "free"},
              "source": {"path": None, "vertices": 6, "bbox_diagonal": 2.0}, "target": {"vertices": 6}}
    path = tmp_path / "octahedron.png"
    save_remeshing_figure(path, V, F, V, F, 0.8 * V, np.linspace(0.0, 0.01, 6), report, dpi=50)
    img = mpimg.imread(str(path))
    assert min(_drawn(img[:, cols]) for cols in np.array_split(np.arange(img.shape[1]), 3)) > 0.08


def test_the_remeshing_colour_scale_ends_at_the_max_the_title_states_for_both_surfaces(tmp_path, result,
                                                                                    monkeypatch):
    import curvdetail.plot as plot

    V, F, r = result
    seen = {}
    monkeypatch.setattr(plot, "save_panels", lambda path, panels, **kw: seen.update(panels=panels, **kw))
    save_remeshing_figure(tmp_path / "f.png", V, F, r["X"], r["Ft"], r["Z"], r["distance"], r["report"],
                          zero_distance=r["zero_distance"])
    top = r["report"]["error"]["hausdorff_max_percent_of_diagonal"]
    assert seen["vrange"] == (0.0, top) and f"max {top:.2f} %" in seen["panels"][1][2]
    rebuilt, zero = seen["panels"][1][3], seen["panels"][2][3]          # both in % of the diagonal
    d = r["report"]["source"]["bbox_diagonal"]
    assert np.allclose(zero, 100 * r["zero_distance"] / d) and rebuilt.max() <= top
    assert zero.max() > top                       # beyond the scale: the top colour (the bar's arrow)


def test_vertex_colours_run_viridis_from_0_to_the_max_clipped_beyond():
    from curvdetail.plot import vertex_colours

    rgba = vertex_colours([0.0, 0.5, 1.0, 3.0], vmax=1.0)
    assert rgba.dtype == np.uint8 and (rgba[:, 3] == 255).all()
    assert rgba[0, :3].tolist() == [68, 1, 84] and rgba[2, :3].tolist() == rgba[3, :3].tolist() == [253, 231, 37]
