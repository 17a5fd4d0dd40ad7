"""Settings of the ``demsplit`` command's own process, which a library must never make.

Imported first by the package's ``__init__``, before numpy, and applied on import (:func:`settle`) only when the
process is the command (:func:`is_command`): the ``demsplit`` console script, or ``python -m demsplit.cli``.
A program that imports demsplit keeps its own settings. What each gains is measured by the command's phase
profile (docs/performance.md, "Standing decisions").

OpenBLAS threads
    ``OPENBLAS_NUM_THREADS=1`` unless the user set it: the command calls no BLAS, but OpenBLAS starts its
    threads when numpy loads it, and each spins on a core before it sleeps. Read when the library loads, so
    it is set before numpy is imported.
Freed memory kept for the next frame
    glibc returns a large freed block to the system (``munmap``), so every frame's arrays would be fresh
    pages the kernel zero-fills again. Allocations up to :data:`MMAP_THRESHOLD` come from the heap instead,
    and the heap is not trimmed below :data:`TRIM_THRESHOLD`, so the next frame reuses the pages of the
    last; a run's memory stays at its peak until it ends.
No huge pages on a guest that hands free memory back to its host
    numpy asks for transparent huge pages for arrays of 4 MiB or more. A virtual-machine guest that reports
    its free memory to the host (:func:`guest_reports_free_memory`) hands back free blocks of 2 MiB, and the
    first write to such a huge page waits for the host to map it again, while small pages cost the same
    either way. ``NUMPY_MADVISE_HUGEPAGE=0`` is set only on such a guest, unless the user set it.
An exit without teardown
    When the work is done, :func:`exit_now` runs the ``atexit`` handlers, flushes the standard streams and
    ends the process (``os._exit``) instead of freeing every object one by one; every file the command
    writes is closed (and the store fsynced) before ``main`` returns.
numba's BLAS probe skipped
    Applied by :mod:`demsplit.runtime.jit` when it is imported in the command's process:
    :func:`demsplit.runtime.jit.load_registries_without_blas_probe`.
Rare cyclic garbage collections
    :data:`GC_THRESHOLDS` instead of Python's (700, 10, 10): a collection holds the GIL, which the parse and
    compression threads need to hand back their pieces, and the command's data (numpy arrays) make no
    reference cycles.
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
    return all(
        mallopt(option, value) == 1
        for option, value in (
            (_M_MMAP_THRESHOLD, MMAP_THRESHOLD),
            (_M_TRIM_THRESHOLD, TRIM_THRESHOLD),
            (_M_TOP_PAD, TOP_PAD),
        )
    )


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
