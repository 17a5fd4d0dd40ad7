"""What each of the ``demsplit`` command's process settings (:mod:`demsplit.command`) gains on a run.

    python benchmarks/command_settings.py /tmp/bench_big [--repeat 6] [--pause 0] [--only all,no-pages]

``demsplit run DIR/in.bench -q`` in fresh processes started as a program that imports demsplit (so
:func:`demsplit.command.settle` does nothing), each with a subset of the settings made by hand before
the run: ``none``, ``blas`` (one OpenBLAS thread, set before numpy loads), ``malloc`` (glibc keeps
freed memory), ``gc`` (rare collections), ``pages`` (numpy asks for no huge pages, set before numpy
loads: what the command does on a guest that reports free memory to its host), ``all`` (every setting)
and ``no-pages`` (every setting but ``pages``). ``--only`` picks variants. Each run starts ``--pause``
seconds after the previous one ended: with a pause, on a guest that reports free memory, its memory
has gone back to the host (``benchmarks/fresh_memory.py``); without, it starts on the pages the last
run freed. The variants run interleaved, ``--repeat`` rounds; printed per variant: median and best
wall seconds, median user and system CPU seconds and the largest peak RSS (``wait4``), every round's
time, and the load average before and after. The store each run writes is deleted after its time is
taken.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

VARIANTS = {"none": (), "blas": ("blas",), "malloc": ("malloc",), "gc": ("gc",), "pages": ("pages",),
            "all": ("blas", "malloc", "gc", "pages"), "no-pages": ("blas", "malloc", "gc")}

CHILD = r"""
import gc, os, sys
settings = sys.argv[1].split(",")
if "blas" in settings:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"   # before numpy is imported, as the command does
if "pages" in settings:
    os.environ["NUMPY_MADVISE_HUGEPAGE"] = "0"
from demsplit import command
if "malloc" in settings:
    command.keep_freed_memory()
if "gc" in settings:
    gc.set_threshold(*command.GC_THRESHOLDS)
from demsplit.cli import main
sys.exit(main(["run", sys.argv[2], "-o", sys.argv[3], "-q"]))
"""


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--repeat", type=int, default=6)
    ap.add_argument("--pause", type=float, default=0.0, help="seconds between one run's end and the next's start")
    ap.add_argument("--only", default=",".join(VARIANTS), help="comma-separated variants to run")
    a = ap.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "NUMPY_MADVISE_HUGEPAGE")}
    variants = {name: VARIANTS[name] for name in a.only.split(",")}
    results: dict[str, list[tuple[float, float, float, float]]] = {name: [] for name in variants}
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    with tempfile.TemporaryDirectory(prefix="demsplit-settings-") as tmp:
        out = Path(tmp) / "out.h5"
        for _ in range(a.repeat):
            for name, settings in variants.items():
                os.sync()
                time.sleep(a.pause)
                t = time.perf_counter()
                proc = subprocess.Popen([sys.executable, "-c", CHILD, ",".join(settings), str(a.dir / "in.bench"),
                                         str(out)], env=env)
                _, status, usage = os.wait4(proc.pid, 0)
                seconds = time.perf_counter() - t
                if status != 0:
                    raise SystemExit(f"the run with settings {name!r} failed (status {status})")
                out.unlink()
                results[name].append((seconds, usage.ru_utime, usage.ru_stime, usage.ru_maxrss / 1024))
    print("load average after: ", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    for name, rows in results.items():
        wall, user, system = ([r[k] for r in rows] for k in range(3))
        print(f"{name:8s} median {statistics.median(wall):.2f} s, best {min(wall):.2f} s; "
              f"user {statistics.median(user):.2f} s, system {statistics.median(system):.2f} s; "
              f"peak {max(r[3] for r in rows):.0f} MB; all " + " ".join(f"{w:.2f}" for w in wall))


if __name__ == "__main__":
    main()
