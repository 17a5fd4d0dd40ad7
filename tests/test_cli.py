"""The ``demsplit`` command: one message and exit 2 for bad input (the
traceback only with --debug), ``info`` on every kind of file, ``check`` on
good and bad runs, and ``--on-bad-frame skip``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import demsplit
import pytest
from demsplit.runtime.hashing import file_digest

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"
PACKING = SAMPLES / "liggghts" / "packing"


def demsplit_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "demsplit.cli", *map(str, args)], capture_output=True, text=True, timeout=300
    )


def damage_atom_row(run_dir: Path, frame: int) -> int:
    """Put a non-numeric token in row 5 of atom frame ``frame``; return its line."""
    line = 10 + 309 * frame + 5
    path = run_dir / "atoms_full.txt"
    lines = path.read_bytes().split(b"\n")
    tokens = lines[line - 1].split(b" ")
    tokens[3] = b"oops"
    lines[line - 1] = b" ".join(tokens)
    path.write_bytes(b"\n".join(lines))
    return line


@pytest.mark.slow
def test_bad_input_is_one_message_and_exit_2(run_dir, tmp_path):
    line = damage_atom_row(run_dir, 0)
    proc = demsplit_cli("run", run_dir / "in.packing", "-o", tmp_path / "o.h5")
    assert proc.returncode == 2
    assert proc.stderr.startswith("demsplit: error: ") and proc.stderr.count("\n") == 1
    assert "Traceback" not in proc.stderr
    assert f"atoms_full.txt:{line}, timestep 200000" in proc.stderr and "'oops'" in proc.stderr


@pytest.mark.slow
def test_debug_shows_the_traceback(run_dir, tmp_path):
    damage_atom_row(run_dir, 0)
    proc = demsplit_cli("run", run_dir / "in.packing", "-o", tmp_path / "o.h5", "--debug")
    assert proc.returncode == 2
    assert "Traceback (most recent call last)" in proc.stderr and "InputFormatError" in proc.stderr
    assert proc.stderr.rstrip().splitlines()[-1].startswith("demsplit: error: ")


@pytest.mark.slow
def test_damaged_store_is_one_message(tmp_path):
    """A store file with the format mark but no tables: report and info say so, exit 2."""
    import h5py
    from demsplit.results.store import FORMAT

    bad = tmp_path / "weird.h5"
    with h5py.File(bad, "w") as h5:
        h5.attrs.update(format=FORMAT, format_version=1, provenance="{}", walls_meta="{}")
    for command in ("report", "info"):
        proc = demsplit_cli(command, bad)
        assert proc.returncode == 2, proc.stderr
        assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr and "weird.h5" in proc.stderr


def test_a_bug_is_an_internal_error_exit_3(monkeypatch, capsys):
    from demsplit import cli

    def broken(args):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(cli, "cmd_info", broken)
    assert cli.main(["info", "x"]) == cli.EXIT_BUG
    err = capsys.readouterr().err
    assert "internal error (ZeroDivisionError: a bug)" in err and "--debug" in err and "Traceback" not in err
    assert cli.main(["info", "x", "--debug"]) == cli.EXIT_BUG
    assert "Traceback" in capsys.readouterr().err


@pytest.mark.parametrize(
    "path, words",
    [
        (
            PACKING / "atoms.txt",
            [
                "kind:     atoms (label ATOMS)",
                "frames:   3, steps 200000..204000, every 2000",
                "rows:     300 per frame",
                "x                    6",
                "id               exact",
            ],
        ),
        (
            PACKING / "pairs_full.txt.gz",
            ["gzip-compressed", "kind:     local (label ENTRIES)", "rows:     555 per frame", "c_cpgl[1]           17"],
        ),
        (PACKING / "pairs.txt", ["kind:     local (label CONTACTS)"]),
        (PACKING / "atoms.bin", ["binary", "frames:   3", "col16"]),
        (
            SAMPLES / "yade" / "mindlin_box.h5",
            [
                "snapshot file",
                "snapshots: 3",
                "yade:Law2_ScGeom_MindlinPhys_Mindlin",
                "Law2_ScGeom_MindlinPhys_Mindlin",
                "24000",
            ],
        ),
        (
            SAMPLES / "yade" / "cundall_periodic.npys",
            ["snapshot file", "yade:Law2_ScGeom_FrictPhys_CundallStrack", "periodic True"],
        ),
        (
            PACKING / "in.packing",
            [
                "LIGGGHTS input script",
                "liggghts:hertz (tangential='history')",
                "1: E=1e+08 Pa nu=0.25",
                "wpost (cylinder, type 3)",
                "dpair17",
                "full precision",
            ],
        ),
    ],
)
@pytest.mark.slow
def test_info_on_each_kind_of_file(path, words):
    proc = demsplit_cli("info", path)
    assert proc.returncode == 0, proc.stderr
    for w in words:
        assert w in proc.stdout, w


@pytest.mark.slow
def test_info_on_a_result_store(tmp_path):
    out = tmp_path / "r.h5"
    assert demsplit_cli("run", PACKING / "in.packing", "-o", out, "-q").returncode == 0
    proc = demsplit_cli("info", out)
    assert proc.returncode == 0, proc.stderr
    assert "demsplit result store" in proc.stdout and "frames:   3" in proc.stdout
    assert "particles        900 rows" in proc.stdout and "in.packing" in proc.stdout
    script = (PACKING / "in.packing").resolve()
    assert f"{script}  ({script.stat().st_size} bytes, blake3 {file_digest(script)[:12]}...)" in proc.stdout


@pytest.mark.slow
def test_info_shows_the_sha256_of_a_store_written_before_blake3(tmp_path):
    """Stores written before the provenance moved to BLAKE3 name their inputs' sha256: info shows that."""
    import json

    import h5py

    out = tmp_path / "r.h5"
    assert demsplit_cli("run", PACKING / "in.packing", "-o", out, "-q").returncode == 0
    with h5py.File(out, "r+") as h5:
        prov = json.loads(h5.attrs["provenance"])
        for f in prov["inputs"]:
            f["sha256"] = "ab" * 32
            del f["blake3"]
        h5.attrs["provenance"] = json.dumps(prov)
    proc = demsplit_cli("info", out)
    assert proc.returncode == 0, proc.stderr
    assert "bytes, sha256 abababababab..." in proc.stdout and "blake3" not in proc.stdout


@pytest.mark.slow
def test_info_on_a_missing_file(tmp_path):
    proc = demsplit_cli("info", tmp_path / "nope.txt")
    assert proc.returncode == 2 and "no such file" in proc.stderr


@pytest.mark.slow
def test_check_ok(run_dir):
    proc = demsplit_cli("check", run_dir / "in.packing")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "OK: no problem found" in proc.stdout
    assert "overlaps:    pairs: dumped delta" in proc.stdout
    assert "law:         liggghts:hertz (tangential='history'): Hertz u_n" in proc.stdout
    assert "not computed: u_t" not in proc.stdout
    assert "of primitive-wall contacts are NOT COMPUTED" in proc.stdout


@pytest.mark.slow
def test_check_ok_on_yade():
    proc = demsplit_cli("check", SAMPLES / "yade" / "cundall_periodic.npys")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "YADE penetrationDepth" in proc.stdout


@pytest.mark.slow
def test_check_lists_every_problem(run_dir):
    """A damaged row in frame 1, a contact listed twice in frame 0, a wall frame
    missing: all listed, each with file, timestep and line."""
    row_line = damage_atom_row(run_dir, 1)
    pairs = run_dir / "pairs.txt"
    lines = pairs.read_bytes().split(b"\n")
    lines[20 - 1] = lines[10 - 1]
    pairs.write_bytes(b"\n".join(lines))
    wall = run_dir / "wall.txt"
    wall.write_bytes(b"ITEM: TIMESTEP".join(wall.read_bytes().split(b"ITEM: TIMESTEP")[:3]))  # drop the last frame
    proc = demsplit_cli("check", run_dir / "in.packing")
    assert proc.returncode == 1, proc.stdout + proc.stderr
    out = proc.stdout
    assert f"atoms_full.txt:{row_line}, timestep 202000" in out
    assert "pairs.txt:20, timestep 200000" in out and "listed twice" in out
    assert "wall.txt, timestep 204000" in out and "no frame at timestep 204000" in out
    assert "wall.txt, timestep 204000: 1 timestep(s) of the atom dump have no frame here" in out
    assert "4 problem(s):" in out and "OK" not in out


@pytest.mark.slow
def test_check_missing_material(run_dir):
    atoms = run_dir / "atoms_full.txt"
    lines = atoms.read_bytes().split(b"\n")
    tokens = lines[12 - 1].split(b" ")
    tokens[1] = b"7"  # a particle of type 7, which has no material
    lines[12 - 1] = b" ".join(tokens)
    atoms.write_bytes(b"\n".join(lines))
    proc = demsplit_cli("check", run_dir / "in.packing")
    assert proc.returncode == 1
    assert "atoms_full.txt:12, timestep 200000: particle type 7 has no material" in proc.stdout
    fixed = demsplit_cli("check", run_dir / "in.packing", "--material", "7:1e7:0.3")
    assert fixed.returncode == 0, fixed.stdout


@pytest.mark.slow
def test_check_overlap_out_of_range(run_dir):
    pairs = run_dir / "pairs.txt"
    lines = pairs.read_bytes().split(b"\n")
    tokens = lines[15 - 1].split(b" ")
    tokens[37] = b"-1e-06"  # c_cpgl[38]: delta
    lines[15 - 1] = b" ".join(tokens)
    pairs.write_bytes(b"\n".join(lines))
    proc = demsplit_cli("check", run_dir / "in.packing")
    assert proc.returncode == 1
    assert "pairs.txt:15, timestep 200000" in proc.stdout and "delta <= 0" in proc.stdout


@pytest.mark.slow
def test_check_bad_script_is_a_problem_not_a_crash(run_dir):
    script = run_dir / "in.packing"
    script.write_text(script.read_text().replace("poissonsRatio peratomtype 0.25", "poissonsRatio peratomtype 0.7"))
    proc = demsplit_cli("check", script)
    assert proc.returncode == 1 and "0.7" in proc.stdout and "in.packing:" in proc.stdout


@pytest.mark.slow
def test_on_bad_frame_skip(run_dir, tmp_path):
    line = damage_atom_row(run_dir, 1)
    out = tmp_path / "o.h5"
    stop = demsplit_cli("run", run_dir / "in.packing", "-o", out, "-q")
    assert stop.returncode == 2 and not out.exists()
    assert not (tmp_path / ".o.h5.partial").exists()  # a refused run leaves nothing (frame 0 is not kept)
    proc = demsplit_cli("run", run_dir / "in.packing", "-o", out, "--on-bad-frame", "skip")
    assert proc.returncode == 0, proc.stderr
    assert "1 bad frame(s) skipped" in proc.stdout and "frame 1 (step 202000)" in proc.stdout
    assert f"atoms_full.txt:{line}" in proc.stdout
    results = demsplit.load_results(out)
    assert results.frames["step"].tolist() == [200000, 204000]  # the frame after the bad one is processed
    (bad,) = results.provenance["bad_frames"]
    assert bad["frame"] == 1 and bad["step"] == 202000 and f"atoms_full.txt:{line}" in bad["error"]
    reference = demsplit.analyze(PACKING / "in.packing")
    last = results.particles[results.particles["step"] == 204000].reset_index(drop=True)
    ref = reference.particles[reference.particles["step"] == 204000].reset_index(drop=True)
    assert (last["u"] - ref["u"]).abs().max() <= 1e-5 * ref["u"].abs().max()  # %g contacts vs full
