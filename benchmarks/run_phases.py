"""Where ``demsplit run`` spends its time, phase by phase, and what a change of the code or of its process changes.

    python benchmarks/run_phases.py /tmp/bench_big [--repeat 3] [--rev REV] [--variant V ...] [--pause S] [--stages]

Each repeat is ``demsplit run DIR/in.bench -q`` in a fresh process (``harness.fresh``) whose phases are timed
by wrapping, in that process only: ``open_run`` (script, index scans), ``read frame`` (``LiggghtsRun.frame``:
parse and join), ``frame_tables`` (validation, energies, split, tables), ``append`` (the store's compression
and writes), ``close`` (the store's last chunks, ``fsync`` and rename), and "after main", from ``main``'s
return to the process's end (the interpreter's teardown, or the command's ``exit_now``). For each phase:
wall seconds (for a phase run once per frame, the first frame's call and the mean of the later ones too),
CPU seconds of the whole process while it ran (user + system, every thread: the background digests
included) and their ratio, the cores in use, and the fresh memory of its first call (MiB of pages the
process touched for the first time: its minor page faults, every thread's). The totals run from ``main``:
the interpreter's start and the imports are not in them. On a machine of N cores, ``N - cores`` is the
share of a phase in which cores had nothing to do. The repeat with the shortest total is printed. With more
than one thread the frames overlap (:mod:`demsplit.runtime.stages`: the next frame read and the last one
stored while one is computed), so the phases' walls add up to more than the total and each phase's CPU
seconds include the other stages' work in the same moments; the totals still hold.

Versions, run interleaved (``harness.rounds``), ``--repeat`` times each: the working tree; with ``--rev
REV`` that git revision's package; with ``--variant V`` (repeatable) the working tree with one change made
in the child before the run:

``no-hash``
    the inputs' digests replaced by a constant (``file_digest`` and the background hashing patched out):
    against the working tree, what the background digests cost;
``sha256``
    every digest (in the background, taken over, or asked for) by sha256 instead of BLAKE3;
``no-prefault``
    the first frame's memory not mapped ahead while the run opens (``first_frame_prefaulted`` patched out):
    the first frame's fresh memory without the warm-up;
``settings=LIST``
    the process started as a program that imports demsplit (so :mod:`demsplit.runtime.command` makes none of the
    command's settings), then only the settings of LIST made by hand before the run: ``blas`` (one
    OpenBLAS thread), ``malloc`` (glibc keeps freed memory), ``gc`` (rare collections), ``pages`` (numpy
    asks for no huge pages); ``settings=`` makes none. Such a process ends as a library program does,
    through the interpreter's teardown.

``--pause S`` starts each run S seconds after the last one ended (with a pause, a virtual machine that hands
its free memory back to its host has done so; without, a run starts on the pages the last one freed).
Printed per version: the phases of its shortest run, then the whole process (interpreter start, imports and
end included: what ``bench.py`` times): median and best wall seconds, median user and system CPU seconds,
the largest peak resident memory, every run's time. The machine and load average are printed before, the
load after. ``--stages`` then prints, from one more process, each dump's index scan and parse alone (GB/s
on the pool's threads; the parse of the columns ``demsplit run`` reads) and the contact dump's BLAKE3 and
sha256 digests on one thread.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import harness

VARIANTS = ("no-hash", "sha256", "no-prefault")
SETTINGS = ("blas", "malloc", "gc", "pages")

CHILD = r"""
import contextlib, os, resource, sys, time
variant = sys.argv[3]
if variant.startswith("settings="):  # a program that imports demsplit, with the listed settings made by hand
    settings = set(filter(None, variant.split("=", 1)[1].split(",")))
    if "blas" in settings:
        os.environ["OPENBLAS_NUM_THREADS"] = "1"  # before numpy is imported, as the command does
    if "pages" in settings:
        os.environ["NUMPY_MADVISE_HUGEPAGE"] = "0"
    import gc
    try:
        from demsplit.runtime import command
    except ImportError:  # a revision from before demsplit.runtime
        from demsplit import command
    if "malloc" in settings:
        command.keep_freed_memory()
    if "gc" in settings:
        gc.set_threshold(*command.GC_THRESHOLDS)
else:
    sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.runtime.command)
phases, calls, fresh = {}, {}, {}
PAGE_MIB = resource.getpagesize() / 2**20

def timed(owner, name, label):
    f = getattr(owner, name)
    def wrapper(*args, **kwargs):
        t0, c0, m0 = time.perf_counter(), os.times(), resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        try:
            return f(*args, **kwargs)
        finally:
            c1 = os.times()
            wall, cpu = phases.get(label, (0.0, 0.0))
            phases[label] = (wall + time.perf_counter() - t0, cpu + c1.user - c0.user + c1.system - c0.system)
            calls.setdefault(label, []).append(time.perf_counter() - t0)
            fresh.setdefault(label, (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - m0) * PAGE_MIB)
    setattr(owner, name, wrapper)

import demsplit.pipeline as pipeline
import demsplit.readers as readers
from demsplit.readers.liggghts import LiggghtsRun
try:  # where each piece lives now, and in a revision from before demsplit.runtime
    import demsplit.executors as executors
    import demsplit.runtime.hashing as hashing
    from demsplit.results.writer import ResultWriter
except ImportError:
    import demsplit.fingerprint as hashing
    from demsplit.results.store import ResultWriter
    executors = pipeline
if variant == "sha256":
    import hashlib, types
    hashing.blake3 = types.SimpleNamespace(blake3=hashlib.sha256)
elif variant == "no-hash":
    pipeline.hash_in_background = hashing.hash_in_background = lambda paths: None
    hashing.file_digest = lambda path: "0" * 64
elif variant == "no-prefault":
    pipeline.first_frame_prefaulted = lambda rows: contextlib.nullcontext()
timed(readers, "open_run", "open_run")
timed(LiggghtsRun, "frame", "read frame")
timed(executors, "frame_tables", "frame_tables")
timed(ResultWriter, "append", "append")
timed(ResultWriter, "close", "close")
from demsplit.cli import main
t0, c0 = time.perf_counter(), os.times()
rc = main(["run", sys.argv[1], "-o", sys.argv[2], "-q"])
c1 = os.times()
total = (time.perf_counter() - t0, c1.user - c0.user + c1.system - c0.system)
os.unlink(sys.argv[2])
report(rc=rc, total=total, phases=phases, calls=calls, fresh=fresh, main_end=time.time())
if not variant.startswith("settings="):
    try:  # the process ends as this revision's console script ends it
        from demsplit.runtime.command import exit_now
    except ImportError:
        try:
            from demsplit.command import exit_now
        except ImportError:  # a revision from before exit_now: the interpreter's teardown
            exit_now = None
    if exit_now is not None:
        exit_now(rc)
sys.exit(rc)
"""

STAGES = r"""
import hashlib, os, sys
try:
    from demsplit.runtime.hashing import file_digest
except ImportError:  # a revision from before demsplit.runtime
    from demsplit.fingerprint import file_digest
from demsplit.readers import lammps_dump, open_run

def sha256(path):
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()

run = open_run(sys.argv[1])
for dump, names in ((run.atoms, None), (run.pairs, run._pair_names)):
    cols = ["id", "type", "x", "y", "z", "radius"] if names is None else run._wanted(names)

    def scan():
        with open(dump.path, "rb") as f:
            lammps_dump._scan(f)

    def parse():
        for k in range(len(dump)):
            dump.frame(k, cols)

    size = sum(e.data_end - e.data_start for e in dump._index())
    t_scan, t_parse = best_of(scan, 3), best_of(parse, 2)
    print(f"{os.path.basename(dump.path):10s} scan {t_scan:.3f} s ({size / t_scan / 1e9:.1f} GB/s)   parse of "
          f"{len(cols)} columns {t_parse:.3f} s ({size / t_parse / 1e9:.2f} GB/s, {len(dump)} frames)")
size = os.path.getsize(run.pairs.path)
for name, digest in (("BLAKE3", file_digest), ("sha256", sha256)):
    best = best_of(lambda: digest(run.pairs.path), 3)
    print(f"{name:10s} digest of {os.path.basename(run.pairs.path)} on one thread {best:.3f} s "
          f"({size / best / 1e9:.2f} GB/s)")
"""


def variant_name(value: str) -> str:
    """``--variant``'s argument, checked."""
    if value in VARIANTS:
        return value
    if value.startswith("settings="):
        unknown = set(filter(None, value.split("=", 1)[1].split(","))) - set(SETTINGS)
        if not unknown:
            return value
    raise argparse.ArgumentTypeError(
        f"{value!r}: one of {', '.join(VARIANTS)}, or settings=LIST of {','.join(SETTINGS)}"
    )


def package_of(rev: str, where: Path) -> str:
    """A directory holding revision ``rev``'s package as ``demsplit`` (for PYTHONPATH)."""
    tree = where / "tree"
    subprocess.run(
        ["git", "-C", str(harness.REPO), "worktree", "add", "-f", "--detach", str(tree), rev],
        check=True,
        capture_output=True,
    )
    shutil.copytree(tree / "plugin", where / "pkg" / "demsplit")
    shutil.copytree(tree / "readers", where / "pkg" / "demsplit" / "readers")
    subprocess.run(
        ["git", "-C", str(harness.REPO), "worktree", "remove", "--force", str(tree)], check=True, capture_output=True
    )
    return str(where / "pkg")


def environment(pythonpath: str | None) -> dict:
    """The children's environment: without the variables the command sets for itself (so that the command,
    or a ``settings=`` variant, makes them), with ``pythonpath`` first on the module path."""
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "NUMPY_MADVISE_HUGEPAGE")}
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    return env


def phases(script: Path, out: Path, env: dict, variant: str, pause: float) -> dict:
    """One fresh ``demsplit run`` with its phases timed (:data:`CHILD`): its report, the whole process's wall,
    user and system seconds, and the seconds from ``main``'s return to the process's end."""
    proc = harness.python(CHILD, script, out, variant, env=env, pause=pause)
    end = time.time()
    return {
        **proc.report,
        "process": proc.seconds,
        "user": proc.user,
        "system": proc.system,
        "exit": end - proc.report["main_end"],
    }


def report(label: str, runs: list[dict]) -> None:
    best = min(runs, key=lambda r: r["total"][0])
    wall, cpu = best["total"]
    totals = ", ".join(f"{r['total'][0]:.2f}" for r in runs)
    print(f"demsplit run ({label}): wall {wall:.2f} s, CPU {cpu:.2f} s, {cpu / wall:.2f} cores (all totals: {totals})")
    rest_wall, rest_cpu = wall, cpu
    for name, (w, c) in best["phases"].items():
        calls = best["calls"].get(name, [])
        frames = (
            f"   first frame {calls[0]:.3f} s, later {statistics.mean(calls[1:]):.3f} s each" if len(calls) > 1 else ""
        )
        print(
            f"  {name:14s} wall {w:5.2f} s   CPU {c:5.2f} s   {c / w if w else 0:4.2f} cores   "
            f"fresh {best['fresh'].get(name, 0):6.1f} MiB{frames}"
        )
        rest_wall, rest_cpu = rest_wall - w, rest_cpu - c
    if rest_wall < 0:
        print(f"  {'overlapped':14s} wall {-rest_wall:5.2f} s   (the phases' walls exceed the total: they ran at once)")
    else:
        print(f"  {'the rest':14s} wall {rest_wall:5.2f} s   CPU {rest_cpu:5.2f} s")
    print(f"  {'after main':14s} wall {best['exit']:5.2f} s   (the process's end: teardown, or exit_now)")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rev", help="also time this git revision's package")
    ap.add_argument(
        "--variant",
        type=variant_name,
        action="append",
        default=[],
        help=f"also time the working tree with a change: {', '.join(VARIANTS)}, settings=LIST",
    )
    ap.add_argument("--pause", type=float, default=0.0, help="seconds between one run's end and the next's start")
    ap.add_argument("--stages", action="store_true", help="then time the index scans, parses and digests alone")
    a = ap.parse_args(argv)
    script = a.dir / "in.bench"
    print("machine:", harness.machine())
    with tempfile.TemporaryDirectory(prefix="demsplit-phases-") as tmp:
        out = Path(tmp) / "o.h5"
        versions = {"working tree": (environment(None), "")}
        if a.rev:
            versions[a.rev] = (environment(package_of(a.rev, Path(tmp))), "")
        for variant in a.variant:
            versions[variant] = (versions["working tree"][0], variant)
        for env in {id(env): env for env, _ in versions.values()}.values():
            phases(script, out, env, "", 0.0)  # load (or compile) each package's kernels once, untimed
        runs: dict[str, list[dict]] = {label: [] for label in versions}
        for order in harness.rounds(list(versions), a.repeat):
            for label in order:
                env, variant = versions[label]
                runs[label].append(phases(script, out, env, variant, a.pause))
    for label, rows in runs.items():
        report(label, rows)
    for label, rows in runs.items():
        wall = [r["process"] for r in rows]
        print(
            f"whole process ({label}): median {harness.median(wall):.2f} s, best {min(wall):.2f} s; "
            f"user {harness.median([r['user'] for r in rows]):.2f} s, "
            f"system {harness.median([r['system'] for r in rows]):.2f} s; "
            f"peak {max(r['peak_mib'] for r in rows):.0f} MiB; all: {', '.join(f'{t:.2f}' for t in wall)}"
        )
    if a.stages:
        print(harness.python("from harness import best_of\n" + STAGES, script).stdout, end="")
    print(f"load average after: {harness.load():.2f}")


if __name__ == "__main__":
    main()
