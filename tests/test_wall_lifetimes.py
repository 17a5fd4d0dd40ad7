"""A wall exists exactly in the frames the simulation has it (docs/design.md, "Energy modes, split rules and
completeness").

The script reader follows the ``run`` commands and where each wall fix, ``unfix`` and dump line stands
among them; a frame is written by the run whose timesteps hold it (the first of two that share a
boundary step). The sample ``sample_dumps/liggghts/gate`` is a real Debian LIGGGHTS run in motion: a
primitive floor added after the first run, a primitive gate removed by ``unfix`` after the second, no
damping and no tangential history, so each particle's dumped force is gravity plus the Hertz springs of
the contacts it has: the contacts demsplit rebuilds must close it at every frame, no more and no fewer.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from demsplit import analyze
from demsplit.physics.bodies import FrameContacts, LawRows
from demsplit.readers import open_run
from demsplit.readers.lammps_dump import open_dump
from demsplit.readers.liggghts import walls_present
from demsplit.readers.liggghts_script import read_script

GATE = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts" / "gate" / "in.gate"
GRAVITY = np.array([0.0, 0.0, -9.81])


def script(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "in.walls"
    path.write_text(
        "units si\nregion d block 0 1 0 1 0 1 units box\ncreate_box 2 d\n"
        "fix m1 all property/global youngsModulus peratomtype 1e7 1e7\n"
        "fix m2 all property/global poissonsRatio peratomtype 0.3 0.3\n"
        "pair_style gran model hertz tangential history\n" + body
    )
    return path


def present(path: Path, steps: list[int], dump: str = "d") -> list[tuple[int, ...] | None]:
    s = read_script(path)
    spec = next(d for d in s.dumps if d.id == dump)
    return [walls_present(s, spec, step) for step in steps]


def test_walls_follow_the_runs_fix_and_unfix(tmp_path):
    path = script(
        tmp_path,
        "dump d all custom 100 a.txt id type x y z radius\n"
        "fix a all wall/gran model hertz tangential history primitive type 2 zplane 0\n"
        "run 1000\n"
        "fix b all wall/gran model hertz tangential history primitive type 2 zplane 1\n"
        "run 1000\n"
        "unfix a\n"
        "run 1000\n",
    )
    # step 1000 ends the first run (b not yet), 2000 the second (a still there)
    assert present(path, [0, 1000, 1100, 2000, 2100, 3000]) == [(0,), (0,), (0, 1), (0, 1), (1,), (1,)]


def test_a_dump_defined_between_runs_writes_the_boundary_step_in_the_next_run(tmp_path):
    path = script(
        tmp_path,
        "run 1000\n"
        "fix a all wall/gran model hertz tangential history primitive type 2 zplane 0\n"
        "dump d all custom 100 a.txt id type x y z radius\n"
        "run 1000 upto\n"  # to timestep 1000: nothing runs, the dump writes step 1000
        "run 500\n",
    )
    assert present(path, [1000, 1100, 1500]) == [(0,), (0,), (0,)]
    path = script(
        tmp_path,
        "reset_timestep 5000\n"
        "dump d all custom 100 a.txt id type x y z radius\n"
        "run 100\n"
        "fix a all wall/gran model hertz tangential history primitive type 2 zplane 0\n"
        "run 100\n",
    )
    assert present(path, [5000, 5100, 5200]) == [(), (), (0,)]


def test_walls_there_from_the_start_to_the_end_need_no_filter(tmp_path):
    path = script(
        tmp_path,
        "fix a all wall/gran model hertz tangential history primitive type 2 zplane 0\n"
        "dump d all custom 100 a.txt id type x y z radius\nrun 100\nrun 100\n",
    )
    assert present(path, [0, 100, 200]) == [None, None, None]


@pytest.fixture(scope="module")
def frames():
    with open_run(GATE) as run:
        return run.scene, [frame for frame in run]


def test_no_contact_with_a_wall_where_it_does_not_exist(frames):
    scene, frames = frames
    names = [w.name for w in scene.walls]
    gate, floor = names.index("gate"), names.index("floor")
    seen = {"gate after unfix": 0, "floor before its fix": 0, "gate frames": 0, "floor frames": 0}
    for frame in frames:
        walls = frame.contacts["wall"]
        assert frame.walls is not None and set(np.unique(walls[walls >= 0])) <= set(frame.walls)
        if frame.step > 8000:  # the gate is gone: 2000-step runs after a 6000-step one
            assert gate not in frame.walls
            seen["gate after unfix"] += 1
        if frame.step <= 6000:
            assert floor not in frame.walls
            seen["floor before its fix"] += 1
        seen["gate frames"] += int(np.any(walls == gate))
        seen["floor frames"] += int(np.any(walls == floor))
    assert min(seen.values()) > 0, seen  # each case happens in the sample


def test_every_dumped_force_is_gravity_plus_the_rebuilt_contacts(frames):
    """f_i = m_i g + sum over i's contacts of the Hertz spring along the normal, to 1e-12 of the frame's
    largest force, for every particle of every frame: a phantom wall contact or a missing one breaks it."""
    scene, frames = frames
    law = scene.model.contact_law
    dumped_frames = {
        f.step: f for f in open_dump(GATE.parent / "atoms.txt.gz").frames(["id", "mass", "fx", "fy", "fz"])
    }
    checked = 0
    for frame in frames:
        p, c = frame.particles, frame.contacts
        if not len(p["id"]):
            continue
        atoms = dumped_frames[frame.step]
        assert np.array_equal(atoms.int_column("id"), p["id"])
        rows = LawRows(FrameContacts(c, scene, p), slice(None), law.key)
        fn = law.normal_force(rows)  # repulsive magnitude, N
        n = np.stack([c["nx"], c["ny"], c["nz"]], axis=-1)  # from body 1 to body 2
        index = {int(i): k for k, i in enumerate(p["id"])}
        total = atoms.columns["mass"][:, None] * GRAVITY
        np.add.at(total, [index[int(i)] for i in c["id1"]], -fn[:, None] * n)
        pair = c["wall"] < 0
        np.add.at(total, [index[int(i)] for i in c["id2"][pair]], fn[pair, None] * n[pair])
        dumped = np.stack([atoms.columns[k] for k in ("fx", "fy", "fz")], axis=-1)
        scale = np.max(np.abs(dumped))
        assert np.max(np.abs(total - dumped)) <= 1e-12 * scale, frame.step
        checked += len(c["delta"])
    assert checked > 400


def test_the_walls_table_has_a_row_only_where_the_wall_exists(tmp_path):
    res = analyze(GATE)
    names = [m["name"] for m in res.walls_meta]
    gate_rows = res.walls[res.walls["wall"] == names.index("gate")]
    floor_rows = res.walls[res.walls["wall"] == names.index("floor")]
    assert gate_rows["step"].max() == 8000 and floor_rows["step"].min() == 6250
    assert set(res.walls["wall"]) == set(range(len(names)))
