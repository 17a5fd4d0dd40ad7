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
    proc = subprocess.run(["stdbuf", "-o0", "-e0", liggghts, "-in", out.name], cwd=out.parent, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, [line for line in proc.stdout.splitlines() if "ERROR" in line]
    return out


@pytest.mark.simulator
def test_a_mesh_wall_script(tmp_path):
    out = prepared_run(user_script(tmp_path))
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert (res.contacts["wall"] == 0).any() and "not_computed" not in res.walls  # the floor was dumped
    last = res.frames.iloc[-1]
    assert last["n_contacts"] == 5 and last["u_n"] > 0


@pytest.mark.simulator
def test_primitive_walls_only(tmp_path):
    def primitive(s: str) -> str:
        s = s.replace("fix floor all mesh/surface file floor.stl type 4\n", "")
        return s.replace("fix wfloor all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor",
                         "fix wfloor all wall/gran model hertz tangential history primitive type 4 zplane 0.0")
    script = user_script(tmp_path, primitive)
    out = prepared_run(script)
    assert "wall/gran/local" not in out.read_text()  # LIGGGHTS refuses it with primitive walls only
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    floor = res.contacts[res.contacts["wall"] == 0]
    assert len(floor) and np.all(floor["not_computed"] == 2)  # u_t of primitive-wall contacts: unknowable


@pytest.mark.simulator
@pytest.mark.parametrize("words, prop, mode", [
    ("rolling_friction epsd2", "coefficientRollingFriction peratomtypepair 4 " + " ".join(["0.1"] * 16), "u_r"),
    ("cohesion sjkr2", "cohesionEnergyDensity peratomtypepair 4 " + " ".join(["1e3"] * 16), "u_adh"),
])
def test_rolling_and_cohesion(tmp_path, words, prop, mode):
    def extend(s: str) -> str:
        s = s.replace("tangential history", f"tangential history {words}")
        return s.replace("pair_style      gran", f"fix extra all property/global {prop}\npair_style      gran", 1)
    out = prepared_run(user_script(tmp_path, extend))
    assert main(["run", str(out), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert mode in res.contacts and "not_computed" not in res.walls
    if mode == "u_adh":  # (the stacks are vertical: nothing rolls, the rolling springs hold 0)
        assert (res.contacts[mode] < 0).any()


def test_a_wall_fix_after_the_first_run_is_explained(tmp_path, capsys):
    def late(s: str) -> str:
        wall = "fix wfloor all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor\n"
        s = s.replace(wall, "")
        return s.replace("run 2000", wall + "run 2000")
    script = user_script(tmp_path, late)
    assert main(["prepare", str(script)]) == 2
    err = capsys.readouterr().err
    assert "after the first 'run'" in err and "write_restart" in err
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
