"""How the reproduction and benchmark scripts write their files: each checked before any work
(an existing one refused unless the script's --force), then written through
:func:`curvdetail.io.atomic_write` when its content is ready, one after another."""

import json
import os

from curvdetail.io import atomic_write, check_output_path


def check_outputs(parser, paths, force, flag="--force"):
    """``parser.error`` (exit status 2) for the first of ``paths`` that cannot be written: it
    exists (unless ``force``), is a folder, or its folder is not writable. A missing folder is
    made when the file is written."""
    for path in paths:
        if path is None or not os.path.isdir(os.path.dirname(os.path.abspath(path))):
            continue
        try:
            check_output_path(path, force)
        except FileExistsError:
            parser.error(f"{path} exists; pass {flag} to replace it.")
        except ValueError as exc:
            parser.error(str(exc))


def write_bytes(path, content, force):
    """Write ``content`` to ``path`` atomically, making its folder where missing."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with atomic_write(path, overwrite=force) as tmp, open(tmp, "wb") as fh:
        fh.write(content)


def write_text(path, text, force):
    write_bytes(path, text.encode("utf-8"), force)


def write_json(path, obj, force, *, end="", **dump_options):
    write_text(path, json.dumps(obj, **dump_options) + end, force)


def save_figure(fig, path, force, **savefig_options):
    """``fig.savefig`` to ``path`` atomically (the format from ``path``'s extension)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with atomic_write(path, overwrite=force) as tmp:
        fig.savefig(tmp, format=os.path.splitext(path)[1].lstrip(".").lower() or "png", **savefig_options)


def render_panels(path, panels, force, **options):
    """:func:`curvdetail.plot.save_panels` to ``path``, making its folder."""
    from curvdetail.plot import save_panels

    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    save_panels(path, panels, overwrite=force, **options)


def stack_pictures(path, sources, force, dpi=100):
    """The PNG files ``sources``, one row each, top to bottom, at their own resolution, to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt

    pictures = [mpimg.imread(source) for source in sources]
    width = max(p.shape[1] for p in pictures)
    fig, axes = plt.subplots(len(pictures), 1, figsize=(width / dpi, sum(p.shape[0] for p in pictures) / dpi),
                             gridspec_kw={"height_ratios": [p.shape[0] for p in pictures]})
    for ax, picture in zip(axes, pictures):
        ax.imshow(picture)
        ax.set_axis_off()
    fig.subplots_adjust(left=0, right=1, bottom=0, top=1, hspace=0)
    try:
        save_figure(fig, path, force, dpi=dpi)
    finally:
        plt.close(fig)


def measured_conditions():
    """``{"utc", "load_average", "peak_rss_gb"}``: when and under what load a script measured,
    and this process's peak resident memory so far; call it after the work."""
    import datetime
    import resource
    import sys

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss    # KiB on Linux, bytes on macOS
    return {"utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S"),
            "load_average": list(os.getloadavg()),
            "peak_rss_gb": rss / 1024.0 ** (3 if sys.platform == "darwin" else 2)}


def environment():
    """``{"machine", "cpus", "python", "versions"}``: the machine and the library versions of a run
    (numpy, scipy, pymeshlab, pypardiso where installed)."""
    import platform
    from importlib import metadata

    versions = {}
    for name in ("numpy", "scipy", "pymeshlab", "pypardiso"):
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    return {"machine": platform.platform(), "cpus": os.cpu_count(), "python": platform.python_version(),
            "versions": versions}


def environment_line(env):
    """The line that heads a table: machine, CPU count, Python and library versions."""
    libs = ", ".join(f"{name} {version}" for name, version in env["versions"].items())
    return f"Machine: {env['machine']}, {env['cpus']} CPUs; Python {env['python']}, {libs}."
