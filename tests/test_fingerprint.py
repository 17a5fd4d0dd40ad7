"""Input fingerprints: the digest is the file's BLAKE3 as Debian's ``b3sum``
prints it, the digest hashed in the background is the same, a changed file is
hashed again, and a missing file is named."""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import pytest
from conftest import SAMPLES, require_program
from demsplit import fingerprint
from demsplit.errors import StoreError
from demsplit.runtime import hashing


def b3sum(path) -> str:
    """The digest of ``path`` as the independent ``b3sum`` (Debian's package, the BLAKE3 team's Rust
    implementation) prints it: what a user checks a store's provenance with."""
    out = subprocess.run([require_program("b3sum"), str(path)], capture_output=True, text=True, check=True)
    return out.stdout.split()[0]


@pytest.mark.parametrize("size", [0, 3, 1024, 1025, hashing._BLOCK - 1, hashing._BLOCK, 3 * hashing._BLOCK + 17])
def test_the_digest_is_what_b3sum_prints(tmp_path, size):
    """Sizes around BLAKE3's 1 KiB chunk and the 1 MiB blocks the file is read in."""
    path = tmp_path / "f.bin"
    path.write_bytes(np.random.default_rng(size).integers(0, 256, size, dtype=np.uint8).tobytes())
    assert hashing.file_digest(path) == b3sum(path)


def test_background_digest_is_the_files_and_a_change_invalidates_it(tmp_path):
    path = tmp_path / "pairs.txt"
    shutil.copy(SAMPLES / "liggghts" / "packing" / "pairs.txt", path)
    hashing.hash_in_background([path])
    key = hashing._key(path)
    assert key in hashing._PENDING
    assert fingerprint.file_fingerprint(path)["blake3"] == b3sum(path)
    assert key in hashing._KNOWN and key not in hashing._PENDING  # waited for, then remembered
    with open(path, "ab") as f:  # the file changes: the digest no longer applies
        f.write(b"\n")
    os.utime(path, ns=(1, 1))
    assert fingerprint.file_fingerprint(path)["blake3"] == b3sum(path)


def test_an_error_of_the_background_hash_is_named_with_the_file(tmp_path):
    """The hashing thread gives up on a file it cannot read; whoever needs the digest reads it again and
    reports the error with the file."""
    unreadable = tmp_path / "a-directory"
    unreadable.mkdir()  # stat works, reading does not (as root, a file's permissions would not stop it)
    job = hashing._Digest(unreadable)
    hashing._PENDING[hashing._key(unreadable)] = (os.getpid(), job)
    job.hash_in_background()  # as the thread runs it: the error ends the attempt
    assert job.digest is None
    with pytest.raises(StoreError, match="cannot read input file to fingerprint it: Is a directory") as err:
        fingerprint.file_fingerprint(unreadable)
    assert str(unreadable) in str(err.value)
    hashing.hash_in_background([tmp_path / "never-existed.txt"])  # left for file_fingerprint to report
    with pytest.raises(StoreError, match="cannot read input file"):
        fingerprint.file_fingerprint(tmp_path / "never-existed.txt")


class _Stalled:
    """A file for the background thread's hashing that gives ``blocks`` blocks and then fails: the thread
    stops there, as one the scheduler keeps off the cores makes no more progress."""

    def __init__(self, path, mode, buffering, blocks: int) -> None:
        self.f, self.blocks = open(path, mode, buffering=buffering), blocks

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.f.close()

    def seek(self, offset):
        return self.f.seek(offset)

    def readinto(self, buf):
        if self.blocks == 0:
            raise InterruptedError(4, "stalled")
        self.blocks -= 1
        return self.f.readinto(buf)


@pytest.mark.parametrize("published", [0, 1, 2, 3])
def test_a_waiter_takes_the_hashing_over_from_the_last_published_block(tmp_path, monkeypatch, published):
    """The digest finished by the waiter, from where the background thread stopped (its start, a middle
    block, the last full one), is the file's; a thread that comes back after the take-over changes
    nothing."""
    monkeypatch.setattr(hashing, "_BLOCK", 1024)
    path = tmp_path / "dump.txt"
    path.write_bytes(np.random.default_rng(published).integers(0, 256, 3 * 1024 + 100, dtype=np.uint8).tobytes())
    job = hashing._Digest(path)
    with monkeypatch.context() as m:
        m.setattr(hashing, "open", lambda p, mode, buffering: _Stalled(p, mode, buffering, published), raising=False)
        job.hash_in_background()
    assert job._offset == published * 1024 and job.digest is None
    assert job.take_over() == b3sum(path) == job.digest
    job.hash_in_background()  # a thread that comes back after the take-over leaves the digest alone
    assert job.digest == b3sum(path)


def test_the_hashing_thread_runs_on_idle_cores_and_a_waiter_does_not_wait_for_it(tmp_path, monkeypatch):
    """The thread asks for SCHED_IDLE (Linux); while it is held up, file_fingerprint finishes the digest
    itself; wait=False reports it as not known yet."""
    if not hasattr(os, "SCHED_IDLE"):
        pytest.skip("SCHED_IDLE is Linux's")
    import threading

    gate, policies = threading.Event(), []
    real = hashing._Digest.hash_in_background

    def held_up(job):
        policies.append(os.sched_getscheduler(0))
        gate.wait(60)
        real(job)

    monkeypatch.setattr(hashing._Digest, "hash_in_background", held_up)
    path = tmp_path / "pairs.txt"
    shutil.copy(SAMPLES / "liggghts" / "packing" / "pairs.txt", path)
    hashing.hash_in_background([path])
    assert fingerprint.file_fingerprint(path, wait=False)["blake3"] is None
    assert fingerprint.file_fingerprint(path)["blake3"] == b3sum(path)  # with the thread still held up
    assert policies == [os.SCHED_IDLE]
    gate.set()


@pytest.mark.slow
def test_a_run_stores_the_digest_of_every_input(tmp_path):
    """demsplit run hashes its inputs in the background while it computes the
    first frame; the store's provenance holds the files' own BLAKE3 digest."""
    import json

    import h5py
    from demsplit.cli import main

    out = tmp_path / "o.h5"
    assert main(["run", str(SAMPLES / "liggghts" / "packing" / "in.packing"), "-o", str(out), "-q"]) == 0
    with h5py.File(out) as h5:
        inputs = json.loads(h5.attrs["provenance"])["inputs"]
    assert {os.path.basename(i["path"]) for i in inputs} >= {"in.packing", "atoms_full.txt.gz", "pairs_full.txt.gz"}
    for i in inputs:
        assert i["blake3"] == b3sum(i["path"]) and i["size"] == os.path.getsize(i["path"]), i["path"]


def test_a_file_replaced_by_another_of_the_same_size_and_time_is_hashed_again(tmp_path):
    """A copy that keeps its times (cp -p, shutil.copy2) of another file of the same size: the digest of the
    file it replaced was reused, or its failed pending hash (the old file deleted) reported (found by the
    fuzzer, which runs many inputs in one process)."""
    path = tmp_path / "dump.txt"
    path.write_bytes(b"A" * 1000)
    os.utime(path, ns=(10**18, 10**18))
    first = fingerprint.file_fingerprint(path)["blake3"]
    other = tmp_path / "other.txt"
    other.write_bytes(b"B" * 1000)
    os.utime(other, ns=(10**18, 10**18))
    path.unlink()
    shutil.copy2(other, path)
    assert fingerprint.file_fingerprint(path)["blake3"] == b3sum(other) != first
