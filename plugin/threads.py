"""The process's worker threads, for work that releases the GIL.

The compiled parser (:mod:`demsplit.readers.fastparse`), the store's chunk
compression (:mod:`demsplit.results.store`) and the ingest cache's reads
(:mod:`demsplit.readers.cache`) each cut their work into pieces and run them
on :func:`pool`: numba kernels compiled ``nogil``, ISA-L/zlib compression and
``os.preadv`` all release the GIL, so the pieces run on every core. Tasks on
the pool must not wait for other tasks on it.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

THREADS = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
"""Cores this process may run on: the pool's size."""

_pool: tuple[int, ThreadPoolExecutor] | None = None  # (process id, that process's threads)


def pool() -> ThreadPoolExecutor:
    """The pool of :data:`THREADS` threads of this process (a forked worker
    process gets its own: its parent's threads were not forked with it)."""
    global _pool
    if _pool is None or _pool[0] != os.getpid():
        _pool = (os.getpid(), ThreadPoolExecutor(max_workers=THREADS, thread_name_prefix="demsplit"))
    return _pool[1]
