"""How the reproduction and benchmark scripts write their files (JSON, markdown, pictures, and
the blocks they refresh inside docs/*.md): checked before any work, committed together after it.

A script makes one :class:`Run` right after parsing its arguments, naming every file it writes:

* Before any work, each output is checked, and the first that cannot be written stops the
  script (``parser.error``: usage message, exit status 2) with a message naming it and the fix:
  a file that exists, unless the script's ``--force`` (bench_reconstruct.py: ``--overwrite``, as
  its ``--force`` runs the cases left out by default); a folder given for a file; a folder that
  does not exist (except the script's own ``--out`` folder, which it makes: then the folder it
  would be made in is checked), that is a file, or that is not writable.
* During the work, the outputs are kept in memory (pictures are rendered in a scratch folder
  and read back); no destination is touched.
* :meth:`Run.commit` writes them together through :func:`curvdetail._output.atomic_outputs`:
  every output to a temporary file beside its destination first, then all renamed into place.
  A failure before the renames removes the temporary files and leaves every old file as it was;
  a rename that fails takes back those done (the error names the output; the run's results
  go with the process). The renames are still one system call each, not one for all: a process
  reading the files during the commit, or a crash in the middle of it, can see some new files
  and some old (that module's docstring says what is left). bench_reconstruct.py also commits
  its JSON after each group of a run of several, on purpose: a run stopped part-way keeps them.
"""

import contextlib
import io
import json
import os
import shlex
import tempfile

from curvdetail._output import Output, atomic_output, atomic_outputs, check_output_path


class _Planned:
    """One output of a :class:`Run`: its path as given, whether an existing file may be replaced,
    and the option a refusal names."""

    def __init__(self, path, force, flag):
        self.path, self.force, self.flag = path, force, flag


def _key(path):
    return os.path.abspath(os.fsdecode(path))


class Run:
    """The output files of one run of a script: checked now, kept during the work, written
    together by :meth:`commit` (see the module docstring).

    Parameters
    ----------
    parser : argparse.ArgumentParser   its ``error`` refuses an output (exit status 2)
    paths : iterable of str or None    the files the run writes (None: not written this run)
    force : bool                       an existing file may be replaced
    flag : str                         the option that a refusal of an existing file names
    makes : iterable of str            folders the run makes where they are missing (its
                                       ``--out`` folder; :meth:`commit` makes them): checked that
                                       they can be made. Every other output's folder must exist.
    """

    def __init__(self, parser, paths=(), force=False, flag="--force", *, makes=()):
        self._parser = parser
        self._makes = {_key(folder) for folder in makes}
        self._planned = {}          # abspath -> _Planned
        self._content = {}          # abspath -> bytes, in the order written
        self.check(paths, force, flag)

    def check(self, paths, force, flag="--force"):
        """Check more outputs, with their own ``force`` and ``flag``, before any work."""
        for path in paths:
            if path is None:
                continue
            key = _key(path)
            if key in self._planned:
                self._parser.error(f"{path} is given for two outputs; name a separate file for each.")
            problem = self._folder_problem(path) or _file_problem(path, force, flag)
            if problem:
                self._parser.error(problem)
            self._planned[key] = _Planned(path, force, flag)

    def _folder_problem(self, path):
        """Why ``path``'s folder cannot take it (a message naming the fix), or None."""
        folder = os.path.dirname(_key(path))
        shown = os.path.dirname(path) or "."
        existing = folder
        while not os.path.lexists(existing):
            existing = os.path.dirname(existing)
        if not os.path.isdir(existing):
            return (f"cannot write {path!r}: {existing!r} is not a folder; name a folder for it "
                    "(or move that file away).")
        if existing != folder and folder not in self._makes:
            return (f"cannot write {path!r}: folder {shown!r} does not exist; create it first "
                    f"(mkdir -p {shlex.quote(shown)}) or name a folder that exists.")
        if not os.access(existing, os.W_OK | os.X_OK):
            what = f"folder {shown!r} is not writable" if existing == folder else \
                f"folder {shown!r} cannot be made: {existing!r} is not writable"
            return f"cannot write {path!r}: {what}; make it writable or name another folder."
        return None

    def _find(self, path):
        key = _key(path)
        if key not in self._planned:
            raise ValueError(f"{path} was not checked before the work; name it in the Run's outputs.")
        return key

    def _keep(self, path, content):
        self._content[self._find(path)] = content

    def write_text(self, path, text):
        """Keep ``text`` (UTF-8) for ``path``."""
        self._keep(path, text.encode("utf-8"))

    def write_json(self, path, obj, *, end="", **dump_options):
        """Keep ``json.dumps(obj, **dump_options)`` and ``end`` for ``path``."""
        self._keep(path, (json.dumps(obj, **dump_options) + end).encode("utf-8"))

    @contextlib.contextmanager
    def stage(self, path):
        """Yield a path in a new scratch folder, with ``path``'s name (so its extension), to
        write ``path``'s content to; the content is kept when the block succeeds, and the
        scratch folder removed either way."""
        self._find(path)
        with tempfile.TemporaryDirectory(prefix="curvdetail-stage-") as scratch:
            tmp = os.path.join(scratch, os.path.basename(path))
            yield tmp
            with open(tmp, "rb") as fh:
                content = fh.read()
        self._keep(path, content)

    def save_figure(self, fig, path, **savefig_options):
        """Keep ``fig.savefig``'s picture for ``path`` (see :func:`save_figure`)."""
        with self.stage(path) as tmp:
            save_figure(fig, tmp, False, **savefig_options)

    def render_panels(self, path, panels, **options):
        """Keep :func:`curvdetail.plot.save_panels`'s picture for ``path``."""
        from curvdetail.plot import save_panels

        with self.stage(path) as tmp:
            save_panels(tmp, panels, **options)

    def stack_pictures(self, path, sources, dpi=100):
        """Keep for ``path`` the pictures kept for ``sources`` (PNG), one row each, top to bottom,
        each at its own resolution (``dpi`` pixels per inch): the labels stay readable."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt

        pictures = [mpimg.imread(io.BytesIO(self.read(source))) for source in sources]
        width = max(p.shape[1] for p in pictures)
        fig, axes = plt.subplots(len(pictures), 1, figsize=(width / dpi, sum(p.shape[0] for p in pictures) / dpi),
                                 gridspec_kw={"height_ratios": [p.shape[0] for p in pictures]})
        for ax, picture in zip(axes, pictures):
            ax.imshow(picture)
            ax.set_axis_off()
        fig.subplots_adjust(left=0, right=1, bottom=0, top=1, hspace=0)
        try:
            self.save_figure(fig, path, dpi=dpi)
        finally:
            plt.close(fig)

    def read(self, path):
        """The content kept for ``path`` (bytes), e.g. a picture that a composite reuses."""
        return self._content[self._find(path)]

    def commit(self, paths=None):
        """Write the outputs kept so far (``paths``: only these) together, all or none (see the
        module docstring), making the ``makes`` folders they need; afterwards they are this
        run's own files, which a later commit (a progress save updated) may replace.

        Raises what :func:`curvdetail._output.atomic_outputs` raises: ``FileExistsError`` where
        a file refused now appeared during the work, ``OSError`` where an output cannot be
        written (the message names it; no output was written, folders made are removed).
        """
        keys = list(self._content) if paths is None else [self._find(p) for p in paths]
        if not keys:
            return
        planned = [self._planned[key] for key in keys]
        made = []
        try:
            for out in planned:
                folder = os.path.dirname(_key(out.path))
                if folder in self._makes:
                    made += _make_folder(folder)
            for out in planned:     # a file that appeared during the work, where none may be replaced
                if not out.force:
                    check_output_path(out.path, False, hint=None, error=FileNotFoundError, flag=out.flag)
            outputs = [Output(out.path, None, FileNotFoundError, out.flag) for out in planned]
            with atomic_outputs(outputs, overwrite=any(out.force for out in planned)) as temps:
                for tmp, key in zip(temps, keys):
                    with open(tmp, "wb") as fh:
                        fh.write(self._content[key])
        except BaseException:
            for folder in reversed(made):
                with contextlib.suppress(OSError):
                    os.rmdir(folder)
            raise
        for key, out in zip(keys, planned):
            del self._content[key]
            out.force = True


def _file_problem(path, force, flag):
    """Why ``path`` itself cannot be written (it exists, or is a folder), or None."""
    if not os.path.isdir(os.path.dirname(_key(path))):
        return None                 # its folder is made by the run: nothing there to replace
    try:
        check_output_path(path, force, hint=None, error=FileNotFoundError, flag=flag)
    except OSError as exc:
        return str(exc)
    return None


def _make_folder(folder):
    """``os.makedirs(folder)``; the folders it made, outermost first."""
    missing = []
    while not os.path.lexists(folder):
        missing.append(folder)
        folder = os.path.dirname(folder)
    for made in reversed(missing):
        os.mkdir(made)
    return missing[::-1]


def save_figure(fig, path, force, flag="--force", **savefig_options):
    """``fig.savefig`` to ``path`` atomically, the format (from ``path``'s extension) given
    explicitly, as the temporary file's name does not choose it."""
    fmt = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    with atomic_output(path, overwrite=force, hint=None, error=FileNotFoundError, flag=flag) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_options)


def measured_conditions():
    """``{"utc", "load_average", "peak_rss_gb"}``: when and under what load a script measured,
    and this process's peak resident memory so far (``ru_maxrss``, as scripts/bench_*.py record
    it), for its JSON; call it after the work."""
    import datetime
    import resource
    import sys

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss    # KiB on Linux, bytes on macOS
    return {"utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S"),
            "load_average": list(os.getloadavg()),
            "peak_rss_gb": rss / 1024.0 ** (3 if sys.platform == "darwin" else 2)}
