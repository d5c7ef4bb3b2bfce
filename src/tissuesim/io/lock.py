"""One run at a time per output directory: ``run_lock`` holds an operating-system lock on
``<directory>/.tissuesim-run.lock`` for the whole run, so a second run into the folder of a run
in progress refuses (OutputError, one line) instead of mixing its frames with the first's.

The lock is the kernel's (``flock`` on POSIX, ``msvcrt.locking`` on Windows), not the file's
existence: when a run is killed (``kill -9``, a crash, a power cut) the operating system
releases it with the process, so a lock file left behind never blocks the next run; the file
only holds the holder's pid, host and start time for the message. The run removes the file
when it ends.
"""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from tissuesim.errors import OutputError

__all__ = ["LOCK_FILE", "run_lock"]

LOCK_FILE = ".tissuesim-run.lock"


def _try_lock(fd: int) -> bool:
    """Take the lock on ``fd`` without waiting; False if another process holds it."""
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError:  # a file system without locks: no protection, but the run goes on
        return True
    return True


def _holder(path: Path) -> str:
    try:
        text = path.read_text(encoding="utf-8").split()
    except OSError:
        return ""
    return f" (pid {text[0]} on {text[1]}, started {' '.join(text[2:])})" if len(text) > 2 else ""


@contextmanager
def run_lock(directory: Path) -> Iterator[None]:
    """Hold ``directory``'s run lock while the block runs (the directory exists); OutputError
    naming the folder and the run that holds it if another run is writing there."""
    path = directory / LOCK_FILE
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        if not _try_lock(fd):
            os.close(fd)
            raise OutputError(
                f"output directory {str(directory)!r} is in use by another run"
                f"{_holder(path)}; wait for it to end, or choose another --out"
            )
        # the holder before us may have removed the file between our open and our lock: the
        # lock is then on a deleted file; take it again on the file now at the path
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except OSError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        stamp = time.strftime("%Y-%m-%dT%H:%M:%S")
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()} {socket.gethostname()} {stamp}\n".encode())
        yield
    finally:
        try:  # removed while still locked, so no one can lock the old file after we leave
            path.unlink(missing_ok=True)
        except OSError:  # Windows: an open file cannot be removed; it is harmless there
            pass
        os.close(fd)
