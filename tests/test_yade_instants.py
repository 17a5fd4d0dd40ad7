"""YADE states saved the ways users save them, of scenes in motion, against YADE's own numbers of that instant.

sample_dumps/yade/saved_instants.py runs one scene per YADE law of the registry (and a periodic cell under
compression, rotating clumps, Walls, Facets, a Box, inline materials), every scene with particles falling and
colliding, and saves each four ways: from a PyRunner before the InteractionLoop, between it and the
NewtonIntegrator, at the end of O.engines, and after ``O.run(N, True)``. Beside each state the YADE script
writes, at the moment of the save, YADE's own numbers of that instant: the law's energy functions
(``normElastEnergy()``, ...), ``O.energy``, sums of each mode over the real interactions' ``i.phys`` and
``i.geom`` (the law's energy as its source defines it, e.g. 2/5 kno penetrationDepth^2.5),
``O.interactions.countReal()``, and the spheres' positions at the InteractionLoop that computed the forces.
sample_dumps/yade/jcfpm_example.py runs YADE's own JCFpm example (trimmed) and saves after ``O.run``.
"""

from __future__ import annotations

import json
from pathlib import Path

import demsplit
import numpy as np
import pytest
from conftest import require_program
from demsplit.cli import main
from demsplit.physics import laws
from demsplit.readers.yade_state import convert_states, state_files
from demsplit.results.report import text_summary, write_html
from demsplit.results.store import load_results
from demsplit.scene import Material
from test_yade_simulator import SAMPLE_SCRIPTS, run_yade

pytestmark = pytest.mark.simulator

SCENES = {
    "mindlin": "yade:Law2_ScGeom_MindlinPhys_Mindlin",
    "cundall": "yade:Law2_ScGeom_FrictPhys_CundallStrack",
    "periodic": "yade:Law2_ScGeom_MindlinPhys_Mindlin",
    "clumps": "yade:Law2_ScGeom_MindlinPhys_Mindlin",
    "viscel": "yade:Law2_ScGeom_ViscElPhys_Basic",
    "viscofrict": "yade:Law2_ScGeom_ViscoFrictPhys_CundallStrack",
    "hertz_linear": "yade:Law2_ScGeom_MindlinPhys_HertzWithLinearShear",
    "deresiewitz": "yade:Law2_ScGeom_MindlinPhys_MindlinDeresiewitz",
    "adhesion": "yade:Law2_ScGeom_MindlinPhys_Mindlin",
    "cohfrict": "yade:Law2_ScGeom6D_CohFrictPhys_CohesionMoment",
    "jcfpm": "yade:Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM",
}
TAGS = ("before", "between", "end", "run")
"""Where the state was saved from: a PyRunner before the InteractionLoop, between it and NewtonIntegrator, at
the end of O.engines; after O.run(N, True)."""
FUNCTION_MODES = {
    "normElastEnergy": ("u_n", "u_adh"),
    "elasticEnergy": ("u_n", "u_t"),
    "shearElastEnergy": ("u_t",),
    "bendingElastEnergy": ("u_r",),
    "twistElastEnergy": ("u_tw",),
    "elastPotential": ("u_n", "u_t"),
}
"""The modes whose sum each of YADE's own energies is (YADE's sources: HertzMindlin.cpp, ElasticContactLaw.cpp,
CohesiveFrictionalContactLaw.cpp; normElastEnergy includes the adhesion work where includeAdhesion is set)."""
VISCEL_MODULI = {0: Material(2e7, 0.3), 1: Material(1e8, 0.2)}
"""The split's moduli for the ViscEl scene, whose law does not read E and nu (--material)."""


def test_every_supported_yade_law_has_a_scene():
    assert set(SCENES.values()) == {k for k in laws.supported() if k.startswith("yade:")}


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> Path:
    """Every scene's states and their JSON, converted once (one YADE process) into ``cache``."""
    yade = require_program("yade")
    out = tmp_path_factory.mktemp("instants")
    run_yade(yade, SAMPLE_SCRIPTS / "saved_instants.py", out)
    run_yade(yade, SAMPLE_SCRIPTS / "jcfpm_example.py", out)
    assert not convert_states(state_files(out), out / "cache")[1]
    return out


def states(out: Path, scene: str) -> list[Path]:
    return [state for tag in TAGS for state in state_files(Path(f"{out}/{scene}-{tag}.*"))]


def reference(state: Path) -> dict:
    return json.loads(Path(f"{state}.json").read_text())


_analysed: dict = {}


def analysed(out: Path, scene: str):
    """The four states of a scene analysed as one run (once per module)."""
    if scene not in _analysed:
        _analysed[scene] = demsplit.analyze(
            states(out, scene), state_cache=out / "cache", materials=VISCEL_MODULI if scene == "viscel" else None
        )
    return _analysed[scene]


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_totals_and_contacts_are_those_of_the_saved_instant(saved, scene):
    """Per mode, demsplit's totals equal YADE's own energy functions and sums over i.phys, and the contacts
    are the real interactions YADE had, whichever place in the engine loop the state was saved from."""
    res = analysed(saved, scene)
    assert res.provenance["model"]["law"] == SCENES[scene]
    frames = res.frames.set_index("step")
    assert len(frames) == len(TAGS)
    worst = []  # relative differences, printed for docs/yade.md (pytest -s)
    for state in states(saved, scene):
        ref = reference(state)
        fr = frames.loc[ref["iter"]]
        assert fr["n_contacts"] == ref["count_real"] > 0, state.name
        own = {**ref["law_energies"]}
        if ref["tag"] != "before":  # O.energy's elastic entry is zeroed by ForceResetter before the InteractionLoop
            own.update({k: v for k, v in ref["energy"].items() if k == "elastPotential"})
        pairs = [((state.name, mode), fr[mode], value) for mode, value in ref["sums"].items()]
        pairs += [
            ((state.name, name), sum(fr[m] for m in FUNCTION_MODES[name] if m in fr), value)
            for name, value in own.items()
        ]
        for what, ours, value in pairs:
            assert value != 0 and ours == pytest.approx(value, rel=1e-9), what
            worst.append(abs(ours - value) / abs(value))
    print(f"\n{scene}: {len(worst)} totals, largest relative difference {max(worst):.1e}")


def test_each_law_has_its_own_energies_checked(saved):
    """The scenes exercise YADE's own functions where the law has them (else the sums over i.phys)."""
    names = {scene: set(reference(states(saved, scene)[-1])["law_energies"]) for scene in SCENES}
    assert names["mindlin"] == names["adhesion"] == {"normElastEnergy"}
    assert names["cundall"] == names["viscofrict"] == {"elasticEnergy"}
    assert names["cohfrict"] == {"normElastEnergy", "shearElastEnergy", "bendingElastEnergy", "twistElastEnergy"}
    assert "elastPotential" in reference(states(saved, "cundall")[-1])["energy"]


@pytest.mark.parametrize("scene", ["mindlin", "cundall", "periodic", "clumps", "cohfrict", "jcfpm"])
def test_positions_are_those_of_the_forces_instant(saved, scene):
    """The particle table holds the positions the saved forces were computed from: the saved ones, or stepped
    back by v dt (a clump's members along its rotation) when saved after the integrator moved them, in the
    periodic cell of that instant."""
    res = analysed(saved, scene)
    for state in states(saved, scene):
        ref = reference(state)
        p = res.particles[res.particles["step"] == ref["iter"]].set_index("id")
        expected = np.array([ref["positions"][str(i)] for i in p.index])
        # measured: 0 for free spheres, 7e-18 m in the cell, 7e-13 m for clump members (spheres of 2.5-3.5 mm)
        np.testing.assert_allclose(p[["x", "y", "z"]].to_numpy(), expected, rtol=0, atol=1e-11, err_msg=state.name)


def test_the_states_are_in_motion(saved):
    """At every save of every scene particles move (above 0.1 m/s, the fastest of them) and contacts have
    just formed (in the last 100 iterations), and its energy changes from one save to the next."""
    for scene in SCENES:
        refs = [reference(s) for s in states(saved, scene)]
        assert all(r["max_speed"] > 0.1 and r["made_in_last_100"] > 0 for r in refs), scene
        assert len({r["sums"]["u_n"] for r in refs}) == len(refs), scene


def test_inline_materials_give_the_material_split(saved):
    """Facets and a Box made with material=FrictMat(...) inline (not in O.materials, all with id -1), and Walls of
    two inline materials, keep their own moduli, numbered after O.materials: the normal share of each wall
    contact is the compliance ratio (1 - nu^2)/E of its two materials, not 50/50."""
    for scene, inline in (("mindlin", {2: (1e9, 0.3), 3: (5e8, 0.25)}), ("clumps", {2: (3e8, 0.3), 3: (6e8, 0.2)})):
        res = analysed(saved, scene)
        mats = {int(t): (m["E"], m["nu"]) for t, m in res.provenance["scene"]["materials"].items()}
        assert {t: v for t, v in mats.items() if t >= 2} == inline
        wall_types = np.array([w["type"] for w in res.provenance["scene"]["walls"]])
        c = res.contacts[res.contacts["wall"] >= 0]
        t1 = res.particles.set_index(["step", "id"])["type"].loc[list(zip(c["step"], c["id1"]))].to_numpy()
        t2 = wall_types[c["wall"].to_numpy()]
        c1, c2 = ([(1 - mats[t][1] ** 2) / mats[t][0] for t in types] for types in (t1, t2))
        expected = np.array(c1) / (np.array(c1) + np.array(c2))
        np.testing.assert_allclose(c["share_n1"].to_numpy(), expected, rtol=1e-12)
        on_inline = np.isin(t2, list(inline))
        assert on_inline.sum() > 0 and np.all(expected[on_inline] > 0.7), scene  # the particle is the softer


def test_viscel_needs_the_split_moduli(saved, tmp_path, capsys):
    """ViscEl's stiffness comes from the materials' kn, ks: the law never reads young and poisson (ViscElMat's
    defaults), so the split's moduli are refused without --material and taken from it with it."""
    state = states(saved, "viscel")[-1]
    assert main(["run", str(state), "-o", str(tmp_path / "no.h5"), "-q", "--state-cache", str(saved / "cache")]) == 2
    err = capsys.readouterr().err
    assert "never reads its young and poisson" in err and "--material" in err
    assert not (tmp_path / "no.h5").exists()
    assert (
        main(
            [
                "run",
                str(state),
                "-o",
                str(tmp_path / "yes.h5"),
                "-q",
                "--state-cache",
                str(saved / "cache"),
                "--material",
                "0:3e7:0.25",
                "--material",
                "1:9e7:0.2",
            ]
        )
        == 0
    )
    materials = load_results(tmp_path / "yes.h5").provenance["scene"]["materials"]
    assert (materials["0"]["E"], materials["0"]["nu"], materials["1"]["E"]) == (3e7, 0.25, 9e7)


def test_jcfpm_example_runs_through_demsplit_run(saved, tmp_path):
    """YADE's own JCFpm example (smooth joint): contacts on the joint overlap by more than the smaller radius
    by design, and the law says so; its totals are YADE's sums over i.phys."""
    state = saved / "jcfpm_example.yade.gz"
    ref = reference(state)
    assert ref["on_joint"] > 0
    assert main(["run", str(state), "-o", str(tmp_path / "j.h5"), "-q", "--state-cache", str(saved / "cache")]) == 0
    fr = load_results(tmp_path / "j.h5").frames.iloc[0]
    assert fr["n_contacts"] == ref["count_real"]
    for mode, value in ref["sums"].items():
        assert fr[mode] == pytest.approx(value, rel=1e-9), mode


def test_the_report_prints_yades_own_total(saved, tmp_path):
    """A run that tracks O.energy: the terminal summary and the HTML report print YADE's elastPotential beside
    demsplit's u_n + u_t."""
    out = tmp_path / "c.h5"
    assert (
        main(["run", *map(str, states(saved, "cundall")), "-o", str(out), "-q", "--state-cache", str(saved / "cache")])
        == 0
    )
    res = load_results(out)
    value = reference(states(saved, "cundall")[-1])["energy"]["elastPotential"]
    text = text_summary(res)
    assert f"YADE's own O.energy['elastPotential'] = {value:.10g} J, demsplit's u_n + u_t" in text
    html = write_html(res, tmp_path / "r.html").read_text()
    assert "YADE&#x27;s own O.energy[&#x27;elastPotential&#x27;]" in html
    before = text_summary(res, step=int(reference(states(saved, "cundall")[0])["iter"]))
    assert "ForceResetter zeroes it" in before


def test_info_lists_every_material_of_the_states(saved):
    """demsplit info on a glob of states: each material id with its split moduli (the inline ones numbered
    after O.materials), or why it has none and the option that gives them."""
    from demsplit.inspection import describe_file

    text = describe_file(Path(f"{saved}/mindlin-*"))
    assert "YADE saved state(s), 4" in text and "1 box, 10 facet" in text
    assert "2: E=1e+09 Pa nu=0.3 (inline FrictMat of body" in text and "3: E=5e+08 Pa nu=0.25" in text
    text = describe_file(states(saved, "viscel")[-1])
    assert "0: no moduli for the split" in text and "--material 0:E:NU" in text and "not analysable" in text
