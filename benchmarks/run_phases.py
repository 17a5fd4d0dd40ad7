"""Where ``demsplit run`` spends its wall and CPU time, phase by phase, and how many cores each phase keeps busy.

    python benchmarks/run_phases.py /tmp/bench_big [--repeat 3]

Each repeat is ``demsplit run DIR/in.bench -q`` in a fresh process whose phases are timed by wrapping, in that
process only: ``open_run`` (script, index scans), ``read frame`` (``LiggghtsRun.frame``: parse and join),
``frame_tables`` (validation, energies, split, tables), ``append`` (the store's compression and writes) and
``close`` (the store's ``fsync`` and rename). For each phase: wall seconds, CPU seconds of the whole process
while it ran (user + system, every thread: the background fingerprint thread included) and their ratio, the
cores in use (the totals run from ``main``: the interpreter's start and the imports are not in them). On a
2-core machine ``2 - cores`` is the share of a phase in which a core had nothing to do:
where running more work alongside would pay. The repeat with the shortest total is printed; the load average
before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, os, sys, time
sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.command)
phases = {}

def timed(owner, name, label):
    f = getattr(owner, name)
    def wrapper(*args, **kwargs):
        t0, c0 = time.perf_counter(), os.times()
        try:
            return f(*args, **kwargs)
        finally:
            c1 = os.times()
            wall, cpu = phases.get(label, (0.0, 0.0))
            phases[label] = (wall + time.perf_counter() - t0, cpu + c1.user - c0.user + c1.system - c0.system)
    setattr(owner, name, wrapper)

import demsplit.pipeline as pipeline
import demsplit.readers as readers
from demsplit.readers.liggghts import LiggghtsRun
from demsplit.results.store import ResultWriter
timed(readers, "open_run", "open_run")
timed(LiggghtsRun, "frame", "read frame")
timed(pipeline, "frame_tables", "frame_tables")
timed(ResultWriter, "append", "append")
timed(ResultWriter, "close", "close")
from demsplit.cli import main
t0, c0 = time.perf_counter(), os.times()
rc = main(["run", sys.argv[1], "-o", sys.argv[2], "-q"])
c1 = os.times()
total = (time.perf_counter() - t0, c1.user - c0.user + c1.system - c0.system)
os.unlink(sys.argv[2])
print(json.dumps({"rc": rc, "total": total, "phases": phases}))
"""


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    runs = []
    with tempfile.TemporaryDirectory(prefix="demsplit-phases-") as tmp:
        for _ in range(a.repeat):
            out = subprocess.run([sys.executable, "-c", CHILD, str(a.dir / "in.bench"), str(Path(tmp) / "o.h5")],
                                 capture_output=True, text=True, check=True)
            runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    best = min(runs, key=lambda r: r["total"][0])
    wall, cpu = best["total"]
    totals = ", ".join(f"{r['total'][0]:.2f}" for r in runs)
    print(f"demsplit run: wall {wall:.2f} s, CPU {cpu:.2f} s, {cpu / wall:.2f} cores (all totals: {totals})")
    rest_wall, rest_cpu = wall, cpu
    for label, (w, c) in best["phases"].items():
        print(f"  {label:14s} wall {w:5.2f} s   CPU {c:5.2f} s   {c / w if w else 0:4.2f} cores")
        rest_wall, rest_cpu = rest_wall - w, rest_cpu - c
    print(f"  {'the rest':14s} wall {rest_wall:5.2f} s   CPU {rest_cpu:5.2f} s")
    print("load average after:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
