"""Compare two result stores table by table, column by column, bit for bit.

    python benchmarks/compare_stores.py BEFORE.h5 AFTER.h5 [BEFORE2.h5 AFTER2.h5 ...]

For refactors that must not change a number: every table of ``demsplit run``'s
store (particles, contacts, walls, frames) must have the same columns, dtypes
and bytes (NaN equal to NaN). Provenance (version, options, paths) is not
compared. Prints one line per store pair and exits 1 on any difference.
"""

from __future__ import annotations

import sys

import numpy as np
from demsplit.results import TABLES, load_results


def differences(before: str, after: str) -> list[str]:
    """What differs between the tables of two stores (empty: identical)."""
    a, b = load_results(before), load_results(after)
    out = []
    for name in TABLES:
        ta, tb = getattr(a, name), getattr(b, name)
        if list(ta.columns) != list(tb.columns):
            out.append(f"{name}: columns {list(ta.columns)} != {list(tb.columns)}")
            continue
        for col in ta.columns:
            x, y = ta[col].to_numpy(), tb[col].to_numpy()
            if x.dtype != y.dtype or x.shape != y.shape:
                out.append(f"{name}.{col}: {x.dtype}{x.shape} != {y.dtype}{y.shape}")
            elif not np.array_equal(x.view(np.uint8) if x.dtype.kind != "O" else x,
                                    y.view(np.uint8) if y.dtype.kind != "O" else y):
                out.append(f"{name}.{col}: values differ")
    return out


def main(argv: list[str]) -> int:
    if len(argv) < 2 or len(argv) % 2:
        print(__doc__)
        return 2
    bad = 0
    for before, after in zip(argv[::2], argv[1::2]):
        diff = differences(before, after)
        print(f"{'identical' if not diff else 'DIFFERENT'}: {before} vs {after}")
        for line in diff:
            print(f"  {line}")
        bad += bool(diff)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
