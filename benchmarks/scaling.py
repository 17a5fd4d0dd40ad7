"""Cost of ``demsplit run`` against the size of a run: particles and frames.

For each cell of a grid of (particles, frames), a run is written by
:func:`generate.generate` (two contacts per particle, ``%g`` dumps) into a
temporary directory outside the repository, and ``demsplit run -q`` is timed in a fresh process
(``harness.fresh``: inputs in the page cache), serially (best of two) and with ``--jobs 2``; the peak
resident memory is the child's own ``VmHWM``. The run's directory is removed before the next cell is written.
Printed: one row per cell (seconds, MB/s of input, peak memory), then the
exponent b of the fit seconds = a (particles x frames)^b by least squares in
log-log over the cells that take at least one second (below that, process
start and imports dominate) and over those of at least five, the least-squares
split of the time into a cost per run, per frame and per particle-frame (which
is what keeps b below 1), the peak memory as a cost per run plus one per
particle of a frame, and the ratio of ``--jobs 2`` to serial per cell.
Then the per-file overhead: a run of ``--files`` frames (1,000 by default) of
100 particles, read once from one file per dump and once from one file per
timestep (``dump ... atoms*.txt``, :mod:`demsplit.readers.dump_series`):
the difference over the number of files.
The machine and its load average are printed before, the load after (a timed run's own threads raise it
towards the number of cores); a grid that started with a load above 1 is marked "under load".

    python benchmarks/scaling.py [--big] [--cells 10000x1,10000x10] [--keep DIR] [--json FILE]

``--big`` adds a 1e7-particle frame (about 10 GB of text; about 10 minutes to
write). ``--keep DIR`` writes the runs into DIR and keeps them, and reuses
the ones already there (``generate.py`` writes ``in.bench`` last): the
writing, which takes longer than the timing, can then be done beforehand,
while the machine is busy with something else (``--generate-only``).
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

import harness
import numpy as np
from generate import generate

GRID = [
    (10_000, 1),
    (10_000, 10),
    (10_000, 100),
    (100_000, 1),
    (100_000, 10),
    (100_000, 30),
    (1_000_000, 1),
    (1_000_000, 3),
]
BIG = [(10_000_000, 1)]
CHILD = """
sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.runtime.command)
from demsplit.cli import main
rc = main(sys.argv[1:])
report(rc=rc)
sys.exit(rc)
"""


def timed_run(script: Path, out: Path, jobs: int) -> tuple[float, float]:
    """Wall seconds and peak memory (MiB) of ``demsplit run`` in a fresh process."""
    proc = harness.python(
        CHILD,
        "run",
        script,
        "-o",
        out,
        "-q",
        "--jobs",
        jobs,
        inputs=[p for p in script.parent.iterdir() if p.suffix == ".txt"],
    )
    out.unlink(missing_ok=True)
    return proc.seconds, proc.peak_mib


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--big", action="store_true", help="add a 1e7-particle frame (about 10 GB)")
    ap.add_argument("--cells", help="instead of the grid, e.g. 10000x1,10000x10 (particles x frames)")
    ap.add_argument("--files", type=int, default=1000, help="frames (files per dump) of the per-file overhead run")
    ap.add_argument("--json", type=Path, help="also write the measurements here")
    ap.add_argument("--keep", type=Path, help="write the runs here, keep them, reuse those already written")
    ap.add_argument("--generate-only", action="store_true", help="with --keep: write the runs, time nothing")
    a = ap.parse_args(argv)
    if a.generate_only and not a.keep:
        ap.error("--generate-only needs --keep DIR")
    grid = [tuple(int(v) for v in c.split("x")) for c in a.cells.split(",")] if a.cells else GRID
    grid += BIG if a.big else []
    if a.generate_only:
        for particles, frames in grid:
            _written(a.keep, particles, frames)
        return
    before = harness.machine()
    load0 = harness.load()
    print(f"machine: {before}", flush=True)
    rows = []
    # a throw-away run first, so that numba's cached kernels are compiled before any cell is timed
    with tempfile.TemporaryDirectory(prefix="demsplit-scaling-") as work:
        timed_run(harness.SAMPLE, Path(work) / "warm.h5", 1)
        for particles, frames in grid:
            d = _written(a.keep, particles, frames) if a.keep else Path(work) / f"run_{particles}_{frames}"
            if not a.keep:
                generate(d, particles, 2 * particles, frames)
            size = sum((d / f).stat().st_size for f in ("atoms.txt", "pairs.txt"))
            serial, rss = min(timed_run(d / "in.bench", Path(work) / "out.h5", 1) for _ in range(2))
            parallel, rss2 = timed_run(d / "in.bench", Path(work) / "out.h5", 2)
            rows.append(
                {
                    "particles": particles,
                    "frames": frames,
                    "bytes": size,
                    "seconds": serial,
                    "peak_mib": rss,
                    "seconds_jobs2": parallel,
                    "peak_mib_jobs2": rss2,
                    "load": harness.load(),
                }
            )
            r = rows[-1]
            print(
                f"{particles:>10,d} particles x {frames:>3d} frames  {size / 1e6:8.0f} MB  {serial:7.2f} s  "
                f"{size / serial / 1e6:6.0f} MB/s  peak {rss:6.0f} MiB  | --jobs 2 {parallel:7.2f} s "
                f"({serial / parallel:.2f}x serial)  load {r['load']:.2f}",
                flush=True,
            )
            if not a.keep:
                shutil.rmtree(d)
        per_file = per_file_overhead(Path(work), a.files)
    load1 = harness.load()
    marked = " (under load: other work was running when it started)" if load0 > 1 else ""
    print(f"\nload average {load0:.2f} before / {load1:.2f} after{marked}")
    for floor in (1.0, 5.0):
        fit = [r for r in rows if r["seconds"] >= floor]
        if len(fit) >= 2:
            x = np.log([r["particles"] * r["frames"] for r in fit])
            b, log_a = np.polyfit(x, np.log([r["seconds"] for r in fit]), 1)
            print(
                f"fit over the {len(fit)} cells of >= {floor:g} s: seconds = {np.exp(log_a):.3g} "
                f"(particles x frames)^{b:.3f}"
            )
    if len(rows) >= 3:  # what makes the exponent less than 1: a cost per run and one per frame
        design = np.array([[1.0, r["frames"], r["particles"] * r["frames"]] for r in rows])
        (c0, c_frame, c_row), *_ = np.linalg.lstsq(design, [r["seconds"] for r in rows], rcond=None)
        print(
            f"least squares over all cells: seconds = {c0:.2f} + {1e3 * c_frame:.1f} ms x frames + "
            f"{1e9 * c_row:.0f} ns x particles x frames"
        )
        (m0, m1), *_ = np.linalg.lstsq(
            np.array([[1.0, r["particles"]] for r in rows]), [r["peak_mib"] for r in rows], rcond=None
        )
        print(f"peak memory: {m0:.0f} MiB + {m1 * 2**20:.0f} B x particles (of one frame; the frames do not add)")
    worst = max(rows, key=lambda r: r["seconds_jobs2"] / r["seconds"])
    print(
        f"--jobs 2 against serial: slowest {worst['seconds_jobs2'] / worst['seconds']:.2f}x "
        f"({worst['particles']:,d} particles x {worst['frames']} frames)"
    )
    print(
        f"{a.files} frames of 100 particles: one file per dump {per_file['single']:.2f} s, one file per timestep "
        f"({2 * a.files} files) {per_file['series']:.2f} s: {per_file['per_file_ms']:.2f} ms per file"
    )
    if a.json:
        a.json.write_text(
            json.dumps({"rows": rows, "per_file": per_file, "machine": before, "load_after": load1}, indent=1)
        )


def _written(keep: Path, particles: int, frames: int) -> Path:
    """The run of ``particles`` x ``frames`` in ``keep``, written unless it is there already."""
    d = keep / f"run_{particles}_{frames}"
    if not (d / "in.bench").exists():
        generate(d, particles, 2 * particles, frames)
    return d


def per_file_overhead(work: Path, frames: int) -> dict:
    """Seconds of ``demsplit run`` on ``frames`` frames of 100 particles in one file per dump and in one
    file per timestep, and the difference per file (ms)."""
    d = work / "files"
    generate(d, 100, 200, frames)
    single, _ = timed_run(d / "in.bench", work / "out.h5", 1)
    script = (d / "in.bench").read_text()
    for name in ("atoms", "pairs"):
        text = (d / f"{name}.txt").read_text()
        for block in text.split("ITEM: TIMESTEP\n")[1:]:
            (d / f"{name}_{int(block.split(chr(10), 1)[0])}.txt").write_text("ITEM: TIMESTEP\n" + block)
        (d / f"{name}.txt").unlink()
        script = script.replace(f" {name}.txt", f" {name}_*.txt")
    (d / "in.bench").write_text(script)
    series, _ = timed_run(d / "in.bench", work / "out.h5", 1)
    shutil.rmtree(d)
    return {"single": single, "series": series, "per_file_ms": 1e3 * (series - single) / (2 * frames)}


if __name__ == "__main__":
    main()
