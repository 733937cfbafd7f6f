"""How the reproduction and benchmark scripts write their files (JSON, markdown, pictures, and
the blocks they refresh inside docs/*.md): through :mod:`curvdetail._output`, as the package's
own outputs are.

* Before any work, :func:`refuse_existing` stops a script (``parser.error``, exit status 2) at
  an output file that exists, naming the file and the flag that allows replacing it (``--force``;
  bench_reconstruct.py: ``--overwrite``, as its ``--force`` runs the cases left out by default).
* Every file is written atomically (:func:`curvdetail._output.atomic_output`: a temporary file
  in the destination's folder, renamed over it once complete), so a failed or interrupted write
  leaves the old file as it was and no temporary file; matplotlib figures are saved to the
  temporary path with their format given explicitly.
"""

import contextlib
import json
import os

from curvdetail._output import atomic_output, check_output_path


def refuse_existing(parser, paths, force, flag="--force"):
    """Check the outputs of a run before any work; ``parser.error`` (exit status 2) at the first
    that cannot be written.

    ``paths``: the files the run writes (None: not written this run). One that exists is refused
    unless ``force`` (the message names it and ``flag``); a folder given for a file, or an
    existing folder that is not writable, is refused too. A file whose folder does not exist yet
    (the script makes it) has nothing to replace.
    """
    for path in paths:
        if path is None or not os.path.isdir(os.path.dirname(os.path.abspath(path))):
            continue
        try:
            check_output_path(path, force, hint=None, error=FileNotFoundError, flag=flag)
        except OSError as exc:
            parser.error(str(exc))


@contextlib.contextmanager
def atomic(path, force, flag="--force"):
    """:func:`curvdetail._output.atomic_output` for a script's output: yields the temporary path
    to write ``path``'s content to; ``force`` allows replacing an existing file (a refusal names
    ``flag``)."""
    with atomic_output(path, overwrite=force, hint=None, error=FileNotFoundError, flag=flag) as tmp:
        yield tmp


def write_text(path, text, force, flag="--force"):
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic(path, force, flag) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


def write_json(path, obj, force, flag="--force", *, end="", **dump_options):
    """``json.dump(obj)`` (with ``dump_options``) and ``end`` to ``path`` atomically."""
    with atomic(path, force, flag) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(obj, fh, **dump_options)
            fh.write(end)


def save_figure(fig, path, force, flag="--force", **savefig_options):
    """``fig.savefig`` to ``path`` atomically, the format (from ``path``'s extension) given
    explicitly, as the temporary file's name does not choose it."""
    fmt = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    with atomic(path, force, flag) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_options)


def render_panels(path, panels, force, **options):
    """:func:`curvdetail.deformation_benchmark.render_panels` (which writes atomically) with
    ``overwrite=force``; :func:`refuse_existing` has checked ``path`` before the work."""
    from curvdetail.deformation_benchmark import render_panels as render

    render(path, panels, overwrite=force, **options)
