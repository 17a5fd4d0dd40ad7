"""Input fingerprints: the digest the dump scan records is the file's sha256, and a changed file is hashed again."""

from __future__ import annotations

import hashlib
import os
import shutil

from demsplit import fingerprint
from demsplit.readers.lammps_dump import open_dump

from conftest import SAMPLES


def test_scan_records_the_sha256_and_a_change_invalidates_it(tmp_path):
    path = tmp_path / "pairs.txt"
    shutil.copy(SAMPLES / "liggghts" / "packing" / "pairs.txt", path)
    open_dump(path).steps  # builds the index: one read of every byte, hashed on the way
    assert any(key[0] == str(path.resolve()) for key in fingerprint._KNOWN)
    assert fingerprint.file_fingerprint(path)["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    with open(path, "ab") as f:  # the file changes: the recorded digest no longer applies
        f.write(b"\n")
    os.utime(path, ns=(1, 1))
    assert fingerprint.file_fingerprint(path)["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
