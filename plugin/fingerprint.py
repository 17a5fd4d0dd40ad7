"""Fingerprints (size and BLAKE3 digest) of input files, for provenance.

The digest is BLAKE3's (256 bits, the ``blake3`` package): a cryptographic hash that anyone can check with
Debian's ``b3sum FILE``, and several times as fast as sha256. Hashing a multi-GB dump still costs a full
read of it, so a pipeline that will need the fingerprints starts them early on idle cores
(:func:`demsplit.runtime.hashing.hash_in_background`) and takes over whatever is left when it needs them.
"""

from __future__ import annotations

from pathlib import Path

from .errors import StoreError
from .runtime.hashing import digest

DIGEST = "blake3"
"""The provenance's name for the digest of an input file (the key beside ``path`` and ``size``)."""


def file_fingerprint(path: str | Path, *, wait: bool = True) -> dict:
    """``{"path", "size" (bytes), "blake3"}`` of an input file (:func:`demsplit.runtime.hashing.digest`);
    ``wait=False`` gives None as the digest while it is still being computed in the background."""
    path = Path(path)
    try:
        key, value = digest(path, wait=wait)
    except OSError as exc:
        raise StoreError(
            f"cannot read input file to fingerprint it: {exc.strerror}.",
            file=path,
            fix="check that the file exists and is readable.",
        ) from exc
    return {"path": key[0], "size": key[1], DIGEST: value}
