"""``demsplit prepare``: a user's LIGGGHTS script, made to write what demsplit needs, runs in Debian's
LIGGGHTS and is analysed by ``demsplit run`` with no further edit.

The user scripts are the analytic sample (two stacks on a mesh floor) with demsplit's own dump
lines removed, then varied: only primitive walls, rolling friction, cohesion, a mesh wall fix
placed after the first run.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import demsplit
import numpy as np
import pytest
from conftest import SAMPLES
from demsplit.cli import main

ANALYTIC = SAMPLES / "liggghts" / "analytic"


def user_script(tmp_path: Path, edit=lambda s: s) -> Path:
    """The analytic sample as a user would have written it: no demsplit dump lines, a short last run."""
    shutil.copy(ANALYTIC / "floor.stl", tmp_path / "floor.stl")
    lines = (ANALYTIC / "in.analytic").read_text().split("\n")
    kept = [line for line in lines if not line.startswith(("dump", "compute cpgl", "compute cwgl"))]
    text = "\n".join(kept).replace("run             300000", "run             100000")
    text = text.replace("run             0", "run 2000")
    script = tmp_path / "in.user"
    script.write_text(edit(text))
    return script


def prepared_run(script: Path) -> Path:
    """prepare, run the prepared script in LIGGGHTS, return the prepared script's path."""
    from conftest import require_program

    liggghts = require_program("liggghts")
    original = script.read_bytes()
    assert main(["prepare", str(script), "-q"]) == 0
    assert script.read_bytes() == original  # the input is never touched
    out = script.with_name(script.name + ".demsplit")
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", out.name], cwd=out.parent, capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, [line for line in proc.stdout.splitlines() if "ERROR" in line]
    return out


@pytest.mark.simulator
def test_a_mesh_wall_script(tmp_path):
    out = prepared_run(user_script(tmp_path))
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert (res.contacts["wall"] == 0).any() and not res.walls["not_computed"].any()  # the floor was dumped
    last = res.frames.iloc[-1]
    assert last["n_contacts"] == 5 and last["u_n"] > 0


@pytest.mark.simulator
def test_primitive_walls_only(tmp_path):
    def primitive(s: str) -> str:
        s = s.replace("fix floor all mesh/surface file floor.stl type 4\n", "")
        return s.replace(
            "fix wfloor all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor",
            "fix wfloor all wall/gran model hertz tangential history primitive type 4 zplane 0.0",
        )

    script = user_script(tmp_path, primitive)
    out = prepared_run(script)
    text = out.read_text()
    assert "wall/gran/local" not in text  # LIGGGHTS refuses it with primitive walls only
    assert "primitive type 4 zplane 0.0 store_force yes" in text and "f_force_wfloor[3]" in text
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    floor = res.contacts[res.contacts["wall"] == 0]
    # u_t of the primitive floor's contacts, rebuilt from its stored force: every one known
    assert len(floor) and np.all(floor["not_computed"] == 0) and floor["u_t"].notna().all()


@pytest.mark.simulator
@pytest.mark.parametrize(
    "words, prop, mode",
    [
        ("rolling_friction epsd2", "coefficientRollingFriction peratomtypepair 4 " + " ".join(["0.1"] * 16), "u_r"),
        ("cohesion sjkr2", "cohesionEnergyDensity peratomtypepair 4 " + " ".join(["1e3"] * 16), "u_adh"),
    ],
)
def test_rolling_and_cohesion(tmp_path, words, prop, mode):
    def extend(s: str) -> str:
        s = s.replace("tangential history", f"tangential history {words}")
        return s.replace("pair_style      gran", f"fix extra all property/global {prop}\npair_style      gran", 1)

    out = prepared_run(user_script(tmp_path, extend))
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert mode in res.contacts and not res.walls["not_computed"].any()
    if mode == "u_adh":  # (the stacks are vertical: nothing rolls, the rolling springs hold 0)
        assert (res.contacts[mode] < 0).any()


@pytest.mark.simulator
def test_compute_elastic_potential_widens_the_dumped_history(tmp_path):
    """computeElasticPotential on adds 10 history values to the pair compute and 14 to the wall compute
    (with rolling friction: 32 + 6 + 10 = 48 and 32 + 6 + 14 = 52 columns): the prepared dumps hold them
    all, LIGGGHTS writes them and the run is analysed with no further edit (prepare cut the list at the
    law's own history before)."""

    def extend(s: str) -> str:
        s = s.replace("tangential history", "tangential history rolling_friction epsd2")
        s = s.replace("meshes floor", "meshes floor computeElasticPotential on")
        prop = "coefficientRollingFriction peratomtypepair 4 " + " ".join(["0.1"] * 16)
        return s.replace(
            "pair_style      gran model hertz tangential history rolling_friction epsd2",
            f"fix extra all property/global {prop}\npair_style      gran model hertz tangential "
            "history rolling_friction epsd2 computeElasticPotential on",
            1,
        )

    script = user_script(tmp_path, extend)
    assert script.read_text().count("computeElasticPotential on") == 2
    out = prepared_run(script)
    text = out.read_text()
    assert "c_dsPair[48]" in text and "c_dsPair[49]" not in text and "c_dsWall[52]" in text
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert "u_r" in res.contacts and (res.contacts["wall"] == 0).any() and not res.walls["not_computed"].any()
    assert res.frames.iloc[-1]["u_n"] > 0


WALL = "fix wfloor all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor\n"
USER_DUMP = (
    "dump mine all custom 500 mine.txt id type x y z vx vy vz fx fy fz omegax omegay omegaz\n"
    'dump_modify mine format "%d %d' + " %.17g" * 12 + '" sort id\n'
)


def late_wall(s: str) -> str:
    """The floor's wall fix moved after the first run (3000 steps of fall before it exists), and a dump of
    the user's own declared before that run."""
    s = s.replace(WALL, "").replace("run             100000", USER_DUMP + "run 3000")
    return s.replace("run 2000", WALL + "run 2000")


def dump_frames(path: Path) -> dict[int, str]:
    """Text of each frame of a text dump, by timestep."""
    frames = {}
    for block in path.read_text().split("ITEM: TIMESTEP\n")[1:]:
        step, _, rest = block.partition("\n")
        frames[int(step)] = rest
    return frames


@pytest.mark.slow
@pytest.mark.simulator
def test_a_wall_fix_after_a_run_splits_the_script_with_the_same_physics(tmp_path, capsys):
    """prepare splits the script at the late wall fix (write_restart / read_restart); both parts run in
    LIGGGHTS, the user's own dump continues bit for bit as in the unsplit run, and demsplit analyses the
    second part, whose mesh-wall contacts are now dumped, with no edit."""
    from conftest import require_program

    liggghts = require_program("liggghts")
    original = tmp_path / "original"
    original.mkdir()
    script = user_script(original, late_wall)
    proc = subprocess.run([liggghts, "-in", script.name], cwd=original, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:]
    split = tmp_path / "split"
    split.mkdir()
    script = user_script(split, late_wall)
    assert main(["prepare", str(script)]) == 0
    out = capsys.readouterr().out
    assert "split: the mesh wall fix on line" in out and "write_restart" in out
    parts = [split / "in.user.demsplit", split / "in.user.demsplit.part2"]
    assert "write_restart ds_split1.restart" in parts[0].read_text()
    assert "read_restart ds_split1.restart" in parts[1].read_text()
    for part in parts:
        proc = subprocess.run([liggghts, "-in", part.name], cwd=split, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, [line for line in proc.stdout.splitlines() if "ERROR" in line]
    unsplit = dump_frames(original / "mine.txt")
    joined = {**dump_frames(split / "mine.part2.txt"), **dump_frames(split / "mine.txt")}
    assert sorted(joined) == sorted(unsplit) and max(unsplit) == 5000
    assert all(joined[step] == unsplit[step] for step in unsplit)  # bit for bit: the same physics
    for k, part in enumerate(parts):
        assert main(["run", str(part), "-o", str(tmp_path / f"r{k}.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r1.h5")
    assert (res.contacts["wall"] == 0).any() and not res.walls["not_computed"].any()  # the late floor is dumped


def test_a_split_that_prepare_cannot_carry_is_refused_with_the_steps(tmp_path, capsys):
    script = user_script(tmp_path, lambda s: late_wall(s).replace("timestep", "include nothing.in\ntimestep", 1))
    (tmp_path / "nothing.in").write_text("# empty\n")
    assert main(["prepare", str(script)]) == 2
    err = capsys.readouterr().err
    assert "include" in err and "write_restart" in err and "read_restart" in err
    assert not script.with_name(script.name + ".demsplit").exists()


def test_nothing_to_add_to_a_complete_script(tmp_path, capsys):
    shutil.copy(ANALYTIC / "floor.stl", tmp_path / "floor.stl")
    shutil.copy(ANALYTIC / "in.analytic", tmp_path / "in.analytic")
    assert main(["prepare", str(tmp_path / "in.analytic")]) == 0
    assert "nothing to add" in capsys.readouterr().out
    assert not (tmp_path / "in.analytic.demsplit").exists()


def test_prepare_never_writes_over_its_input(tmp_path, capsys):
    script = user_script(tmp_path)
    assert main(["prepare", str(script), "-o", str(script)]) == 2
    assert "input" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.simulator
def test_a_moving_mesh_wall_created_after_a_run_is_refused_then_prepared(tmp_path, capsys):
    """The moving-mesh tutorial's shape: a mesh moved by fix move/mesh, its wall fix created after the first
    run, the contact dumps a user copies (atoms, pairs) but no wall compute (LIGGGHTS refuses it there).
    demsplit run refuses the run naming the wall and prepare; check says so; the prepared split is analysed."""
    from conftest import require_program
    from demsplit.prepare import prepare_script

    liggghts = require_program("liggghts")

    def moving(s: str) -> str:
        return late_wall(s).replace(WALL, "fix move all move/mesh mesh floor linear 0. 0. 0.01\n" + WALL)

    script = user_script(tmp_path, moving)
    copied = [
        line
        for line in prepare_script(script).added
        if line.startswith(
            ("dump dsAtoms", "dump_modify dsAtoms", "compute dsPair", "dump ddsPair", "dump_modify ddsPair")
        )
    ]
    assert len(copied) == 5
    script.write_text(script.read_text().replace("run 3000", "\n".join(copied) + "\nrun 3000", 1))
    proc = subprocess.run([liggghts, "-in", script.name], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:]
    assert main(["run", str(script), "-o", str(tmp_path / "r.h5"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "mesh wall 'floor'" in err and "demsplit prepare" in err and "--allow-missing floor" in err
    assert not (tmp_path / "r.h5").exists()
    assert main(["check", str(script)]) == 1
    assert "wall 'floor' (mesh): no dump holds its contacts" in capsys.readouterr().out
    assert main(["prepare", str(script), "-q"]) == 0
    for part in ("in.user.demsplit", "in.user.demsplit.part2"):
        proc = subprocess.run([liggghts, "-in", part], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, [line for line in proc.stdout.splitlines() if "ERROR" in line]
    assert main(["run", str(tmp_path / "in.user.demsplit.part2"), "-o", str(tmp_path / "r2.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r2.h5")
    assert (res.contacts["wall"] == 0).any() and not res.walls["not_computed"].any()


BRIDGE_PROPERTIES = "".join(
    f"fix b{k} all property/global {p}\n"
    for k, p in enumerate(
        (
            "surfaceLiquidContentInitial scalar 0.02",
            "surfaceTension scalar 0.072",
            "contactAngle peratomtype 20 35 10 25",
            "minSeparationDistanceRatio scalar 1.01",
            "maxSeparationDistanceRatio scalar 1.1",
            "fluidViscosity scalar 0.001",
        ),
        1,
    )
)


@pytest.mark.slow
@pytest.mark.simulator
def test_liquid_bridges_get_their_liquid_content_with_the_same_physics(tmp_path):
    """A liquid-bridge cohesion model: prepare's atom dump writes the liquid content f_surfaceLiquidContent, and
    creates before it the fix the model would create at the first run (LIGGGHTS checks a dump's f_ columns when it
    reads it); the user's own dump is bit for bit that of the unprepared run, and demsplit analyses the prepared run
    with no edit. (easo: the analytic stacks start exactly touching, where washino's force is 0/0 in LIGGGHTS 3.8.0
    and the unprepared run itself stops; prepare writes the same lines for both.)"""
    model = "easo/capillary/viscous"
    from conftest import require_program

    liggghts = require_program("liggghts")

    def wet(s: str) -> str:
        s = s.replace("tangential history", f"tangential history cohesion {model}")
        s = s.replace("pair_style      gran", BRIDGE_PROPERTIES + "pair_style      gran", 1)
        return s.replace("run             100000", USER_DUMP + "run             100000")

    original = tmp_path / "original"
    original.mkdir()
    script = user_script(original, wet)
    proc = subprocess.run([liggghts, "-in", script.name], cwd=original, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:]
    out = prepared_run(user_script(tmp_path, wet))
    text = out.read_text()
    assert "fix liquidtransfer all transportequation/scalar" in text and "f_surfaceLiquidContent" in text
    assert text.index("fix liquidtransfer") < text.index("dump dsAtoms") < text.index("run             100000")
    theirs, ours = dump_frames(original / "mine.txt"), dump_frames(tmp_path / "mine.txt")
    assert sorted(ours) == sorted(theirs) and all(ours[step] == theirs[step] for step in theirs)
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert (res.contacts["u_adh"] < 0).all() and not res.walls["not_computed"].any()
