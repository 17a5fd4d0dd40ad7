"""Input files hashed with BLAKE3 on idle cores, and handed over to whoever needs a digest first.

:func:`hash_in_background` starts one daemon thread that hashes files while the frames are read and
computed. The thread asks the scheduler to run it only on idle cores (Linux's ``SCHED_IDLE``), so the
frames' own threads keep the cores and the hashing fills the moments one of them waits. Whoever needs a
digest sooner does not wait for that thread: :func:`digest` takes the hashing over from the last block the
thread finished (:class:`_Digest`) and completes it at its own priority. A digest is reused as long as the
file's size, modification time, inode and inode change time are unchanged; a changed or replaced file is
read again.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterable
from pathlib import Path

import blake3

from .threads import run_on_idle_cores

_BLOCK = 1 << 20  # bytes read and hashed at a time: in L2 cache between the copy and the hash
_KNOWN: dict[tuple[str, int, int, int, int], str] = {}
_PENDING: dict[tuple[str, int, int, int, int], tuple[int, _Digest]] = {}  # key -> (process id, the digest to come)


def _key(path: Path) -> tuple[str, int, int, int, int]:
    """The file as the digests know it: its path, size, modification time, inode and inode change time (a
    file replaced by another of the same size and time, a copy that kept its times, is another file, even
    on the inode the replaced one freed: a new file's change time is its creation)."""
    st = os.stat(path)
    return (str(path.resolve()), st.st_size, st.st_mtime_ns, st.st_ino, st.st_ctime_ns)


class _Digest:
    """One file's BLAKE3 digest in the making, which one thread starts and another may finish.

    The background thread (:meth:`hash_in_background`) publishes its progress, the offset and a copy of
    the hash state (a copy costs far less than hashing a block), after every 1 MiB block; :meth:`take_over`
    continues from the last published block in the calling thread, and the background thread drops its
    block in flight when it sees that. So a waiter never depends on a thread the scheduler may be keeping
    off the cores."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._offset = 0
        self._state = blake3.blake3()
        self._digest: str | None = None
        self._taken = False

    @property
    def digest(self) -> str | None:
        """The hex digest, or None while it is being computed."""
        with self._lock:
            return self._digest

    def hash_in_background(self) -> None:
        """Hash the file from the last published block on (nothing if it is taken over). An error reading
        it ends the attempt: :meth:`take_over` meets it again and reports it."""
        try:
            self._hash(background=True)
        except OSError:
            pass

    def take_over(self) -> str:
        """The digest: finished here from the last block the background thread completed (or from the
        file's start); raises ``OSError`` when the file cannot be read."""
        return self._hash(background=False)

    def _hash(self, background: bool) -> str | None:
        with self._lock:
            if self._digest is not None or (background and self._taken):
                return self._digest
            self._taken |= not background
            offset, state = self._offset, self._state.copy()
        buf = bytearray(_BLOCK)
        view = memoryview(buf)
        with open(self.path, "rb", buffering=0) as f:
            f.seek(offset)
            while n := f.readinto(buf):  # ``blake3`` releases the GIL while it hashes a block
                state.update(view[:n])
                offset += n
                if background:
                    with self._lock:
                        if self._taken:
                            return None
                        self._offset, self._state = offset, state.copy()
        digest = state.hexdigest()
        with self._lock:
            if background and self._taken:
                return None
            self._digest = digest
        return digest


def file_digest(path: Path) -> str:
    """BLAKE3 digest (hex, 256 bits; what ``b3sum`` prints) of the file's bytes, hashed now."""
    return _Digest(path).take_over()


def _hash_all(jobs: list[_Digest]) -> None:
    run_on_idle_cores()
    for job in jobs:
        job.hash_in_background()


def hash_in_background(paths: Iterable[str | Path]) -> None:
    """Start hashing ``paths`` in one daemon thread that runs on idle cores (files already hashed or
    being hashed are skipped; a file that cannot be stat'ed is left for :func:`file_fingerprint` to
    report)."""
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
        job = _Digest(path)
        _PENDING[key] = (os.getpid(), job)
        jobs.append(job)
    if jobs:
        threading.Thread(target=_hash_all, args=(jobs,), name="demsplit-fingerprint", daemon=True).start()


def digest(path: Path, *, wait: bool = True) -> tuple[tuple[str, int, int, int, int], str | None]:
    """``(key, hex digest)`` of the file at ``path``, ``key`` being ``(resolved path, size, ...)``
    (:func:`_key`): the digest :func:`hash_in_background` computed, or its hashing taken over and finished
    now (:class:`_Digest`), or the file hashed now. ``wait=False`` never hashes here: the digest is None
    while it is still being computed (a file not yet being hashed is handed to :func:`hash_in_background`).
    Raises ``OSError`` when the file cannot be read."""
    key = _key(path)
    known = _KNOWN.get(key)
    if known is not None:
        return key, known
    pid, job = _PENDING.get(key, (None, None))
    if pid != os.getpid():  # none, or a forked process's copy without its parent's hashing thread
        job = None
    if not wait:
        if job is None:
            hash_in_background([path])
        value = job.digest if job is not None else None
    else:
        value = job.take_over() if job is not None else file_digest(path)
    if value is not None:
        _PENDING.pop(key, None)
        _KNOWN[key] = value
    return key, value
