"""Settings of the ``demsplit`` command's own process, which a library must never make.

Imported first by the package's ``__init__``, before numpy, and applied on import (:func:`settle`) only when the
process is the command (:func:`is_command`): the ``demsplit`` console script, or
``python -m demsplit.cli``. A program that imports demsplit keeps its own
settings. One OpenBLAS thread, freed memory kept and rare collections together
took ``demsplit run`` on the benchmark run (3 GB of dumps, 3 frames) from a
median of 4.09 s to 3.93 s (six interleaved rounds, ``python
benchmarks/command_settings.py /tmp/bench_big``, which also times each setting
alone: each alone is within the rounds' spread; docs/performance.md, "The
command's process settings"); the huge-page setting is measured on its own
below:

OpenBLAS threads
    ``OPENBLAS_NUM_THREADS=1`` unless the user set it. The command calls no BLAS,
    but OpenBLAS starts its threads when numpy (and numba's scipy) load it, and
    each spins on a core for about 0.1 s before it sleeps: 0.17 CPU seconds taken
    from the parse at start-up (``python -c "import numpy, scipy.linalg"``:
    0.31 s of user time, 0.13 s with one thread). Read when the library loads,
    so it is set before numpy is imported.
Freed memory kept for the next frame
    glibc returns a large block to the system when it is freed (``munmap``), so
    every frame's arrays are fresh pages that the kernel zero-fills again: 13 %
    of the command's CPU samples in ``perf record`` (``clear_page_erms``). Allocations
    up to :data:`MMAP_THRESHOLD` come from the heap instead, and the heap is not
    trimmed below :data:`TRIM_THRESHOLD`, so the next frame reuses the pages of
    the last. The peak is about the same (877 MB against 860 MB on the
    benchmark: pages the heap keeps); a run's memory stays at its peak until
    it ends.
No huge pages asked for on a guest that hands free memory back to its host
    numpy asks the kernel for transparent huge pages (2 MiB) for every array of 4 MiB or more
    (``madvise``), unless ``NUMPY_MADVISE_HUGEPAGE=0``. A virtual machine's guest that reports its free
    memory to the host (Linux's ``page_reporting``, virtio-balloon free page reporting:
    :func:`guest_reports_free_memory`) reports free blocks of 2 MiB, and the host takes them back. A
    huge page is such a block, and its first write then waits for the host to map it again: 2.1 s per
    GB after a 10 s pause against 0.06 s right after another process freed memory, while small pages
    cost 0.35 s per GB either way (``python benchmarks/fresh_memory.py --pause 10``). On this project's
    machine ``demsplit run`` on the benchmark took a median of 3.28 s without the advice against
    3.86 s with it when each run started 10 s after the last, and 3.23 s against 3.48 s back to back
    (``python benchmarks/command_settings.py /tmp/bench_big --only all,no-pages --pause 10``, then
    ``--pause 0``; docs/performance.md, "Fresh memory on this machine"). Set only on such a guest,
    unless the user set the variable; read when numpy loads.
An exit without teardown
    When the work is done, :func:`exit_now` runs the ``atexit`` handlers, flushes
    the standard streams and ends the process (``os._exit``): Python's own
    finalization would free every object one by one (numba's type registries,
    the last frame's arrays): 0.15 s from ``main``'s return to the process's
    end on the benchmark run, 0.03 s with ``exit_now`` (``python
    benchmarks/run_phases.py /tmp/bench_big --rev ffe0c7d``, "after main"); the
    kernel frees the process's memory at once. Every file the command
    writes is closed (and the store fsynced) before ``main`` returns.
numba's BLAS probe skipped
    Applied by :mod:`demsplit.jit` when it is imported in the command's process (it belongs to the moment
    numba loads): :func:`demsplit.jit.load_registries_without_blas_probe`.
Rare cyclic garbage collections
    :data:`GC_THRESHOLDS` instead of Python's (700, 10, 10). A collection holds
    the GIL, which the parse and compression threads need to hand back their
    pieces, and the command's data are numpy arrays, which make no reference
    cycles: a whole ``demsplit run`` with the collector off leaves 1734
    unreachable objects at its end, the same for 3 frames of 10^6 particles
    and for 100 frames of 2000 (the command in docs/performance.md).
"""

from __future__ import annotations

import atexit
import gc
import os
import sys
from typing import NoReturn

NAMES = frozenset({"demsplit", "demsplit.exe"})
"""Names of the console script (``[project.scripts]`` in pyproject.toml)."""

MMAP_THRESHOLD = 1 << 30
"""Bytes above which an allocation is still mapped on its own (``M_MMAP_THRESHOLD``): 1 GiB, more than
any column of a frame of 10 million contacts."""
TRIM_THRESHOLD = (1 << 31) - 1
"""Free bytes at the top of the heap before glibc gives them back (``M_TRIM_THRESHOLD``; the largest
value ``mallopt`` takes)."""
TOP_PAD = 1 << 28
"""Bytes the heap grows by beyond what a request needs (``M_TOP_PAD``), so that a frame's arrays grow the
heap a few times rather than once per array; address space only until touched."""
GC_THRESHOLDS = (100_000, 50, 100)
"""``gc.set_threshold``: a young collection per 100,000 new container objects, an old one rarely."""
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3  # glibc's <malloc.h>


REPORTED_KIB = "/sys/module/page_reporting/parameters/reported_kib"
"""Linux's count of the KiB of free memory this guest has reported to its host (absent on a machine
without free page reporting)."""


def guest_reports_free_memory() -> bool:
    """Whether this machine is a virtual-machine guest that has handed free memory back to its host
    (free page reporting: :data:`REPORTED_KIB` is above zero)."""
    try:
        with open(REPORTED_KIB) as f:
            return int(f.read()) > 0
    except (OSError, ValueError):
        return False


def is_command() -> bool:
    """Whether this process is the ``demsplit`` command: started as the console script, or as
    ``python -m demsplit.cli`` (while the package is imported, ``sys.argv[0]`` is then ``-m``;
    ``sys.orig_argv`` keeps the module's name)."""
    argv = getattr(sys, "argv", None) or [""]
    if os.path.basename(argv[0] or "") in NAMES:
        return True
    orig = getattr(sys, "orig_argv", [])
    return any(a == "-m" and b == "demsplit.cli" for a, b in zip(orig, orig[1:]))


def keep_freed_memory() -> bool:
    """Have glibc keep freed blocks for reuse (:data:`MMAP_THRESHOLD`, :data:`TRIM_THRESHOLD`,
    :data:`TOP_PAD`); False where the C library has no ``mallopt`` (not glibc) or refuses a value."""
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt  # the C library the interpreter runs on
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return all(mallopt(option, value) == 1 for option, value in (
        (_M_MMAP_THRESHOLD, MMAP_THRESHOLD), (_M_TRIM_THRESHOLD, TRIM_THRESHOLD), (_M_TOP_PAD, TOP_PAD)))


def exit_now(code: int) -> NoReturn:
    """End the command's process with exit status ``code`` without tearing the interpreter down: the
    ``atexit`` handlers run (the worker threads' shutdown, h5py's, temporary directories'), the standard
    streams are flushed, and then ``os._exit``. Called by the console script (``cli.command``) once
    ``main`` has returned, every file it wrote closed; never by the library."""
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing more can be said on it
            pass
    os._exit(code)


FREED_MEMORY_KEPT = False
"""Whether :func:`settle` had glibc keep freed memory for reuse (:func:`keep_freed_memory`): this process is
the command, on glibc."""


def settle() -> None:
    """Apply the module's settings when this process is the command (:func:`is_command`); nothing otherwise.
    Called before numpy is imported."""
    global FREED_MEMORY_KEPT
    if not is_command():
        return
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        if guest_reports_free_memory():
            os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")
    FREED_MEMORY_KEPT = keep_freed_memory()
    gc.set_threshold(*GC_THRESHOLDS)


settle()
