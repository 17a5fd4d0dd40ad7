"""Skipping unread fields with a 64-bit separator mask per 64 bytes (simdjson style): what the mask costs.

The parser steps over a run of columns it does not read with
:func:`demsplit.readers.fastparse._skip_fields`, which builds, per 64 bytes, a mask of the separator bytes
(<= 32) and counts them. This script measures what the mask alone costs against the parse kernel stepping
over every field and converting none, on the first ``--mb`` MB of rows of a benchmark's ``pairs.txt``, one
thread: the masks of consecutive blocks in one loop (which LLVM vectorises), the mask of one block per call
written as a numba loop (which it does not vectorise), and the mask of one block per call by
:func:`demsplit.jit.bytes_below` (one vector compare emitted as LLVM IR), as the parse now asks for it:

    python benchmarks/separator_mask.py /tmp/bench_big [--mb 100]

History: with the numba-loop mask per call, ``parse_rows`` measured 0.92 GB/s against 1.77 for the 8-byte
word-at-a-time skip of the time (``benchmarks/parse_kernel.py``, 2026-11-26, load 1.1), and the mask was
dropped; with ``bytes_below`` the parse reads 3.30 GB/s against 2.45 GB/s for the word-at-a-time skip
(``benchmarks/parse_kernel.py /tmp/bench_big --rev 2a2c648 --mb 300``), and the mask is kept.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--mb", type=int, default=100)
    a = ap.parse_args(argv)
    from demsplit.jit import address, bytes_below, kernel
    from demsplit.readers import fastparse
    from demsplit.readers.lammps_dump import open_dump

    @kernel
    def separator_masks(text: np.ndarray, out: np.ndarray) -> None:
        for b in range(out.size):
            m = np.uint64(0)
            for j in range(64):
                m |= np.uint64(text[b * 64 + j] <= 32) << np.uint64(j)
            out[b] = m

    @kernel
    def one_mask(text: np.ndarray, p: int) -> np.uint64:
        m = np.uint64(0)
        for j in range(64):
            m |= np.uint64(text[p + j] <= 32) << np.uint64(j)
        return m

    @kernel
    def mask_per_call(text: np.ndarray, out: np.ndarray) -> None:
        for b in range(out.size):
            out[b] = one_mask(text, b * 64)

    @kernel
    def vector_mask_per_call(text: np.ndarray, out: np.ndarray) -> None:
        base = address(text)
        for b in range(out.size):
            out[b] = bytes_below(base, b * 64, 33)

    entry = open_dump(a.dir / "pairs.txt")._index()[0]
    with open(a.dir / "pairs.txt", "rb") as f:
        f.seek(entry.data_start)
        data = f.read(a.mb * 10**6)
    data = data[: data.rfind(b"\n") + 1]
    text = np.frombuffer(data, np.uint8)
    ncols, rows = len(entry.names), data.count(b"\n")
    masks = np.empty(text.size // 64, np.uint64)
    none = np.zeros(ncols, np.int64)
    empty_r, empty_i = np.empty((0, rows)), np.empty((0, rows), np.int64)

    def skip() -> None:
        fastparse.parse_rows(text, 0, text.size, ncols, True, none, none, empty_r, empty_i, 0, rows,
                             np.empty((1, 4), np.int64))

    for name, fn in (("masks, one loop", lambda: separator_masks(text, masks)),
                     ("masks, one per call", lambda: mask_per_call(text, masks)),
                     ("bytes_below, per call", lambda: vector_mask_per_call(text, masks)),
                     ("the parse's skip", skip)):
        fn()  # compile
        best = min(_timed(fn) for _ in range(5))
        print(f"{name:22s} {text.size / best / 1e9:5.2f} GB/s  {best / rows * 1e9:6.1f} ns per row (one thread)")
    print("load average:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


def _timed(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


if __name__ == "__main__":
    main()
