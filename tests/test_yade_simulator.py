"""Run Debian's YADE, export with demsplit.yade.snapshot, read, partition, and
compare with YADE's own energies and with hand calculations."""

from __future__ import annotations

import os
import subprocess
import sysconfig
from pathlib import Path

import numpy as np
import pytest
from conftest import require_program
from demsplit.physics.partition import partition, per_particle
from demsplit.readers.yade_snapshot import open_yade_snapshot

SAMPLE_SCRIPTS = Path(__file__).resolve().parent.parent / "sample_dumps" / "yade"
SITE = sysconfig.get_paths()["purelib"]  # where demsplit is installed (editable) for this Python


def run_yade(program: str, script: Path, out: Path, **env: str) -> str:
    """Run ``program -n -j1 -x script`` with demsplit importable; return stdout."""
    full_env = {**os.environ, "DEMSPLIT_SITE": SITE, "DEMSPLIT_OUT": str(out), **env}
    proc = subprocess.run(
        [program, "-n", "-j1", "-x", str(script)], cwd=out, env=full_env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "Traceback" not in proc.stdout + proc.stderr, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc.stdout


@pytest.mark.slow
@pytest.mark.simulator
def test_mindlin_normal_energy_matches_normElastEnergy(yade, tmp_path):
    run_yade(yade, SAMPLE_SCRIPTS / "mindlin_box.py", tmp_path, DEMSPLIT_ITER="16000", DEMSPLIT_EVERY="4000")
    for name in ("mindlin_box.h5", "mindlin_box.npys"):
        run = open_yade_snapshot(tmp_path / name)
        assert len(run) == 4
        n_wall = 0
        for k, frame in enumerate(run):
            e = partition(frame.contacts, run.scene, frame.particles)
            reference = run.meta(k)["law_energies"]["mindlin_normElastEnergy"]
            assert reference > 0
            assert e.u_n.sum() == pytest.approx(reference, rel=1e-10)
            n_wall += int((frame.contacts["wall"] >= 0).sum())
        assert n_wall > 0


@pytest.mark.slow
@pytest.mark.simulator
def test_cundallstrack_energy_matches_elastPotential(yade, tmp_path):
    run_yade(yade, SAMPLE_SCRIPTS / "cundall_periodic.py", tmp_path, DEMSPLIT_ITER="6000", DEMSPLIT_EVERY="2000")
    run = open_yade_snapshot(tmp_path / "cundall_periodic.npys")
    assert run.frame(0).box.periodic == (True, True, True)
    for k, frame in enumerate(run):
        e = partition(frame.contacts, run.scene, frame.particles)
        meta = run.meta(k)
        total = (e.u_n + e.u_t).sum()
        assert meta["energy"]["elastPotential"] > 0 and e.u_t.sum() > 0
        assert total == pytest.approx(meta["energy"]["elastPotential"], rel=1e-10)
        assert total == pytest.approx(meta["law_energies"]["cundallstrack_elasticEnergy"], rel=1e-10)


SHARES_SCENE = """
import os, site
site.addsitedir(os.environ["DEMSPLIT_SITE"])
import demsplit.yade
from yade import utils
soft = O.materials.append(FrictMat(young=1e7, poisson=0.3, density=2600, frictionAngle=0.5))
stiff = O.materials.append(FrictMat(young=5e7, poisson=0.2, density=2600, frictionAngle=0.5))
R = 0.01
O.bodies.append([
    utils.sphere((0, 0, 0.5), R, material=soft),                     # 0: soft sphere on ...
    utils.sphere((0, 0, 0.5198), R, material=stiff),                 # 1: ... a stiff sphere, delta 2e-4
    utils.sphere((1.0099, 0, 0), R, material=stiff),                 # 2: stiff sphere on the soft Wall, delta 1e-4
    utils.sphere((0, 0, 2.0099), R, material=soft),                  # 3: soft sphere on the stiff Facet, delta 1e-4
    utils.sphere((3, 0, 0.0599), R, material=soft),                  # 4: soft sphere on the stiff Box, delta 1e-4
    utils.wall(1.0, axis=0, sense=1, material=soft),                 # 5
    utils.facet([(-0.1, -0.1, 2), (0.1, -0.1, 2), (0, 0.1, 2)], material=stiff),  # 6
    utils.box((3, 0, 0), (0.05, 0.05, 0.05), fixed=True, material=stiff),        # 7
])
O.engines = [ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb(), Bo1_Facet_Aabb(), Bo1_Box_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom(),
                     Ig2_Box_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_MindlinPhys()],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    PyRunner(command='demsplit.yade.snapshot(os.path.join(os.environ["DEMSPLIT_OUT"], "shares.npys"))',
             iterPeriod=1, initRun=True),
    NewtonIntegrator(gravity=(0, 0, 0))]
O.dt = 1e-7
O.run(1, True)
"""


@pytest.mark.slow
@pytest.mark.simulator
def test_shares_of_pair_wall_facet_box_by_hand(yade, tmp_path):
    script = tmp_path / "shares.py"
    script.write_text(SHARES_SCENE)
    run_yade(yade, script, tmp_path)
    run = open_yade_snapshot(tmp_path / "shares.npys")
    frame = run.frame(0)
    c = frame.contacts
    row = {(int(a), int(w)): k for k, (a, w) in enumerate(zip(c["id1"], c["wall"]))}
    pair, wall, facet, box = row[(0, -1)], row[(2, 0)], row[(3, 1)], row[(4, 2)]
    assert [w.kind for w in run.scene.walls] == ["yade_wall", "facet", "box"]
    assert c["id2"][pair] == 1 and (c["id2"][[wall, facet, box]] == -1).all()

    # compliances c = (1 - nu^2)/E: soft (1 - 0.09)/1e7 = 9.1e-8, stiff (1 - 0.04)/5e7 = 1.92e-8 (1/Pa)
    soft_n = 9.1e-8 / (9.1e-8 + 1.92e-8)  # = 0.8257713248638839
    stiff_n = 1.92e-8 / (9.1e-8 + 1.92e-8)  # = 0.1742286751361162
    # Mindlin compliances 2(2 - nu)(1 + nu)/E: soft 2*1.7*1.3/1e7 = 4.42e-7, stiff 2*1.8*1.2/5e7 = 8.64e-8
    soft_t = 4.42e-7 / (4.42e-7 + 8.64e-8)  # = 0.8364875094625284
    stiff_t = 8.64e-8 / (4.42e-7 + 8.64e-8)
    e = partition(c, run.scene, frame.particles)
    np.testing.assert_allclose(e.share_n1[[pair, wall, facet, box]], [soft_n, stiff_n, soft_n, soft_n], rtol=1e-14)
    np.testing.assert_allclose(e.share_t1[[pair, wall, facet, box]], [soft_t, stiff_t, soft_t, soft_t], rtol=1e-14)

    # energy 2/5 kno delta^2.5, kno = 4/3 E* sqrt(R*), E* = 1/(9.1e-8 + 1.92e-8) = 9.074410163339383e6 Pa;
    # R* as YADE built it: pair and Wall R/2 = 0.005 m, Box R/2, Facet (2R R)/(3R) = 2R/3 m
    E_star = 1.0 / (9.1e-8 + 1.92e-8)
    R = 0.01
    kno = 4.0 / 3.0 * E_star * np.sqrt([R / 2, R / 2, 2 * R / 3, R / 2])
    np.testing.assert_allclose(c["kno"][[pair, wall, facet, box]], kno, rtol=1e-13)
    delta = np.array([2e-4, 1e-4, 1e-4, 1e-4])
    np.testing.assert_allclose(c["delta"][[pair, wall, facet, box]], delta, rtol=1e-10)
    np.testing.assert_allclose(e.u_n[[pair, wall, facet, box]], 0.4 * kno * delta**2.5, rtol=1e-9)

    # contact point x_c = x1 + (r1 - share_n1 delta) n, with n from the particle towards its partner
    cp = e.cp[[pair, wall, facet, box]]
    np.testing.assert_allclose(cp[0], [0, 0, 0.5 + R - soft_n * 2e-4], atol=1e-15)  # n = +z
    np.testing.assert_allclose(cp[1], [1.0099 - (R - stiff_n * 1e-4), 0, 0], atol=1e-15)  # n = -x
    np.testing.assert_allclose(cp[2], [0, 0, 2.0099 - (R - soft_n * 1e-4)], atol=1e-15)  # n = -z
    np.testing.assert_allclose(cp[3], [3, 0, 0.0599 - (R - soft_n * 1e-4)], atol=1e-15)  # n = -z


SMALL_SCENE = """
import os, site
site.addsitedir(os.environ["DEMSPLIT_SITE"])
import demsplit.yade
from yade import utils
soft = O.materials.append(FrictMat(young=1e7, poisson=0.3, density=2600, frictionAngle=0.5))
stiff = O.materials.append(FrictMat(young=5e7, poisson=0.2, density=2600, frictionAngle=0.5))
k = 0
for i in range(2):
    for j in range(2):
        for m in range(3):
            O.bodies.append(utils.sphere((0.0099 + 0.0197 * i, 0.0099 + 0.0196 * j, 0.0098 + 0.0195 * m), 0.01,
                                         material=soft if k % 2 else stiff))
            k += 1
O.bodies.append([utils.wall(0, axis=2, sense=1, material=stiff), utils.wall(0, axis=0, sense=1, material=soft)])
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_MindlinPhys()],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    PyRunner(command='demsplit.yade.snapshot(os.path.join(os.environ["DEMSPLIT_OUT"], "small.npys"))',
             iterPeriod=20, initRun=False),
    NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.2)]
O.dt = 2e-6
O.run(41, True)
"""


def per_particle_energy(path: Path) -> list[np.ndarray]:
    run = open_yade_snapshot(path)
    out = []
    for frame in run:
        e = partition(frame.contacts, run.scene, frame.particles)
        table, _ = per_particle(frame.contacts, e, frame.particles, len(run.scene.walls))
        out.append(table["u"])
    return out


@pytest.mark.slow
@pytest.mark.simulator
def test_mpfr150_build_gives_the_same_per_particle_energies(yade, tmp_path):
    mpfr = require_program("yade-mpfr150")
    script = tmp_path / "small.py"
    script.write_text(SMALL_SCENE)
    (tmp_path / "double").mkdir()
    (tmp_path / "mpfr").mkdir()
    run_yade(yade, script, tmp_path / "double")
    run_yade(mpfr, script, tmp_path / "mpfr")
    double = per_particle_energy(tmp_path / "double" / "small.npys")
    high = per_particle_energy(tmp_path / "mpfr" / "small.npys")
    assert len(double) == len(high) == 2
    for u_d, u_h in zip(double, high):
        assert (u_d > 0).sum() >= 10
        # measured: 5.6e-14 relative after 40 steps (double rounding); 1e-11 leaves a margin
        np.testing.assert_allclose(u_h, u_d, rtol=1e-11, atol=1e-14 * u_d.max())
    run = open_yade_snapshot(tmp_path / "mpfr" / "small.npys")
    assert run.meta(0)["precision_name"] != "PrecisionDouble" and run.meta(0)["high_precision"]
    text = run.depth_text(0)
    frame = run.frame(0)
    assert len(text) == frame.n_contacts
    digits = [len(t.replace(".", "").replace("-", "").split("e")[0].lstrip("0")) for t in text]
    assert min(digits) > 100  # the build's 150 digits, not a double's 17
    np.testing.assert_allclose([float(t) for t in text], frame.contacts["delta"], rtol=1e-15)
    assert open_yade_snapshot(tmp_path / "double" / "small.npys").depth_text(0) is None
