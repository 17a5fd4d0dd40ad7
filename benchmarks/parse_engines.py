"""Which compiled text parser reads one LAMMPS/LIGGGHTS dump frame fastest?

Generates, in a temporary directory, one realistic frame of each kind:

* a ``dump local`` contact frame: ``--local-rows`` rows (default 2e6) of 41
  ``%g`` columns (ids written as doubles, as LIGGGHTS does), and
* a ``dump custom`` atom frame: ``--atom-rows`` rows (default 1e6) of
  ``id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass``,

both with LAMMPS's 9 header lines and the trailing space on every line. Then
each engine parses the frame's data rows (starting at the byte offset of the
first row, as the reader does) into float64/int64 numpy arrays, once with all
columns and once with 6 of them. Every measurement runs in a fresh Python
process, so that the peak RSS reported (``ru_maxrss`` of that child, minus its
value after the imports, which are not timed) belongs to that engine alone.

Run::

    python benchmarks/parse_engines.py [--local-rows 2000000] [--atom-rows 1000000] [--repeat 2]

Engines: pandas' C engine (``read_csv`` on a seeked file with ``nrows``),
pandas with ``engine="pyarrow"``, ``pyarrow.csv.read_csv`` on a zero-copy
``mmap`` slice, ``polars.read_csv`` on the frame's bytes, and
``numpy.loadtxt`` (compiled since numpy 1.23) for reference, and ``demsplit``:
``open_dump(path).frame(0, columns)`` (the index scan, polars per block with the shape check, the
validation and the digit count).
"""

from __future__ import annotations

import argparse
import json
import mmap
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ATOM_COLUMNS = ["id", "type", "x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz",
                "omegax", "omegay", "omegaz", "radius", "mass"]
ENGINES = ["pandas-c", "pandas-pyarrow", "pyarrow", "polars", "numpy-loadtxt", "demsplit"]
SUBSET = 6
BLOCK = 100_000  # rows formatted once and repeated (formatting is slow, parsing is what we time)


def _format_block(values: np.ndarray, int_cols: int) -> bytes:
    """Rows of ``values`` as LAMMPS prints them: ``%d`` for the first
    ``int_cols`` columns, ``%g`` after, single spaces, a trailing space."""
    import pandas as pd

    df = pd.DataFrame(values)
    for c in range(int_cols):
        df[c] = df[c].astype(np.int64)
    text = df.to_csv(sep=" ", header=False, index=False, float_format="%g", lineterminator=" \n")
    return text.encode()


def write_local_frame(path: Path, rows: int, rng: np.random.Generator) -> None:
    """A 41-column ``dump local`` frame of plausible contact values."""
    n = min(rows, BLOCK)
    v = rng.normal(size=(n, 41)) * 10.0 ** rng.integers(-9, -1, size=41)
    v[:, 0:6] = rng.uniform(0.0, 0.05, size=(n, 6))               # positions (m)
    v[:, 12:14] = rng.integers(1, 2_000_000, size=(n, 2))          # ids as doubles
    v[:, 14] = rng.integers(0, 2, size=n)                          # periodic flag
    v[:, 37] = rng.uniform(1e-8, 1e-5, size=n)                     # delta (m)
    block = _format_block(v, 0)
    head = (f"ITEM: TIMESTEP\n1000\nITEM: NUMBER OF ENTRIES\n{rows}\n"
            "ITEM: BOX BOUNDS pp pp ff\n0 0.05\n0 0.05\n0 0.1\nITEM: ENTRIES "
            + "".join(f"c_cpgl[{k}] " for k in range(1, 42)) + "\n").encode()
    _write_repeated(path, head, block, rows, n)


def write_atom_frame(path: Path, rows: int, rng: np.random.Generator) -> None:
    """A 16-column ``dump custom`` atom frame."""
    n = min(rows, BLOCK)
    v = rng.normal(size=(n, 16)) * 10.0 ** rng.integers(-7, 0, size=16)
    v[:, 0] = np.arange(1, n + 1)
    v[:, 1] = rng.integers(1, 4, size=n)
    v[:, 2:5] = rng.uniform(0.0, 0.05, size=(n, 3))
    v[:, 14] = rng.choice([0.001, 0.0015, 0.002], size=n)
    v[:, 15] = 4.0 / 3.0 * np.pi * v[:, 14] ** 3 * 2500.0
    block = _format_block(v, 2)
    head = (f"ITEM: TIMESTEP\n1000\nITEM: NUMBER OF ATOMS\n{rows}\n"
            "ITEM: BOX BOUNDS pp pp ff\n0 0.05\n0 0.05\n0 0.1\nITEM: ATOMS "
            + "".join(c + " " for c in ATOM_COLUMNS) + "\n").encode()
    _write_repeated(path, head, block, rows, n)


def _write_repeated(path: Path, head: bytes, block: bytes, rows: int, n: int) -> None:
    with open(path, "wb") as f:
        f.write(head)
        for _ in range(rows // n):
            f.write(block)
        rest = rows % n
        if rest:
            f.write(b"".join(block.splitlines(keepends=True)[:rest]))


def data_offset(path: Path) -> tuple[int, int, int]:
    """Byte offset of the first data row, number of rows and of columns."""
    with open(path, "rb") as f:
        head = [f.readline() for _ in range(9)]
        return f.tell(), int(head[3]), len(head[8].split()) - 2


def parse(engine: str, path: Path, usecols: list[int]) -> dict[int, np.ndarray]:
    """Parse the frame's rows with ``engine``; return {column index: array}."""
    offset, nrows, ncols = data_offset(path)
    if engine == "pandas-c":
        import pandas as pd
        with open(path, "rb") as f:
            f.seek(offset)
            df = pd.read_csv(f, sep=" ", header=None, usecols=usecols, nrows=nrows, engine="c")
        return {c: df[c].to_numpy() for c in usecols}
    if engine == "pandas-pyarrow":
        import pandas as pd
        with open(path, "rb") as f:
            f.seek(offset)
            df = pd.read_csv(f, sep=" ", header=None, usecols=usecols, engine="pyarrow")
        return {c: df.iloc[:, i].to_numpy() for i, c in enumerate(usecols)}
    if engine == "pyarrow":
        import pyarrow as pa
        import pyarrow.csv as pc
        with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            buf = pa.py_buffer(mm).slice(offset)
            names = [f"c{k}" for k in range(ncols + 1)]
            t = pc.read_csv(pa.BufferReader(buf),
                            read_options=pc.ReadOptions(column_names=names),
                            parse_options=pc.ParseOptions(delimiter=" "),
                            convert_options=pc.ConvertOptions(include_columns=[names[c] for c in usecols]))
            out = {c: t.column(names[c]).to_numpy() for c in usecols}
            del t, buf
        return out
    if engine == "polars":
        import polars as pl
        with open(path, "rb") as f:
            f.seek(offset)
            data = f.read()
        df = pl.read_csv(data, separator=" ", has_header=False, columns=usecols, n_rows=nrows)
        return {c: s.to_numpy() for c, s in zip(usecols, df.get_columns())}
    if engine == "numpy-loadtxt":
        with open(path, "rb") as f:
            f.seek(offset)
            a = np.loadtxt(f, usecols=usecols, max_rows=nrows, ndmin=2)
        return {c: a[:, i] for i, c in enumerate(usecols)}
    if engine == "demsplit":  # the reader itself: index scan + validation + digits included
        from demsplit.readers.lammps_dump import open_dump
        dump = open_dump(path)
        f = dump.frame(0, columns=[dump.columns[c] for c in usecols])
        return {c: f.columns[dump.columns[c]] for c in usecols}
    raise ValueError(engine)


def run_one(engine: str, path: str, usecols: list[int]) -> None:
    """Child process: time one parse, print JSON (seconds, peak RSS MiB above
    the RSS after importing every engine, rows)."""
    import pyarrow.csv  # noqa: F401  (imports are not timed)

    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t0 = time.perf_counter()
    out = parse(engine, Path(path), usecols)
    dt = time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 - base
    n = len(next(iter(out.values())))
    print(json.dumps({"seconds": dt, "rss_mib": rss, "rows": n}))


def measure(engine: str, path: Path, usecols: list[int], repeat: int) -> dict:
    best = None
    for _ in range(repeat):
        p = subprocess.run([sys.executable, __file__, "--one", engine, str(path),
                            ",".join(map(str, usecols))], capture_output=True, text=True)
        if p.returncode != 0:
            return {"error": p.stderr.strip().splitlines()[-1]}
        r = json.loads(p.stdout)
        if best is None or r["seconds"] < best["seconds"]:
            best = r
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--local-rows", type=int, default=2_000_000)
    ap.add_argument("--atom-rows", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=2, help="runs per case; the fastest is reported")
    ap.add_argument("--engines", default=",".join(ENGINES))
    ap.add_argument("--one", nargs=3, metavar=("ENGINE", "PATH", "COLS"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        run_one(a.one[0], a.one[1], [int(c) for c in a.one[2].split(",")])
        return
    rng = np.random.default_rng(1)
    with tempfile.TemporaryDirectory() as tmp:
        frames = {"local 41 cols": (Path(tmp) / "local.dump", a.local_rows, write_local_frame, 41),
                  "atoms 16 cols": (Path(tmp) / "atoms.dump", a.atom_rows, write_atom_frame, 16)}
        print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores")
        for label, (path, rows, writer, ncols) in frames.items():
            writer(path, rows, rng)
            size = path.stat().st_size / 2**20
            print(f"\n{label}: {rows} rows, {size:.0f} MiB")
            cases = {"all": list(range(ncols)), f"{SUBSET} cols": [0, 1, 2, 12, 13, 37][:SUBSET]
                     if ncols == 41 else [0, 1, 2, 3, 4, 14]}
            for case, cols in cases.items():
                results = {e: measure(e, path, cols, a.repeat) for e in a.engines.split(",")}
                ok = [r["seconds"] for r in results.values() if "seconds" in r]
                fastest = min(ok) if ok else float("nan")
                for e, r in results.items():
                    if "error" in r:
                        print(f"  {case:>7} {e:<15} failed: {r['error']}")
                    else:
                        print(f"  {case:>7} {e:<15} {r['seconds']:7.2f} s  x{r['seconds'] / fastest:5.2f}"
                              f"  peak RSS +{r['rss_mib']:5.0f} MiB  ({r['rows']} rows)")


if __name__ == "__main__":
    main()
