"""Write a file so that its final path never holds a partial file.

Every output demsplit writes (report, exports, ingest cache, the store's
commit records) goes through :func:`atomic_path`: the content is written to a
temporary name in the target directory, flushed to disk, and renamed over the
final path only when complete; on an error the temporary file is removed. The
result store, written over a whole run in its own work directory, is given
its final name by :func:`publish`, the same fsync and rename; while it is
written, :class:`WriteBack` has the kernel start writing its pages to disk, so
that the final fsync finds little left to write.
"""

from __future__ import annotations

import ctypes
import functools
import os
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from .threads import run_on_idle_cores

SYNC_FILE_RANGE_WRITE = 2
"""``sync_file_range``'s flag (Linux, ``<fcntl.h>``): start writing the range's dirty pages, wait for none."""


@contextmanager
def atomic_path(path: str | Path, *, durable: bool = True) -> Iterator[Path]:
    """Yield ``path.tmp`` (same directory) to write; on success fsync it and
    rename it to ``path``, on an exception remove it.

    ``durable=False`` skips the fsync: the file then survives a killed process
    (the kernel's page cache outlives it) but not a power cut, which may
    leave it empty or short under its final name; for the store's commit
    record, whose reader names a short one (see :mod:`demsplit.results.store`)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        yield tmp
        publish(tmp, path, durable=durable)
    finally:
        tmp.unlink(missing_ok=True)


def publish(tmp: str | Path, path: str | Path, *, durable: bool = True) -> None:
    """Give the complete file ``tmp`` its final name ``path`` (same file system):
    fsync it (unless ``durable=False``), then rename it over ``path``."""
    if durable:
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
    os.replace(tmp, path)


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
    or the file is gone. A hint for speed: a file is durable only once fsynced (:func:`publish`)."""
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
    runs only on idle cores (:func:`~demsplit.threads.run_on_idle_cores`).

    Without it the result store's pages stay in memory until :func:`publish`'s fsync, which writes them
    all while both cores idle: the store's ``close`` took 0.23 s for the benchmark's 860 MB store, 0.08 s
    with it (``python benchmarks/run_phases.py /tmp/bench_big --rev 4b2240f``; docs/performance.md, "The
    goals of issue 19 at the fifth stop"). :meth:`request` after each frame; the writer never waits for the thread,
    which opens the file by its path each time (a file renamed or removed meanwhile is skipped)."""

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
