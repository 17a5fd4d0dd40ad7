"""One validation for every reader's frames (plugin/validate.py), by class of bad input: a non-finite
number, a value out of range, a narrow or foreign dtype, an implausible overlap, an energy that overflows.
Each is one message (exit 2) that names the file, the timestep, the column and the row; nothing is stored."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from demsplit.cli import main
from demsplit.readers.yade_snapshot import _open_store
from demsplit.yade import write_snapshot

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"
SNAPSHOT = SAMPLES / "yade" / "mindlin_box.npys"


def damaged_snapshot(tmp_path: Path, table: str, column: str, value, row: int = 3, dtype=None) -> Path:
    """The last snapshot of the Mindlin sample with one value (or one column's dtype) changed."""
    meta, tables = _open_store(SNAPSHOT).snapshot(2)
    col = tables[table][column].copy()
    if dtype is not None:
        col = col.astype(dtype)
    else:
        col[row] = value
    tables[table][column] = col
    out = tmp_path / f"{column}.npys"
    write_snapshot(out, meta, tables, format="npy")
    return out


def run(path: Path, tmp_path: Path, capsys) -> tuple[int, str]:
    rc = main(["run", str(path), "-o", str(tmp_path / "out.h5"), "-q"])
    return rc, capsys.readouterr().err


@pytest.mark.parametrize("table, column, value", [
    ("interactions", "depth", np.nan), ("interactions", "fsx", np.inf), ("interactions", "nx", np.nan),
    ("interactions", "kno", -np.inf), ("bodies", "radius", np.nan), ("bodies", "x", np.inf),
])
def test_a_non_finite_number_is_refused_with_its_place(tmp_path, capsys, table, column, value):
    rc, err = run(damaged_snapshot(tmp_path, table, column, value), tmp_path, capsys)
    assert rc == 2 and "timestep 24000" in err and "row" in err
    assert "not a finite number" in err or "unit normal" in err  # a NaN component makes |n| NaN too
    assert not (tmp_path / "out.h5").exists()


@pytest.mark.parametrize("table, column, value, what", [
    ("bodies", "radius", -1e-3, "must be > 0"), ("interactions", "kno", -5.0, "must be >= 0"),
    ("interactions", "nx", 0.9, "unit normal"), ("interactions", "depth", 1.0, "larger than its smaller radius"),
])
def test_a_value_out_of_range_or_implausible_is_refused(tmp_path, capsys, table, column, value, what):
    rc, err = run(damaged_snapshot(tmp_path, table, column, value), tmp_path, capsys)
    assert rc == 2 and what in err and "timestep 24000" in err and "(row " in err
    assert not (tmp_path / "out.h5").exists()


def test_a_narrow_integer_stiffness_is_upcast_not_wrapped(tmp_path, capsys):
    """kn stored as int16 must give the energies of the same values as float64, never negative ones."""
    meta, tables = _open_store(SAMPLES / "yade" / "cundall_periodic.npys").snapshot(2)
    tables["interactions"]["kn"] = np.full(len(tables["interactions"]["kn"]), 30000, dtype=np.int16)
    path = tmp_path / "int16.npys"
    write_snapshot(path, meta, tables, format="npy")
    assert main(["run", str(path), "-o", str(tmp_path / "out.h5"), "-q"]) == 0
    from demsplit.results import load_results

    u_n = load_results(tmp_path / "out.h5").contacts["u_n"].to_numpy()
    assert np.all(u_n >= 0) and np.any(u_n > 0)


def test_an_energy_that_overflows_is_refused(tmp_path, capsys):
    rc, err = run(damaged_snapshot(tmp_path, "interactions", "fsx", 1e200), tmp_path, capsys)
    assert rc == 2 and "energy that is not finite" in err
    assert not (tmp_path / "out.h5").exists()


def test_a_binary_atom_dump_with_an_infinite_position_is_refused(tmp_path, capsys):
    """A LAMMPS binary dump (atoms.bin of the periodic sample) with x = inf in one atom."""
    src = SAMPLES / "liggghts" / "periodic"
    data = bytearray((src / "atoms.bin").read_bytes())
    # header: step (q), n (q), triclinic (i), boundary (6i), box (6d), size_one (i), nchunk (i), n values (i)
    head = struct.calcsize("=qqi6i6dii")
    n = struct.unpack_from("=i", data, head)[0]
    assert n > 16
    struct.pack_into("=d", data, head + 4 + 8 * 2, np.inf)  # the first atom's x (columns id type x ...)
    for name in ("in.periodic", "pairs.txt", "wall.txt", "floor.stl"):
        (tmp_path / name).write_bytes((src / name).read_bytes())
    (tmp_path / "atoms.bin").write_bytes(bytes(data))
    rc = main(["run", str(tmp_path / "in.periodic"), "--atoms", str(tmp_path / "atoms.bin"),
               "-o", str(tmp_path / "out.h5"), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and "x = inf is not a finite number" in err and "atoms.bin" in err
    assert not (tmp_path / "out.h5").exists()


@pytest.mark.parametrize("damage", ["cut", "flipped byte", "cut member"])
def test_a_damaged_compressed_dump_reads_like_a_cut_file(tmp_path, capsys, damage):
    """What a killed simulation leaves in a .gz dump: exit 2 naming the file and the frame where it stops,
    and with --on-bad-frame skip the frames before it are analysed."""
    import gzip

    src = SAMPLES / "liggghts" / "packing"
    for name in ("in.packing", "atoms_full.txt.gz", "wall_full.txt.gz", "floor.stl"):
        (tmp_path / name).write_bytes((src / name).read_bytes())
    data = (src / "pairs_full.txt.gz").read_bytes()
    if damage == "cut":
        data = data[: int(len(data) * 0.8)]
    elif damage == "flipped byte":
        k = int(len(data) * 0.8)
        data = data[:k] + bytes([data[k] ^ 0xFF]) + data[k + 1:]
    else:  # a second gzip member cut short: the first member is whole
        data = data + gzip.compress(b"ITEM: TIMESTEP\n206000\nITEM: NUMBER OF ENTRIES\n")[:20]
    (tmp_path / "pairs_full.txt.gz").write_bytes(data)
    out = tmp_path / "out.h5"
    rc = main(["run", str(tmp_path / "in.packing"), "-o", str(out), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and "pairs_full.txt.gz" in err and "timestep" in err and "internal error" not in err, err
    skipped = tmp_path / "skipped.h5"  # (out's committed frames wait for --resume)
    rc = main(["run", str(tmp_path / "in.packing"), "-o", str(skipped), "-q", "--on-bad-frame", "skip"])
    assert rc == 0
    from demsplit.results import load_results

    assert load_results(skipped).steps.tolist()[:2] == [200000, 202000]  # the frames before the damage


@pytest.mark.parametrize("length", [b"-000000000000100", b"9999999999999999", b"abcdefghijklmnop"])
def test_a_record_length_beyond_the_file_is_damage_not_a_hang(tmp_path, length):
    """A .npys record whose declared length is negative, larger than the file or not a number: the records
    before it are read, the damaged one is named (it looped forever on a negative length)."""
    from demsplit.yade import NPY_STREAM_MAGIC, npy_records

    data = bytearray(SNAPSHOT.read_bytes())
    records, problem = npy_records(SNAPSHOT)
    assert problem is None and len(records) == 3
    head = records[1][0] - 23  # the second record's header: 'DSREC ' + 16 digits + newline
    assert data[head:head + 6] == b"DSREC " and len(NPY_STREAM_MAGIC) < head
    data[head + 6:head + 22] = length
    bad = tmp_path / "bad.npys"
    bad.write_bytes(bytes(data))
    records, problem = npy_records(bad)
    assert len(records) == 1 and "snapshot 1" in problem and "cut short or damaged" in problem


def test_memory_follows_the_bodies_not_the_largest_id(tmp_path, capsys):
    """A YADE body id of 1e12 (the dense id table needed 8 TB, MemoryError) is read like any other."""
    meta, tables = _open_store(SNAPSHOT).snapshot(2)
    ids, inter = tables["bodies"]["id"], tables["interactions"]
    big = 10**12
    old = int(ids[5])
    ids[5] = big
    for c in ("id1", "id2"):
        inter[c][inter[c] == old] = big
    path = tmp_path / "big.npys"
    write_snapshot(path, meta, tables, format="npy")
    assert main(["run", str(path), "-o", str(tmp_path / "out.h5"), "-q"]) == 0, capsys.readouterr().err
    from demsplit.results import load_results

    assert big in set(load_results(tmp_path / "out.h5").particles["id"].tolist())


@pytest.mark.parametrize("kind", ["external storage", "external link", "virtual dataset"])
def test_hdf5_inputs_never_read_data_from_elsewhere(tmp_path, capsys, kind):
    """A snapshot whose dataset points at /etc/passwd (or links to another file) is refused."""
    import shutil

    h5py = pytest.importorskip("h5py")
    snap = tmp_path / "snap.h5"
    shutil.copy(SAMPLES / "yade" / "mindlin_box.h5", snap)
    secret = tmp_path / "secret.bin"
    secret.write_bytes(b"root:x:0:0:root:/root:/bin/bash\n" * 64)
    with h5py.File(snap, "a") as f:
        group = f["snapshots"][sorted(f["snapshots"])[0]]
        if kind == "external storage":
            group.create_dataset("stolen", shape=(256,), dtype="f8", external=[(str(secret), 0, 2048)])
        elif kind == "external link":
            group["stolen"] = h5py.ExternalLink(str(secret), "/x")
        else:
            layout = h5py.VirtualLayout(shape=(4,), dtype="f8")
            layout[:] = h5py.VirtualSource(str(secret), "x", shape=(4,))
            group.create_virtual_dataset("stolen", layout)
    rc = main(["run", str(snap), "-o", str(tmp_path / "out.h5"), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and "outside" in err and "root:x" not in err
