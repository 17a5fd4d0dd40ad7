"""YADE clumps: run Debian's YADE on a Hertz-Mindlin scene with rigid clumps
and free spheres settling on a floor, then check that demsplit sees only the
member spheres (never the clump bodies), that ``Results.per_clump`` is the sum
over each clump's members, and that the energy matches YADE's own
``Law2_ScGeom_MindlinPhys_Mindlin.normElastEnergy()``."""

from __future__ import annotations

import json

import demsplit
import numpy as np
import pytest
from demsplit.readers.yade_snapshot import open_yade_snapshot
from test_yade_simulator import run_yade

# Three clumps (a 3-sphere rod and a 2-sphere dumbbell on the floor, a 3-sphere
# triangle resting on the floor layer) and four free spheres, two materials,
# inside a box of five Walls. At iteration 6000 the pile holds clump-clump,
# clump-free, clump-floor and clump-side-wall contacts. appendClumped returns (clump id, member ids); the script
# writes them to clumps.json so the test knows the membership independently of
# the snapshot.
CLUMP_SCENE = """
import json, os, site
site.addsitedir(os.environ["DEMSPLIT_SITE"])
import demsplit.yade
from yade import utils
soft = O.materials.append(FrictMat(young=1e7, poisson=0.3, density=2600, frictionAngle=0.5))
stiff = O.materials.append(FrictMat(young=5e7, poisson=0.2, density=2600, frictionAngle=0.5))
R = 0.01
L = 0.03  # half width of the box: the floor layer fills it, so the settling pile presses sideways
O.bodies.append([utils.wall(0, axis=2, sense=1, material=stiff),
                 utils.wall(-L, axis=0, sense=1, material=soft), utils.wall(L, axis=0, sense=-1, material=soft),
                 utils.wall(-L, axis=1, sense=1, material=stiff), utils.wall(L, axis=1, sense=-1, material=stiff)])
clumps = {}
def clump(centres, radii, mats):
    cid, members = O.bodies.appendClumped([utils.sphere(c, r, material=m) for c, r, m in zip(centres, radii, mats)])
    clumps[cid] = list(members)
# floor layer, 0.1-0.6 mm gaps: a rod clump, a row of free spheres, a dumbbell clump
clump([(-0.018, -0.0199, 0.0101), (0, -0.0199, 0.0101), (0.018, -0.0199, 0.0101)], [R, R, R], [soft, stiff, soft])
free = O.bodies.append([utils.sphere((x, 0, 0.0096), 0.0095, material=m)
                        for x, m in ((-0.0196, stiff), (0, soft), (0.0196, stiff))])
clump([(-0.009, 0.0199, 0.0101), (0.009, 0.0199, 0.0081)], [R, 0.8 * R], [stiff, soft])
# second layer: a triangle clump in the hollows over the rod and the free row, and a small free sphere on top
clump([(-0.01, -0.01, 0.026), (0.01, -0.01, 0.026), (0, 0.01, 0.026)], [R, R, 0.9 * R], [soft, soft, stiff])
free += O.bodies.append([utils.sphere((0.02, 0.015, 0.04), 0.7 * R, material=soft)])
with open(os.path.join(os.environ["DEMSPLIT_OUT"], "clumps.json"), "w") as f:
    json.dump({"clumps": {str(k): v for k, v in clumps.items()}, "free": list(free)}, f)
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_MindlinPhys()],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    PyRunner(command='demsplit.yade.snapshot(os.path.join(os.environ["DEMSPLIT_OUT"], "clumps.npys"))',
             iterPeriod=int(os.environ["DEMSPLIT_EVERY"])),
    NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.4)]
O.dt = 0.3 * utils.PWaveTimeStep()
O.run(int(os.environ["DEMSPLIT_ITER"]), True)
"""


@pytest.fixture
def clump_run(yade, tmp_path):
    script = tmp_path / "clumps.py"
    script.write_text(CLUMP_SCENE)
    # PyRunner(iterPeriod=2000) fires at iterations 2000, 4000, 6000: the last needs 6001 steps
    run_yade(yade, script, tmp_path, DEMSPLIT_ITER="6001", DEMSPLIT_EVERY="2000")
    layout = json.loads((tmp_path / "clumps.json").read_text())
    clumps = {int(k): v for k, v in layout["clumps"].items()}
    return tmp_path / "clumps.npys", clumps, layout["free"]


@pytest.mark.slow
@pytest.mark.simulator
def test_clump_energies_are_member_sums(clump_run):
    path, clumps, free = clump_run
    res = demsplit.analyze(path)
    members = {m: cid for cid, ms in clumps.items() for m in ms}
    assert len(clumps) == 3 and len(members) == 8 and len(free) == 4
    steps = res.steps
    assert len(steps) == 3

    # (1) contacts name member spheres and walls only, never a clump body
    c = res.contacts
    ids = np.concatenate([c["id1"].to_numpy(), c["id2"].to_numpy()])
    assert not np.isin(ids, list(clumps)).any()
    assert set(ids[ids >= 0]) <= set(members) | set(free)
    assert set(res.particles["id"]) == set(members) | set(free)

    # the settled scene has clump-clump, clump-free and clump-wall contacts
    last = c[c["step"] == steps[-1]]
    c1, c2 = last["id1"].map(members), last["id2"].map(members)
    assert (c1.notna() & c2.notna() & (c1 != c2)).any(), "no clump-clump contact"
    is_free1, is_free2 = last["id1"].isin(free), last["id2"].isin(free)
    assert ((c1.notna() & is_free2) | (c2.notna() & is_free1)).any(), "no clump-free contact"
    assert (c1.notna() & (last["wall"] >= 0)).any(), "no clump-wall contact"

    # (3) free spheres carry clump == -1, members their clump's id
    p = res.particles
    clump_of = p["id"].map(lambda i: members.get(i, -1))
    assert (p["clump"].to_numpy() == clump_of.to_numpy()).all()
    assert (p.loc[p["id"].isin(free), "clump"] == -1).all()

    # (2) per_clump = member sums, computed here from the particles table and the script's membership
    pc = res.per_clump().set_index(["step", "clump"]).sort_index()
    assert len(pc) == len(steps) * len(clumps)
    for step in steps:
        ps = p[p["step"] == step].set_index("id")
        for cid, ms in clumps.items():
            row = pc.loc[(step, cid)]
            assert row["n_members"] == len(ms)
            for col in ("u", "u_n", "u_t"):
                assert row[col] == pytest.approx(ps.loc[ms, col].sum(), rel=1e-14, abs=0)
            assert row["n_contacts"] == ps.loc[ms, "n_contacts"].sum()
    assert (pc["u"] > 0).all() and (pc["u_t"] > 0).any()


@pytest.mark.slow
@pytest.mark.simulator
def test_clump_scene_normal_energy_matches_normElastEnergy(clump_run):
    path, clumps, free = clump_run
    res = demsplit.analyze(path)
    run = open_yade_snapshot(path)
    assert len(run) == len(res.steps)
    for k in range(len(run)):
        meta = run.meta(k)
        reference = meta["law_energies"]["mindlin_normElastEnergy"]
        assert reference > 0
        u_n = res.contacts.loc[res.contacts["step"] == meta["iter"], "u_n"].sum()
        assert u_n == pytest.approx(reference, rel=1e-10)


@pytest.mark.slow
@pytest.mark.simulator
def test_the_clump_table_is_exported_next_to_the_spheres(clump_run, tmp_path):
    import pandas as pd
    from demsplit.results.exports.tables import export_tables

    res = demsplit.analyze(clump_run[0])
    written = export_tables(res, tmp_path / "csv", fmt="csv")
    assert tmp_path / "csv" / "clumps.csv" in written
    clumps = pd.read_csv(tmp_path / "csv" / "clumps.csv")
    pd.testing.assert_frame_equal(clumps, res.per_clump(), check_dtype=False)
