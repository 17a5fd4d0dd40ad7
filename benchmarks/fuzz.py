"""Fuzz the LIGGGHTS run reader and the pipeline with damaged copies of a sample run.

Each input is a copy of ``sample_dumps/liggghts/packing`` (full-precision atom
dump, %g pair and wall dumps, uncompressed) in which one file got one
mutation: bytes flipped, the file cut short, a line duplicated, a line dropped,
or a token replaced by another (a number, ``nan``, ``inf``, garbage). Every
mutated run is opened and every frame computed. The promise checked: reading
either succeeds with finite results or raises a
:class:`~demsplit.errors.DemsplitError`; anything else is a bug.

    python benchmarks/fuzz.py --seconds 60 [--seed 1]

prints how many inputs it tried and the outcome counts (ok, each DemsplitError
class, and any other exception with its first occurrence). Exit status 1 when
an input escaped the promise. ``tests/test_fuzz.py`` runs the same mutations
through hypothesis, bounded.
"""

from __future__ import annotations

import argparse
import collections
import gzip
import random
import shutil
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
SAMPLE = REPO / "sample_dumps" / "liggghts" / "packing"
TARGETS = ("atoms_full.txt", "pairs.txt", "wall.txt", "in.packing")
"""Files of the fuzzed run, in the order ``Mutation.target`` indexes them."""
KINDS = ("flip", "truncate", "duplicate_line", "drop_line", "replace_token")
TOKENS = (b"nan", b"inf", b"-inf", b"x", b"", b"1e400", b"-1", b"0", b"1.5", b"99999999", b"1.23457e+06",
          b"ITEM:", b"  ", b"\t", b"\r")


def make_run(directory: Path) -> Path:
    """Copy the packing sample into ``directory`` as the fuzz base (plain text dumps);
    return the input script."""
    directory.mkdir(parents=True, exist_ok=True)
    for name in ("in.packing", "floor.stl", "pairs.txt", "wall.txt"):
        shutil.copy(SAMPLE / name, directory / name)
    with gzip.open(SAMPLE / "atoms_full.txt.gz", "rb") as f:
        (directory / "atoms_full.txt").write_bytes(f.read())
    return directory / "in.packing"


def mutate(data: bytes, kind: str, where: float, size: int, token: int) -> bytes:
    """One mutation of ``data``. ``where`` in [0, 1) picks the position, ``size``
    (>= 1) how many bytes are flipped, ``token`` which replacement token."""
    n = len(data)
    pos = min(int(where * n), n - 1)
    if kind == "flip":
        a = bytearray(data)
        rng = random.Random(pos * 7919 + size)
        for i in range(pos, min(pos + size, n)):
            a[i] = rng.randrange(256)
        return bytes(a)
    if kind == "truncate":
        return data[:pos]
    start = data.rfind(b"\n", 0, pos) + 1
    end = data.find(b"\n", pos)
    end = n if end == -1 else end + 1
    line = data[start:end]
    if kind == "duplicate_line":
        return data[:end] + line + data[end:]
    if kind == "drop_line":
        return data[:start] + data[end:]
    if kind == "replace_token":
        # replace the whitespace-separated token around pos
        s = max(data.rfind(b" ", start, pos), start - 1) + 1
        e = data.find(b" ", pos, end)
        e = end - 1 if e == -1 else e
        return data[:s] + TOKENS[token % len(TOKENS)] + data[e:]
    raise ValueError(kind)


def check_run(script: Path) -> str:
    """Open the run and compute every frame. Returns ``'ok'`` or the name of the
    DemsplitError class raised; any other exception propagates (a bug).
    An 'ok' run must give finite energies."""
    from demsplit.errors import DemsplitError
    from demsplit.pipeline import frame_tables
    from demsplit.readers import open_run

    try:
        run = open_run(script)
        try:
            for k in range(len(run)):
                tables = frame_tables(run.frame(k), run.scene)
                for name, table in tables.items():
                    for col, values in table.items():
                        if values.dtype.kind == "f" and col not in ("time", "overlap_max_rel_error"):
                            if not np.all(np.isfinite(values)):
                                raise AssertionError(f"non-finite {name}.{col} in frame {k} without an error")
        finally:
            run.close()
    except DemsplitError as exc:
        return type(exc).__name__
    return "ok"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=60.0, help="how long to fuzz")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    rng = random.Random(args.seed)
    counts: collections.Counter = collections.Counter()
    escapes: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as tmp:
        base = make_run(Path(tmp) / "base")
        originals = {t: (base.parent / t).read_bytes() for t in TARGETS}
        work = Path(tmp) / "run"
        shutil.copytree(base.parent, work)
        t0 = time.monotonic()
        while time.monotonic() - t0 < args.seconds:
            target = rng.choice(TARGETS)
            kind = rng.choice(KINDS)
            m = (kind, rng.random(), rng.randint(1, 8), rng.randrange(len(TOKENS)))
            (work / target).write_bytes(mutate(originals[target], *m))
            try:
                outcome = check_run(work / "in.packing")
            except Exception as exc:  # the promise broken: record the first of each kind
                outcome = f"ESCAPED {type(exc).__name__}"
                escapes.setdefault(outcome, f"{target} {m}\n{traceback.format_exc()}")
            counts[outcome] += 1
            (work / target).write_bytes(originals[target])
    total = sum(counts.values())
    print(f"{total} inputs in {args.seconds:g} s (seed {args.seed})")
    for outcome, n in counts.most_common():
        print(f"  {n:6d}  {outcome}")
    for outcome, where in escapes.items():
        print(f"\nfirst {outcome}: {where}")
    return 1 if escapes else 0


if __name__ == "__main__":
    sys.exit(main())
