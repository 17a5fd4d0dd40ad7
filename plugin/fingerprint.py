"""Fingerprints (size and sha256) of input files, for provenance.

Hashing a multi-GB dump costs a full read of it. Readers that read every byte
anyway (the text-dump index scan) hash while they read and :func:`record`
the digest; :func:`file_fingerprint` then reuses it as long as the file's
size and modification time are unchanged, and reads the file otherwise.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from .errors import StoreError

_KNOWN: dict[tuple[str, int, int], str] = {}


def _key(path: Path) -> tuple[str, int, int]:
    st = os.stat(path)
    return (str(path.resolve()), st.st_size, st.st_mtime_ns)


def record(path: str | Path, sha256_hex: str) -> None:
    """Remember the sha256 of ``path`` as it is now (size and mtime)."""
    _KNOWN[_key(Path(path))] = sha256_hex


def file_fingerprint(path: str | Path) -> dict:
    """``{"path", "size" (bytes), "sha256"}`` of an input file (hashed in 1 MiB
    blocks unless a reader already recorded its digest)."""
    path = Path(path)
    try:
        key = _key(path)
        digest = _KNOWN.get(key)
        if digest is None:
            h = hashlib.sha256()
            with open(path, "rb") as f:
                for block in iter(lambda: f.read(1 << 20), b""):
                    h.update(block)
            digest = h.hexdigest()
    except OSError as exc:
        raise StoreError(f"cannot read input file to fingerprint it: {exc.strerror}.", file=path,
                         fix="check that the file exists and is readable.") from exc
    return {"path": key[0], "size": key[1], "sha256": digest}
