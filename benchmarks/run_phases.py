"""Where ``demsplit run`` spends its wall and CPU time, phase by phase, and how many cores each phase keeps busy.

    python benchmarks/run_phases.py /tmp/bench_big [--repeat 3] [--rev 4b2240f]

Each repeat is ``demsplit run DIR/in.bench -q`` in a fresh process whose phases are timed by wrapping, in that
process only: ``open_run`` (script, index scans), ``read frame`` (``LiggghtsRun.frame``: parse and join),
``frame_tables`` (validation, energies, split, tables), ``append`` (the store's compression and writes),
``close`` (the store's ``fsync`` and rename), and "after main", from ``main``'s return to the process's end
(the interpreter's teardown, or the command's ``exit_now``). For each phase: wall seconds (for a phase run once per
frame, the first frame's call and the mean of the later ones too), CPU seconds of the
whole process while it ran (user + system, every thread: the background fingerprint thread included) and
their ratio, the cores in use (the totals run from ``main``: the interpreter's start and the imports are not
in them). On a 2-core machine ``2 - cores`` is the share of a phase in which a core had nothing to do: where
running more work alongside would pay. The repeat with the shortest total is printed; the load average
before and after. With ``--rev REV`` the same for that git revision's package, the two alternating, and the
median of each one's whole process (interpreter start, imports and the process's end included: what
``bench.py`` times) for the change between them.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from read_stages import package_of

CHILD = r"""
import json, os, sys, time
sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.command)
phases, calls = {}, {}

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
            calls.setdefault(label, []).append(time.perf_counter() - t0)
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
print(json.dumps({"rc": rc, "total": total, "phases": phases, "calls": calls, "main_end": time.time()}), flush=True)
try:  # the process ends as this revision's console script ends it
    from demsplit.command import exit_now
except ImportError:  # a revision from before exit_now: the interpreter's teardown
    pass
else:
    exit_now(rc)
"""


def phases(script: Path, out: Path, pythonpath: str | None) -> dict:
    """One fresh ``demsplit run`` with its phases timed (:data:`CHILD`), and its whole process's wall seconds."""
    env = dict(os.environ, **({"PYTHONPATH": pythonpath} if pythonpath else {}))
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", CHILD, str(script), str(out)], capture_output=True, text=True,
                          check=True, env=env)
    end = time.time()
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    return {**report, "process": time.perf_counter() - t, "exit": end - report["main_end"]}


def report(label: str, runs: list[dict]) -> None:
    best = min(runs, key=lambda r: r["total"][0])
    wall, cpu = best["total"]
    totals = ", ".join(f"{r['total'][0]:.2f}" for r in runs)
    print(f"demsplit run ({label}): wall {wall:.2f} s, CPU {cpu:.2f} s, {cpu / wall:.2f} cores (all totals: {totals})")
    rest_wall, rest_cpu = wall, cpu
    for name, (w, c) in best["phases"].items():
        calls = best.get("calls", {}).get(name, [])
        frames = (f"   first frame {calls[0]:.3f} s, later {statistics.mean(calls[1:]):.3f} s each"
                  if len(calls) > 1 else "")
        print(f"  {name:14s} wall {w:5.2f} s   CPU {c:5.2f} s   {c / w if w else 0:4.2f} cores{frames}")
        rest_wall, rest_cpu = rest_wall - w, rest_cpu - c
    print(f"  {'the rest':14s} wall {rest_wall:5.2f} s   CPU {rest_cpu:5.2f} s")
    print(f"  {'after main':14s} wall {best['exit']:5.2f} s   (the process's end: teardown, or exit_now)")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rev", help="also time this git revision's package, alternating with the working tree's")
    a = ap.parse_args(argv)
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    with tempfile.TemporaryDirectory(prefix="demsplit-phases-") as tmp:
        versions: dict[str, str | None] = {"working tree": None}
        if a.rev:
            versions[a.rev] = package_of(a.rev, Path(tmp))
            for path in versions.values():  # load (or compile) each version's kernels once, untimed
                phases(a.dir / "in.bench", Path(tmp) / "o.h5", path)
        runs: dict[str, list[dict]] = {label: [] for label in versions}
        for _ in range(a.repeat):
            for label, path in versions.items():
                runs[label].append(phases(a.dir / "in.bench", Path(tmp) / "o.h5", path))
    for label, rows in runs.items():
        report(label, rows)
    if a.rev:
        for label, rows in runs.items():
            times = [r["process"] for r in rows]
            print(f"whole process ({label}): median {statistics.median(times):.2f} s; "
                  f"all: {', '.join(f'{t:.2f}' for t in times)}")
    print("load average after:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
