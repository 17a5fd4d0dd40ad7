"""What one pass over a dump in the page cache costs, by the ways a reader can make it.

    python benchmarks/page_cache.py /tmp/bench_big/pairs.txt [--repeat 3]

The reader passes over the inputs three times: the index scan, the parse and the provenance's hash each read
every byte. This prints, for one file already in the page cache, the wall and CPU seconds (user + system, one
thread) of

* ``preadv`` into a reused buffer of 256 KiB to 16 MiB (what the scan, the parse and the hash do), alone and
  followed by the compiled newline count over the buffer (``fastparse.count_newlines``: what the scan adds);
* ``mmap`` of 16 MiB windows, touching one byte per 4 KiB page: mapped by page faults, by ``MAP_POPULATE``,
  and by ``madvise(MADV_POPULATE_READ)`` (a map costs the same as a copy: the page lookups dominate);

each the best of ``--repeat``, interleaved. The load average is printed before and after.
"""

from __future__ import annotations

import argparse
import mmap
import os
import time

import numpy as np

MIB = 1 << 20
WINDOW = 16 * MIB
MADV_POPULATE_READ = getattr(mmap, "MADV_POPULATE_READ", 22)  # Linux >= 5.14; Python names it from 3.13 on


def _cpu() -> float:
    t = os.times()
    return t.user + t.system


def copy(fd: int, size: int, buffer: int, count: bool) -> None:
    """Every byte of ``fd`` read with ``os.preadv`` into one reused buffer of ``buffer`` bytes (and its
    newlines counted when ``count``)."""
    from demsplit.readers.fastparse import count_newlines

    buf = np.empty(buffer, np.uint8)
    buf[:] = 1  # touched: the first pass does not pay for fresh pages
    view = memoryview(buf)
    for offset in range(0, size, buffer):
        n = os.preadv(fd, [view], offset)
        if count:
            count_newlines(buf, 0, n)


def mapped(fd: int, size: int, how: str) -> None:
    """Every 4 KiB page of ``fd`` mapped window by window (``WINDOW`` bytes) and one byte of each read."""
    flags = mmap.MAP_SHARED | (mmap.MAP_POPULATE if how == "populate" else 0)
    for offset in range(0, size, WINDOW):
        m = mmap.mmap(fd, min(WINDOW, size - offset), flags=flags, prot=mmap.PROT_READ, offset=offset)
        if how == "madvise":
            m.madvise(MADV_POPULATE_READ)
        pages = np.frombuffer(m, np.uint8)[::4096]
        int(pages.sum())
        del pages
        m.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("path")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    fd = os.open(args.path, os.O_RDONLY)
    size = os.fstat(fd).st_size
    copy(fd, size, MIB, True)  # the file into the page cache, the kernel compiled or loaded
    ways = {f"preadv, {b // 1024} KiB buffer": (copy, b, False) for b in (MIB // 4, MIB, 4 * MIB, WINDOW)}
    ways |= {f"preadv, {b // 1024} KiB buffer, + newline count": (copy, b, True) for b in (MIB, WINDOW)}
    ways |= {f"mmap 16 MiB windows, {how}": (mapped, how) for how in ("faults", "populate", "madvise")}
    best: dict[str, tuple[float, float]] = {}
    for _ in range(args.repeat):
        for name, (fn, *rest) in ways.items():
            t0, c0 = time.perf_counter(), _cpu()
            fn(fd, size, *rest)
            wall, cpu = time.perf_counter() - t0, _cpu() - c0
            if name not in best or wall < best[name][0]:
                best[name] = (wall, cpu)
    print(f"{args.path}: {size / 1e9:.2f} GB, one thread, best of {args.repeat}")
    for name, (wall, cpu) in best.items():
        print(f"  {name:42s} wall {wall:.3f} s  CPU {cpu:.3f} s  {size / wall / 1e9:5.2f} GB/s  "
              f"{cpu / (size / 1e9):.3f} CPU-s per GB")
    print("load average after:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
