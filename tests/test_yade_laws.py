"""The YADE laws of the registry against Debian's YADE itself (sample_dumps/yade/laws_box.py).

For each law one small scene (two materials, spheres in a box of facets) is run
by ``yade`` with demsplit's snapshot exporter. demsplit's totals per mode equal
YADE's own energy functions where the law has them (CohFrict's normElastEnergy,
shearElastEnergy, bendingElastEnergy, twistElastEnergy; ViscoFrict's
elasticEnergy) to 1e-10 relative, and otherwise an independent recomputation
from the raw interaction state in the snapshot (not through demsplit's reader or
laws). Every mode is conserved by the split.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import require_program
from demsplit.errors import UnsupportedModelError
from demsplit.physics.partition import partition, per_particle
from demsplit.readers.yade_snapshot import _open_store, open_yade_snapshot
from demsplit.yade import write_snapshot
from test_yade_simulator import SAMPLE_SCRIPTS, run_yade

LAWS = {
    "viscel": "yade:Law2_ScGeom_ViscElPhys_Basic",
    "viscofrict": "yade:Law2_ScGeom_ViscoFrictPhys_CundallStrack",
    "hertz_linear": "yade:Law2_ScGeom_MindlinPhys_HertzWithLinearShear",
    "deresiewitz": "yade:Law2_ScGeom_MindlinPhys_MindlinDeresiewitz",
    "cohfrict": "yade:Law2_ScGeom6D_CohFrictPhys_CohesionMoment",
    "jcfpm": "yade:Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM",
    "adhesion": "yade:Law2_ScGeom_MindlinPhys_Mindlin",
    "capillary": "yade:Law2_ScGeom_FrictPhys_CundallStrack",
}

pytestmark = pytest.mark.simulator


@pytest.fixture(scope="module", params=sorted(LAWS))
def law_run(request, tmp_path_factory):
    yade = require_program("yade")
    out = tmp_path_factory.mktemp(request.param)
    run_yade(yade, SAMPLE_SCRIPTS / "laws_box.py", out, DEMSPLIT_LAW=request.param)
    return request.param, out / f"laws_box_{request.param}.h5"


def independent(law: str, t: dict) -> dict[str, float]:
    """Energy per mode from the raw interaction table of a snapshot, as the law's documentation says."""
    d = np.maximum(t["depth"], 0.0)
    fs2 = t["fsx"] ** 2 + t["fsy"] ** 2 + t["fsz"] ** 2 if "fsx" in t else None
    if law == "viscel":
        ks = t["ks"] > 0
        return {"u_n": float(np.sum(0.5 * t["kn"] * d**2)), "u_t": float(np.sum(fs2[ks] / (2 * t["ks"][ks])))}
    if law == "jcfpm":  # stored springs, bonds in tension included (no depth mask)
        fn2 = t["fnx"] ** 2 + t["fny"] ** 2 + t["fnz"] ** 2
        return {"u_n": float(np.sum(fn2 / (2 * t["kn"]))), "u_t": float(np.sum(fs2 / (2 * t["ks"])))}
    if law in ("hertz_linear", "deresiewitz"):
        u = {"u_n": float(np.sum(0.4 * t["kno"] * d**2.5))}
        if law == "hertz_linear":
            u["u_t"] = float(np.sum(fs2 / (2 * t["kso"])))
        return u
    raise KeyError(law)


@pytest.mark.slow
def test_totals_per_mode_equal_yades_own_or_an_independent_sum(law_run):
    law, path = law_run
    run = open_yade_snapshot(path)
    assert run.scene.model.law == LAWS[law]
    store = _open_store(path)
    assert len(run) == 2
    for k, frame in enumerate(run):
        e = partition(frame.contacts, run.scene, frame.particles)
        assert not e.missing
        ours = {m.column: float(e.u[i].sum()) for i, m in enumerate(e.modes)}
        if e.u_adh is not None:
            ours["u_adh"] = float(e.u_adh.sum())
            assert ours["u_adh"] < 0
        assert ours["u_n"] > 0
        reference = run.meta(k)["law_energies"]
        if reference:  # the law's own energy functions
            for name, (_, modes) in run.scene.model.contact_law.simulator_energies.items():
                assert sum(ours[m] for m in modes) == pytest.approx(reference[name], rel=1e-10), name
        else:
            _, raw = store.snapshot(k)
            for mode, value in independent(law, raw["interactions"]).items():
                assert ours[mode] == pytest.approx(value, rel=1e-12, abs=1e-300), mode
        pt, wt = per_particle(frame.contacts, e, frame.particles, n_walls=len(run.scene.walls))
        for mode, total in ours.items():
            assert pt[mode].sum() + wt[mode].sum() == pytest.approx(total, rel=1e-12, abs=1e-300), mode


def test_the_quirks_the_laws_rely_on(law_run):
    """Deresiewitz in 2023.02a has no shear spring (its law has the normal mode only); HertzWithLinearShear keeps
    its shear stiffness in kso; CohFrict bonds hold energy in tension (kept with delta < 0)."""
    law, path = law_run
    _, raw = _open_store(path).snapshot(1)
    t = raw["interactions"]
    if law == "adhesion":  # the DMT force is 4 pi R* gamma; its work is apart from the elastic energy
        run = open_yade_snapshot(path)
        assert run.scene.model.params["include_adhesion"] is True
        c = run.frame(1).contacts
        np.testing.assert_allclose(
            c["adhesion_force"][c["wall"] < 0], 4 * np.pi * 0.5 / (1 / c["r1"] + 1 / c["r2"])[c["wall"] < 0], rtol=1e-12
        )
    if law == "capillary":  # without Debian-shipped tables every capillary force is 0: said, not assumed
        frame = open_yade_snapshot(path).frame(1)
        assert np.all(t["fcapx"] == 0) and any("every capillary force is 0" in n for n in frame.notes)
        meta, tables = _open_store(path).snapshot(1)
        tables["interactions"]["fcapx"] = np.full(len(t["fcapx"]), 1e-3)  # bridges with forces: work unknown
        with_forces = path.with_name("with_forces.npys")
        write_snapshot(with_forces, meta, tables, format="npy")
        with pytest.raises(UnsupportedModelError, match="nonzero capillary forces"):
            open_yade_snapshot(with_forces).frame(0)
    if law == "deresiewitz":  # the exporter writes what the law reads: the normal force and kno
        assert "fsx" not in t and open_yade_snapshot(path).scene.model.contact_law.modes == ("u_n",)
    if law == "hertz_linear":
        assert "ks" not in t and np.all(t["kso"] > 0) and np.any(t["fsx"] != 0)
    if law in ("cohfrict", "jcfpm"):
        frame = open_yade_snapshot(path).frame(1)
        assert len(frame.contacts["delta"]) == len(t["depth"])  # separated bonds are contacts
        if law == "cohfrict":
            assert np.all(frame.contacts["kr"] > 0) and np.any(frame.contacts["mtw"] > 0)
        else:
            assert np.any(frame.contacts["delta"] < 0)  # bonds in tension hold energy
