"""A file's pages sent to disk while it grows, on idle cores.

Without it a large output's pages stay in memory until the fsync that makes it durable before it is renamed
into place (:func:`demsplit.outputs.publish`), which then writes them all while the cores idle.
:class:`WriteBack` has the kernel start writing them earlier, on a thread that runs only on idle cores; the
same fsync still runs, so durability is unchanged.
"""

from __future__ import annotations

import ctypes
import functools
import os
import threading
from collections.abc import Callable
from pathlib import Path

from .threads import run_on_idle_cores

SYNC_FILE_RANGE_WRITE = 2
"""``sync_file_range``'s flag (Linux, ``<fcntl.h>``): start writing the range's dirty pages, wait for none."""


@functools.cache
def _sync_file_range() -> Callable[[int, int, int, int], int] | None:
    """The C library's ``sync_file_range(fd, offset, nbytes, flags)`` (Linux), or None."""
    try:
        fn = ctypes.CDLL(None, use_errno=True).sync_file_range
    except (OSError, AttributeError):
        return None
    fn.argtypes, fn.restype = (ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_uint), ctypes.c_int
    return fn


def start_write_back(path: str | Path) -> None:
    """Have the kernel start writing the dirty pages of the file at ``path`` to disk, without waiting
    (``sync_file_range(SYNC_FILE_RANGE_WRITE)`` of the whole file); nothing where there is no such call
    or the file is gone. A hint for speed: a file is durable only once fsynced (:func:`demsplit.outputs.publish`)."""
    fn = _sync_file_range()
    if fn is None:
        return
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        fn(fd, 0, 0, SYNC_FILE_RANGE_WRITE)
    finally:
        os.close(fd)


class WriteBack:
    """Starts the write-back of a file as it grows (:func:`start_write_back`), on a thread of its own that
    runs only on idle cores (:func:`~demsplit.runtime.threads.run_on_idle_cores`).

    :meth:`request` after each piece of writing (the result store asks after each frame); the writer never
    waits for the thread, which opens the file by its path each time (a file renamed or removed meanwhile is
    skipped)."""

    def __init__(self) -> None:
        self._wake = threading.Condition()
        self._path: Path | None = None
        self._stopped = False
        self._thread: threading.Thread | None = None

    def request(self, path: str | Path) -> None:
        """Start the write-back of ``path`` (at once if the thread is idle, else after its current one)."""
        with self._wake:
            if self._stopped:
                return
            self._path = Path(path)
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="demsplit-write-back", daemon=True)
                self._thread.start()
            self._wake.notify()

    def stop(self) -> None:
        """End the thread after its current write-back (not waited for)."""
        with self._wake:
            self._stopped = True
            self._wake.notify()

    def _run(self) -> None:
        run_on_idle_cores()
        while True:
            with self._wake:
                while self._path is None and not self._stopped:
                    self._wake.wait()
                if self._stopped:
                    return
                path, self._path = self._path, None
            start_write_back(path)
