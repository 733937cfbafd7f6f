"""Output files for the remeshing, filter and editing code: checked before any work, written
atomically with a normal file's permissions.

:func:`atomic_output` gives a temporary path in the destination's folder; the caller writes
there (with pymeshlab, matplotlib, ``open``...), and the file is renamed over the destination
only when the ``with`` block succeeded, with the permissions a new file gets from the umask
(``tempfile.mkstemp`` alone leaves ``0600``). A failed block removes the temporary file, so no
half-written output is ever left behind.

:func:`atomic_outputs` does the same for the several outputs of one run (mesh, report,
picture), committed together in two phases: every output is written to its temporary file
first; only when the whole ``with`` block succeeded are the destinations checked again and the
files renamed into place, each destination's old file kept meanwhile in a hidden folder
``.curvdetail-old-XXXXXXXX`` beside it (a hard link, so that the destination is never missing;
where the file system refuses one, the file itself is moved there). If a rename fails, the
outputs already placed are taken back (new files removed, old ones put back) and the error
names the output that failed. So a run writes all its outputs or none, and leaves every
destination as it was when it writes none.

Without ``overwrite`` a file is put in place by a hard link (then its temporary name removed),
not a rename: the link fails where the destination exists, so a file another process made
after the last check is never replaced. Where the file system refuses hard links (FAT, some
network ones) it is renamed, and a file made in the moment between the check and the rename
is replaced.

What POSIX does not allow: the renames are one system call each, not one for all.

- A process reading the destinations during the commit (a few system calls) may see some new
  files and some old ones.
- A crash of the machine, or SIGKILL, in the middle of a commit leaves that mix, and beside
  each output the commit had reached a hidden ``.curvdetail-old-*`` folder holding the output's
  old file under its own name (where hard links are refused, the output being replaced may be
  missing, its old file only there). Nothing removes these folders later, the next run
  neither: move a file back, or delete them. (The ``.curvdetail-*`` temporary files of a
  killed run are left the same way.)
- Where taking an output back fails too, the error names it and where its old file is kept.
- SIGTERM and SIGINT (Ctrl-C) end a CLI run through its watcher thread, which takes
  :data:`COMMIT_LOCK` and so waits for a commit in progress: a run ends before the commit
  (nothing written) or after it (everything written, though the exit status, 143 or 130, says
  terminated or interrupted). In Python, a KeyboardInterrupt during a commit takes back the
  renames done (none written).
"""

import contextlib
import errno
import os
import tempfile
import threading
import typing

from .curvature._validate import check_bool
from .curvature.errors import MeshError

_FORMATS_HINT = "use .ply, .obj, .off, .stl, ..."

#: Temporary files of the :func:`atomic_outputs` blocks in progress, for the CLI's SIGTERM /
#: SIGINT watcher, which removes them before it ends the process.
PENDING = set()

#: Held while :func:`atomic_outputs` renames its files into place. The SIGTERM / SIGINT watcher
#: takes it before it removes :data:`PENDING` and ends the process, so that a commit is never cut short
#: (the old files kept aside would be left in hidden folders, and the outputs a mix).
COMMIT_LOCK = threading.Lock()

#: how a refusal of an existing output says to replace it by default: Python's argument (the
#: CLI says ``--overwrite`` instead, see ``cli._in_command_words``; the scripts name their own option)
OVERWRITE_FLAG = "overwrite=True"


def check_output_path(path, overwrite=False, *, hint=_FORMATS_HINT, error=MeshError, flag=OVERWRITE_FLAG):
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

    ``flag`` is how the refusal of an existing file says to replace it (the scripts under
    scripts/ name their own option).
    """
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise ValueError(f"an output path must be a str or os.PathLike; got {type(path).__name__}.")
    check_bool(overwrite, "overwrite")
    path = os.fsdecode(path)
    if os.path.isdir(path):       # --overwrite cannot help: a folder is never replaced
        kind = IsADirectoryError if issubclass(error, OSError) else error
        raise kind(f"cannot write {path!r}: it is a folder; name a file (in it, or elsewhere).")
    if os.path.lexists(path) and not overwrite:     # a dangling link exists too
        what = "is a link to a missing file" if not os.path.exists(path) else "exists"
        raise FileExistsError(f"{path} {what}; pass {flag} to replace it.")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise error(f"cannot write {path!r}: folder {folder!r} does not exist.")
    if not os.access(folder, os.W_OK | os.X_OK):       # found now, not after minutes of work
        kind = PermissionError if issubclass(error, OSError) else error
        raise kind(f"cannot write {path!r}: folder {folder!r} is not writable.")
    if hint is not None and not os.path.splitext(path)[1]:
        raise error(f"cannot write {path!r}: no file extension to choose the format from ({hint}).")
    _check_name_length(path, folder, error)
    return path


#: ``tempfile.mkstemp``'s name for a temporary file: this prefix, 8 random characters, the suffix
_TEMPORARY_PREFIX = ".curvdetail-"
_RANDOM_CHARACTERS = 8


def _check_name_length(path, folder, error):
    """Raise ``error`` if the file name of ``path``, or that of its temporary file (the prefix,
    8 characters and ``path``'s extension), is longer than ``folder``'s file system allows
    (found now, not as ENAMETOOLONG at the rename after the work)."""
    try:
        name_max = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):       # no pathconf (Windows), or it cannot say
        name_max = 255
    if name_max is None or name_max <= 0:               # -1: no limit
        return
    name = len(os.fsencode(os.path.basename(path)))
    temporary = len(_TEMPORARY_PREFIX) + _RANDOM_CHARACTERS + len(os.fsencode(os.path.splitext(path)[1]))
    if name > name_max:
        raise error(f"cannot write {path!r}: its file name is {name} bytes long, and the file system of "
                    f"{folder!r} allows {name_max}; choose a shorter name.")
    if temporary > name_max:
        raise error(f"cannot write {path!r}: its extension is too long for the temporary file it is first "
                    f"written to ({temporary} bytes; the file system of {folder!r} allows {name_max}); choose "
                    "a shorter extension.")


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


class Output(typing.NamedTuple):
    """One output of :func:`atomic_outputs`: its path, and ``hint``, ``error`` and ``flag`` for
    :func:`check_output_path`."""

    path: typing.Any
    hint: typing.Optional[str] = _FORMATS_HINT
    error: type = MeshError
    flag: str = OVERWRITE_FLAG


@contextlib.contextmanager
def atomic_output(path, *, overwrite=False, hint=_FORMATS_HINT, error=MeshError, flag=OVERWRITE_FLAG):
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
    with atomic_outputs([Output(path, hint, error, flag)], overwrite=overwrite) as (tmp,):
        yield tmp


@contextlib.contextmanager
def atomic_outputs(outputs, *, overwrite=False):
    """Context manager yielding the temporary paths (a list, in order) to write ``outputs`` to;
    all are renamed into place together, or none (see the module docstring).

    ``outputs`` holds :class:`Output` entries, or None for an output not asked for (its
    temporary path is None). Every destination is checked (:func:`check_output_path`, in order)
    before any temporary file is made, and again before any rename.

    Raises
    ------
    ValueError  two outputs name one file
    OSError     (its own type) a temporary file could not be made, or an output could not be
                renamed into place (the message names it; no output was written)
    and what :func:`check_output_path` raises.

    Examples
    --------
    >>> import os, tempfile
    >>> folder = tempfile.mkdtemp()
    >>> a, b = os.path.join(folder, "a.txt"), os.path.join(folder, "b.txt")
    >>> with atomic_outputs([Output(a), None, Output(b)]) as (tmp_a, nothing, tmp_b):
    ...     for tmp, text in ((tmp_a, "one"), (tmp_b, "two")):
    ...         with open(tmp, "w") as fh:
    ...             _ = fh.write(text)
    >>> open(a).read(), open(b).read(), nothing
    ('one', 'two', None)
    """
    outputs = list(outputs)
    paths = [None if out is None else
             check_output_path(out.path, overwrite, hint=out.hint, error=out.error, flag=out.flag)
             for out in outputs]
    _check_distinct([p for p in paths if p is not None])
    temps = []
    try:
        for path in paths:
            temps.append(None if path is None else _temporary(path))
        yield list(temps)
        with COMMIT_LOCK:
            for path, out in zip(paths, outputs):       # what changed during the work
                if out is not None:
                    check_output_path(path, overwrite, hint=out.hint, error=out.error, flag=out.flag)
            mode = 0o666 & ~_umask()
            for tmp in temps:
                if tmp is not None:
                    os.chmod(tmp, mode)
            _commit([(tmp, path, out.flag) for tmp, path, out in zip(temps, paths, outputs) if tmp is not None],
                    overwrite)
    finally:
        for tmp in temps:
            if tmp is not None:
                PENDING.discard(tmp)
                with contextlib.suppress(FileNotFoundError):    # renamed, or the signal watcher took it
                    os.remove(tmp)


def _check_distinct(paths):
    real = [os.path.realpath(p) for p in paths]
    for k, r in enumerate(real):
        if r in real[:k]:
            raise ValueError(f"{paths[k]} is given for two outputs; name a separate file for each.")


def _temporary(path):
    """An empty temporary file for ``path`` in its folder, with its extension, in :data:`PENDING`."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=_TEMPORARY_PREFIX, suffix=os.path.splitext(path)[1],
                                   dir=os.path.dirname(os.path.abspath(path)))
    except OSError as exc:        # its message would name the temporary file, not the output
        raise type(exc)(exc.errno, f"cannot write {path!r}: {exc.strerror}") from None
    os.close(fd)
    PENDING.add(tmp)
    return tmp


class _Aside:
    """A destination's old file, kept during a commit in a new hidden folder beside it under
    its own name: a hard link (the destination keeps its file until it is replaced) or, where
    the file system refuses one (FAT, Linux's protected_hardlinks for another user's file),
    the file itself moved there."""

    def __init__(self, path):
        self.path = path
        self.folder = tempfile.mkdtemp(prefix=".curvdetail-old-", dir=os.path.dirname(os.path.abspath(path)))
        self.file = os.path.join(self.folder, os.path.basename(path))
        self.moved = False
        try:
            os.link(path, self.file, follow_symlinks=False)
        except (OSError, NotImplementedError):
            try:
                os.rename(path, self.file)
            except BaseException:
                os.rmdir(self.folder)
                raise
            self.moved = True

    def restore(self, replaced):
        """Put the old file back (``replaced``: the new file is in its place)."""
        if replaced or self.moved:
            os.replace(self.file, self.path)
        else:
            os.remove(self.file)                        # the destination still is the old file
        os.rmdir(self.folder)

    def drop(self):
        with contextlib.suppress(OSError):              # the outputs are written: not worth failing for
            os.remove(self.file)
            os.rmdir(self.folder)


def _commit(outputs, overwrite):
    """Put each ``(tmp, path, flag)``'s file at ``path`` (:func:`_place`), keeping the old files
    aside; on a failure take back those done and raise, naming the output."""
    placed = []         # (tmp, path, its _Aside or None)
    keep = len(outputs) > 1           # a single rename that fails has changed nothing
    try:
        for tmp, path, flag in outputs:
            aside = _Aside(path) if keep and os.path.lexists(path) else None
            placed.append((tmp, path, aside))
            _place(tmp, path, overwrite, flag)
    except BaseException as exc:    # KeyboardInterrupt too: half a commit is what this prevents
        stuck = _take_back(placed)
        if not isinstance(exc, OSError):
            raise
        raise _naming(exc, path, stuck) from exc
    for _, _, aside in placed:
        if aside is not None:
            aside.drop()


#: errno values of a file system that refuses hard links (FAT, some network and FUSE ones)
_NO_HARD_LINKS = {errno.EPERM, errno.EXDEV, errno.EMLINK, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP}


def _place(tmp, path, overwrite, flag):
    """Move the file ``tmp`` to ``path``: renamed over it with ``overwrite``; without, hard-linked
    there (which fails, atomically, where ``path`` exists: a file another process made after
    the check before the commit is not replaced) and ``tmp`` removed. Where the file system
    refuses hard links, renamed after all: there a file made between the last check and the
    rename is replaced."""
    if not overwrite:
        try:
            os.link(tmp, path, follow_symlinks=False)
        except FileExistsError:
            raise FileExistsError(errno.EEXIST, f"it was made while the output was being written; pass {flag} "
                                                "to replace it") from None
        except OSError as exc:
            if exc.errno not in _NO_HARD_LINKS:
                raise
        else:
            with contextlib.suppress(OSError):      # the output is in place; a leftover name goes in the end
                os.remove(tmp)
            return
    os.replace(tmp, path)


def _placed(tmp, path):
    """Whether :func:`_place` put ``tmp``'s file at ``path`` (renamed: ``tmp`` gone; linked: one file)."""
    if not os.path.lexists(tmp):
        return True
    try:
        return os.path.samefile(tmp, path)
    except OSError:
        return False


def _take_back(placed):
    """Undo the renames of a failed commit, newest first; return the messages of the old files
    that could not be put back (where they are kept)."""
    stuck = []
    for tmp, path, aside in reversed(placed):
        replaced = _placed(tmp, path)                   # os.replace and os.link either did all or nothing
        try:
            if aside is not None:
                aside.restore(replaced)
            elif replaced:
                os.remove(path)
        except OSError as exc:
            where = f"; its old file is kept in {aside.file!r}" if aside is not None else ""
            stuck.append(f"{path!r} could not be taken back ({exc.strerror}){where}")
    return stuck


def _naming(exc, path, stuck):
    """``exc`` (an OSError), its message naming the output ``path`` and what a failed commit left."""
    reason = exc.strerror or str(exc)
    if stuck:
        left = "the outputs placed could not all be taken back: " + "; ".join(stuck)
    else:
        left = "no output was written, the existing files are as they were"
    message = f"cannot write {path!r}: {reason}; {left}"
    return type(exc)(exc.errno, message) if exc.errno is not None else type(exc)(message)
