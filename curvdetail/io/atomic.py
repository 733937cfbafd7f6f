"""One atomic write for every output: a temporary file in the destination's folder, renamed over
the destination only when the writer succeeded.

A failed or interrupted write (an exception, Ctrl-C, or SIGTERM where the CLI turns it into an
exception) removes the temporary file, so no partial output is ever left. An existing file is
replaced only with ``overwrite=True``; without it the file is put in place with a hard link,
which fails if another process made the destination meanwhile.
"""

import contextlib
import os
import tempfile

from ..curvature.errors import MeshError


def check_output_path(path, overwrite=False, *, parameter="path"):
    """Return ``os.fspath(path)``, or raise before any work if it cannot be written.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False.
    MeshError
        ``path`` is not a path, is a folder, or its folder does not exist or is not writable
        (``e.parameter`` is ``parameter``).
    """
    try:
        path = os.fspath(path)
    except TypeError:
        raise MeshError(f"{parameter} must be a file path, not {type(path).__name__}",
                        parameter=parameter, value=path) from None
    if os.path.isdir(path):
        raise MeshError(f"{path!r} is a folder", parameter=parameter, value=path,
                        hint="give a file name")
    if os.path.lexists(path) and not overwrite:
        err = FileExistsError(f"{path!r} exists; pass overwrite=True to replace it")
        err.filename, err.parameter, err.value = path, parameter, path
        raise err
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise MeshError(f"the folder of {path!r} does not exist", parameter=parameter, value=path,
                        hint="create it first")
    if not os.access(folder, os.W_OK):
        raise MeshError(f"the folder of {path!r} is not writable", parameter=parameter, value=path,
                        hint="choose another folder")
    return path


@contextlib.contextmanager
def atomic_write(path, *, overwrite=False, parameter="path"):
    """Yield a temporary path beside ``path`` (same extension); on success move it into place.

    Write the output to the yielded path with any library (pymeshlab, plyfile, matplotlib,
    ``open``). The file gets a normal file's permissions (the umask's), not ``mkstemp``'s 0600.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False (checked before and after writing).
    OSError
        The write or the rename failed (``e.filename`` is ``path``); nothing is left behind.

    Examples
    --------
    >>> import os, tempfile
    >>> out = os.path.join(tempfile.mkdtemp(), "a.txt")
    >>> with atomic_write(out) as tmp:
    ...     _ = open(tmp, "w").write("hello")
    >>> open(out).read()
    'hello'
    """
    path = check_output_path(path, overwrite, parameter=parameter)
    folder, name = os.path.split(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".curvdetail-", suffix=os.path.splitext(name)[1], dir=folder)
    try:
        os.close(fd)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        yield tmp
        try:
            if overwrite:
                os.replace(tmp, path)
            else:
                os.link(tmp, path)
        except OSError as exc:
            if exc.filename is None:
                exc.filename = path
            raise
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.remove(tmp)
