"""The first frame's memory, mapped while the run is opened, on the core the opening leaves idle.

A frame's arrays are fresh memory the first time: the kernel maps and zero-fills each 4 KiB page on its
first write (a page fault). Later frames reuse the pages of the first (:mod:`demsplit.command`, "Freed memory
kept for the next frame"), so the first frame pays for all of them: on the benchmark run (10^6 particles,
2*10^6 contacts) 765 MB of fresh pages in its read, tables and store append
(``python benchmarks/first_frame_memory.py /tmp/bench_big``), and its read and tables took 0.415 s and
0.218 s against 0.280 s and 0.130 s for each later frame (``python benchmarks/run_phases.py /tmp/bench_big
--repeat 6 --rev 624eafb``, the revision before this module; 0.309 s and 0.206 s with it; docs/performance.md,
"The goals of issue 19 at the ninth stop"). The run's opening before it leaves a core idle while numba loads
on one thread: ``open_run`` kept 1.46 of the 2 cores busy over its 0.45 s in the same run, 0.24 core-seconds
idle (1.85 cores with this module).

:func:`first_frame_prefaulted`, around ``open_run`` in :func:`demsplit.pipeline.run_to_store`, listens for
the first frame's size, which the LIGGGHTS reader reads from its dumps' first headers before it indexes them
(:func:`demsplit.readers.base.first_frame_size`). It allocates :func:`first_frame_bytes` from the heap
(:class:`Prefault`), and a thread that runs on idle cores only writes zeros over it, a piece at a time. When
the run is open the thread stops after its current piece and the block is freed: the first frame's arrays
are carved from pages already mapped. ``madvise(MADV_POPULATE_WRITE)`` maps pages without writing them, but
it holds the address space's lock while it maps a piece, which the imports' own mappings wait for:
``open_run`` took longer than without any warm-up (a one-off variant).

Only in the command's process with glibc keeping freed memory (:data:`demsplit.command.FREED_MEMORY_KEPT`;
elsewhere a freed block this large goes back to the system at once) and only when the frames are computed in
this process. The estimate is about two thirds of what the first frame touches, so that the pages mapped
are pages the frame would have mapped from the main heap: the run's peak memory is unchanged
(``python benchmarks/first_frame_memory.py`` measures the frame's fresh memory and the peak with and
without the warm-up; an estimate near the frame's whole fresh memory raised the benchmark run's peak, as
part of that memory is the worker threads' own heaps).
"""

from __future__ import annotations

import ctypes
import functools
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from .command import MMAP_THRESHOLD
from .readers.base import first_frame_size
from .threads import run_on_idle_cores

BYTES_PER_PARTICLE = 140
"""Memory mapped ahead per particle of the first frame (bytes): about two thirds of the 206 bytes of fresh
memory per particle that ``python benchmarks/first_frame_memory.py`` fits over three generated runs (that
fit counts the worker threads' heaps too; 170 and 250 bytes raised the benchmark run's peak)."""
BYTES_PER_CONTACT = 200
"""Memory mapped ahead per contact of the first frame (bytes): about two thirds of the 292 bytes fitted by
the same command."""
LARGEST = MMAP_THRESHOLD - (1 << 20)
"""The largest block (bytes): glibc serves a larger one from a mapping of its own, which ``free`` unmaps, so
its pages would not stay with the heap (:data:`demsplit.command.MMAP_THRESHOLD`)."""
PIECE = 16 << 20
"""Bytes written per call: :meth:`Prefault.release` waits for the thread to finish at most one piece."""


def first_frame_bytes(particles: int, contacts: int) -> int:
    """The memory (bytes) mapped ahead for a first frame of ``particles`` and ``contacts`` rows:
    ``BYTES_PER_PARTICLE * particles + BYTES_PER_CONTACT * contacts``."""
    return BYTES_PER_PARTICLE * particles + BYTES_PER_CONTACT * contacts


@functools.cache
def _libc() -> ctypes.CDLL:
    libc = ctypes.CDLL(None)  # the C library the interpreter runs on
    libc.malloc.argtypes, libc.malloc.restype = (ctypes.c_size_t,), ctypes.c_void_p
    libc.free.argtypes, libc.free.restype = (ctypes.c_void_p,), None
    return libc


class Prefault:
    """``nbytes`` allocated with ``malloc`` and written with zeros by a thread of their own that runs on idle
    cores only, :data:`PIECE` bytes at a time, until :meth:`release` frees them (see the module docstring).
    ``mapped``: bytes written so far."""

    def __init__(self, nbytes: int) -> None:
        self.nbytes = max(0, int(nbytes))
        self.mapped = 0
        self._stop = threading.Event()
        self._block = _libc().malloc(self.nbytes) if self.nbytes else None  # None: nothing, or no memory
        self._thread = None
        if self._block:
            self._thread = threading.Thread(target=self._map, name="demsplit-prefault", daemon=True)
            self._thread.start()

    def _map(self) -> None:
        run_on_idle_cores()
        for at in range(0, self.nbytes, PIECE):
            if self._stop.is_set():
                return
            n = min(PIECE, self.nbytes - at)
            ctypes.memset(self._block + at, 0, n)  # a foreign call: the GIL is released while it runs
            self.mapped = at + n

    def release(self) -> None:
        """Stop the thread after its current piece and free the block (its pages stay with the heap)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._block:
            _libc().free(self._block)
            self._block = None


@contextmanager
def first_frame_prefaulted(enabled: bool) -> Iterator[None]:
    """Around a run's opening: when ``enabled``, the first frame's memory (:func:`first_frame_bytes` of the
    size a reader announces, at most :data:`LARGEST`) is mapped while the run opens, and freed for the frame
    when the context ends; otherwise nothing."""
    if not enabled:
        yield
        return
    blocks: list[Prefault] = []

    def listener(particles: int, contacts: int) -> None:
        if not blocks:  # one run: its first frame
            blocks.append(Prefault(min(first_frame_bytes(particles, contacts), LARGEST)))

    try:
        with first_frame_size(listener):
            yield
    finally:
        for block in blocks:
            block.release()
