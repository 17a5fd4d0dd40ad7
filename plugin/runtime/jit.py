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

import sys
from collections.abc import Callable
from typing import TypeVar

from .command import is_command

try:
    import numba
except ImportError:  # an embedded interpreter without numba: see the module docstring
    numba = None

F = TypeVar("F", bound=Callable)
BLAS_PROBE = "scipy.linalg.cython_blas"
"""The module numba imports to learn whether BLAS is there (``numba.np.linalg.ensure_blas``)."""


def load_registries_without_blas_probe() -> None:
    """Load numba's registries now, with its BLAS probe answered "no BLAS" at once: what the ``demsplit``
    command's process does when it imports this module (:func:`demsplit.runtime.command.is_command`).

    A kernel's first call makes numba load its registries, and one of them (``numba.np.arraymath``) probes
    for BLAS by importing ``scipy.linalg.cython_blas``, which imports all of ``scipy.linalg`` and
    ``numpy.f2py`` in the command's single-threaded start-up. The answer changes one thing in numba:
    ``np.correlate`` and ``np.convolve`` in a kernel would sum with a plain loop instead of BLAS, which no
    kernel here calls. The probe's module is answered by a ``None`` in ``sys.modules`` only while the
    registries load, so ``scipy.linalg`` imports as usual afterwards; nothing is done when it is already
    imported. A workaround of numba's start-up: if numba drops the probe, this can go."""
    if numba is None or BLAS_PROBE in sys.modules:
        return
    from numba.core.registry import cpu_target

    sys.modules[BLAS_PROBE] = None
    try:
        cpu_target.target_context.refresh()  # what a kernel's first call does: every registry, typing included
    finally:
        if sys.modules.get(BLAS_PROBE, False) is None:
            del sys.modules[BLAS_PROBE]


def kernel(fn: F) -> F:
    """``fn`` compiled by numba with the settings above (compiled on its first
    call, or loaded from the cache); kernels may call other kernels."""
    if numba is None:
        return fn
    return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)


def inlined(fn: F) -> F:
    """``fn`` as :func:`kernel` compiles it, but copied into each kernel that calls it (numba's
    ``inline="always"``) instead of called: for the small steps of a hot loop, where a call's
    cost (its arguments and tuple result through memory) is as large as the step. A function
    inlined this way takes no arrays (each would be reference-counted at every use): it reads
    memory through :func:`byte_at` and :func:`word_at`."""
    if numba is None:
        return fn
    return numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")(fn)


def _word_intrinsics():
    """The word-at-a-time primitives of the dump parser, compiled as LLVM intrinsics (plain Python,
    through ``ctypes``, where numba is absent):

    ``address(a)``
        the address of a contiguous array's first element (int64), for the two loads below; the
        caller keeps ``a`` alive while it is used;
    ``byte_at(base, i)``
        the byte at ``base + i`` (int64);
    ``word_at(base, i)``
        the 8 bytes from ``base + i`` as one little-endian uint64 (an unaligned load);
    ``trailing_zeros(x)``
        of a nonzero uint64;
    ``popcount(x)``
        the set bits of a uint64;
    ``bytes_below(base, i, bound)``
        the 64 bytes from ``base + i`` compared with ``bound`` (0-255) at once: a uint64 whose bit j is
        set when byte ``i + j`` is below ``bound`` (one vector compare and its mask: two on AVX2, one on
        AVX-512).

    The loads check no bounds: the caller keeps ``i`` (``i + 8`` for a word, ``i + 64`` for
    ``bytes_below``) within the array."""
    if numba is None:
        import ctypes

        def address(a):
            return a.ctypes.data

        def byte_at(base, i):
            return ctypes.c_uint8.from_address(base + i).value

        def word_at(base, i):
            return int.from_bytes(ctypes.string_at(base + i, 8), "little")

        def trailing_zeros(x):
            return (int(x) & -int(x)).bit_length() - 1

        def popcount(x):
            return int(x).bit_count()

        def bytes_below(base, i, bound):
            return sum(1 << j for j, b in enumerate(ctypes.string_at(base + i, 64)) if b < bound)

        return address, byte_at, word_at, trailing_zeros, popcount, bytes_below
    from llvmlite import ir
    from numba import types
    from numba.extending import intrinsic

    def _pointer(builder, base, i, bits):
        return builder.inttoptr(builder.add(base, i), ir.IntType(bits).as_pointer())

    @intrinsic
    def address(typingctx, arr):
        def codegen(context, builder, signature, args):
            data = context.make_array(signature.args[0])(context, builder, args[0]).data
            return builder.ptrtoint(data, ir.IntType(64))

        return types.int64(arr), codegen

    @intrinsic
    def byte_at(typingctx, base, i):
        def codegen(context, builder, signature, args):
            return builder.zext(builder.load(_pointer(builder, *args, 8), align=1), ir.IntType(64))

        return types.int64(types.int64, types.int64), codegen

    @intrinsic
    def word_at(typingctx, base, i):
        def codegen(context, builder, signature, args):
            return builder.load(_pointer(builder, *args, 64), align=1)

        return types.uint64(types.int64, types.int64), codegen

    @intrinsic
    def trailing_zeros(typingctx, x):
        def codegen(context, builder, signature, args):
            return builder.cttz(args[0], ir.Constant(ir.IntType(1), 0))

        return types.uint64(types.uint64), codegen

    @intrinsic
    def popcount(typingctx, x):
        def codegen(context, builder, signature, args):
            return builder.ctpop(args[0])

        return types.uint64(types.uint64), codegen

    @intrinsic
    def bytes_below(typingctx, base, i, bound):
        def codegen(context, builder, signature, args):
            vector = ir.VectorType(ir.IntType(8), 64)
            text = builder.load(builder.bitcast(_pointer(builder, *args[:2], 8), vector.as_pointer()), align=1)
            one = builder.insert_element(
                ir.Constant(vector, None), builder.trunc(args[2], ir.IntType(8)), ir.Constant(ir.IntType(32), 0)
            )
            bounds = builder.shuffle_vector(
                one, ir.Constant(vector, None), ir.Constant(ir.VectorType(ir.IntType(32), 64), [0] * 64)
            )
            return builder.bitcast(builder.icmp_unsigned("<", text, bounds), ir.IntType(64))

        return types.uint64(types.int64, types.int64, types.int64), codegen

    return address, byte_at, word_at, trailing_zeros, popcount, bytes_below


address, byte_at, word_at, trailing_zeros, popcount, bytes_below = _word_intrinsics()
if is_command():
    load_registries_without_blas_probe()
