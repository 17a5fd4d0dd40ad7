"""Store size, write (append: every frame, as it arrives), close and read time per compression.

The frames are real results: ``demsplit.compute.frame_tables`` of each frame
of a run (default: the medium benchmark run /tmp/bench_mid/in.bench, 2 frames
of 2e5 particles and 4e5 contacts, written by benchmarks/generate.py),
computed once and then stored with each compression. Times are the best of
``--repeat`` stores; the machine and its load average are printed first.

Run: python benchmarks/store_compression.py [RUN] [--repeat 3] [--auto-max-ratio 0.5 0.75 0.9]

``--auto-max-ratio`` adds ``auto`` rows with other thresholds (the default
row uses demsplit.results.chunks.AUTO_MAX_RATIO); ``--columns`` first prints, for
each column of the first frame with at least a chunk of rows, the size of its
chunks after shuffle + deflate (fraction of the raw size) and the deflate
speed (one thread, MB/s of raw data) with the store's deflate (ISA-L level 1,
``isal``) and with zlib levels 1 and 4 (the store's before), and ``auto``'s
choice.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
import zlib

import demsplit.results.chunks as C
import harness
import numpy as np
from demsplit.compute import Options, frame_tables
from demsplit.readers import open_run
from demsplit.results.schema import TABLES
from demsplit.results.store import read_store
from demsplit.results.writer import ResultWriter
from isal import isal_zlib


def real_frames(path: str) -> list[dict]:
    run = open_run(path)
    try:
        return [frame_tables(frame, run.scene, Options()) for frame in run]
    finally:
        run.close()


def column_table(tables: dict) -> None:
    deflates = {
        "isal 1": lambda c: isal_zlib.compress(c, C.GZIP_LEVEL),
        "zlib 1": lambda c: zlib.compress(c, 1),
        "zlib 4": lambda c: zlib.compress(c, 4),
    }
    print(
        "| column | first chunk, isal 1 | "
        + " | ".join(f"all, {k}" for k in deflates)
        + " | "
        + " | ".join(f"MB/s {k}" for k in deflates)
        + " | auto |"
    )
    print("|---" * (3 + 2 * len(deflates)) + "|")
    for name, table in tables.items():
        for col, values in table.items():
            whole = len(values) // C.CHUNK_ROWS * C.CHUNK_ROWS
            if not whole:
                continue
            chunks = [C._shuffled(values[k : k + C.CHUNK_ROWS]) for k in range(0, whole, C.CHUNK_ROWS)]
            ratio, speed = {}, {}
            for key, deflate in deflates.items():
                t0 = time.perf_counter()
                size = sum(len(deflate(c)) for c in chunks)
                speed[key] = whole * values.itemsize / (time.perf_counter() - t0) / 1e6
                ratio[key] = size / (whole * values.itemsize)
            first = len(deflates["isal 1"](chunks[0])) / len(chunks[0])
            print(
                f"| {name}/{col} | {first:.3f} | "
                + " | ".join(f"{ratio[k]:.3f}" for k in deflates)
                + " | "
                + " | ".join(f"{speed[k]:.0f}" for k in deflates)
                + f" | {C._choose_filter(np.asarray(values[: C.CHUNK_ROWS]))} |"
            )


def store_once(frames: list[dict], compression: str, directory: str) -> dict:
    out = os.path.join(directory, "out.h5")
    t0 = time.perf_counter()
    w = ResultWriter(out, {"inputs": []}, compression=compression)
    for tables in frames:
        w.append(tables)
    t1 = time.perf_counter()
    w.close()
    t2 = time.perf_counter()
    read_store(out)
    t3 = time.perf_counter()
    result = {"size": os.path.getsize(out), "append": t1 - t0, "close": t2 - t1, "read": t3 - t2}
    os.remove(out)
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", nargs="?", default="/tmp/bench_mid/in.bench")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--auto-max-ratio", type=float, nargs="*", default=[])
    ap.add_argument("--columns", action="store_true")
    args = ap.parse_args()

    frames = real_frames(args.run)
    raw = sum(v.nbytes for f in frames for t in f.values() for v in t.values())
    rows = {t: sum(len(next(iter(f[t].values()), ())) for f in frames if t in f) for t in TABLES}
    print("machine:", harness.machine())
    print(f"{args.run}: {len(frames)} frames, {rows}, {raw / 2**20:.1f} MiB of arrays")
    if args.columns:
        column_table(frames[0])
    cases = [(c, C.AUTO_MAX_RATIO) for c in C.COMPRESSIONS] + [("auto", r) for r in args.auto_max_ratio]
    print("| compression | size (MiB) | append (s) | close (s) | append + close (s) | read_store (s) |")
    print("|---|---|---|---|---|---|")
    default = C.AUTO_MAX_RATIO
    for compression, ratio in cases:
        C.AUTO_MAX_RATIO = ratio
        d = tempfile.mkdtemp()
        try:
            runs = [store_once(frames, compression, d) for _ in range(args.repeat)]
        finally:
            shutil.rmtree(d)
            C.AUTO_MAX_RATIO = default
        best = {k: min(r[k] for r in runs) for k in ("size", "append", "close", "read")}
        label = compression + (f" (<= {ratio:g})" if compression == "auto" else "")
        total = min(r["append"] + r["close"] for r in runs)
        print(
            f"| {label} | {best['size'] / 2**20:.1f} | {best['append']:.2f} | {best['close']:.2f} | {total:.2f} "
            f"| {best['read']:.2f} |"
        )


if __name__ == "__main__":
    main()
