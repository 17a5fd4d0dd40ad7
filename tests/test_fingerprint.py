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


def b3sum(path) -> str:
    """The digest of ``path`` as the independent ``b3sum`` (Debian's package, the BLAKE3 team's Rust
    implementation) prints it: what a user checks a store's provenance with."""
    out = subprocess.run([require_program("b3sum"), str(path)], capture_output=True, text=True, check=True)
    return out.stdout.split()[0]


@pytest.mark.parametrize("size", [0, 3, 1024, 1025, fingerprint._BLOCK - 1, fingerprint._BLOCK,
                                  3 * fingerprint._BLOCK + 17])
def test_the_digest_is_what_b3sum_prints(tmp_path, size):
    """Sizes around BLAKE3's 1 KiB chunk and the 1 MiB blocks the file is read in."""
    path = tmp_path / "f.bin"
    path.write_bytes(np.random.default_rng(size).integers(0, 256, size, dtype=np.uint8).tobytes())
    assert fingerprint.file_digest(path) == b3sum(path)


def test_background_digest_is_the_files_and_a_change_invalidates_it(tmp_path):
    path = tmp_path / "pairs.txt"
    shutil.copy(SAMPLES / "liggghts" / "packing" / "pairs.txt", path)
    fingerprint.hash_in_background([path])
    key = fingerprint._key(path)
    assert key in fingerprint._PENDING
    assert fingerprint.file_fingerprint(path)["blake3"] == b3sum(path)
    assert key in fingerprint._KNOWN and key not in fingerprint._PENDING  # waited for, then remembered
    with open(path, "ab") as f:  # the file changes: the digest no longer applies
        f.write(b"\n")
    os.utime(path, ns=(1, 1))
    assert fingerprint.file_fingerprint(path)["blake3"] == b3sum(path)


def test_an_error_of_the_background_hash_is_named_with_the_file(tmp_path):
    """The hashing thread hands its error to whoever waits for the digest."""
    from concurrent.futures import Future

    path = tmp_path / "unreadable.txt"
    path.write_bytes(b"x" * 100)
    failed: Future = Future()
    failed.set_exception(PermissionError(13, "Permission denied"))
    fingerprint._PENDING[fingerprint._key(path)] = (os.getpid(), failed)  # as _hash_all leaves it
    with pytest.raises(StoreError, match="cannot read input file to fingerprint it: Permission denied") as err:
        fingerprint.file_fingerprint(path)
    assert str(path) in str(err.value)
    fingerprint.hash_in_background([tmp_path / "never-existed.txt"])  # left for file_fingerprint to report
    with pytest.raises(StoreError, match="cannot read input file"):
        fingerprint.file_fingerprint(tmp_path / "never-existed.txt")


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
