"""Pictures of meshes (matplotlib, headless): one renderer for every figure of the package.

`draw_mesh` draws a mesh, grey or coloured by per-vertex values, into a 2-D matplotlib axes
(orthographic camera, Lambert shading, faces drawn far to near); `save_panels` saves a row
of such panels as a PNG; `save_remeshing_figure` is the picture of one remeshing experiment.
"""

import os

import numpy as np

from .io.atomic import atomic_write

#: Light direction in the camera frame (x right, y up, z towards the viewer).
LIGHT = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
#: Colour of a mesh drawn without values (a light blue-grey).
GREY = (0.75, 0.78, 0.85)


def camera(elev, azim):
    """Rotation ``R`` taking world coordinates (z up) to the camera's (x right, y up, z to the
    viewer) for an elevation and azimuth in degrees: ``V @ R.T`` are camera coordinates."""
    e, a = np.radians(elev), np.radians(azim)
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, np.cos(e - np.pi / 2), -np.sin(e - np.pi / 2)],
                   [0, np.sin(e - np.pi / 2), np.cos(e - np.pi / 2)]])
    return Rx @ Rz.T


def view_direction(elev, azim):
    """Unit vector (world, z up) from the scene towards the viewer of this camera."""
    return camera(elev, azim)[2].copy()


def top_view(V, F):
    """Rotation ``R`` taking a patch's area-weighted mean normal to +z (``V @ R.T`` is seen from
    above); where the normals cancel (a closed surface), the direction in which the vertices spread
    least, its largest component positive."""
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F)
    normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n = normals.sum(0)
    if not np.linalg.norm(n) > 1e-9 * np.linalg.norm(normals, axis=1).sum():
        n = np.linalg.svd(V - V.mean(0), full_matrices=False)[2][-1]
        n = -n if n[np.argmax(np.abs(n))] < 0 else n
    z = n / max(np.linalg.norm(n), np.finfo(float).tiny)
    x = np.cross([1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def draw_mesh(ax, V, F, values=None, *, elev=20.0, azim=-60.0, cmap="viridis", title="", vrange=None):
    """Draw a shaded mesh into a 2-D matplotlib axes, fitted to the axes with equal aspect.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        A plain (2-D) axes; its axis lines are turned off.
    V : (n, 3) float array
        Vertex positions, world coordinates with z up.
    F : (m, 3) int array
        Triangles.
    values : (n,) float array, optional
        Per-vertex values; each face is coloured by its vertices' mean, from ``vrange`` (default:
        the values' minimum to their maximum; values beyond it take the end colours). Without
        values the mesh is grey.
    elev, azim : float
        Camera, as for `camera`.
    cmap : str or matplotlib.colors.Colormap
        Colour map of ``values``.
    title : str
        Panel title.
    vrange : (float, float), optional
        The values at the two ends of the colour map.

    Returns
    -------
    mappable : matplotlib.cm.ScalarMappable or None
        The values' colour scale (for a colour bar); None without values.
    """
    import matplotlib
    from matplotlib.cm import ScalarMappable
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import Normalize

    P = np.asarray(V, dtype=np.float64) @ camera(elev, azim).T
    F = np.asarray(F)
    tri = P[F]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), np.finfo(float).tiny)
    shade = 0.25 + 0.75 * np.abs(normal @ LIGHT)
    mappable = None
    if values is None:
        rgb = np.tile(GREY, (F.shape[0], 1))
    else:
        values = np.asarray(values, dtype=np.float64)
        lo, hi = vrange if vrange is not None else (float(np.nanmin(values)), float(np.nanmax(values)))
        cmap = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
        mappable = ScalarMappable(Normalize(lo, hi if hi > lo else lo + 1.0), cmap)
        rgb = mappable.to_rgba(values[F].mean(axis=1))[:, :3]
    colours = np.clip(rgb * shade[:, None], 0.0, 1.0)
    order = np.argsort(tri[:, :, 2].mean(axis=1))            # far faces first
    ax.add_collection(PolyCollection(tri[order][:, :, :2], facecolors=colours[order], edgecolors="none",
                                     antialiased=False))
    ax.set_xlim(P[:, 0].min(), P[:, 0].max())
    ax.set_ylim(P[:, 1].min(), P[:, 1].max())
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)
    return mappable


def save_panels(path, panels, *, elev=20.0, azim=-60.0, title=None, panel_size=4.0, dpi=100,
                colorbar=None, vrange=None, overwrite=False):
    """Save meshes side by side, seen by one camera, as a PNG, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Destination ``.png``; ``panel_size * dpi`` pixels high, ``len(panels)`` times that wide.
    panels : list of (V, F, label) or (V, F, label, values)
        The meshes, drawn by `draw_mesh`.
    elev, azim : float
        Camera, as for `camera`.
    title : str, optional
        Figure title.
    panel_size : float
        Size of one panel in inches.
    dpi : int
        Pixels per inch.
    colorbar : str, optional
        Label of a colour bar drawn under every panel with values; none without it.
    vrange : (float, float), optional
        One colour scale for every panel (`draw_mesh`); default: each panel its own.
    overwrite : bool
        Replace an existing file.

    Raises
    ------
    FileExistsError
        If ``path`` exists and ``overwrite`` is False.

    Examples
    --------
    >>> import os, tempfile
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5); V[:, 2] = V[:, 0] * V[:, 1]
    >>> save_panels(os.path.join(tempfile.mkdtemp(), "p.png"), [(V, F, "flat"), (V, F, "height", V[:, 2])])
    """
    from matplotlib.figure import Figure

    with atomic_write(path, overwrite=overwrite) as tmp:
        fig = Figure(figsize=(panel_size * len(panels), panel_size))
        for ax, (V, F, label, *values) in zip(fig.subplots(1, len(panels), squeeze=False)[0], panels):
            mappable = draw_mesh(ax, V, F, values[0] if values else None, elev=elev, azim=azim, title=label,
                                 vrange=vrange)
            if colorbar and mappable is not None:
                over = vrange is not None and np.nanmax(values[0]) > vrange[1]
                bar = fig.colorbar(mappable, ax=ax, orientation="horizontal", fraction=0.05, pad=0.02, shrink=0.7,
                                   extend="max" if over else "neither")
                bar.set_label(colorbar, fontsize=8)
                bar.ax.tick_params(labelsize=7)
        if title:
            fig.suptitle(title, fontsize=11)
        fig.tight_layout(pad=1.6)
        fig.savefig(tmp, dpi=dpi, format="png")


def save_remeshing_figure(path, V, F, X, Ft, Z, distance, report, *, zero_distance=None, overwrite=False, dpi=110):
    """Save the picture of one remeshing experiment: the source, the rebuilt target coloured by
    its distance to the source, and the zero-detail baseline, the errors in the titles. Both
    coloured surfaces share one scale, in % of the bbox diagonal, from 0 to the rebuilt
    surface's Hausdorff maximum its title states (a zero-detail surface farther away takes the
    top colour there, the colour bar's arrow).

    Parameters
    ----------
    path : str or os.PathLike
        Destination ``.png``.
    V, F : (n, 3) float array, (m, 3) int array
        The source mesh.
    X, Ft : (p, 3) float array, (q, 3) int array
        The rebuilt target; ``Z`` (p, 3) is the zero-detail baseline on the same triangles.
    distance : (p,) float array
        Distance of each vertex of ``X`` to the source.
    zero_distance : (p,) float array, optional
        Distance of each vertex of ``Z`` to the source (``run_experiment``'s
        ``result["zero_distance"]``); the zero-detail panel is grey without it.
    report : dict
        The report of `curvdetail.remesh.remesh_experiment`, measured (``evaluate=True``).

    Raises
    ------
    ValueError
        If ``report`` lacks the measurements or ``distance`` is not one finite value per vertex of X.
    FileExistsError
        If ``path`` exists and ``overwrite`` is False.
    """
    missing = [key for key in ("error", "baseline_zero_detail", "floor_retriangulated") if key not in report]
    if missing:
        raise ValueError(f"report has no {', '.join(missing)}: pass the report of a run with evaluate=True")
    X = np.asarray(X, dtype=np.float64)
    distance = np.asarray(distance if distance is not None else [], dtype=np.float64)
    if distance.shape != (X.shape[0],) or not np.isfinite(distance).all():
        raise ValueError(f"distance has shape {distance.shape} for {X.shape[0]} rebuilt vertices: pass one finite "
                         "distance per vertex of X (run_experiment's result['distance'])")
    V = np.asarray(V, dtype=np.float64)
    R = top_view(V, F)
    e, b, fl = report["error"], report["baseline_zero_detail"], report["floor_retriangulated"]
    rms, top = "hausdorff_rms_percent_of_diagonal", "hausdorff_max_percent_of_diagonal"
    name = os.path.basename(report["source"].get("path") or "source")
    o = report["options"]
    panels = [(V @ R.T, F, f"{name}: {report['source']['vertices']:,} vertices"),
              (X @ R.T, Ft, f"rebuilt ({o['transfer']}, rows={o['rows']}): {report['target']['vertices']:,} "
                            f"vertices\nRMS {e[rms]:.3f} %  max {e[top]:.2f} %  "
                            f"(floor {fl[rms]:.3f} %)",
               100 * distance / report["source"]["bbox_diagonal"])]
    if Z is not None and b is not None:     # none for a closed piece (it collapses onto its anchor)
        panels.append((np.asarray(Z, dtype=np.float64) @ R.T, Ft, f"zero detail\nRMS {b[rms]:.2f} %  max {b[top]:.1f} %")
                      + (() if zero_distance is None else
                         (100 * np.asarray(zero_distance) / report["source"]["bbox_diagonal"],)))
    save_panels(path, panels, elev=50.0, azim=20.0, panel_size=4.0, dpi=dpi, overwrite=overwrite,
                title="Remeshing from curvature detail (all figures: % of the source's bbox diagonal)",
                colorbar="distance to source, % of bbox diagonal", vrange=(0.0, max(e[top], 1e-300)))


#: The colour map of the vertex colours written next to a per-vertex error or curvature.
COLOUR_MAP = "viridis"


def vertex_colours(values, vmax, vmin=0.0, cmap=COLOUR_MAP):
    """Per-vertex RGBA colours, ``cmap`` over ``[vmin, vmax]`` (values beyond it clipped), so that
    a viewer that shows vertex colours on open (MeshLab) shows the values.

    Parameters
    ----------
    values : (n,) float array
    vmax, vmin : float
        The values at the two ends of the map (``vmax <= vmin``: every vertex the bottom colour).
    cmap : str
        A matplotlib colour map (pymeshlab's ``compute_color_from_scalar_per_vertex`` has the
        same viridis as ``colormap="Viridis"``).

    Returns
    -------
    (n, 4) uint8 array   red, green, blue, alpha (255)

    Examples
    --------
    >>> vertex_colours([0.0, 1.0, 2.0], vmax=1.0)[:, :3].tolist()
    [[68, 1, 84], [253, 231, 37], [253, 231, 37]]
    """
    import matplotlib

    values = np.asarray(values, dtype=np.float64)
    span = vmax - vmin if vmax > vmin else 1.0
    rgba = matplotlib.colormaps[cmap](np.clip((values - vmin) / span, 0.0, 1.0))
    return np.rint(rgba * 255.0).astype(np.uint8)
