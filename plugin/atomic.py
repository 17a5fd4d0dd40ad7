"""Write a file so that its final path never holds a partial file.

Every output demsplit writes (report, exports, ingest cache, the store's
commit records) goes through :func:`atomic_path`: the content is written to a
temporary name in the target directory, flushed to disk, and renamed over the
final path only when complete; on an error the temporary file is removed. The
result store, written over a whole run in its own work directory, is given
its final name by :func:`publish`, the same fsync and rename.
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
    leave it empty or short under its final name; for the store's commit
    record, whose reader names a short one (see :mod:`demsplit.results.store`)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        yield tmp
        publish(tmp, path, durable=durable)
    finally:
        tmp.unlink(missing_ok=True)


def publish(tmp: str | Path, path: str | Path, *, durable: bool = True) -> None:
    """Give the complete file ``tmp`` its final name ``path`` (same file system):
    fsync it (unless ``durable=False``), then rename it over ``path``."""
    if durable:
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
    os.replace(tmp, path)
