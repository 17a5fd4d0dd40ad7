"""The first frame's memory, mapped while the run is opened, on the core the opening leaves idle.

A frame's arrays are fresh memory the first time: the kernel maps and zero-fills each 4 KiB page on its
first write. Later frames reuse the pages of the first (:mod:`demsplit.runtime.command`, "Freed memory kept
for the next frame"), so the first frame pays for all of them, while the run's opening (numba's import, the
dumps' index scan) leaves a core idle.

:func:`first_frame_prefaulted`, around the run's opening in :func:`demsplit.pipeline.run_to_store`, takes the
first frame's size, which a reader can tell from its files' first lines
(:meth:`demsplit.readers.base.Run.first_frame_rows`), allocates :func:`first_frame_bytes` from the heap
(:class:`Prefault`), and a thread that runs on idle cores only writes zeros over it, a piece at a time.
When the run is open the thread stops after its current piece and the block is freed: the first frame's
arrays are carved from pages already mapped. (``madvise(MADV_POPULATE_WRITE)`` maps without writing, but
holds the address space's lock, which the imports' own mappings then wait for.)

Only in the command's process with glibc keeping freed memory
(:data:`demsplit.runtime.command.FREED_MEMORY_KEPT`; elsewhere a freed block this large goes back to the
system at once) and only when the frames are computed in this process. The estimate is about two thirds of
what the first frame touches, so that the pages mapped are pages the frame would have mapped from the main
heap and the run's peak memory is unchanged (part of a frame's fresh memory is the worker threads' own
heaps, which the block cannot serve).
"""

from __future__ import annotations

import ctypes
import functools
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from .command import MMAP_THRESHOLD
from .threads import run_on_idle_cores

BYTES_PER_PARTICLE = 140
"""Memory mapped ahead per particle of the first frame (bytes): about two thirds of the fresh memory per
particle of a generated run (docs/performance.md, "Standing decisions")."""
BYTES_PER_CONTACT = 200
"""Memory mapped ahead per contact of the first frame (bytes), likewise."""
LARGEST = MMAP_THRESHOLD - (1 << 20)
"""The largest block (bytes): glibc serves a larger one from a mapping of its own, which ``free`` unmaps, so
its pages would not stay with the heap (:data:`demsplit.runtime.command.MMAP_THRESHOLD`)."""
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
def first_frame_prefaulted(rows: tuple[int, int] | None) -> Iterator[None]:
    """Around a run's opening: with ``rows`` (the first frame's particles and contacts, walls' included),
    that frame's memory (:func:`first_frame_bytes`, at most :data:`LARGEST`) is mapped while the run opens,
    and freed for the frame when the context ends; with None, nothing."""
    block = Prefault(min(first_frame_bytes(*rows), LARGEST)) if rows is not None else None
    try:
        yield
    finally:
        if block is not None:
            block.release()
