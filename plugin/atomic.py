"""Write a file so that its final path never holds a partial file.

Every output demsplit writes (result store, report, exports, ingest cache,
store parts) goes through :func:`atomic_path`: the content is written to a
temporary name in the target directory, flushed to disk, and renamed over the
final path only when complete; on an error the temporary file is removed.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | Path, *, durable: bool = True) -> Iterator[Path]:
    """Yield ``path.tmp`` (same directory) to write; on success fsync it and
    rename it to ``path``, on an exception remove it.

    ``durable=False`` skips the fsync: the file then survives a killed process
    (the kernel's page cache outlives it) but not a power cut, which may
    leave it empty or short under its final name; for the store's parts,
    whose reader names a short part (see :mod:`demsplit.store`)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        yield tmp
        if durable:
            with open(tmp, "rb") as f:
                os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
