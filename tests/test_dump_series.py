"""Dumps written one file per timestep (``dump ... atoms*.txt``, the LIGGGHTS tutorials' habit) are read as
one dump: the same results as the same frames in one file, errors naming the frame's own file."""

from __future__ import annotations

import gzip
import shutil
import subprocess

import pytest
from conftest import SAMPLES, require_program
from demsplit import analyze
from demsplit.cli import main
from test_parallel import assert_same_results

PACKING = SAMPLES / "liggghts" / "packing"
ANALYTIC = SAMPLES / "liggghts" / "analytic"


def split_per_step(text: str, stem: str, directory, compress: bool = False) -> list[str]:
    """Write each frame of a dump's ``text`` to ``directory/STEM<step>.txt`` (as LAMMPS names them)."""
    names = []
    for block in text.split("ITEM: TIMESTEP\n")[1:]:
        step = int(block.split("\n", 1)[0])
        data = ("ITEM: TIMESTEP\n" + block).encode()
        name = f"{stem}{step}.txt" + (".gz" if compress else "")
        (directory / name).write_bytes(gzip.compress(data) if compress else data)
        names.append(name)
    return names


@pytest.fixture
def per_step(tmp_path):
    """The packing sample with its full-precision atom, pair and wall dumps one file per timestep (the pair
    dump compressed), and a script naming them with '*'."""
    shutil.copy(PACKING / "floor.stl", tmp_path / "floor.stl")
    script = (PACKING / "in.packing").read_text()
    for stem, source, compress in (
        ("atoms_full", "atoms_full.txt.gz", False),
        ("pairs_full", "pairs_full.txt.gz", True),
        ("wall_full", "wall_full.txt.gz", False),
    ):
        files = split_per_step(
            gzip.decompress((PACKING / source).read_bytes()).decode(), f"{stem}_", tmp_path, compress
        )
        assert len(files) > 1
        script = script.replace(f" {stem}.txt ", f" {stem}_*.txt ")
    (tmp_path / "in.packing").write_text(script)
    return tmp_path / "in.packing"


@pytest.mark.slow
def test_a_dump_per_timestep_gives_the_results_of_one_file(per_step):
    whole = analyze(PACKING / "in.packing")
    series = analyze(per_step)
    assert len(series.frames) == len(whole.frames) > 1
    assert_same_results(series, whole)
    names = {f["path"].rsplit("/", 1)[-1] for f in series.provenance["inputs"]}
    written = {p.name for p in per_step.parent.glob("*_full_*.txt*")}
    assert written <= names and len(written) == 3 * len(whole.frames)  # every file fingerprinted


@pytest.mark.slow
def test_an_error_names_the_file_of_the_frame(per_step, capsys):
    last = sorted(per_step.parent.glob("atoms_full_*.txt"), key=lambda p: int(p.stem.rsplit("_", 1)[1]))[-1]
    last.write_text(last.read_text().replace("ITEM: NUMBER OF ATOMS\n", "ITEM: NUMBER OF ATOMS\n1", 1))
    assert main(["run", str(per_step), "-o", str(per_step.parent / "out.h5"), "-q"]) == 2
    assert last.name in capsys.readouterr().err


@pytest.mark.slow
def test_one_file_per_processor_is_refused(per_step, capsys):
    per_step.write_text(per_step.read_text().replace(" atoms_full_*.txt ", " atoms_full_%.txt "))
    assert main(["run", str(per_step), "-o", str(per_step.parent / "out.h5"), "-q"]) == 2
    assert "one file per processor" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.simulator
def test_liggghts_per_step_dumps_equal_its_single_file_dumps(tmp_path):
    """Debian's LIGGGHTS writing the same output both ways: demsplit's results are identical."""
    liggghts = require_program("liggghts")
    shutil.copy(ANALYTIC / "floor.stl", tmp_path / "floor.stl")
    text = (ANALYTIC / "in.analytic").read_text().replace("run             300000", "run 3000")
    text = text.replace("dump datoms17 all custom 1 ", "dump datoms17 all custom 1000 ")
    text = text.replace("dump dpair17 all local 1 ", "dump dpair17 all local 1000 ")
    text = text.replace("dump dwall17 all local 1 ", "dump dwall17 all local 1000 ")
    text = text.replace("run             0", "run 3000")
    single = tmp_path / "single"
    series = tmp_path / "series"
    for d in (single, series):
        d.mkdir()
        shutil.copy(tmp_path / "floor.stl", d / "floor.stl")
    (single / "in.run").write_text(text)
    (series / "in.run").write_text(
        text.replace(" atoms_full.txt ", " post/atoms*.txt ")
        .replace(" pairs_full.txt ", " post/pairs*.txt ")
        .replace(" wall_full.txt ", " post/wall*.txt ")
    )
    (series / "post").mkdir()
    for d in (single, series):
        proc = subprocess.run([liggghts, "-in", "in.run"], cwd=d, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stdout[-2000:]
    assert len(list((series / "post").glob("atoms*.txt"))) > 2
    assert_same_results(analyze(series / "in.run"), analyze(single / "in.run"))
