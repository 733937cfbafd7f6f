"""A picture of one remeshing experiment: source, rebuilt target coloured by error, zero-detail
baseline (matplotlib, headless)."""

import os

import numpy as np

from ..io.atomic import atomic_write, check_output_path


#: Below this fraction of the triangles' total area, the area-weighted mean normal is taken as
#: zero (a closed surface, a symmetric patch: rounding alone, pointing anywhere).
FLAT_NORMAL_RELATIVE = 1e-9


def _view_frame(V, F):
    """Rotation taking the patch's area-weighted mean normal to +z (we look down on it); where the
    normals cancel (a closed surface, a symmetric patch), the direction in which the vertices
    spread least (the last right singular vector of the centred points; sign: its largest
    component positive)."""
    normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n = normals.sum(0)
    if not np.linalg.norm(n) > FLAT_NORMAL_RELATIVE * np.linalg.norm(normals, axis=1).sum():
        n = np.linalg.svd(V - V.mean(0), full_matrices=False)[2][-1]
        n = -n if n[np.argmax(np.abs(n))] < 0 else n
    z = n / max(np.linalg.norm(n), np.finfo(float).tiny)
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def _draw(ax, V, F, R, centre, scale, values=None, vmax=None, title=""):
    from matplotlib import cm
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    P = (V - centre) @ R.T / scale
    tri = P[F]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), np.finfo(float).tiny)
    light = np.array([0.3, -0.4, 0.87])
    shade = 0.35 + 0.65 * np.clip(np.abs(normal @ light), 0, 1)
    if values is None:
        colour = np.column_stack([0.75 * shade, 0.78 * shade, 0.85 * shade, np.ones_like(shade)])
    else:
        face_val = values[F].mean(1) / max(vmax, np.finfo(float).tiny)
        colour = cm.viridis(np.clip(face_val, 0, 1))
        colour[:, :3] *= shade[:, None] * 0.4 + 0.6
    coll = Poly3DCollection(tri, facecolors=colour, edgecolors="none", linewidths=0)
    ax.add_collection3d(coll)
    ax.set_xlim(-0.5, 0.5)
    ax.set_ylim(-0.5, 0.5)
    ax.set_zlim(-0.5, 0.5)
    ax.view_init(elev=50, azim=-70)
    ax.set_box_aspect((1, 1, 1), zoom=1.35)
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)


def save_figure(path, V, F, X, Ft, Z, distance, report, *, overwrite=False, dpi=110):
    """Write a PNG with three panels: the source, the rebuilt target coloured by its distance to
    the source (colour scale: 0 to the largest vertex distance), and the zero-detail baseline;
    the error figures are in the titles. Written atomically; an existing file is kept unless
    ``overwrite``.

    Parameters
    ----------
    path : str                   PNG file
    V, F : source mesh
    X, Ft : rebuilt target
    Z : (p, 3) float array       zero-detail baseline positions (triangles ``Ft``)
    distance : (p,) float array  per-vertex distance of ``X`` to the source
    report : dict                from :func:`remesh_experiment`, measured (``evaluate=True``)

    Raises
    ------
    ValueError         ``report`` without the measurements (a run with ``evaluate=False``), or
                       ``distance`` not one finite value per vertex of ``X``
    FileExistsError    ``path`` exists and ``overwrite`` is False
    """
    missing = [key for key in ("error", "baseline_zero_detail", "floor_retriangulated") if key not in report]
    if missing:
        raise ValueError(f"report has no {', '.join(missing)}: the figure shows the measured errors; pass the "
                         "report of a run with evaluate=True (remesh_experiment's default).")
    X = np.asarray(X, dtype=np.float64)
    got = "is None" if distance is None else f"has shape {np.shape(distance)}"
    distance = np.asarray(distance if distance is not None else [], dtype=np.float64)
    if distance.shape != (X.shape[0],) or not np.isfinite(distance).all():
        raise ValueError(f"distance {got} for {X.shape[0]} rebuilt vertices: pass one finite "
                         "distance per vertex of X (run_experiment's result['distance'], measured with "
                         "evaluate=True).")
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    path = check_output_path(path, overwrite)
    R = _view_frame(V, F)
    centre = 0.5 * (V.max(0) + V.min(0))
    P = (V - centre) @ R.T
    scale = float((P.max(0) - P.min(0)).max())
    e, b, fl = report["error"], report["baseline_zero_detail"], report["floor_retriangulated"]
    name = os.path.basename(report["source"].get("path") or "source")
    fig = plt.figure(figsize=(12, 4.4))
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    _draw(ax, V, F, R, centre, scale, title=f"{name}: {report['source']['vertices']:,} vertices")
    ax = fig.add_subplot(1, 3, 2, projection="3d")
    vmax = float(np.max(distance)) if len(distance) else 1.0
    o = report["options"]
    _draw(ax, X, Ft, R, centre, scale, values=distance, vmax=vmax,
          title=(f"rebuilt ({o['transfer']}, rows={o['rows']}): {report['target']['vertices']:,} vertices\n"
                 f"RMS {100 * e['hausdorff_rms']:.3f} %  max {100 * e['hausdorff_max']:.2f} %  "
                 f"(floor {100 * fl['hausdorff_rms']:.3f} %)"))
    ax = fig.add_subplot(1, 3, 3, projection="3d")
    _draw(ax, Z, Ft, R, centre, scale,
          title=f"zero detail\nRMS {100 * b['hausdorff_rms']:.2f} %  max {100 * b['hausdorff_max']:.1f} %")
    from matplotlib import cm
    from matplotlib.colors import Normalize

    sm = cm.ScalarMappable(norm=Normalize(0, 100 * vmax / report["source"]["bbox_diagonal"]),
                           cmap=cm.viridis)
    cb = fig.colorbar(sm, ax=fig.axes[1], shrink=0.6, pad=0.02, orientation="horizontal")
    cb.set_label("distance to source, % of bbox diagonal", fontsize=8)
    fig.suptitle("Remeshing from curvature detail (all figures: % of the source's bbox diagonal)", fontsize=10)
    try:
        with atomic_write(path, overwrite=overwrite) as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format="png")
    finally:
        plt.close(fig)
