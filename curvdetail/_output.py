"""Output files for the remeshing, filter and editing code: checked before any work, written
atomically with a normal file's permissions.

:func:`atomic_output` gives a temporary path in the destination's folder; the caller writes
there (with pymeshlab, matplotlib, ``open``...), and the file is renamed over the destination
only when the ``with`` block succeeded, with the permissions a new file gets from the umask
(``tempfile.mkstemp`` alone leaves ``0600``). A failed block removes the temporary file, so no
half-written output is ever left behind. Several outputs of one run (mesh, report, picture)
nest in one ``with`` statement and appear together, only when all were written.
"""

import contextlib
import os
import tempfile

from .curvature._validate import check_bool
from .curvature.errors import MeshError

_FORMATS_HINT = "use .ply, .obj, .off, .stl, ..."

#: Temporary files of the :func:`atomic_output` blocks in progress, for the CLI's SIGTERM
#: watcher, which removes them before it ends the process.
PENDING = set()


def check_output_path(path, overwrite=False, *, hint=_FORMATS_HINT, error=MeshError):
    """Return ``os.fspath(path)`` or raise before any work if it cannot be written.

    Raises
    ------
    ValueError        ``path`` is not a path, or ``overwrite`` is not a bool
    FileExistsError   ``path`` exists and ``overwrite`` is False
    IsADirectoryError ``path`` is a folder, where ``error`` is an ``OSError`` (else ``error``)
    PermissionError   its folder is not writable, where ``error`` is an ``OSError`` (else
                      ``error``)
    error             (default :class:`~curvdetail.curvature.errors.MeshError`; the filters
                      pass their ``MeshFileError``) ``path`` is a folder, its folder does not
                      exist, or ``path`` has no extension to pick the format (``hint`` says
                      which to use; ``hint=None``: any name will do)
    """
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise ValueError(f"an output path must be a str or os.PathLike; got {type(path).__name__}.")
    check_bool(overwrite, "overwrite")
    path = os.fsdecode(path)
    if os.path.isdir(path):       # --overwrite cannot help: a folder is never replaced
        kind = IsADirectoryError if issubclass(error, OSError) else error
        raise kind(f"cannot write {path!r}: it is a folder; name a file (in it, or elsewhere).")
    if os.path.exists(path) and not overwrite:
        raise FileExistsError(f"{path} exists; pass --overwrite (overwrite=True) to replace it.")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise error(f"cannot write {path!r}: folder {folder!r} does not exist.")
    if not os.access(folder, os.W_OK | os.X_OK):       # found now, not after minutes of work
        kind = PermissionError if issubclass(error, OSError) else error
        raise kind(f"cannot write {path!r}: folder {folder!r} is not writable.")
    if hint is not None and not os.path.splitext(path)[1]:
        raise error(f"cannot write {path!r}: no file extension to choose the format from ({hint}).")
    return path


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_output(path, *, overwrite=False, hint=_FORMATS_HINT, error=MeshError):
    """Context manager yielding a temporary path to write ``path``'s content to.

    The destination is checked first (:func:`check_output_path`). The temporary file exists
    (empty) and has ``path``'s extension, so writers that pick the format from it work; write
    to it with ``overwrite=True`` where the writer refuses existing files.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "note.txt")
    >>> with atomic_output(path) as tmp:
    ...     with open(tmp, "w") as fh:
    ...         _ = fh.write("done")
    >>> open(path).read()
    'done'
    """
    path = check_output_path(path, overwrite, hint=hint, error=error)
    try:
        fd, tmp = tempfile.mkstemp(prefix=".curvdetail-", suffix=os.path.splitext(path)[1],
                                   dir=os.path.dirname(os.path.abspath(path)))
    except OSError as exc:        # its message would name the temporary file, not the output
        raise type(exc)(exc.errno, f"cannot write {path!r}: {exc.strerror}") from None
    os.close(fd)
    PENDING.add(tmp)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        PENDING.discard(tmp)
        with contextlib.suppress(FileNotFoundError):     # the SIGTERM watcher may have taken it
            os.remove(tmp)
