"""Cells run in a child process of the Dask worker, so that a cell past its time limit is truly
stopped (the process is killed and a fresh one started) and a crash in native code (pymeshlab,
a solver) or the kernel's out-of-memory killer costs one failed row, not the worker.

Each worker thread keeps one such process (``python -m curvdetail.evaluate.runner FD``), which
imports the package once and then runs cells one at a time, sent over a socket pair; its BLAS,
MKL and OpenMP threads are pinned to 1, one core per cell.
"""

import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from multiprocessing.connection import Connection

import psutil

from .cell import failed_row, run_cell

#: Seconds a fresh process may take to import the package before the cell is failed.
STARTUP_TIMEOUT = 300.0
#: Seconds between checks of a running cell's time and memory.
CHECK_EVERY = 0.1
#: Environment of the process: one thread for every numeric library.
ONE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                     "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")}


class Runner:
    """A child process that runs cells (`run_cell`) one at a time.

    Raises
    ------
    RuntimeError
        The process did not start (its exit status in the message).
    """

    def __init__(self):
        ours, theirs = socket.socketpair()
        package_root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        env = dict(os.environ, **ONE_THREAD,
                   PYTHONPATH=os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")])))
        self.process = subprocess.Popen([sys.executable, "-m", "curvdetail.evaluate.runner", str(theirs.fileno())],
                                        pass_fds=[theirs.fileno()], env=env, stdin=subprocess.DEVNULL)
        theirs.close()
        self.connection = Connection(ours.detach())
        if not (self.connection.poll(STARTUP_TIMEOUT) and self._receive() == "ready"):
            self.stop()
            raise RuntimeError(f"the cell process did not start (exit status {self.process.returncode})")

    def _receive(self):
        try:
            return self.connection.recv()
        except (EOFError, OSError):
            return None

    def alive(self):
        return self.process.poll() is None

    def run(self, task, timeout=None, memory=None):
        """The row of ``task``; a failed row where it ran past ``timeout`` seconds
        (``status="timeout"``) or its resident memory past ``memory`` MiB (``status="memory"``),
        the process then killed, or where its process died (``error_class="CellProcessDied"``)."""
        self.connection.send(task)
        start, limit = time.monotonic(), None
        while limit is None and not self.connection.poll(CHECK_EVERY):
            if timeout is not None and time.monotonic() - start > timeout:
                limit = ("timeout", "CellTimeout", f"the cell ran past its time limit of {timeout:g} s")
            elif memory is not None and psutil.Process(self.process.pid).memory_info().rss > memory * 2.0 ** 20:
                limit = ("memory", "CellMemoryLimit", f"the cell's process grew past its limit of {memory:g} MiB")
        if limit is not None:
            self.stop()
            status, error_class, message = limit
            return dict(failed_row(task, status=status, error_class=error_class, message=message + " and was stopped"),
                        pid=self.process.pid)
        row = self._receive()
        if row is None:
            self.stop()
            code = self.process.returncode
            why = f"signal {signal.Signals(-code).name}" if code < 0 else f"exit status {code}"
            return dict(failed_row(task, error_class="CellProcessDied", message=f"the cell's process ended ({why}), "
                                   "e.g. killed for memory or crashed in native code"), pid=self.process.pid)
        return row

    def stop(self):
        """Kill the process and wait for it."""
        self.process.kill()
        self.process.wait()
        self.connection.close()


_local = threading.local()


def evaluate_cell(task, timeout=None, memory=None, data=None):
    """Dask task: the row of one cell, run in this worker thread's `Runner` (started on
    first use, again after a limit or a crash; ``timeout`` seconds, ``memory`` MiB); never
    raises for the cell's failure. ``data``: the mesh file's bytes where they were shipped,
    read from a temporary copy with the file's extension."""
    runner = getattr(_local, "runner", None)
    copy = None
    try:
        if data is not None:
            fd, copy = tempfile.mkstemp(suffix=os.path.splitext(task["path"])[1], prefix="curvdetail-mesh-")
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            task = dict(task, read_path=copy)
        if runner is None or not runner.alive():
            runner = _local.runner = Runner()
        row = runner.run(task, timeout, memory)
    except (RuntimeError, OSError, psutil.Error) as exc:
        row = failed_row(task, exc)
    finally:
        if copy is not None:
            os.remove(copy)
    try:
        from distributed import get_worker

        row["worker"] = get_worker().address
    except (ImportError, ValueError):          # called outside a worker
        row["worker"] = "local"
    return row


def _exit_with_parent(parent):
    """Exit when the process that started this one is gone (a killed worker leaves no orphan)."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os._exit(1)


def main(fd):
    connection = Connection(fd)
    threading.Thread(target=_exit_with_parent, args=(os.getppid(),), daemon=True).start()
    connection.send("ready")
    while True:
        try:
            task = connection.recv()
        except (EOFError, OSError):
            return
        connection.send(run_cell(task))


if __name__ == "__main__":
    main(int(sys.argv[1]))
