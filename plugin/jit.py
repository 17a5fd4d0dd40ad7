"""Compiled kernels: one decorator with the project's numba settings.

Hot loops over millions of rows (the dump parser, the per-contact physics, the
sums per particle) are written as plain Python loops over arrays and compiled
by numba (``nopython``). Settings, for every kernel:

``cache=True``
    machine code is cached next to the module (or in numba's user cache
    directory when that is read-only), so only the first run after an install
    compiles; later processes load it in milliseconds.
``nogil=True``
    a kernel releases the GIL, so threads (``concurrent.futures``) run kernels
    on disjoint slices of a frame on every core; numba's own ``parallel=True``
    is not used (slow to compile, and its threading layers differ by platform).
``error_model="numpy"``
    division by zero gives inf/NaN as in numpy instead of raising, which keeps
    the loops free of checks; kernels test their inputs explicitly.
No ``fastmath``: results are bit-for-bit those of the same IEEE operations in
numpy.

Modules that define kernels import numba when they are imported; they are
imported lazily (by the functions that call them), so ``import demsplit`` stays
numpy-only: the YADE exporter, :mod:`demsplit.yade`, runs inside YADE's own
Python, where numba is usually absent. Where numba cannot be imported a kernel
runs as the plain Python it is written in: correct, but orders of magnitude
slower; numba is a dependency of the package, so this happens only in such
embedded interpreters.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

try:
    import numba
except ImportError:  # an embedded interpreter without numba: see the module docstring
    numba = None

F = TypeVar("F", bound=Callable)


def kernel(fn: F) -> F:
    """``fn`` compiled by numba with the settings above (compiled on its first
    call, or loaded from the cache); kernels may call other kernels."""
    if numba is None:
        return fn
    return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)
