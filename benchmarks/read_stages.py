"""Where the time of reading and running the benchmark run goes, stage by stage, in fresh processes.

    python benchmarks/read_stages.py /tmp/bench_big [--rev 196ef03] [--repeat 3]

Prints, each the best of ``--repeat`` fresh processes (interleaved):

* ``read``: ``open_run`` (imports, script, index scans of both dumps) and ``run.frame(k)`` of every frame,
  wall, user and system seconds and peak RSS; with ``--rev REV`` the same for that git revision's package
  (its ``plugin/`` and ``readers/`` copied into a temporary directory as ``demsplit``), alternating;
* ``scan``: the index scan of each dump alone (``lammps_dump._scan``), best of three in one process;
* ``parse``: each frame of each dump parsed with the columns ``demsplit run`` reads, GB/s (two threads);
* ``digest``: the contact dump's BLAKE3 digest (``fingerprint.file_digest``) and its sha256 (``hashlib``),
  one thread each, best of three;
* ``run``, ``run, sha256`` and ``run, no hash``: ``demsplit run`` with the provenance's BLAKE3 digests of
  the inputs, with sha256 digests instead (the hash ``fingerprint`` makes patched, in the background and
  where it is taken over: what the provenance held before), and with the digest replaced by a constant
  (``file_digest`` and the background hashing patched out): what the hash costs.

The load average is printed before and after.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

READ = """
import resource, sys, time
t0 = time.perf_counter()
from demsplit.readers import open_run
run = open_run(sys.argv[1])
t1 = time.perf_counter()
for k in range(len(run)):
    frame = run.frame(k)
    del frame
t2 = time.perf_counter()
u = resource.getrusage(resource.RUSAGE_SELF)
print(t2 - t0, t1 - t0, u.ru_utime, u.ru_stime, u.ru_maxrss / 1024)
"""

SHA256 = """
import hashlib
def sha256(path):
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()
"""
"""The sha256 of a file, as the provenance held it before BLAKE3 (defined in the children below)."""

RUN = """
import os, sys, time
sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.command)
import demsplit.fingerprint as fp
if sys.argv[2] == "sha256":  # the background hashing, its take-over and file_digest: every digest
    import hashlib, types
    fp.blake3 = types.SimpleNamespace(blake3=hashlib.sha256)
elif sys.argv[2] == "nohash":
    import demsplit.pipeline as pl
    pl.hash_in_background = fp.hash_in_background = lambda paths: None
    fp.file_digest = lambda path: "0" * 64
from demsplit.cli import main
t = time.perf_counter()
rc = main(["run", sys.argv[1], "-o", sys.argv[3], "-q"])
print(time.perf_counter() - t)
os.unlink(sys.argv[3])
sys.exit(rc)
"""

STAGES = SHA256 + """
import sys, time
import numpy as np
def _timed(f, *args):
    t = time.perf_counter()
    f(*args)
    return time.perf_counter() - t
from demsplit.readers import lammps_dump, open_run
run = open_run(sys.argv[1])
for dump, names in ((run.atoms, None), (run.pairs, run._pair_names)):
    cols = ["id", "type", "x", "y", "z", "radius"] if names is None else run._wanted(names)
    scans = []
    for _ in range(3):
        t = time.perf_counter()
        with open(dump.path, "rb") as f:
            lammps_dump._scan(f)
        scans.append(time.perf_counter() - t)
    size = sum(e.data_end - e.data_start for e in dump._index())
    parse = []
    for _ in range(2):
        t = time.perf_counter()
        for k in range(len(dump)):
            dump.frame(k, cols)
        parse.append(time.perf_counter() - t)
    print(f"{dump.path.split(chr(47))[-1]:10s} scan {min(scans):.3f} s "
          f"({size / min(scans) / 1e9:.1f} GB/s)   parse of {len(cols)} columns {min(parse):.3f} s "
          f"({size / min(parse) / 1e9:.2f} GB/s, {len(dump)} frames)")
import os
from demsplit.fingerprint import file_digest
size = os.path.getsize(run.pairs.path)
for name, digest in (("BLAKE3", file_digest), ("sha256", sha256)):
    best = min(_timed(digest, run.pairs.path) for _ in range(3))
    print(f"{name:10s} digest of {run.pairs.path.split(chr(47))[-1]} on one thread {best:.3f} s "
          f"({size / best / 1e9:.2f} GB/s)")
"""


def child(code: str, args: list[str], pythonpath: str | None = None) -> list[float]:
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, env=env, check=True)
    return [float(v) for v in out.stdout.split()]


def package_of(rev: str, where: Path) -> str:
    """A directory holding revision ``rev``'s package as ``demsplit`` (for PYTHONPATH)."""
    tree = where / "tree"
    subprocess.run(["git", "-C", str(REPO), "worktree", "add", "-f", "--detach", str(tree), rev],
                   check=True, capture_output=True)
    shutil.copytree(tree / "plugin", where / "pkg" / "demsplit")
    shutil.copytree(tree / "readers", where / "pkg" / "demsplit" / "readers")
    subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(tree)], check=True,
                   capture_output=True)
    return str(where / "pkg")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--rev", help="also time reading with this git revision's package")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    script = str(a.dir / "in.bench")
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    with tempfile.TemporaryDirectory(prefix="demsplit-stages-") as tmp:
        versions = {"working tree": None}
        if a.rev:
            versions[a.rev] = package_of(a.rev, Path(tmp))
        for path in versions.values():  # compile / load each version's kernels once, untimed
            child(READ, [script], path)
        reads: dict[str, list[list[float]]] = {v: [] for v in versions}
        modes = {"run": "blake3", "run, sha256": "sha256", "run, no hash": "nohash"}
        runs: dict[str, list[float]] = {label: [] for label in modes}
        for _ in range(a.repeat):
            for label, path in versions.items():
                reads[label].append(child(READ, [script], path))
            for label, mode in modes.items():
                runs[label].append(child(RUN, [script, mode, str(Path(tmp) / "out.h5")])[0])
        for label, rows in reads.items():
            best = min(rows)
            print(f"read ({label:12s}) {best[0]:.2f} s (open_run {best[1]:.2f} s), user {best[2]:.2f} s, "
                  f"system {best[3]:.2f} s, peak {best[4]:.0f} MiB; all: {', '.join(f'{r[0]:.2f}' for r in rows)}")
        for label, times in runs.items():
            print(f"{label:15s} {min(times):.2f} s; all: {', '.join(f'{t:.2f}' for t in times)}")
        print(subprocess.run([sys.executable, "-c", STAGES, script], capture_output=True, text=True,
                             check=True).stdout, end="")
    print("load average after:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
