"""The fresh memory a run's first frame touches, against what ``demsplit.prefault`` maps ahead for it.

    python benchmarks/first_frame_memory.py [DIR ...]

Each DIR is a run written by ``benchmarks/generate.py``; without any, three are generated in a temporary
directory (10^6 particles and 5*10^5 contacts, 2*10^5 and 6*10^5, 5*10^5 and 10^6; one frame each). For
each run, ``demsplit run`` in a fresh process counts the minor page faults (``ru_minflt``: pages mapped
for the first time) of the first frame's read, tables and store append, once with the first frame's memory
mapped ahead (:func:`demsplit.prefault.first_frame_prefaulted`) and once without. It prints the frame's
particles and contacts, the fresh memory without the warm-up, the estimate the warm-up maps
(:func:`demsplit.prefault.first_frame_bytes`) and their ratio (below 1: the pages mapped ahead are pages
the frame would have mapped), the fresh memory left with the warm-up, the peak resident memory
(``VmHWM``) without and with the warm-up (the largest of ``--repeat`` processes each: the warm-up must not
raise it), and the least-squares fit of the fresh memory as ``a * particles + b * contacts``. The fresh
memory counts the worker threads' own heaps too, which the warm-up does not serve; an estimate near
the fit raised the benchmark run's peak, which is why ``BYTES_PER_PARTICLE`` and
``BYTES_PER_CONTACT`` are about two thirds of the fit.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SIZES = ((1_000_000, 500_000), (200_000, 600_000), (500_000, 1_000_000))

CHILD = r"""
import contextlib, json, os, resource, sys
sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.command)
import demsplit.pipeline as pipeline
import demsplit.readers.liggghts as liggghts
from demsplit.readers.liggghts import LiggghtsRun
from demsplit.results.store import ResultWriter
from demsplit.cli import main
from demsplit.prefault import first_frame_bytes
if sys.argv[3] == "off":
    pipeline.first_frame_prefaulted = lambda enabled: contextlib.nullcontext()
seen = {"faults": 0, "calls": {}}

def first_call(owner, name):
    f = getattr(owner, name)
    def wrapper(*args, **kwargs):
        calls = seen["calls"][name] = seen["calls"].get(name, 0) + 1
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        try:
            return f(*args, **kwargs)
        finally:
            if calls == 1:
                seen["faults"] += resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
    setattr(owner, name, wrapper)

announce = liggghts.announce_first_frame
def record(particles, contacts):
    seen["size"] = (particles, contacts)
    announce(particles, contacts)
liggghts.announce_first_frame = record
first_call(LiggghtsRun, "frame")
first_call(pipeline, "frame_tables")
first_call(ResultWriter, "append")
rc = main(["run", sys.argv[1], "-o", sys.argv[2], "-q"])
os.unlink(sys.argv[2])
hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")][0]
print(json.dumps({"rc": rc, "size": seen["size"], "fresh": seen["faults"] * resource.getpagesize(),
                  "estimate": first_frame_bytes(*seen["size"]), "peak": int(hwm.split()[1]) * 1024}))
"""


def first_frame(script: Path, out: Path, warm: bool) -> dict:
    """One fresh ``demsplit run``: the first frame's size, its fresh memory (bytes) and the estimate."""
    proc = subprocess.run([sys.executable, "-c", CHILD, str(script), str(out), "on" if warm else "off"],
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="*", type=Path, help="runs written by benchmarks/generate.py")
    ap.add_argument("--repeat", type=int, default=3, help="processes of each kind per run (peaks: the largest)")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="demsplit-first-frame-") as tmp:
        dirs = a.dirs
        if not dirs:
            dirs = [Path(tmp) / f"run{k}" for k in range(len(SIZES))]
            for d, (particles, contacts) in zip(dirs, SIZES):
                subprocess.run([sys.executable, str(HERE / "generate.py"), str(d), "--particles", str(particles),
                                "--contacts", str(contacts), "--frames", "1"], check=True, capture_output=True)
        rows = []
        print(f"{'particles':>10} {'contacts':>10} {'fresh MB':>9} {'estimate MB':>12} {'ratio':>6} "
              f"{'fresh MB, warmed':>17} {'peak MB':>8} {'peak MB, warmed':>16}")
        for d in dirs:
            off = [first_frame(d / "in.bench", Path(tmp) / "o.h5", warm=False) for _ in range(a.repeat)]
            on = [first_frame(d / "in.bench", Path(tmp) / "o.h5", warm=True) for _ in range(a.repeat)]
            particles, contacts = off[0]["size"]
            fresh, estimate = off[0]["fresh"], off[0]["estimate"]
            rows.append((particles, contacts, fresh))
            print(f"{particles:10d} {contacts:10d} {fresh / 1e6:9.1f} {estimate / 1e6:12.1f} "
                  f"{estimate / fresh:6.2f} {min(r['fresh'] for r in on) / 1e6:17.1f} "
                  f"{max(r['peak'] for r in off) / 1e6:8.1f} {max(r['peak'] for r in on) / 1e6:16.1f}")
    x = np.array([[p, c] for p, c, _ in rows], dtype=float)
    y = np.array([f for _, _, f in rows], dtype=float)
    (a_fit, b_fit), *_ = np.linalg.lstsq(x, y, rcond=None)
    print(f"fit: fresh bytes = {a_fit:.0f} * particles + {b_fit:.0f} * contacts")
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
