"""One validation for every reader's frames (plugin/validate.py), by class of bad input: a non-finite
number, a value out of range, a narrow or foreign dtype, an implausible overlap, an energy that overflows.
Each is one message (exit 2) that names the file, the timestep, the column and the row; nothing is stored."""

from __future__ import annotations

import json
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


@pytest.mark.parametrize(
    "table, column, value",
    [
        ("interactions", "depth", np.nan),
        ("interactions", "fsex", np.inf),
        ("interactions", "nx", np.nan),
        ("interactions", "kno", -np.inf),
        ("bodies", "radius", np.nan),
        ("bodies", "x", np.inf),
    ],
)
def test_a_non_finite_number_is_refused_with_its_place(tmp_path, capsys, table, column, value):
    rc, err = run(damaged_snapshot(tmp_path, table, column, value), tmp_path, capsys)
    assert rc == 2 and "timestep 24000" in err and "row" in err
    assert "not a finite number" in err or "unit normal" in err  # a NaN component makes |n| NaN too
    assert not (tmp_path / "out.h5").exists()


@pytest.mark.parametrize(
    "table, column, value, what",
    [
        ("bodies", "radius", -1e-3, "must be > 0"),
        ("interactions", "kno", -5.0, "must be >= 0"),
        ("interactions", "nx", 0.9, "unit normal"),
        ("interactions", "depth", 1.0, "larger than its smaller radius"),
    ],
)
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
    rc, err = run(damaged_snapshot(tmp_path, "interactions", "fsex", 1e200), tmp_path, capsys)
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
    rc = main(
        [
            "run",
            str(tmp_path / "in.periodic"),
            "--atoms",
            str(tmp_path / "atoms.bin"),
            "-o",
            str(tmp_path / "out.h5"),
            "-q",
        ]
    )
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
        data = data[:k] + bytes([data[k] ^ 0xFF]) + data[k + 1 :]
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
    assert data[head : head + 6] == b"DSREC " and len(NPY_STREAM_MAGIC) < head
    data[head + 6 : head + 22] = length
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


# --- a YADE snapshot record of another layout: one message, never another exception ----------------------------


def rewritten(tmp_path: Path, fmt: str, change) -> Path:
    """The Mindlin sample's snapshots with ``change(snapshots)`` applied, rewritten valid (framing, checksums)."""
    store = _open_store(SNAPSHOT)
    snapshots = [store.snapshot(k) for k in range(len(store))]
    change(snapshots)
    out = tmp_path / f"changed.{'npys' if fmt == 'npy' else 'h5'}"
    for meta, tables in snapshots:
        write_snapshot(out, meta, tables, format=fmt)
    return out


def _set(table: str, column: str, value):
    def change(snapshots):
        snapshots[1][1][table][column] = value(snapshots[1][1][table][column])

    return change


def _meta(key, value):
    def change(snapshots):
        snapshots[1][0][key] = value

    return change


RECORD_DAMAGE = {
    "missing column": (lambda s: s[1][1]["interactions"].pop("ny"), "column interactions.ny is missing"),
    "one component of a force missing": (
        lambda s: s[1][1]["interactions"].pop("fsey"),
        "column interactions.fsey is missing",
    ),
    "text in a number column": (_set("bodies", "vy", lambda c: c.astype("S8")), "bodies.vy holds |S8 values"),
    "2-D column": (_set("bodies", "radius", lambda c: c.reshape(-1, 1)), "bodies.radius has shape"),
    "short column": (_set("interactions", "depth", lambda c: c[:-1]), "interactions.depth has"),
    "fractional ids": (_set("interactions", "id2", lambda c: c + 0.5), "interactions.id2 must hold integers"),
    "no law": (_meta("functors", {"law": 3}), "'functors.law' is not a list"),
    "iteration as text": (_meta("iter", "24000"), "'iter' is not an iteration number"),
    "time as text": (_meta("time", "later"), "'time' is not a finite time"),
    "time beyond the doubles": (_meta("time", 2**1100), "'time' is not a finite time"),
    "a kind that is not ASCII": (
        _set("bodies", "kind", lambda c: np.where(np.arange(len(c)) == 3, b"\x8e\xff", c)),
        "bodies.kind holds text that is not ASCII",
    ),
    "material not a number": (lambda s: s[0][0]["materials"][0].update(young="soft"), "are not both finite numbers"),
    "cell of 2 numbers": (lambda s: s[1][0].update(periodic=True, hSize=[1.0, 2.0]), "'hSize' is not a 3x3"),
    "an iteration twice": (lambda s: s.insert(2, s[1]), "iteration 16000 is in the file twice"),
}


HDF5_CANNOT_HOLD = {"time beyond the doubles"}
"""Damage the HDF5 snapshot writer cannot write (2**1100 is no attribute value): npy only."""


@pytest.mark.parametrize(
    "fmt, damage",
    [
        (fmt, damage)
        for fmt in ("npy", "hdf5")
        for damage in RECORD_DAMAGE
        if not (fmt == "hdf5" and damage in HDF5_CANNOT_HOLD)
    ],
)
def test_a_snapshot_record_of_another_layout_is_one_message(tmp_path, capsys, fmt, damage):
    """A column missing, of another dtype, shape or length, metadata of the wrong type: exit 2 naming the
    snapshot and what is wrong (they were KeyError, TypeError, IndexError, ValueError: internal errors)."""
    change, words = RECORD_DAMAGE[damage]
    rc, err = run(rewritten(tmp_path, fmt, change), tmp_path, capsys)
    assert rc == 2 and words in err and err.count("\n") == 1 and "internal error" not in err, err
    assert not (tmp_path / "out.h5").exists()


def test_a_pickled_object_column_is_refused_not_unpickled(tmp_path, capsys):
    """np.save of an object array pickles it; the reader never unpickles (exit 2, it was a ValueError)."""
    import io
    import zlib

    from demsplit.yade import NPY_STREAM_MAGIC

    meta, tables = _open_store(SNAPSHOT).snapshot(0)
    tables["bodies"]["radius"] = np.array(list(tables["bodies"]["radius"]), dtype=object)
    columns = [[t, c] for t, table in tables.items() for c in table]
    buf = io.BytesIO()
    np.save(buf, np.frombuffer(json.dumps({**meta, "columns": columns}).encode(), np.uint8))
    for t, c in columns:
        np.save(buf, tables[t][c], allow_pickle=True)
    payload = buf.getvalue()
    path = tmp_path / "pickled.npys"
    path.write_bytes(
        NPY_STREAM_MAGIC
        + b"DSREC %016d\n" % len(payload)
        + payload
        + b"DSEND %08x\n" % (zlib.crc32(payload) & 0xFFFFFFFF)
    )
    rc, err = run(path, tmp_path, capsys)
    assert rc == 2 and "snapshot 0 cannot be read" in err and "allow_pickle" in err, err


@pytest.mark.parametrize("kind", ["group for a column", "meta_json not text", "damaged metadata"])
def test_a_damaged_hdf5_snapshot_is_one_message(tmp_path, capsys, kind):
    import shutil

    h5py = pytest.importorskip("h5py")
    snap = tmp_path / "snap.h5"
    shutil.copy(SAMPLES / "yade" / "mindlin_box.h5", snap)
    if kind == "damaged metadata":  # bytes of the file's object headers flipped: h5py raises KeyError
        data = bytearray(snap.read_bytes())
        for k in range(2000, 2400):
            data[k] ^= 0x5A
        snap.write_bytes(bytes(data))
    else:
        with h5py.File(snap, "a") as f:
            g = f["snapshots"][sorted(f["snapshots"])[1]]
            if kind == "group for a column":
                del g["interactions"]["kn"]
                g["interactions"].create_group("kn")
            else:
                g.attrs["meta_json"] = np.arange(3)
    rc, err = run(snap, tmp_path, capsys)
    assert rc == 2 and err.count("\n") == 1 and "internal error" not in err, err


def test_a_narrow_integer_force_is_computed_in_float64(tmp_path, capsys):
    """Forces stored as int8 (the stored-force law squares them) give the energies of the same values as
    float64: the reader's sums of squares wrapped in the narrow dtype."""
    from demsplit.results import load_results

    meta, tables = _open_store(SAMPLES / "yade" / "cundall_periodic.npys").snapshot(2)
    forces = {c: np.clip(np.round(tables["interactions"][c]) * 50, -100, 100) for c in ("fnx", "fny", "fnz")}
    assert np.any(np.abs(forces["fnx"]) >= 16)  # whose square is beyond int8
    energies = []
    for dtype in ("float64", "int8"):
        tables["interactions"].update({c: f.astype(dtype) for c, f in forces.items()})
        path = tmp_path / f"{dtype}.npys"
        write_snapshot(path, meta, tables, format="npy")
        assert main(["run", str(path), "-o", str(tmp_path / f"{dtype}.h5"), "-q"]) == 0, capsys.readouterr().err
        energies.append(load_results(tmp_path / f"{dtype}.h5").contacts["u_n"].to_numpy())
    np.testing.assert_array_equal(energies[0], energies[1])


@pytest.mark.parametrize("compression", ["gz", "bz2", "xz"])
def test_a_compressed_dump_damaged_at_its_start_is_one_message(tmp_path, capsys, compression):
    """A stream cut (or damaged) in its first block: xz and bzip2 raised EOFError from the first read,
    an internal error."""
    import bz2
    import gzip
    import lzma

    src = SAMPLES / "liggghts" / "packing"
    for name in ("in.packing", "atoms_full.txt.gz", "pairs_full.txt.gz", "floor.stl"):
        (tmp_path / name).write_bytes((src / name).read_bytes())
    text = gzip.decompress((src / "wall_full.txt.gz").read_bytes())
    data = {"gz": gzip.compress, "bz2": bz2.compress, "xz": lzma.compress}[compression](text)
    walls = tmp_path / f"wall_full.txt.{compression}"
    walls.write_bytes(data[:101])
    rc = main(["run", str(tmp_path / "in.packing"), "--walls", str(walls), "-o", str(tmp_path / "out.h5"), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and walls.name in err and err.count("\n") == 1 and "internal error" not in err, err


def test_a_frame_time_that_is_not_finite_is_refused(tmp_path, capsys):
    """time = step x timestep beyond the doubles (timestep 1e304 at step 200000): stored as inf before."""
    src = SAMPLES / "liggghts" / "packing"
    for name in ("atoms_full.txt.gz", "pairs_full.txt.gz", "wall_full.txt.gz", "floor.stl"):
        (tmp_path / name).write_bytes((src / name).read_bytes())
    script = (src / "in.packing").read_text()
    assert "timestep        2.0e-6" in script
    (tmp_path / "in.packing").write_text(script.replace("timestep        2.0e-6", "timestep        1e304"))
    rc, err = run(tmp_path / "in.packing", tmp_path, capsys)
    assert rc == 2 and "the frame's time inf s is not a finite time" in err and "timestep 200000" in err, err


def test_a_value_in_a_message_is_printed_plain(tmp_path, capsys):
    """An HDF5 format attribute that is a number: "found '7'", not 'found np.int64(7)' (found by the fuzzer)."""
    import shutil

    h5py = pytest.importorskip("h5py")
    snap = tmp_path / "snap.h5"
    shutil.copy(SAMPLES / "yade" / "mindlin_box.h5", snap)
    with h5py.File(snap, "a") as f:
        f.attrs["format"] = 7
    rc, err = run(snap, tmp_path, capsys)
    assert rc == 2 and "(found '7')" in err and "np." not in err, err


@pytest.mark.parametrize("kind", ["a group linked into itself", "a named datatype"])
def test_the_walk_of_an_hdf5_input_ends_and_passes_objects_without_data(tmp_path, capsys, kind):
    """The walk that refuses data from elsewhere recursed without end into a group hard-linked into itself
    (RecursionError) and took a named datatype (what a damaged object header can read as) for a dataset
    (AttributeError): internal errors (found by the fuzzer)."""
    import shutil

    h5py = pytest.importorskip("h5py")
    snap = tmp_path / "snap.h5"
    shutil.copy(SAMPLES / "yade" / "mindlin_box.h5", snap)
    with h5py.File(snap, "a") as f:
        group = f["snapshots"][sorted(f["snapshots"])[0]]
        if kind == "a group linked into itself":
            group["loop"] = f["/"]
        else:
            group["extra"] = np.dtype("f8")
    rc, err = run(snap, tmp_path, capsys)
    assert rc == 0, err


@pytest.mark.parametrize("pieces", [1, 3])
def test_a_dumped_overlap_that_the_positions_do_not_give_is_refused(run_dir, tmp_path, capsys, pieces, monkeypatch):
    """Half a contact's dumped delta passes the radius check and halved its energy with exit 0. The dumped
    overlap must be r1 + r2 - |x2 - x1| within the printing (the samples agree to 4e-18 m); checked in
    one piece or in pieces on the pool's threads."""
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "MIN_RANGE", 1 if pieces > 1 else 1 << 16)
    monkeypatch.setattr(threads, "THREADS", pieces)
    monkeypatch.setattr(threads, "_pool", None)
    pairs = run_dir / "pairs.txt"
    lines = pairs.read_bytes().split(b"\n")
    tokens = lines[15 - 1].split(b" ")
    tokens[37] = b"%g" % (float(tokens[37]) * 0.5)  # c_cpgl[38]: delta, printed as %g like the rest
    lines[15 - 1] = b" ".join(tokens)
    pairs.write_bytes(b"\n".join(lines))
    rc, err = run(run_dir / "in.packing", tmp_path, capsys)
    assert rc == 2 and "pairs.txt:15, timestep 200000" in err and "its particles' positions give" in err, err


@pytest.mark.parametrize("sample", ["laws_box_cohfrict", "laws_box_adhesion"])
def test_a_first_snapshot_without_interactions_gives_the_tables_of_the_others(tmp_path, capsys, sample):
    """Moment springs and the adhesion force were read only from snapshots where some interaction had them,
    so a first snapshot without interactions had fewer energy modes than the next ones: the store refused
    the run (its tables changed columns). Found by the fuzzer."""
    store = _open_store(SAMPLES / "yade" / f"{sample}.h5")
    snapshots = [store.snapshot(k) for k in range(len(store))]
    inter = snapshots[0][1]["interactions"]
    snapshots[0][1]["interactions"] = {c: v[:0] for c, v in inter.items()}
    snapshots[0][0]["n_interactions_potential"] = snapshots[0][0]["n_interactions_real"] = 0
    path = tmp_path / "first_empty.npys"
    for meta, tables in snapshots:
        write_snapshot(path, meta, tables, format="npy")
    rc, err = run(path, tmp_path, capsys)
    assert rc == 0, err
