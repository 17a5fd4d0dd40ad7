"""Bad input through the public entry points: ``demsplit.readers.open_run``,
``demsplit.analyze`` and the ``demsplit`` command.

Every bad input is a copy of ``sample_dumps/liggghts/packing`` (full-precision
atom dump, %g pair and wall dumps, plain text) with one defect. Each test
asserts the exception class and that the message names the file, the timestep
and the line where they apply. Line numbers of the copies: atom frame k
(k = 0, 1, 2; 300 rows) has its header at line 1 + 309 k and its rows at lines
10 + 309 k .. 309 + 309 k; the first pair frame's 555 rows are lines 10..564.
"""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import demsplit
import pytest
from demsplit import (
    ContactError,
    DemsplitError,
    InputFormatError,
    MaterialError,
    PrecisionError,
    ScriptError,
    TruncatedFileError,
    UnsupportedModelError,
)
from demsplit.readers import open_run

PACKING = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts" / "packing"
STEPS = (200000, 202000, 204000)


def atom_row_line(frame: int, row: int) -> int:
    """1-based line of data row ``row`` (0-based) of atom frame ``frame``."""
    return 10 + 309 * frame + row


def edit_lines(path: Path, change) -> None:
    """Rewrite ``path`` with ``change(lines)`` applied to its lines (bytes, without newlines)."""
    lines = path.read_bytes().split(b"\n")
    change(lines)
    path.write_bytes(b"\n".join(lines))


def set_token(path: Path, line: int, column: int, value: bytes) -> None:
    """Replace the 0-based ``column`` token of 1-based ``line``."""

    def change(lines):
        tokens = lines[line - 1].split(b" ")
        tokens[column] = value
        lines[line - 1] = b" ".join(tokens)

    edit_lines(path, change)


def analyze_error(run_dir: Path, **options) -> DemsplitError:
    with pytest.raises(DemsplitError) as info:
        demsplit.analyze(run_dir / "in.packing", **options)
    return info.value


def assert_where(err: DemsplitError, file: str, step: int | None, line: int | None) -> None:
    text = str(err)
    assert Path(err.file).name == file and file in text
    assert err.step == step
    if step is not None:
        assert f"timestep {step}" in text
    assert err.line == line
    if line is not None:
        assert f"{file}:{line}" in text
    assert err.fix and "Fix:" in text


def test_sample_copy_is_good(run_dir):
    """The base of every test analyses without error (so each defect below is what fails)."""
    results = demsplit.analyze(run_dir / "in.packing")
    assert results.frames["step"].tolist() == list(STEPS)


# --- damaged dumps -----------------------------------------------------------------------


def test_truncated_in_the_middle_of_a_row(run_dir):
    atoms = run_dir / "atoms_full.txt"
    data = atoms.read_bytes()
    atoms.write_bytes(data[: len(data) - 40])  # the last row loses its end and its newline
    err = analyze_error(run_dir)
    assert isinstance(err, TruncatedFileError)
    assert_where(err, "atoms_full.txt", STEPS[2], atom_row_line(2, 299))
    assert "middle of a row" in str(err)


def test_truncated_between_frames(run_dir):
    """Cut after frame 1 and two lines of frame 2's header: stop names the header, skip keeps frames 0 and 1."""
    atoms = run_dir / "atoms_full.txt"
    edit_lines(atoms, lambda lines: lines.__delitem__(slice(619 + 2 - 1, None)))
    atoms.write_bytes(atoms.read_bytes() + b"\n")
    err = analyze_error(run_dir)
    assert isinstance(err, TruncatedFileError)
    assert_where(err, "atoms_full.txt", None, 621)
    results = demsplit.analyze(run_dir / "in.packing", on_bad_frame="skip")
    assert results.frames["step"].tolist() == list(STEPS[:2])
    (bad,) = results.provenance["bad_frames"]
    assert bad["step"] is None and "atoms_full.txt:621" in bad["error"]


def test_truncated_exactly_at_a_frame_boundary_is_found_by_check(run_dir):
    """A cut at a frame boundary leaves a valid shorter dump: run computes the
    frames it has, check reports the contact frames that lost their atoms."""
    from demsplit.inspection import check_run

    edit_lines(run_dir / "atoms_full.txt", lambda lines: lines.__delitem__(slice(618, -1)))
    assert demsplit.analyze(run_dir / "in.packing").frames["step"].tolist() == list(STEPS[:2])
    text, ok = check_run(run_dir / "in.packing")
    assert not ok
    assert "pairs.txt, timestep 204000" in text and "no atom frame" in text


def test_empty_file(run_dir):
    (run_dir / "pairs.txt").write_bytes(b"")
    with pytest.raises(InputFormatError) as info:
        open_run(run_dir / "in.packing")
    assert_where(info.value, "pairs.txt", None, 1)
    assert "empty" in str(info.value)


def test_wrong_number_of_atoms(run_dir):
    atoms = run_dir / "atoms_full.txt"
    edit_lines(atoms, lambda lines: lines.__setitem__(310 + 3 - 1, b"301"))
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "atoms_full.txt", STEPS[1], 619)  # the next 'ITEM: TIMESTEP' comes one row early
    assert "NUMBER OF ATOMS" in str(err) and "301" in str(err)


def test_wrong_number_of_entries(run_dir):
    edit_lines(run_dir / "pairs.txt", lambda lines: lines.__setitem__(3, b"554"))
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "pairs.txt", STEPS[0], 10 + 554)  # the first row beyond the count
    assert "NUMBER OF CONTACTS" in str(err)


@pytest.mark.parametrize(
    "change, words",
    [
        (lambda tokens: tokens[:-3] + tokens[-2:], "has 15 values, expected 16"),
        (lambda tokens: tokens[:-1] + [b"7", b""], "has 17 values, expected 16"),
    ],
)
def test_row_with_too_few_or_too_many_values(run_dir, change, words):
    line = atom_row_line(0, 2)
    edit_lines(
        run_dir / "atoms_full.txt",
        lambda lines: lines.__setitem__(line - 1, b" ".join(change(lines[line - 1].split(b" ")))),
    )
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "atoms_full.txt", STEPS[0], line)
    assert words in str(err)


def test_non_numeric_token(run_dir):
    line = atom_row_line(1, 3)
    set_token(run_dir / "atoms_full.txt", line, 2, b"0.01x5")
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "atoms_full.txt", STEPS[1], line)
    assert "'x'" in str(err) and "0.01x5" in str(err) and "expected a number" in str(err)


@pytest.mark.parametrize(
    "file, line, column, token, step",
    [
        ("atoms_full.txt", atom_row_line(0, 4), 3, b"nan", STEPS[0]),
        ("pairs.txt", 10 + 5, 37, b"inf", STEPS[0]),  # c_cpgl[38]: delta
        ("pairs.txt", 10 + 6, 33, b"-inf", STEPS[0]),  # c_cpgl[34]: shearx
    ],
)
def test_nan_and_inf(run_dir, file, line, column, token, step):
    """(NaN/inf in a column the computation does not read, e.g. a force, is not looked at.)"""
    set_token(run_dir / file, line, column, token)
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, file, step, line)
    assert "expected a finite number" in str(err)


def test_duplicate_particle_ids(run_dir):
    atoms = run_dir / "atoms_full.txt"
    line = atom_row_line(2, 7)
    first_id = atoms.read_bytes().split(b"\n")[atom_row_line(2, 0) - 1].split(b" ")[0]
    set_token(atoms, line, 0, first_id)
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "atoms_full.txt", STEPS[2], line)
    assert "duplicated particle id" in str(err) and first_id.decode() in str(err)


def test_contact_with_unknown_particle(run_dir):
    set_token(run_dir / "pairs.txt", 10 + 8, 13, b"9999")  # c_cpgl[14]: id2
    err = analyze_error(run_dir)
    assert isinstance(err, ContactError)
    assert_where(err, "pairs.txt", STEPS[0], 18)
    assert "9999" in str(err)


def test_contact_listed_twice(run_dir):
    pairs = run_dir / "pairs.txt"
    lines = pairs.read_bytes().split(b"\n")
    a, b = lines[10 - 1].split(b" ")[12:14]
    edit_lines(pairs, lambda lines: lines.__setitem__(30 - 1, lines[10 - 1]))
    err = analyze_error(run_dir)
    assert isinstance(err, ContactError)
    assert_where(err, "pairs.txt", STEPS[0], 30)
    assert "listed twice" in str(err) and f"{a.decode()} and {b.decode()}" in str(err) and "lines 10 and 30" in str(err)


def test_contact_listed_twice_in_reverse_order(run_dir):
    def swap(lines):
        tokens = lines[10 - 1].split(b" ")
        tokens[12], tokens[13] = tokens[13], tokens[12]
        lines[40 - 1] = b" ".join(tokens)

    edit_lines(run_dir / "pairs.txt", swap)
    err = analyze_error(run_dir)
    assert isinstance(err, ContactError)
    assert_where(err, "pairs.txt", STEPS[0], 40)


def test_percent_g_destroyed_ids(run_dir):
    set_token(run_dir / "pairs.txt", 10 + 11, 12, b"1.23457e+06")  # c_cpgl[13]: id1, as %g writes 1234567
    err = analyze_error(run_dir)
    assert isinstance(err, PrecisionError)
    assert_where(err, "pairs.txt", STEPS[0], 21)
    assert "1234570.0" in str(err) and "destroyed" in str(err)


def test_negative_radius(run_dir):
    line = atom_row_line(1, 9)
    set_token(run_dir / "atoms_full.txt", line, 14, b"-0.002")
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "atoms_full.txt", STEPS[1], line)
    assert "radius must be > 0" in str(err) and "-0.002" in str(err)


@pytest.mark.parametrize("step", [b"9223372036854775808", b"-2000"])
def test_a_dump_timestep_beyond_int64_or_negative_is_refused(run_dir, step):
    """A timestep >= 2^63 (LAMMPS' bigint) overflowed the store's int64 steps: OverflowError, exit 3."""
    atoms = run_dir / "atoms_full.txt"
    edit_lines(atoms, lambda lines: lines.__setitem__(atom_row_line(1, 0) - 9, step))  # line 311: the step
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "atoms_full.txt", None, atom_row_line(1, 0) - 8)
    assert "a timestep in [0, 2^63)" in str(err)


def test_binary_dump_with_a_wrong_header(run_dir):
    data = bytearray((PACKING / "atoms.bin").read_bytes())
    struct.pack_into("=i", data, 16, 7)  # the triclinic flag (after step and row count, two int64)
    (run_dir / "atoms.bin").write_bytes(bytes(data))
    with pytest.raises(InputFormatError) as info:
        demsplit.analyze(run_dir / "in.packing", atoms=run_dir / "atoms.bin")
    assert_where(info.value, "atoms.bin", STEPS[0], None)
    assert "triclinic=7" in str(info.value) and "byte 0" in str(info.value)


# --- damaged input scripts ---------------------------------------------------------------


def script_error(run_dir: Path, old: str, new: str) -> tuple[DemsplitError, int]:
    script = run_dir / "in.packing"
    text = script.read_text()
    assert text.count(old) == 1
    line = text[: text.index(old)].count("\n") + 1
    script.write_text(text.replace(old, new))
    with pytest.raises(DemsplitError) as info:
        open_run(script)
    return info.value, line


@pytest.mark.parametrize(
    "old, new, bad",
    [
        ("poissonsRatio peratomtype 0.25", "poissonsRatio peratomtype 0.6", "0.6"),
        ("youngsModulus peratomtype 1.0e8", "youngsModulus peratomtype -1.0e8", "-1"),
        ("youngsModulus peratomtype 1.0e8", "youngsModulus peratomtype 0", "0"),
    ],
)
def test_material_out_of_range_in_the_script(run_dir, old, new, bad):
    err, line = script_error(run_dir, old, new)
    assert isinstance(err, MaterialError)
    assert_where(err, "in.packing", None, line)
    assert bad in str(err)


def test_undefined_variable_in_the_script(run_dir):
    err, line = script_error(run_dir, "particles_in_region ${nparticles}", "particles_in_region ${nparts}")
    assert isinstance(err, ScriptError)
    assert_where(err, "in.packing", None, line - 1)  # the command starts on the line the '&' continues
    assert "nparts" in str(err)


def test_unsupported_model_in_the_script(run_dir):
    err, line = script_error(run_dir, "pair_style      gran model hertz", "pair_style      gran model jkr")
    assert isinstance(err, UnsupportedModelError)
    assert_where(err, "in.packing", None, line)
    assert "jkr" in str(err)


def test_script_that_is_not_text(run_dir):
    """Bytes that are not UTF-8 in a comment (a Latin-1 accent) are read, as LIGGGHTS reads them; a control
    character (a binary file) is refused with its line."""
    script = run_dir / "in.packing"
    text = script.read_bytes()
    script.write_bytes(text[:100] + b"\x89\xff" + text[100:])
    assert open_run(script).scene.walls
    script.write_bytes(text[:100] + b"\x01\x89" + text[100:])
    with pytest.raises(ScriptError) as info:
        open_run(script)
    assert_where(info.value, "in.packing", None, 2)


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("zcylinder 0.004 0.0 0.0", "zcylinder nan 0.0 0.0", "'nan' is not a finite number"),
        ("xplane -0.02", "xplane -1e400", "'-1e400' is not a finite number"),
        ("timestep        2.0e-6", "timestep        inf", "'inf' is not a finite number"),
        ("timestep        2.0e-6", "timestep        -2.0e-6", "the timestep must be > 0"),
    ],
)
def test_a_number_of_the_script_that_is_not_finite_is_refused(run_dir, old, new, words):
    """A wall of radius NaN found no contact (exit 0 with its energy missing); an infinite timestep stored
    infinite times."""
    err, line = script_error(run_dir, old, new)
    assert isinstance(err, ScriptError)
    assert_where(err, "in.packing", None, line)
    assert words in str(err)


# --- the command: one message, no traceback, exit 2 ----------------------------------------


@pytest.mark.slow
def test_cli_prints_one_message_for_bad_input(run_dir, tmp_path):
    set_token(run_dir / "pairs.txt", 10 + 8, 13, b"9999")
    out = tmp_path / "out.h5"
    proc = subprocess.run(
        [sys.executable, "-m", "demsplit.cli", "run", str(run_dir / "in.packing"), "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("demsplit: error: ")
    assert "pairs.txt:18, timestep 200000" in proc.stderr and "9999" in proc.stderr
    assert not out.exists() and not (tmp_path / ".out.h5.partial").exists()  # nothing written, nothing left


def test_a_mesh_wall_contact_listed_twice_is_refused(run_dir):
    """It was counted twice; pairs listed twice were already refused."""
    edit_lines(run_dir / "wall.txt", lambda lines: lines.__setitem__(25 - 1, lines[10 - 1]))
    err = analyze_error(run_dir)
    assert isinstance(err, ContactError)
    assert_where(err, "wall.txt", STEPS[0], 25)
    assert "listed twice" in str(err) and "lines 10 and 25" in str(err)


def test_a_timestep_written_twice_is_refused_not_read_from_its_first_copy(run_dir):
    """What a restart appending to a dump leaves: the same step twice. Refused, naming the dump and the step."""
    atoms = run_dir / "atoms_full.txt"
    text = atoms.read_bytes()
    first = text[: text.index(b"ITEM: TIMESTEP", 1)]
    atoms.write_bytes(text + first)
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError) and err.step == STEPS[0]
    assert Path(err.file).name == "atoms_full.txt" and "more than once" in str(err)


@pytest.mark.parametrize("quiet", [[], ["-q"]])
def test_every_frame_bad_under_skip_is_one_failure_with_or_without_quiet(run_dir, tmp_path, capsys, quiet):
    """One rule: nothing to store is exit 2 and no store, whether or not -q is given."""
    from demsplit.cli import main

    pairs = run_dir / "pairs.txt"
    pairs.write_bytes(pairs.read_bytes().replace(b"ITEM: NUMBER OF CONTACTS\n", b"ITEM: NUMBER OF CONTACTS\n9"))
    out = tmp_path / "out.h5"
    assert main(["run", str(run_dir / "in.packing"), "-o", str(out), "--on-bad-frame", "skip", *quiet]) == 2
    err = capsys.readouterr().err
    assert "every frame of the run is bad (3)" in err and not out.exists()
    assert not list(tmp_path.glob(".out.h5*"))  # nothing left behind


def test_a_damaged_column_name_in_the_wall_dump_header_is_refused(run_dir):
    """The wall dump's header with the history column c_cwgl[34] (shearx) damaged to 'nan': its rows lacked
    a column the pair rows have (KeyError 'shearx', exit 3; found by the fuzzer)."""
    edit_lines(
        run_dir / "wall.txt", lambda lines: lines.__setitem__(9 - 1, lines[9 - 1].replace(b"c_cwgl[34]", b"nan"))
    )
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError)
    assert_where(err, "wall.txt", STEPS[0], 9)
    assert "no column for shearx" in str(err)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda line: line + b"\r", "ends with a carriage return (CR LF"),
        (lambda line: b" " + line, "starts with a space"),
        (lambda line: line.replace(b" ", b"  ", 1), "two spaces in a row before value 2"),
    ],
)
@pytest.mark.slow
def test_row_shape_faults_are_named_as_what_they_are(run_dir, change, message):
    """They were 'row 1 has 17 values, expected 16' (CR LF) and '41 values, expected 41' (a leading space)."""
    edit_lines(run_dir / "pairs.txt", lambda lines: lines.__setitem__(13 - 1, change(lines[13 - 1])))
    err = analyze_error(run_dir)
    assert isinstance(err, InputFormatError) and message in str(err)
    assert_where(err, "pairs.txt", STEPS[0], 13)


def test_a_foreign_file_given_as_a_dump_is_named_and_quoted_bounded_and_printable(run_dir, tmp_path, capsys):
    """A dump path that points at another file (as --atoms /etc/shadow would): the message names the file and
    quotes at most 40 characters of its first line, control characters escaped."""
    from demsplit.cli import main

    secret = tmp_path / "shadow"
    secret.write_bytes(b"root:$6$" + b"x" * 200 + b"\x1b[2J:19000:0:99999:7:::\nuser:$6$second line\n")
    rc = main(["run", str(run_dir / "in.packing"), "--atoms", str(secret), "-o", str(tmp_path / "out.h5"), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and str(secret) in err and err.count("\n") == 1
    assert "x" * 41 not in err and "\x1b" not in err and "second line" not in err and "19000" not in err
