"""The process's worker threads, for work that releases the GIL.

The compiled parser (:mod:`demsplit.readers.fastparse`), the store's chunk
compression (:mod:`demsplit.results.chunks`) and the ingest cache's reads
(:mod:`demsplit.readers.cache`) each cut their work into pieces and run them
on :func:`pool`: numba kernels compiled ``nogil``, ISA-L/zlib compression and
``os.preadv`` all release the GIL, so the pieces run on every core. Tasks on
the pool must not wait for other tasks on it.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")


def _cores() -> int:
    """``DEMSPLIT_THREADS`` when set to a positive integer, else the cores this process may run on."""
    value = os.environ.get("DEMSPLIT_THREADS", "")
    if value.isdigit() and int(value) > 0:
        return int(value)
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


THREADS = _cores()
"""Cores this process may run on (or ``DEMSPLIT_THREADS``): the pool's size, unless :func:`limit`-ed."""

_limit: int | None = None  # this process's share of the cores, when it is one of several workers
_pool: tuple[int, ThreadPoolExecutor] | None = None  # (process id, that process's threads)


def count() -> int:
    """Threads this process runs its pieces of work on."""
    return _limit or THREADS


def limit(n: int) -> None:
    """Run this process's work on ``n`` threads (a worker process's share of the cores)."""
    global _limit, _pool
    _limit, _pool = max(1, int(n)), None


def pool() -> ThreadPoolExecutor:
    """The pool of :func:`count` threads of this process (a forked worker
    process gets its own: its parent's threads were not forked with it)."""
    global _pool
    if _pool is None or _pool[0] != os.getpid():
        _pool = (os.getpid(), ThreadPoolExecutor(max_workers=count(), thread_name_prefix="demsplit"))
    return _pool[1]


def run_on_idle_cores() -> None:
    """Ask the scheduler to run the calling thread only on a core no other thread wants (Linux's
    ``SCHED_IDLE``; ``sched_setscheduler`` with pid 0 is the calling thread); elsewhere nothing. For
    background work nobody waits for (the inputs' digests, the store's write-back): it fills the moments a
    core would idle instead of taking cores from the frames' work."""
    try:
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    except (AttributeError, OSError):
        pass


MIN_RANGE = 1 << 16
"""Rows below which :func:`map_ranges` does not split: handing a task to the pool and collecting it costs as
much as a few thousand rows of the cheapest per-row work, so smaller pieces would gain nothing."""


def map_ranges(fn: Callable[[int, int], T], n: int, max_rows: int | None = None) -> list[T]:
    """``fn(lo, hi)`` over contiguous pieces of ``range(n)`` on the pool, the results in order: for
    per-row work that releases the GIL (numba kernels, numpy on large arrays). :func:`count` pieces of
    at least ``MIN_RANGE`` rows, or, with ``max_rows``, pieces of at most that many (which bounds the
    temporaries of numpy expressions to ``max_rows`` rows per thread). Not to be called from a task
    on the pool."""
    k = max(1, min(count(), n // MIN_RANGE))
    if max_rows is not None:
        k = max(k, -(-n // max_rows))
    cuts = [n * i // k for i in range(k + 1)]
    if k == 1:
        return [fn(0, n)]
    return list(pool().map(lambda i: fn(cuts[i], cuts[i + 1]), range(k)))
