"""Compare two result stores table by table, column by column, bit for bit.

    python benchmarks/compare_stores.py --write DIR [--command "python -m demsplit.cli"]
    python benchmarks/compare_stores.py [--added-columns] BEFORE.h5 AFTER.h5 [BEFORE2.h5 AFTER2.h5 ...]
    python benchmarks/compare_stores.py [--added-columns] BEFORE_DIR AFTER_DIR   (every store of BEFORE_DIR)

For refactors that must not change a number: ``--write DIR`` writes the store of every sample run
(:data:`SAMPLE_RUNS`: the LIGGGHTS packing, periodic and analytic runs, the packing's full-precision dumps and
its paper tangential rule, both YADE scenes in both snapshot formats) into DIR with the given command, from
the repository root; run it with the code before a change and after it, into two directories, then compare
them. Every table of ``demsplit run``'s store (particles, contacts, walls, frames) must have the same
columns, dtypes and bytes (NaN equal to NaN). With ``--added-columns`` the AFTER stores may have more columns
(a feature that adds results): those are listed, and every column both have must still be the same bytes.
Provenance (version, options, paths) is not compared. Prints one line per store pair and exits 1 on any
difference (or on a sample run that failed to write its store).
"""

from __future__ import annotations

import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
from demsplit.results import TABLES, load_results

_PACKING = "sample_dumps/liggghts/packing"
SAMPLE_RUNS = {
    **{s: [f"sample_dumps/liggghts/{s}/in.{s}"] for s in ("packing", "periodic", "analytic")},
    **{
        f"{y}_{ext}": [f"sample_dumps/yade/{y}.{ext}"]
        for y in ("cundall_periodic", "mindlin_box")
        for ext in ("h5", "npys")
    },
    "packing_full": [
        f"{_PACKING}/in.packing",
        "--atoms",
        f"{_PACKING}/atoms_full.txt.gz",
        "--contacts",
        f"{_PACKING}/pairs_full.txt.gz",
        "--walls",
        f"{_PACKING}/wall_full.txt.gz",
    ],
    "packing_paper": [f"{_PACKING}/in.packing", "--tangential-rule", "paper"],
}
"""Store name -> the arguments of ``run`` (paths from the repository root) of every sample ``--write`` runs."""


def write(directory: Path, command: list[str]) -> int:
    """Every sample's store into ``directory`` (``NAME.h5``) by ``command run ...``; 1 when one failed."""
    directory.mkdir(parents=True, exist_ok=True)
    failed = 0
    for name, args in SAMPLE_RUNS.items():
        proc = subprocess.run(
            [*command, "run", *args, "-o", str(directory / f"{name}.h5"), "-q"], capture_output=True, text=True
        )
        if proc.returncode != 0:
            print(f"FAILED: {name}: {proc.stderr.strip()[-500:]}")
            failed = 1
    return failed


def differences(before: str, after: str, added_columns: bool = False) -> tuple[list[str], list[str]]:
    """What differs between the tables of two stores (empty: identical), and the columns AFTER adds."""
    a, b = load_results(before), load_results(after)
    out, added = [], []
    for name in TABLES:
        ta, tb = getattr(a, name), getattr(b, name)
        new = [c for c in tb.columns if c not in ta.columns]
        kept = [c for c in tb.columns if c in ta.columns]
        if kept != list(ta.columns) or (new and not added_columns):
            out.append(f"{name}: columns {list(ta.columns)} != {list(tb.columns)}")
            continue
        added += [f"{name}.{c}" for c in new]
        for col in ta.columns:
            x, y = ta[col].to_numpy(), tb[col].to_numpy()
            if x.dtype != y.dtype or x.shape != y.shape:
                out.append(f"{name}.{col}: {x.dtype}{x.shape} != {y.dtype}{y.shape}")
            elif not np.array_equal(
                x.view(np.uint8) if x.dtype.kind != "O" else x, y.view(np.uint8) if y.dtype.kind != "O" else y
            ):
                out.append(f"{name}.{col}: values differ")
    return out, added


def main(argv: list[str]) -> int:
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return 0
    if argv[:1] == ["--write"] and len(argv) in (2, 4) and argv[2:3] in ([], ["--command"]):
        return write(Path(argv[1]), shlex.split(argv[3]) if len(argv) == 4 else [sys.executable, "-m", "demsplit.cli"])
    added_columns = "--added-columns" in argv
    argv = [a for a in argv if a != "--added-columns"]
    if len(argv) == 2 and all(Path(a).is_dir() for a in argv):
        argv = [str(p) for b in sorted(Path(argv[0]).glob("*.h5")) for p in (b, Path(argv[1]) / b.name)]
    if len(argv) < 2 or len(argv) % 2:
        print(__doc__)
        return 2
    bad = 0
    for before, after in zip(argv[::2], argv[1::2]):
        diff, added = differences(before, after, added_columns)
        print(
            f"{'identical' if not diff else 'DIFFERENT'}: {before} vs {after}"
            + (f" (added: {' '.join(added)})" if added else "")
        )
        for line in diff:
            print(f"  {line}")
        bad += bool(diff)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
