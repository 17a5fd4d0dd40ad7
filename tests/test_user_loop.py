"""The loop a new user lives in: prepare a LIGGGHTS script, run LIGGGHTS, check, run, with real runs of
Debian's LIGGGHTS whose particles are inserted over time (the first frames hold no contact).

- ``--allow-missing u_t`` goes on in a run that inserts particles, and ``check`` finds the missing mode
  in the frames that have contacts (it looked at the first frame, which has none, and said OK);
- a prepared script that LIGGGHTS has not run yet is diagnosed as such by ``run`` and ``check`` (they
  advised to prepare it again);
- a wall whose law lacks the pair law's cohesion is named in the note (it read as if the run had none);
- ``prepare`` says which wall energies primitive walls leave uncomputed, keeps a Latin-1 comment, and
  dumps at the script's own output interval (or ``--every``);
- ``check`` of printed positions does not call them full precision.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import demsplit
import numpy as np
import pytest
from conftest import require_program
from demsplit.cli import main
from demsplit.physics.modes import NOT_COMPUTED_BITS

U_T = NOT_COMPUTED_BITS["u_t"]

HEAD = b"""# particles inserted over time into a box of primitive walls: the first frames have no contact
units           si
atom_style      granular
atom_modify     map array
boundary        f f f
newton          off
communicate     single vel yes
region          domain block -0.006 0.006 -0.006 0.006 -0.001 0.03 units box
create_box      2 domain
neighbor        0.0004 bin
neigh_modify    delay 0
fix m1 all property/global youngsModulus peratomtype 2.0e7 5.0e6
fix m2 all property/global poissonsRatio peratomtype 0.25 0.40
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.5 0.5 0.5 0.5
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5
fix m5 all property/global cohesionEnergyDensity peratomtypepair 2 300000 300000 300000 300000
pair_style      gran model hertz tangential history PAIR_EXTRA
pair_coeff      * *
timestep        1.0e-5
fix gravi all gravity 9.81 vector 0.0 0.0 -1.0
fix floor all wall/gran model hertz tangential history primitive type 2 zplane 0.0
fix wxlo all wall/gran model hertz tangential history primitive type 2 xplane -0.005
fix wxhi all wall/gran model hertz tangential history primitive type 2 xplane  0.005
fix wylo all wall/gran model hertz tangential history primitive type 2 yplane -0.005
fix wyhi all wall/gran model hertz tangential history primitive type 2 yplane  0.005
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 2500 radius constant 0.0008
fix pdd all particledistribution/discrete 49979687 1 pts1 1.0
region          insreg block -0.0045 0.0045 -0.0045 0.0045 0.02 0.028 units box
fix ins all insert/pack seed 67867967 distributiontemplate pdd insert_every 2000 overlapcheck yes all_in yes &
    particles_in_region 40 region insreg ntry_mc 10000
fix integr all nve/sphere
"""
"""The head of the runs below: 40 particles inserted every 2000 steps; ``PAIR_EXTRA``: more pair_style words."""

FULL = "%d %d" + " %.17g" * 14
OWN_DUMPS = f"""compute cpgl all pair/gran/local pos id force delta
dump datoms all custom 2500 atoms.txt id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass
dump_modify datoms format "{FULL}"
dump dvis all custom 2500 vis.txt id type x y z radius
dump dpair all local 2500 pairs.txt {" ".join(f"c_cpgl[{k}]" for k in range(1, 14))}
dump_modify dpair format "{" ".join(["%.17g"] * 13)}"
run 30000
""".encode()
"""A full-precision atom dump, a printed one (``vis.txt``, %g) and a pair dump without the tangential history."""


def liggghts_run(script: Path) -> None:
    proc = subprocess.run(
        [require_program("liggghts"), "-in", script.name], cwd=script.parent, capture_output=True, timeout=600
    )
    assert proc.returncode == 0, [line for line in proc.stdout.splitlines() if b"ERROR" in line]


@pytest.fixture(scope="module")
def inserted(tmp_path_factory) -> Path:
    """The insertion run with its own dumps (:data:`OWN_DUMPS`), run by LIGGGHTS."""
    script = tmp_path_factory.mktemp("inserted") / "in.insert"
    script.write_bytes(HEAD.replace(b"PAIR_EXTRA", b"") + OWN_DUMPS)
    liggghts_run(script)
    return script


@pytest.mark.slow
@pytest.mark.simulator
def test_allow_missing_in_a_run_that_inserts_particles(inserted, tmp_path, capsys):
    blocks = (inserted.parent / "pairs.txt").read_text().split("ITEM: NUMBER OF ENTRIES\n")[1:]
    counts = [int(block.split("\n", 1)[0]) for block in blocks]
    assert counts[:3] == [0, 0, 0] and counts[-1] > 100  # no contact before the particles land
    out = tmp_path / "r.h5"
    assert main(["run", str(inserted), "-o", str(out), "-q"]) == 2
    assert "--allow-missing u_t" in capsys.readouterr().err
    assert main(["check", str(inserted)]) == 1  # the first frame has no contact; the later ones lack the history
    assert "NOT COMPUTED: u_t" in capsys.readouterr().out
    assert main(["run", str(inserted), "-o", str(out), "-q", "--allow-missing", "u_t"]) == 0
    res = demsplit.load_results(out)
    assert len(res.steps) == 13 and (res.frames["n_contacts"] == 0).sum() == 3
    for name in ("particles", "contacts", "walls"):
        assert "not_computed" in getattr(res.raw, name), name
    assert (res.frames["n_not_computed"].to_numpy() == res.frames["n_contacts"].to_numpy()).all()
    pairs = res.contacts[res.contacts["wall"] < 0]
    assert len(pairs) and np.all(pairs["not_computed"] == U_T) and pairs["u_t"].isna().all()
    assert res.frames["u_n"].iloc[-1] > 0
    parallel = tmp_path / "j2.h5"
    assert main(["run", str(inserted), "-o", str(parallel), "-q", "-j", "2", "--allow-missing", "u_t"]) == 0
    again = demsplit.load_results(parallel)
    for name in ("particles", "contacts", "walls", "frames"):
        a, b = getattr(res.raw, name), getattr(again.raw, name)
        assert list(a.columns) == list(b.columns)
        np.testing.assert_array_equal(a.to_numpy(dtype=float), b.to_numpy(dtype=float))
    for fmt in ("csv", "vtk"):
        assert main(["export", str(out), f"--{fmt}", str(tmp_path / fmt), "-q"]) == 0


@pytest.mark.simulator
def test_check_of_printed_positions_does_not_call_them_full_precision(inserted, capsys):
    """The first frames hold no particle or no contact; the overlaps are described from the frames that have
    contacts, and the frames refused for their printed digits are counted there."""
    assert main(["check", str(inserted), "--atoms", str(inserted.parent / "vis.txt")]) == 1
    out = capsys.readouterr().out
    said = next(line for line in out.splitlines() if line.strip().startswith("overlaps:"))
    assert "full precision" not in said and "too few digits" in said, said
    assert "positions printed with 6 significant digits" in out


LATIN1 = "# Modèle de référence, écrit sous Windows\n".encode("latin-1")


@pytest.mark.slow
@pytest.mark.simulator
def test_latin1_prepare_then_check_before_and_after_liggghts(tmp_path, capsys):
    script = tmp_path / "in.user"
    script.write_bytes(
        LATIN1
        + HEAD.replace(b"PAIR_EXTRA", b"")
        + b"dump dvis all custom 5000 vis.txt id type x y z radius\nrun 30000\n"
    )
    assert main(["check", str(script)]) != 2 and "UTF-8" not in capsys.readouterr().out
    assert main(["prepare", str(script)]) == 0
    told = capsys.readouterr().out
    out = script.with_name("in.user.demsplit")
    data = out.read_bytes()
    assert data.split(b"\n", 1)[1].startswith(LATIN1)  # after prepare's stamp line, the user's bytes as they were
    assert b"dump dsAtoms all custom 5000 " in data and b"dump ddsPair all local 5000 " in data
    assert "every 5000 steps (the interval of the script's own dump dvis" in told
    liggghts_run(out)
    assert (tmp_path / "ds_atoms.txt").read_text().count("ITEM: TIMESTEP") == 7  # 0, 5000, ..., 30000
    assert main(["check", str(out)]) == 0, capsys.readouterr().out


def test_a_prepared_script_not_run_yet(tmp_path, capsys):
    """The dumps are missing because LIGGGHTS has not run the prepared script: the fix is to run it, not to
    prepare it again."""
    script = tmp_path / "in.user"
    script.write_bytes(HEAD.replace(b"PAIR_EXTRA", b"") + b"run 30000\n")
    assert main(["prepare", str(script), "-q"]) == 0
    out = script.with_name("in.user.demsplit")
    for command in ("run", "check"):
        args = [command, str(out)] + (["-o", str(tmp_path / "r.h5")] if command == "run" else [])
        assert main(args) == (2 if command == "run" else 1)
        said = capsys.readouterr()
        said = said.err if command == "run" else said.out
        assert "is prepared for demsplit" in said and "does not exist yet" in said, said
        assert f"liggghts -in {out.name}" in said and "demsplit prepare" not in said


def test_prepare_every_follows_the_script_or_the_option(tmp_path, capsys):
    script = tmp_path / "in.user"
    body = HEAD.replace(b"PAIR_EXTRA", b"")
    script.write_bytes(body + b"thermo 20000\nrun 6000000\n")
    assert main(["prepare", str(script), "-q"]) == 0
    assert b"dump dsAtoms all custom 20000 " in script.with_name("in.user.demsplit").read_bytes()
    script.write_bytes(body + b"run 6000000\n")
    assert main(["prepare", str(script), "-o", str(tmp_path / "b"), "-q"]) == 0
    assert b"dump dsAtoms all custom 60000 " in (tmp_path / "b").read_bytes()  # 100 frames over the run
    assert main(["prepare", str(script), "-o", str(tmp_path / "c"), "--every", "250", "-q"]) == 0
    assert b"dump dsAtoms all custom 250 " in (tmp_path / "c").read_bytes()
    assert b"dump ddsPair all local 250 " in (tmp_path / "c").read_bytes()


def test_prepare_says_how_primitive_walls_get_their_history(tmp_path, capsys):
    """LIGGGHTS never writes a primitive wall's contact history: prepare says, before the simulation, that it
    adds store_force yes to those walls (their force gives the history back) and names them."""
    script = tmp_path / "in.user"
    script.write_bytes(HEAD.replace(b"PAIR_EXTRA", b"") + b"run 1000\n")
    assert main(["prepare", str(script)]) == 0
    told = capsys.readouterr().out
    note = next(line for line in told.splitlines() if line.startswith("primitive walls"))
    assert "store_force yes added to the fixes floor, wxlo, wxhi, wylo, wyhi" in note and "history" in note
    assert "NOT COMPUTED" not in told


@pytest.mark.slow
@pytest.mark.simulator
def test_a_wall_law_without_the_pair_law_cohesion_is_named(tmp_path, capsys):
    script = tmp_path / "in.user"
    script.write_bytes(HEAD.replace(b"PAIR_EXTRA", b"cohesion sjkr") + b"run 30000\n")
    assert main(["prepare", str(script), "-q"]) == 0
    out = script.with_name("in.user.demsplit")
    liggghts_run(out)
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5")]) == 0
    printed = capsys.readouterr().out
    res = demsplit.load_results(tmp_path / "r.h5")
    assert res.frames["u_adh"].iloc[-1] < 0  # the pairs' cohesion work
    note = next(line for line in printed.splitlines() if line.startswith("note: u_adh is 0"))
    assert "walls 'floor', 'wxlo', 'wxhi', 'wylo', 'wyhi'" in note and "the particle pairs is computed" in note


@pytest.mark.slow
@pytest.mark.simulator
def test_one_material_the_report_says_it_is_the_50_50_split(tmp_path, capsys):
    """Particles and walls of one material, one radius: the material law is the 50/50 split (off by 0), and
    the radius split's whole error is its wall contacts' (a wall, r = inf, gives the particle all of each)."""
    from demsplit.results.report import split_headline

    script = tmp_path / "in.user"
    script.write_bytes(
        HEAD.replace(b"PAIR_EXTRA", b"").replace(b"primitive type 2", b"primitive type 1") + b"run 30000\n"
    )
    assert main(["prepare", str(script), "-q"]) == 0
    out = script.with_name("in.user.demsplit")
    liggghts_run(out)
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    one = res.frame(int(res.steps.max()))
    table, sentences = split_headline(one, {})
    row = table.iloc[0]
    assert len(table) == 1 and abs(row["equal_off_pct"]) < 1e-9 and row["radius_off_pct"] > 1
    assert row["radius_off_walls_pct"] == pytest.approx(row["radius_off_pct"], rel=1e-9)
    said = " ".join(sentences)
    assert "One particle material (E = 2e+07 Pa, nu = 0.25)" in said and "it is the 50/50 split" in said
    assert "(the walls too are of this material)" in said and "against a wall it gives the particle" in said
    assert main(["report", str(tmp_path / "r.h5"), "-o", str(tmp_path / "r.html"), "-q"]) == 0
    box = (tmp_path / "r.html").read_text()
    box = box[box.index("<div class='summary'") : box.index("<h2>Energy per mode</h2>")]
    assert "it is the 50/50 split" in box and "radius off by walls" in box
    assert main(["report", str(tmp_path / "r.h5")]) == 0
    text = capsys.readouterr().out.splitlines()
    assert text[1].startswith(
        "  Against the material law, the 50/50 split agrees with it and the radius split gives type 1 "
    )
