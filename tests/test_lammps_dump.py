"""Tests of the LAMMPS/LIGGGHTS dump readers (demsplit.readers.lammps_dump)."""

from __future__ import annotations

import bz2
import gzip
import lzma
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest
from demsplit.errors import InputFormatError, PrecisionError, TruncatedFileError
from demsplit.readers.lammps_dump import open_dump

ATOM_NAMES = ["id", "type", "x", "y", "z", "radius"]


def atom_frame(
    step: int,
    rows: list[str],
    bounds: str = "pp pp ff",
    box: str = "0 1\n0 1\n0 2\n",
    count: int | None = None,
    names: list[str] = ATOM_NAMES,
) -> str:
    n = len(rows) if count is None else count
    return (
        f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{n}\nITEM: BOX BOUNDS {bounds}\n{box}"
        f"ITEM: ATOMS {' '.join(names)} \n" + "".join(r + " \n" for r in rows)
    )


def local_frame(step: int, rows: list[str], ncols: int, label: str = "ENTRIES") -> str:
    names = " ".join(f"c_cpgl[{k}]" for k in range(1, ncols + 1))
    return (
        f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF {label}\n{len(rows)}\nITEM: BOX BOUNDS ff ff ff\n"
        f"0 1\n0 1\n0 1\nITEM: {label} {names} \n" + "".join(r + " \n" for r in rows)
    )


FRAME_A = ["3 1 0.5 0.25 0.125 0.001", "1 2 0.1 0.2 0.3 0.0015", "2 1 0.7 0.8 0.9 0.001"]
FRAME_B = ["1 2 0.11 0.21 0.31 0.0015", "4 1 0.4 0.5 0.6 0.001"]  # count changes, ids unsorted
TEXT = atom_frame(100, FRAME_A) + atom_frame(200, FRAME_B) + atom_frame(300, []) + atom_frame(400, FRAME_A)


def write(tmp_path: Path, text: str | bytes, name: str = "dump.atoms") -> Path:
    p = tmp_path / name
    p.write_bytes(text.encode() if isinstance(text, str) else text)
    return p


def line_no(text: str, needle: str, occurrence: int = 1) -> int:
    """1-based line number of the `occurrence`-th line starting with `needle`."""
    hits = [i + 1 for i, ln in enumerate(text.split("\n")) if ln.startswith(needle)]
    return hits[occurrence - 1]


# --------------------------------------------------------------------------- text basics


def test_index_and_frames(tmp_path):
    d = open_dump(write(tmp_path, TEXT))
    assert (d.kind, d.label, d.columns) == ("atoms", "ATOMS", ATOM_NAMES)
    assert d.n_frames == 4
    assert d.steps.tolist() == [100, 200, 300, 400]
    f = d.frame(0)
    assert f.n_rows == 3 and f.step == 100
    np.testing.assert_array_equal(f.columns["id"], [3, 1, 2])
    np.testing.assert_array_equal(f.columns["x"], [0.5, 0.1, 0.7])
    assert f.columns["id"].dtype == np.int64 and f.columns["x"].dtype == np.float64
    assert f.first_line == line_no(TEXT, "3 1 0.5")
    assert d.frame(1).first_line == line_no(TEXT, "1 2 0.11")
    assert d.frame(1).n_rows == 2
    np.testing.assert_array_equal(d.frame(1).columns["id"], [1, 4])
    empty = d.frame_at_step(300)
    assert empty.n_rows == 0 and all(len(c) == 0 for c in empty.columns.values())


def test_box_flags_and_triclinic(tmp_path):
    text = (
        atom_frame(1, FRAME_A, bounds="ff ff ff")
        + atom_frame(2, FRAME_A, bounds="pp pp ff")
        + atom_frame(3, FRAME_A, bounds="xy xz yz pp pp pp", box="0 0.013 0.002\n0 0.0105 0.0005\n0 0.01 0.001\n")
    )
    d = open_dump(write(tmp_path, text))
    assert d.frame(0).box.periodic == (False, False, False)
    b = d.frame(1).box
    assert b.periodic == (True, True, False)
    np.testing.assert_array_equal(b.hi, [1, 1, 2])
    t = d.frame(2).box
    # bounding box -> box: xhi = xhi_bound - max(0, xy, xz, xy+xz), yhi = yhi_bound - max(0, yz)
    np.testing.assert_allclose(t.lo, [0, 0, 0])
    np.testing.assert_allclose(t.hi, [0.013 - 0.0025, 0.0105 - 0.001, 0.01])
    np.testing.assert_allclose(t.tilt, [0.002, 0.0005, 0.001])
    assert t.periodic == (True, True, True)


def test_negative_tilt_bounds(tmp_path):
    text = atom_frame(1, FRAME_A, bounds="xy xz yz pp pp pp", box="-0.003 0.01 -0.003\n-0.001 0.01 0\n0 1 -0.001\n")
    b = open_dump(write(tmp_path, text)).frame(0).box
    np.testing.assert_allclose(b.lo, [0.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(b.hi, [0.01, 0.01, 1.0])


def test_columns_subset(tmp_path):
    d = open_dump(write(tmp_path, TEXT))
    f = d.frame(3, columns=["z", "id"])
    assert list(f.columns) == ["z", "id"]
    np.testing.assert_array_equal(f.columns["z"], [0.125, 0.3, 0.9])
    with pytest.raises(InputFormatError, match="no column"):
        d.frame(0, columns=["nope"])


def test_random_access_equals_streaming(tmp_path):
    d = open_dump(write(tmp_path, TEXT))
    streamed = list(d)
    assert len(streamed) == d.n_frames
    for k in [3, 0, 2, 1]:
        f = d.frame(k)
        assert f.step == streamed[k].step and f.first_line == streamed[k].first_line
        for name in ATOM_NAMES:
            np.testing.assert_array_equal(f.columns[name], streamed[k].columns[name])


@pytest.mark.parametrize("compress", [gzip.compress, bz2.compress, lzma.compress])
def test_compressed_copies_read_the_same(tmp_path, compress):
    plain = open_dump(write(tmp_path, TEXT))
    comp = open_dump(write(tmp_path, compress(TEXT.encode()), "dump.atoms.data"))  # suffix says nothing
    assert comp.steps.tolist() == plain.steps.tolist()
    for a, b in zip(plain, comp):
        assert a.first_line == b.first_line and a.n_rows == b.n_rows
        for name in ATOM_NAMES:
            np.testing.assert_array_equal(a.columns[name], b.columns[name])
    np.testing.assert_array_equal(comp.frame(1).columns["x"], plain.frame(1).columns["x"])


def test_local_dump_with_custom_label(tmp_path):
    rows = ["0.1 0.2 1 2 6.27517e-06", "0.3 0.4 2 3 1e-07"]
    d = open_dump(write(tmp_path, local_frame(5, rows, 5, label="CONTACTS")))
    assert (d.kind, d.label) == ("local", "CONTACTS")
    assert d.columns == [f"c_cpgl[{k}]" for k in range(1, 6)]
    np.testing.assert_array_equal(d.frame(0).columns["c_cpgl[5]"], [6.27517e-06, 1e-07])


def test_rows_without_trailing_space(tmp_path):
    text = TEXT.replace(" \n", "\n")
    d = open_dump(write(tmp_path, text))
    np.testing.assert_array_equal(d.frame(0).columns["radius"], [0.001, 0.0015, 0.001])


# --------------------------------------------------------------------------- precision


def test_digits_g_and_17g(tmp_path):
    g = ["1 1 0.00198546 0.00397918 0.0059708 0.001", "2 1 0.0123457 0.1 0.2 0.001"]
    full = ["1 1 0.001985459339780061 0.5 0.25 0.001", "2 1 0.0039791841667424433 0.1 0.2 0.001"]
    d = open_dump(write(tmp_path, atom_frame(1, g) + atom_frame(2, full)))
    f = d.frame(0)
    assert f.digits["x"] == 6
    assert f.digits["radius"] == 6  # round value: gets the frame's precision
    assert f.digits["id"] is None  # integer text is exact
    assert d.frame(1).digits["x"] == 17 and d.frame(1).digits["radius"] == 17


def test_int_column_detects_destroyed_ids(tmp_path):
    rows = ["0.1 999999 1", "0.2 1.23457e+06 1"]
    text = local_frame(7, rows, 3)
    d = open_dump(write(tmp_path, text))
    f = d.frame(0)
    with pytest.raises(PrecisionError) as err:
        f.int_column("c_cpgl[2]")
    e = err.value
    assert e.step == 7 and e.line == line_no(text, "0.2 1.23457e+06")
    assert "%g" in str(e) and "%d" in e.fix
    np.testing.assert_array_equal(f.int_column("c_cpgl[3]"), [1, 1])


def test_int_column_accepts_full_precision_ids(tmp_path):
    rows = ["0.12345678901234 1234567", "0.2 2"]
    f = open_dump(write(tmp_path, local_frame(7, rows, 2))).frame(0)
    np.testing.assert_array_equal(f.int_column("c_cpgl[2]"), [1234567, 2])


def test_int_column_rejects_fractions(tmp_path):
    text = local_frame(3, ["0.5 1", "1.5 2"], 2)
    with pytest.raises(PrecisionError, match="not an exact integer") as err:
        open_dump(write(tmp_path, text)).frame(0).int_column("c_cpgl[1]")
    assert err.value.line == line_no(text, "0.5 1")


def test_integer_column_turning_real_after_sample(tmp_path, monkeypatch):
    import demsplit.readers.lammps_dump as ld

    monkeypatch.setattr(ld, "DIGITS_SAMPLE", 64)  # sample sees only integer ids
    rows = [f"0.{k + 1} {k + 1}" for k in range(20)] + ["0.5 1.23457e+06"]
    f = open_dump(write(tmp_path, local_frame(1, rows, 2))).frame(0)
    assert f.columns["c_cpgl[2]"].dtype == np.float64
    assert f.columns["c_cpgl[2]"][-1] == 1.23457e06
    with pytest.raises(PrecisionError):
        f.int_column("c_cpgl[2]")


# --------------------------------------------------------------------------- errors


def test_empty_file(tmp_path):
    with pytest.raises(InputFormatError, match="empty") as err:
        open_dump(write(tmp_path, ""))
    assert err.value.line == 1 and err.value.fix


def test_not_a_dump(tmp_path):
    with pytest.raises(InputFormatError, match="ITEM: TIMESTEP"):
        open_dump(write(tmp_path, "LAMMPS data file\n\n3 atoms\n"))


def test_truncated_mid_row(tmp_path):
    text = TEXT[: TEXT.rindex("0.7 0.8")] + "0.7 0."  # last frame, third row cut
    d = open_dump(write(tmp_path, text))
    frames = []
    with pytest.raises(TruncatedFileError, match="middle of a row") as err:
        for f in d:
            frames.append(f.step)
    assert frames == [100, 200, 300]  # the good frames first
    assert err.value.step == 400 and err.value.line == len(text.split("\n"))


def test_truncated_between_header_and_rows(tmp_path):
    text = TEXT[: TEXT.rindex("3 1 0.5")]
    d = open_dump(write(tmp_path, text))
    with pytest.raises(TruncatedFileError, match="0 of the 3 rows") as err:
        d.frame(3)
    assert err.value.step == 400 and err.value.line == len(text.split("\n"))


def test_truncated_inside_header(tmp_path):
    text = TEXT + "ITEM: TIMESTEP\n500\nITEM: NUMBER OF ATOMS\n"
    d = open_dump(write(tmp_path, text))
    assert d.n_frames == 4
    with pytest.raises(TruncatedFileError, match="header") as err:
        list(d)
    assert err.value.line == line_no(text, "ITEM: NUMBER OF ATOMS", 5) + 1


def test_count_disagrees_too_few_rows(tmp_path):
    text = atom_frame(1, FRAME_A, count=4) + atom_frame(2, FRAME_B)
    d = open_dump(write(tmp_path, text))
    with pytest.raises(InputFormatError, match="says 4 rows but only 3") as err:
        d.frame(0)
    assert not isinstance(err.value, TruncatedFileError)
    assert err.value.step == 1 and err.value.line == line_no(text, "ITEM: TIMESTEP", 2)
    assert d.frame(1).n_rows == 2  # the next frame is still readable


def test_count_disagrees_too_many_rows(tmp_path):
    text = atom_frame(1, FRAME_A, count=2) + atom_frame(2, FRAME_B)
    with pytest.raises(InputFormatError, match="says 2 rows but 3") as err:
        open_dump(write(tmp_path, text)).frame(0)
    assert err.value.line == line_no(text, "2 1 0.7")


@pytest.mark.parametrize(
    "bad_row, expect",
    [("2 1 0.7 0.8 0.001", "has 5 values, expected 6"), ("2 1 0.7 0.8 0.9 0.001 7", "has 7 values, expected 6")],
)
def test_row_with_wrong_number_of_values(tmp_path, bad_row, expect):
    text = atom_frame(9, FRAME_A[:2] + [bad_row]) + atom_frame(10, FRAME_B)
    with pytest.raises(InputFormatError, match=expect) as err:
        open_dump(write(tmp_path, text)).frame(0, columns=["x"])
    assert err.value.step == 9 and err.value.line == line_no(text, bad_row)


def test_non_numeric_token(tmp_path):
    text = atom_frame(9, [FRAME_A[0], "1 2 0.1 abc 0.3 0.0015", FRAME_A[2]])
    with pytest.raises(InputFormatError) as err:
        open_dump(write(tmp_path, text)).frame(0)
    msg = str(err.value)
    assert "column 4 ('y')" in msg and "'abc'" in msg and "expected a number" in msg
    assert err.value.line == line_no(text, "1 2 0.1 abc")


@pytest.mark.parametrize("token", ["nan", "inf", "-inf"])
def test_non_finite_values(tmp_path, token):
    text = atom_frame(9, [FRAME_A[0], f"1 2 0.1 0.2 {token} 0.0015", FRAME_A[2]])
    with pytest.raises(InputFormatError, match="expected a finite number") as err:
        open_dump(write(tmp_path, text)).frame(0)
    assert "('z')" in str(err.value) and err.value.line == line_no(text, "1 2 0.1 0.2")


def test_damaged_header(tmp_path):
    text = TEXT.replace("ITEM: BOX BOUNDS pp pp ff\n0 1\n", "ITEM: BOX BOUNDS pp pp ff\n0 one\n", 1)
    with pytest.raises(InputFormatError, match="box numbers") as err:
        open_dump(write(tmp_path, text))
    assert err.value.line == 6


# --------------------------------------------------------------------------- binary


def binary_frame(step: int, rows: np.ndarray, tri: int = 0, bounds=(0, 1, 0, 1, 0, 2), chunks: int = 1) -> bytes:
    out = struct.pack("=qqi6i", step, rows.shape[0], tri, 0, 0, 0, 0, 1, 1)
    out += np.asarray(bounds, dtype="=f8").tobytes() + struct.pack("=ii", rows.shape[1], chunks)
    for part in np.array_split(rows, chunks):
        out += struct.pack("=i", part.size) + np.ascontiguousarray(part, dtype="=f8").tobytes()
    return out


def test_binary_frames(tmp_path):
    a = np.array([[3, 1, 0.5, 0.25, 0.125, 0.001], [1, 2, 0.1, 0.2, 0.3, 0.0015]])
    b = np.array([[1, 2, 0.11, 0.21, 0.31, 0.0015]])
    data = binary_frame(10, a, chunks=2) + binary_frame(20, b, tri=1, bounds=(0, 1.5, 0, 1, 0, 2, 0.5, 0, 0))
    p = write(tmp_path, data, "d.bin")
    d = open_dump(p)
    assert d.columns == [f"col{k}" for k in range(1, 7)]
    d = open_dump(p, columns=ATOM_NAMES)
    assert d.steps.tolist() == [10, 20]
    f = d.frame(0)
    np.testing.assert_array_equal(f.columns["x"], a[:, 2])
    assert f.box.periodic == (True, True, False) and f.first_line is None and f.digits["x"] is None
    t = d.frame(1)
    np.testing.assert_allclose(t.box.hi, [1.0, 1.0, 2.0])
    np.testing.assert_array_equal(t.int_column("id"), [1])


def test_binary_wrong_header(tmp_path):
    bad = struct.pack("=qqi6i", 10, 2, 7, 0, 0, 0, 0, 9, 1) + b"\0" * 80
    with pytest.raises(InputFormatError, match="triclinic flag") as err:
        open_dump(write(tmp_path, bad, "d.bin"))
    assert "not a LAMMPS binary dump" in err.value.fix


def test_binary_truncated(tmp_path):
    a = np.arange(12.0).reshape(2, 6)
    data = binary_frame(10, a) + binary_frame(20, a)
    d = open_dump(write(tmp_path, data[:-8], "d.bin"))
    assert d.n_frames == 1
    with pytest.raises(TruncatedFileError, match="ends inside the rows") as err:
        list(d)
    assert err.value.step == 20


def test_binary_wrong_number_of_names(tmp_path):
    with pytest.raises(InputFormatError, match="2 column names given"):
        open_dump(write(tmp_path, binary_frame(1, np.ones((2, 6))), "d.bin"), columns=["a", "b"])


# --------------------------------------------------------------------------- real LIGGGHTS run

LIGGGHTS_SCRIPT = """\
atom_style granular
atom_modify map array
boundary p p f
newton off
communicate single vel yes
units si
region reg block 0 0.01 0 0.01 0 0.02 units box
create_box 1 reg
neighbor 0.0005 bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype 5.e6
fix m2 all property/global poissonsRatio peratomtype 0.45
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.5
fix m4 all property/global coefficientFriction peratomtypepair 1 0.5
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
fix gravi all gravity 9.81 vector 0.0 0.0 -1.0
fix zwall all wall/gran model hertz tangential history primitive type 1 zplane 0.0
region ins block 0.0005 0.0095 0.0005 0.0095 0.0015 0.015 units box
lattice sc 0.00199
create_atoms 1 region ins
set group all density 2500 diameter 0.002
fix integr all nve/sphere
compute cp all pair/gran/local pos id force delta
run 1
dump dg all custom 100 atoms.txt id type x y z vx vy vz radius mass
dump db all custom 100 atoms.bin id type x y z vx vy vz radius mass
dump df all custom 100 atoms17.txt id type x y z vx vy vz radius mass
dump_modify df format "%d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g"
dump dl all local 100 contacts.txt c_cp[1] c_cp[2] c_cp[3] c_cp[4] c_cp[5] c_cp[6] c_cp[7] c_cp[8] c_cp[9] &
    c_cp[10] c_cp[11] c_cp[12] c_cp[13]
dump_modify dl label CONTACTS
run 300
"""
NAMES = ["id", "type", "x", "y", "z", "vx", "vy", "vz", "radius", "mass"]


@pytest.fixture
def liggghts_run(liggghts, tmp_path):
    (tmp_path / "in.test").write_text(LIGGGHTS_SCRIPT)
    p = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", "in.test", "-log", "none"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    return tmp_path


@pytest.mark.simulator
def test_liggghts_binary_equals_full_precision_text(liggghts_run):
    text = open_dump(liggghts_run / "atoms17.txt")
    binary = open_dump(liggghts_run / "atoms.bin", columns=text.columns)
    assert text.columns == NAMES
    assert binary.steps.tolist() == text.steps.tolist() == [100, 200, 300]
    for t, b in zip(text, binary):
        assert t.n_rows == b.n_rows > 0
        assert t.box.periodic == b.box.periodic == (True, True, False)
        np.testing.assert_array_equal(t.box.hi, b.box.hi)
        for name in NAMES:
            np.testing.assert_array_equal(t.columns[name], b.columns[name], err_msg=name)
        assert t.digits["x"] == 17


@pytest.mark.simulator
def test_liggghts_g_text_and_local_dump(liggghts_run):
    g = open_dump(liggghts_run / "atoms.txt")
    full = open_dump(liggghts_run / "atoms17.txt")
    fg, ff = g.frame(-1), full.frame(-1)
    assert fg.digits["x"] == 6
    np.testing.assert_array_equal(fg.columns["id"], ff.columns["id"])
    np.testing.assert_allclose(fg.columns["x"], ff.columns["x"], rtol=5e-6)
    local = open_dump(liggghts_run / "contacts.txt")
    assert (local.kind, local.label) == ("local", "CONTACTS")
    for f in local:
        assert f.n_rows > 0
        ids = f.int_column("c_cp[7]")
        assert set(ids) <= set(ff.columns["id"].tolist())
        assert np.all(f.columns["c_cp[13]"] > 0)  # delta: only touching pairs are listed
    gz = write(liggghts_run, gzip.compress((liggghts_run / "contacts.txt").read_bytes()), "contacts.gz")
    for a, b in zip(local, open_dump(gz)):
        np.testing.assert_array_equal(a.columns["c_cp[13]"], b.columns["c_cp[13]"])
