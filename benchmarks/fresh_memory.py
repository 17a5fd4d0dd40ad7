"""What writing to fresh memory costs on this machine, and why it varies from one process to the next.

    python benchmarks/fresh_memory.py [--mb 1024] [--pause 20] [--repeat 3]

Each measurement is a new process that maps ``--mb`` MiB of anonymous memory and writes one byte per
4 KiB (the first write to a page is when the kernel gives it one), timed, with small pages (4 KiB) and
with transparent huge pages (2 MiB, asked for with ``madvise`` as numpy does for its large arrays).
Two conditions, alternating, ``--repeat`` times each:

* ``after a pause``: the process starts after ``--pause`` seconds in which nothing ran;
* ``right after a free``: the process starts as soon as another one has written to, and freed,
  twice as much memory.

A guest that reports its free memory to its host (Linux's ``page_reporting``, virtio-balloon free page
reporting; ``reported_kib`` in the module's parameters counts what it has given back) reports only
free blocks of ``2**page_reporting_order`` pages (order 9 here: 2 MiB), and the host takes them back.
A huge page is such a block: the first write to one the host took back waits for the host to map it
again. Small pages can also come from the free pieces smaller than a block, which are never reported.
The script prints, for each measurement, the seconds per GB and the KiB the guest reported during the
pause or the other process (when ``/sys/module/page_reporting`` exists), and the load average before and
after. On this project's machine (docs/performance.md, "Fresh memory on this machine"): small pages cost
the same in both conditions, huge pages forty times more after a pause than right after a free. This is
why ``demsplit`` asks for no huge pages on such a guest (:mod:`demsplit.command`), and why a benchmark's
time moves with what ran just before it.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

TOUCH = r"""
import mmap, sys, time
n = int(sys.argv[1]) << 20
m = mmap.mmap(-1, n, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)  # private: huge pages possible
if sys.argv[2] == "huge":
    m.madvise(mmap.MADV_HUGEPAGE)  # as numpy asks for arrays of 4 MiB or more
t = time.perf_counter()
for offset in range(0, n, 4096):
    m[offset] = 1
print(time.perf_counter() - t)
"""
# one byte per page, written from Python: the loop's own cost, about 0.1 s per GB, is in every figure alike
REPORTED = Path("/sys/module/page_reporting/parameters/reported_kib")


def reported_kib() -> int | None:
    """KiB of free memory the guest has reported to the host since it booted, or None without the module."""
    try:
        return int(REPORTED.read_text())
    except (OSError, ValueError):
        return None


def touch(mb: int, pages: str = "small") -> float:
    """Seconds a fresh process takes to write one byte into each 4 KiB of ``mb`` MiB of new memory, in
    ``pages`` ``"small"`` (4 KiB) or ``"huge"`` (transparent huge pages asked for with ``madvise``)."""
    out = subprocess.run([sys.executable, "-c", TOUCH, str(mb), pages], capture_output=True, text=True,
                         check=True)
    return float(out.stdout)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mb", type=int, default=1024, help="MiB each measured process writes to")
    ap.add_argument("--pause", type=float, default=20.0, help="seconds of nothing before 'after a pause'")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    gb = a.mb * 2**20 / 1e9
    for k in range(a.repeat):
        for pages in ("small", "huge"):
            for condition in ("after a pause", "right after a free"):
                before = reported_kib()
                if condition == "after a pause":
                    time.sleep(a.pause)
                else:
                    touch(2 * a.mb, pages)
                after = reported_kib()
                seconds = touch(a.mb, pages)
                reported = "" if before is None else f"; {after - before} KiB reported to the host just before"
                print(f"{k + 1}  {pages:5s} pages, {condition:18s} {a.mb} MiB in {seconds:.3f} s: "
                      f"{seconds / gb:.2f} s per GB{reported}")
    print("load average after:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
