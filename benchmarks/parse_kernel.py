"""The text-dump parse kernel alone: ``fastparse.parse_rows`` on one thread, this version against another.

Reads the first ``--mb`` MB of rows of frame 0 of a benchmark's ``pairs.txt``
(``benchmarks/generate.py``), requests the columns ``demsplit run`` reads, and
times ``parse_rows`` on one thread (best of ``--repeat``) for the working
tree's ``readers/fastparse.py`` and, with ``--rev REV``, for that git
revision's copy of it (with that revision's ``plugin/jit.py``, which holds the
kernel primitives), loaded side by side in this process; the converted columns
of the two must be identical (checked and printed).

    python benchmarks/parse_kernel.py /tmp/bench_big [--rev 2961f7b] [--mb 120] [--repeat 5]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
PATHS = ("readers/fastparse.py", "plugin/jit.py")  # the kernel and its primitives, taken from one revision


def load_fastparse(source: str, jit_source: str, name: str, directory: Path):
    """``source`` (a fastparse.py) loaded as module ``name`` from ``directory``, with the kernel primitives of
    ``jit_source`` (the same revision's plugin/jit.py, loaded as ``demsplit._<name>_jit``)."""
    jit_name = f"demsplit._{name}_jit"
    jit_path = directory / f"{name}_jit.py"
    jit_path.write_text(jit_source)
    spec = importlib.util.spec_from_file_location(jit_name, jit_path)
    jit = sys.modules[jit_name] = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(jit)
    path = directory / f"{name}.py"
    path.write_text(source.replace("from demsplit.jit import", f"from {jit_name} import"))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--rev", help="also time this git revision's readers/fastparse.py")
    ap.add_argument("--mb", type=int, default=120)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)
    from demsplit.readers import open_run
    from demsplit.readers.lammps_dump import open_dump

    entry = open_dump(a.dir / "pairs.txt")._index()[0]
    with open(a.dir / "pairs.txt", "rb") as f:
        f.seek(entry.data_start)
        data = f.read(min(a.mb * 10**6, entry.data_end - entry.data_start))
    data = data[: data.rfind(b"\n") + 1]
    text = np.frombuffer(data, np.uint8)
    run = open_run(a.dir / "in.bench")
    names = run._pair_names
    wanted = run._wanted(names)
    ncols = len(entry.names)
    kind, slot = np.zeros(ncols, np.int64), np.zeros(ncols, np.int64)
    for k, token in enumerate(wanted):
        kind[entry.names.index(token)] = 2 if token in (names.get("id1"), names.get("id2")) else 1
        slot[entry.names.index(token)] = k
    rows = data.count(b"\n")
    trailing = data[: data.find(b"\n")].endswith(b" ")
    sources = {"working tree": tuple((REPO / path).read_text() for path in PATHS)}
    if a.rev:
        sources[a.rev] = tuple(subprocess.run(["git", "-C", str(REPO), "show", f"{a.rev}:{path}"], capture_output=True,
                                              text=True, check=True).stdout for path in PATHS)
    results = {}
    with tempfile.TemporaryDirectory(prefix="demsplit-parse-") as tmp:
        for k, (label, source) in enumerate(sources.items()):
            fp = load_fastparse(*source, f"fastparse_{k}", Path(tmp))
            times = []
            for _ in range(a.repeat + 1):  # the first call compiles
                reals, ints = np.zeros((len(wanted), rows)), np.zeros((len(wanted), rows), np.int64)
                t = time.perf_counter()
                status = fp.parse_rows(text, 0, text.size, ncols, trailing, kind, slot, reals, ints, 0, rows,
                                       np.empty((4096, 4), np.int64))
                times.append(time.perf_counter() - t)
            results[label] = (reals, ints)
            print(f"{label:14s} {text.size / min(times[1:]) / 1e9:5.2f} GB/s, one thread (best of {a.repeat}; "
                  f"{rows} rows, {int((kind > 0).sum())} of {ncols} columns; status {status[0]})")
    if len(results) == 2:
        (r1, i1), (r2, i2) = results.values()
        same = np.array_equal(r1.view(np.uint64), r2.view(np.uint64)) and np.array_equal(i1, i2)
        print("converted columns identical:", same)
    print("load average:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
