"""One atomic write for every output: a temporary file in the destination's folder, renamed over
the destination only when the writer succeeded.

A failed or interrupted write (an exception, Ctrl-C, or SIGTERM where the CLI turns it into an
exception) removes the temporary file, so no partial output is ever left. An existing file is
replaced only with ``overwrite=True``; without it the file is put in place with a hard link,
which fails if another process made the destination meanwhile.
"""

import contextlib
import os
import secrets

from ..curvature.errors import MeshError


def check_output_path(path, overwrite=False, *, parameter="path"):
    """Return ``path`` as a str, or raise before any work if it cannot be written.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False (``e.parameter`` is ``"overwrite"``,
        ``e.hint`` what it does).
    MeshError
        ``path`` is not a path, is a folder, or its folder does not exist or is not writable
        (``e.parameter`` is ``parameter``).
    """
    try:
        path = os.fsdecode(path)
    except TypeError:
        raise MeshError(f"{parameter} must be a file path, not {type(path).__name__}",
                        parameter=parameter, value=path) from None
    if os.path.isdir(path):
        raise MeshError(f"{path!r}: it is a folder", parameter=parameter, value=path, hint="name a file")
    if os.path.lexists(path) and not overwrite:
        err = FileExistsError(f"{path} exists; pass overwrite=True to replace it.")
        err.parameter, err.value, err.problem, err.hint = "overwrite", overwrite, f"{path} exists", "replace it"
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
    ``open``). The temporary file is named ``.curvdetail-<16 hex digits><extension>`` and is
    created with a normal file's permissions (the umask's). It is removed whatever ends the
    block: an exception, KeyboardInterrupt, or a signal handler that raises.

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
    # the name is chosen before the file exists, so that an interrupt at any point after the
    # open finds it in ``tmp`` (mkstemp made the file before returning its name)
    tmp = os.path.join(folder, f".curvdetail-{secrets.token_hex(8)}{os.path.splitext(name)[1]}")
    ours = True
    try:
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            ours = False
            raise
        yield tmp
        try:
            if overwrite:
                os.replace(tmp, path)
            else:
                os.link(tmp, path)
        except OSError as exc:
            if exc.filename is None or exc.filename == tmp:
                exc.filename = path
            raise
    finally:
        if ours:
            with contextlib.suppress(FileNotFoundError):
                os.remove(tmp)
