"""LIGGGHTS contact models checked against the real program: hooke kn, hertz kt.

The analytic stacks of sample_dumps/liggghts/analytic are rerun with
``model hooke`` (pair and wall). At rest the damping force vanishes, so each contact's dumped
normal force is the elastic kn delta, and the elastic energy demsplit computes,
½ kn delta², must equal ½ |F_n| delta with LIGGGHTS' own F_n.
"""

from __future__ import annotations

import shutil
import subprocess

import demsplit
import numpy as np
import pytest
from conftest import SAMPLES
from demsplit.readers import open_run
from demsplit.readers.lammps_dump import open_dump

V = 0.5  # characteristicVelocity (m/s)


@pytest.fixture(scope="module")
def hooke_run(tmp_path_factory, request):
    from conftest import require_program

    liggghts = require_program("liggghts")
    work = tmp_path_factory.mktemp("hooke")
    for f in (SAMPLES / "liggghts" / "analytic").iterdir():
        if f.suffix in (".stl",) or f.name == "in.analytic":
            shutil.copy(f, work / f.name)
    script = (work / "in.analytic").read_text()
    assert script.count("model hertz") == 2
    script = script.replace("model hertz", "model hooke").replace(
        "pair_style      gran", f"fix mV all property/global characteristicVelocity scalar {V}\npair_style      gran", 1
    )
    (work / "in.hooke").write_text(script)
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", "in.hooke"], cwd=work, capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return work / "in.hooke"


@pytest.mark.slow
def test_hooke_energy_is_half_kn_delta_squared_with_liggghts_kn(hooke_run):
    run = open_run(hooke_run)
    assert run.scene.model.law == "liggghts:hooke" and run.scene.model.params["characteristic_velocity"] == V
    frame = run.frame(0)
    res = demsplit.analyze(hooke_run)
    c = res.contacts
    # LIGGGHTS' own normal force of every contact, from the dumps (force_normal columns)
    forces = {}
    for dump, names in ((run.pairs, run._pair_names), (run.walls, run._wall_names)):
        f = open_dump(dump.path).frame(0)
        fn = np.linalg.norm(np.stack([f.columns[names[k]] for k in ("fnx", "fny", "fnz")], -1), axis=1)
        ids = f.int_column(names["id1"])
        other = f.int_column(names["id2"]) if "id2" in names else np.full(len(ids), -1)
        for a, b, F in zip(ids, other, fn):
            forces[(int(a), int(b))] = F
    assert len(forces) == len(c) == frame.n_contacts == 5
    for row in c.itertuples():
        F = forces[(row.id1, row.id2)]
        assert row.u_n == pytest.approx(0.5 * F * row.delta, rel=1e-8)
    # and the hertz energy would be a different number: the model matters
    hertz = demsplit.hertz_energy(c.delta.to_numpy(), 1e-3, np.inf, 1e8, 0.25, 1e8, 0.25)
    assert not np.allclose(hertz, c.u_n.to_numpy(), rtol=1e-2, atol=0)


def test_hertz_kt_reproduces_liggghts_tangential_force():
    """-kt shear with demsplit's kt = 8 G* sqrt(R* delta) reproduces the dumped
    force_tangential of the packing's pair contacts (first frame, full precision).

    The two differ only by tangential damping (-gamma_t v_tr) and by the Coulomb
    cap of sliding contacts, so most contacts agree to well under 1 %; a kt off
    by any constant factor (the paper's (1-2nu)/G instead of (2-nu)/G in G*,
    say) would be off by tens of percent everywhere."""
    from demsplit.physics.bodies import FrameContacts
    from demsplit.physics.elastic import overlap
    from demsplit.physics.formulas import hertz_kt_formula
    from demsplit.physics.moduli import effective_radius, effective_shear_modulus

    run = open_run(SAMPLES / "liggghts" / "packing" / "in.packing")
    frame = run.frame(0)
    c = frame.contacts
    pair = np.flatnonzero(c["wall"] < 0)
    f = open_dump(run.pairs.path).frame(0)
    names = run._pair_names
    ft = np.stack([f.columns[names[k]] for k in ("ftx", "fty", "ftz")], -1)
    bodies = FrameContacts(c, run.scene, frame.particles).bodies
    R = effective_radius(c["r1"][pair], c["r2"][pair])
    G = effective_shear_modulus(bodies.E1[pair], bodies.nu1[pair], bodies.E2[pair], bodies.nu2[pair])
    kt = hertz_kt_formula(overlap(c["delta"][pair]), R, G)
    shear = np.stack([c[k][pair] for k in ("shearx", "sheary", "shearz")], -1)
    rel = np.linalg.norm(-kt[:, None] * shear - ft, axis=1) / np.linalg.norm(ft, axis=1)
    assert len(rel) > 500
    assert np.median(rel) < 2e-3 and np.percentile(rel, 90) < 2e-2
    # and demsplit's u_t is that spring's energy
    e = demsplit.partition(c, run.scene, frame.particles)
    assert e.u_t[pair] == pytest.approx(0.5 * kt * np.einsum("ij,ij->i", shear, shear), rel=1e-12)
