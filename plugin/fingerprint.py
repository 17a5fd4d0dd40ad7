"""Fingerprints (size and BLAKE3 digest) of input files, for provenance.

The digest is BLAKE3's (256 bits, the ``blake3`` package): a cryptographic
hash that anyone can check with Debian's ``b3sum FILE``, and three times as
fast as sha256 here (the benchmark's 2.57 GB contact dump on one core: 0.50 s
against hashlib's sha256 with SHA-NI 1.50 s; ``benchmarks/read_stages.py``,
its "digest" lines). Hashing a multi-GB dump still costs a full read of it.
A pipeline that will need the fingerprints starts them early with
:func:`hash_in_background`: one daemon thread hashes the files
while the first frame is read and computed, and :func:`file_fingerprint`
waits for that thread's result (a digest is reused as long as the file's
size, modification time, inode and inode change time are unchanged; a changed or replaced file is
read again).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterable
from concurrent.futures import Future
from pathlib import Path

import blake3

from .errors import StoreError

DIGEST = "blake3"
"""The provenance's name for the digest of an input file (the key beside ``path`` and ``size``)."""
_BLOCK = 1 << 20  # bytes read and hashed at a time: in L2 cache between the copy and the hash
_KNOWN: dict[tuple[str, int, int, int, int], str] = {}
_PENDING: dict[tuple[str, int, int, int, int], tuple[int, Future]] = {}  # key -> (process id, the digest to come)


def _key(path: Path) -> tuple[str, int, int, int, int]:
    """The file as the digests know it: its path, size, modification time, inode and inode change time (a
    file replaced by another of the same size and time, a copy that kept its times, is another file, even
    on the inode the replaced one freed: a new file's change time is its creation)."""
    st = os.stat(path)
    return (str(path.resolve()), st.st_size, st.st_mtime_ns, st.st_ino, st.st_ctime_ns)


def file_digest(path: Path) -> str:
    """BLAKE3 digest (hex, 256 bits; what ``b3sum`` prints) of the file's bytes, hashed now
    (``blake3`` releases the GIL while it hashes a block)."""
    h = blake3.blake3()
    buf = bytearray(_BLOCK)
    view = memoryview(buf)
    with open(path, "rb", buffering=0) as f:
        while n := f.readinto(buf):
            h.update(view[:n])
    return h.hexdigest()


def _hash_all(jobs: list[tuple[Path, Future]]) -> None:
    for path, future in jobs:
        try:
            future.set_result(file_digest(path))
        except BaseException as exc:  # handed to whoever waits for this digest
            future.set_exception(exc)


def hash_in_background(paths: Iterable[str | Path]) -> None:
    """Start hashing ``paths`` in one daemon thread (files already hashed or
    being hashed are skipped; a file that cannot be stat'ed is left for
    :func:`file_fingerprint` to report)."""
    jobs = []
    for p in paths:
        path = Path(p)
        try:
            key = _key(path)
        except OSError:
            continue
        pending = _PENDING.get(key)
        if key in _KNOWN or (pending is not None and pending[0] == os.getpid()):
            continue
        future: Future = Future()
        _PENDING[key] = (os.getpid(), future)
        jobs.append((path, future))
    if jobs:
        threading.Thread(target=_hash_all, args=(jobs,), name="demsplit-fingerprint", daemon=True).start()


def file_fingerprint(path: str | Path) -> dict:
    """``{"path", "size" (bytes), "blake3"}`` of an input file: the digest
    :func:`hash_in_background` computes (waited for), or hashed now."""
    path = Path(path)
    try:
        key = _key(path)
        digest = _KNOWN.get(key)
        if digest is None:
            pid, future = _PENDING.pop(key, (None, None))
            # a forked process does not have its parent's hashing thread
            digest = future.result() if pid == os.getpid() else file_digest(path)
            _KNOWN[key] = digest
    except OSError as exc:
        raise StoreError(f"cannot read input file to fingerprint it: {exc.strerror}.", file=path,
                         fix="check that the file exists and is readable.") from exc
    return {"path": key[0], "size": key[1], DIGEST: digest}
