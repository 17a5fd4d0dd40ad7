"""Every LIGGGHTS contact law of demsplit against Debian's LIGGGHTS itself.

One small undamped run per model (sample_dumps/liggghts/models: 175 spheres of two
materials, a mesh floor, primitive walls; coefficientRestitution 1, so every damping
coefficient is 0 and the dumped forces are the elastic ones). For every dumped contact:

- the elastic normal force of demsplit's law, dU_n/d(delta) (``normal_force``), equals
  LIGGGHTS' dumped normal force; with cohesion, the dumped force is that force plus the
  cohesion force, which is d(u_adh)/d(delta) of demsplit's cohesion work (``thornton_ning``:
  the derivative along the Hertzian branch through the stored overlap and force);
- the tangential force of demsplit's energy, -dU_t/d(shear) = -2 u_t shear/|shear|^2, equals
  the dumped force_tangential (at the Coulomb cap too: the output evaluation rescales a capped
  spring again only by rounding, as the step's evaluation already capped it);
- with a rolling spring, the rolling torque demsplit reads from the history obeys LIGGGHTS'
  cap mu_r |F_n| R* (``luding``: mu_r |F_n + kc delta - f0| R*, kc = f0 = 0 in these runs), and
  some contacts come near it. ``rolling_friction luding``
  writes the torque it applies into the history, so the dumped ``torque`` minus the moment of
  the tangential force is that torque, |M_r| = sqrt(2 kr u_r); the ``epsd*`` models apply one more
  spring increment than they store at an output step (``rolling_model_epsd.h``: the history is
  written only when ``computeflag``), so their dumped torque is not compared;
- the dumped history is laid out as demsplit's law says (the dump is read by its names);
- totals per mode are conserved by the split, to 1e-12, and for every model equal an independent
  recomputation from LIGGGHTS' dumped forces, torques and history (``liggghts_reference.py``; the
  liquid bridges' here) to 1e-12;
- liquid bridges (``cohesion easo/capillary/viscous``, ``washino/capillary/viscous``; their runs
  also dump the liquid content ``f_surfaceLiquidContent``, and set fluidViscosity 0, so that the
  dumped forces hold no viscous part): the pair dump lists bridges apart (negative overlap) and the
  wall dump contacts apart with and without a bridge; for every one, touching or apart, the dumped
  normal force is Hertz's plus the capillary force of LIGGGHTS' C++ transcribed independently
  (``liggghts_bridges.py``), and demsplit's u_adh is that force integrated from rupture by quadrature.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import demsplit
import liggghts_reference
import mpmath
import numpy as np
import pytest
from conftest import SAMPLES
from demsplit.physics.bodies import FrameContacts, LawRows
from demsplit.readers import open_run
from demsplit.readers.lammps_dump import open_dump
from liggghts_bridges import BRIDGE_MODELS, liggghts_capillary
from liggghts_reference import has_reference, submodels
from scipy.integrate import quad

_spec = importlib.util.spec_from_file_location("make_run", SAMPLES / "liggghts" / "models" / "make_run.py")
make_run = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_run)

pytestmark = pytest.mark.simulator


_RUNS: dict[str, Path] = {}


def liggghts_run(name: str, tmp_path_factory) -> tuple[str, Path]:
    """Model ``name`` run by LIGGGHTS once per session (the fixtures below share it): (name, in.run)."""
    if name not in _RUNS:
        from conftest import require_program

        liggghts = require_program("liggghts")
        script = make_run.write_run(name, tmp_path_factory.mktemp(name.replace("/", "_")))
        make_run.run(script, liggghts)
        _RUNS[name] = script
    return name, _RUNS[name]


ROLLING_SPRINGS = sorted(
    name for name, (words, _, _) in make_run.MODELS.items() if submodels(words).get("rolling_friction", "cdt") != "cdt"
)
"""The models with a rolling spring (``rolling_friction`` but ``cdt``, which has none)."""


FEW_CONTACTS = {"no_history": 20}
"""Contacts a model's run holds at least in each test, where not the usual 100 per frame (200 with the mesh floor)
and 300 in all: without friction and damping the particles of ``no_history`` keep bouncing (22-27 contacts per
frame)."""


def at_least(name: str, usual: int) -> int:
    return FEW_CONTACTS.get(name, usual)


def history_known(c: dict) -> np.ndarray:
    """Per contact, whether demsplit has its history (not a primitive-wall row of a law with one)."""
    return ~c["history_unknown"].astype(bool) if "history_unknown" in c else np.ones(len(c["id1"]), bool)


@pytest.fixture(scope="module", params=sorted(make_run.MODELS))
def model_run(request, tmp_path_factory) -> tuple[str, Path]:
    return liggghts_run(request.param, tmp_path_factory)


@pytest.fixture(scope="module", params=ROLLING_SPRINGS)
def rolling_run(request, tmp_path_factory) -> tuple[str, Path]:
    return liggghts_run(request.param, tmp_path_factory)


def dumped(run, k: int, names: list[str]) -> dict[tuple[int, int], np.ndarray]:
    """LIGGGHTS' own values of the named columns of every contact of frame k, by (id1, id2 or -1 - mesh)."""
    out = {}
    for dump, cols in ((run.pairs, run._pair_names), (run.walls, run._wall_names)):
        f = open_dump(dump.path).frame(k)
        ids = f.int_column(cols["id1"])
        other = f.int_column(cols["id2"]) if "id2" in cols else -1 - f.int_column(cols["mesh_index"])
        values = np.stack([f.columns[cols[c]] for c in names], -1)
        for a, b, v in zip(ids, other, values):
            out[(int(a), int(b))] = v
    return out


def contact_keys(c: dict) -> list[tuple[int, int]]:
    """(id1, id2) of a pair, (id1, -1 - wall) of a mesh-wall contact (one mesh: wall 0)."""
    return [(int(a), int(b) if w < 0 else -1 - int(w)) for a, b, w in zip(c["id1"], c["id2"], c["wall"])]


@pytest.mark.slow
def test_forces_and_torques_are_liggghts_own(model_run):
    name, script = model_run
    run = open_run(script)
    law = run.scene.model.contact_law
    assert run.scene.model.law.startswith("liggghts:")
    compared = 0
    for k in range(len(run)):
        frame = run.frame(k)
        c, p = frame.contacts, frame.particles
        rows = LawRows(FrameContacts(c, run.scene, p), slice(None), law.key)
        theirs = dumped(run, k, ["fnx", "fny", "fnz", "tqx", "tqy", "tqz", "tqtx", "tqty", "tqtz"])
        normal = np.stack([c["nx"], c["ny"], c["nz"]], -1)
        force = law.normal_force(rows)
        if "u_adh" in law.modes:  # plus the cohesion force, -k A = d(u_adh)/d(delta)
            force = force + law.cohesion_force(rows)
        has_history = history_known(c)
        known = [i for i, key in enumerate(contact_keys(c)) if key in theirs and has_history[i]]
        assert len(known) > at_least(name, 100)
        for i in known:
            v = theirs[contact_keys(c)[i]]
            # the force on body 1 is -F_n n (n points from body 1 to body 2)
            assert -v[:3] @ normal[i] == pytest.approx(force[i], rel=1e-9, abs=1e-12 * abs(force).max()), (name, i)
        if "u_r" in law.modes:  # the rolling spring's torque never exceeds LIGGGHTS' cap mu_r |F_n| R*
            m = np.linalg.norm(np.stack([c[f"rolling_torque{x}"] for x in "xyz"], -1), axis=1)[known]
            fn = np.array([np.linalg.norm(theirs[contact_keys(c)[i]][:3]) for i in known])
            r = 1 / (1 / c["r1"][known] + 1 / c["r2"][known])
            cap = rows.type_pair(law.params["rolling_friction"]) * fn * r
            assert np.all(m <= cap * (1 + 1e-9)) and np.any(m > 0.5 * cap)
        compared += len(known)
    assert compared > at_least(name, 300)


def test_rolling_energy_and_history_layout(model_run):
    name, script = model_run
    run = open_run(script)
    law = run.scene.model.contact_law
    c = run.frame(0).contacts
    if "u_r" in law.modes:
        m = np.stack([c[f"rolling_torque{x}"] for x in "xyz"], -1)
        assert np.any(np.abs(m) > 0), "the rolling spring holds a torque in this run"
    # LIGGGHTS accepted a dump of exactly 38 + H columns (make_run.MODELS), H the history demsplit's law
    # declares, and the columns read by name are the law's: the history block sits after the 33 columns
    # of pos vel id force force_normal force_tangential torque torque_normal torque_tangential
    layout = run.script.local_computes["cpgl"].columns
    assert len(layout) == make_run.MODELS[name][2]
    assert layout[33 : 33 + len(law.history_columns())] == law.history_columns()
    assert layout[33 + len(law.history_columns())] == "area"


def test_totals_are_conserved_per_mode(model_run):
    name, script = model_run
    res = demsplit.analyze(script)
    modes = [m for m in ("u_n", "u_t", "u_r", "u_adh") if m in res.contacts]
    law = open_run(script).scene.model.contact_law
    assert set(modes) == set(law.modes) | {"u_n", "u_t"}
    for step, frame in res.raw.contacts.groupby("step"):  # as stored: the known parts add up
        parts = res.raw.particles[res.raw.particles["step"] == step]
        walls = res.raw.walls[res.raw.walls["step"] == step]
        for mode in modes:
            total = frame[mode].sum()
            assert parts[mode].sum() + walls[mode].sum() == pytest.approx(total, rel=1e-12, abs=1e-300), mode
        assert (frame[modes[0]] >= 0).all()
        if "u_r" in modes:
            assert frame["u_r"].sum() > 0
        if "u_adh" in modes:
            assert frame["u_adh"].sum() < 0  # the bonds hold the bodies together


def aligned(run, k: int, names: list[str]) -> tuple[dict, LawRows, np.ndarray, np.ndarray]:
    """Demsplit's contacts of frame k, the law's rows of them, the indices of those LIGGGHTS dumped with their
    history (pairs and mesh walls, not primitive walls) and LIGGGHTS' values of the named columns for them."""
    frame = run.frame(k)
    c, p = frame.contacts, frame.particles
    law = run.scene.model.contact_law
    rows = LawRows(FrameContacts(c, run.scene, p), slice(None), law.key)
    theirs = dumped(run, k, names)
    keys = contact_keys(c)
    has_history = history_known(c)
    known = np.array([i for i, key in enumerate(keys) if key in theirs and has_history[i]])
    return c, rows, known, np.array([theirs[keys[i]] for i in known])


def per_row(value, c: dict, known: np.ndarray) -> np.ndarray:
    """A law value (per row, or one scalar for all) at the rows ``known``."""
    return np.broadcast_to(value, c["delta"].shape)[known]


def test_tangential_force_is_minus_the_energy_gradient(model_run):
    """-dU_t/d(shear) = -2 u_t shear/|shear|^2 of demsplit's u_t (kt |shear|^2/2; tan_luding: kT2kcMax kt) is
    LIGGGHTS' dumped tangential force. A spring at the Coulomb cap needs no exception: the step that stored
    it capped it with the same F_n, so the output evaluation rescales it again by a factor 1 to rounding."""
    name, script = model_run
    run = open_run(script)
    law = run.scene.model.contact_law
    for k in range(len(run)):
        c, rows, known, ft = aligned(run, k, ["ftx", "fty", "ftz"])
        modes = law.energies(rows).modes
        if law.params["tangential"] == "no_history":  # no spring (no u_t), undamped: a tangential force of round-off
            assert "shearx" not in c and "u_t" not in modes and np.abs(ft).max() < 1e-15, name
            continue
        u_t = modes["u_t"][known]
        shear = np.stack([c[f"shear{x}"] for x in "xyz"], -1)[known]
        s2 = np.einsum("ij,ij->i", shear, shear)
        mine = -2.0 * np.divide(u_t, s2, out=np.zeros_like(u_t), where=s2 > 0)[:, None] * shear
        np.testing.assert_allclose(mine, ft, rtol=1e-9, atol=1e-12 * np.abs(ft).max(), err_msg=name)


def test_rolling_torque_is_liggghts_own(rolling_run):
    """The rolling torque LIGGGHTS applies, the dumped torque minus the moment -(r1 - delta/2) e_n x F_t of the
    tangential force (e_n from body 2 to body 1, surface_model_default.h), is that of demsplit's rolling energy,
    sqrt(2 kr u_r) along the stored torque M_r. ``luding`` applies the torque it stores; ``epsd*`` apply M_r plus
    one increment kr w_t dt that they do not store at an output step (rolling_model_epsd*.h write the history
    only when ``computeflag``), w = w1 - w2 (a wall: w1 (r1 - delta/2)/(r1 - delta)) without its normal part,
    capped at mu_r |F_n| R*: this checks demsplit's kr. At the cap the same formula holds on both sides of
    LIGGGHTS' rounding decision (the capped torque differs from the uncapped one by rounding only)."""
    name, script = rolling_run
    run = open_run(script)
    law = run.scene.model.contact_law
    assert "u_r" in law.modes
    for k in range(len(run)):
        c, rows, known, theirs = aligned(run, k, ["tqx", "tqy", "tqz", "ftx", "fty", "ftz", "fnx", "fny", "fnz"])
        n = np.stack([c[f"n{x}"] for x in "xyz"], -1)[known]
        r1, r2, delta = c["r1"][known], c["r2"][known], c["delta"][known]
        applied = -(theirs[:, :3] + (r1 - delta / 2)[:, None] * np.cross(-n, theirs[:, 3:6]))
        stored = np.stack([c[f"rolling_torque{x}"] for x in "xyz"], -1)[known]
        kr = per_row(law.kr(rows), c, known)
        m = np.linalg.norm(stored, axis=1)
        mine = (np.sqrt(2 * kr * law.energies(rows).modes["u_r"][known]) / np.where(m > 0, m, 1))[:, None] * stored
        if law.params["rolling"] != "luding":
            atoms = open_dump(run.atoms.path).frame(k)
            omega = dict(zip(atoms.int_column("id"), np.stack([atoms.columns[f"omega{x}"] for x in "xyz"], -1)))
            wall = np.isinf(r2)
            w1 = np.array([omega[int(i)] for i in c["id1"][known]])
            w2 = np.array([omega.get(int(i), np.zeros(3)) for i in c["id2"][known]])
            w = np.where(wall[:, None], w1 * ((r1 - delta / 2) / (r1 - delta))[:, None], w1 - w2)
            w_t = w - np.einsum("ij,ij->i", w, n)[:, None] * n
            mine = mine + (kr * run.script.timestep)[:, None] * w_t
            cap = (
                per_row(rows.type_pair(law.params["rolling_friction"]), c, known)
                * np.linalg.norm(theirs[:, 6:], axis=1)
                / (1 / r1 + 1 / r2)
            )
            mine *= np.minimum(1.0, cap / np.linalg.norm(mine, axis=1))[:, None]
        np.testing.assert_allclose(mine, applied, rtol=1e-9, atol=1e-12 * np.abs(applied).max(), err_msg=name)


def raw_contacts(run, k: int) -> dict[str, np.ndarray]:
    """Every contact LIGGGHTS dumped in frame k (pair rows, then mesh-wall rows), from the dump files alone:
    the normal force F (N, > 0 repulsive), delta, the tangential force ft and torque tq on body 1, the
    history columns by name, the radii, masses, types and liquid contents (NaN without; a wall: dry) of both bodies
    (a wall: r2 = m2 = inf, its type), the normal n from body 1 to body 2."""
    atoms = open_dump(run.atoms.path).frame(k)
    row = {int(i): j for j, i in enumerate(atoms.int_column("id"))}
    radius, mass, types = atoms.columns["radius"], atoms.columns["mass"], atoms.int_column("type")
    liquid = atoms.columns.get(LIQUID, np.full(len(radius), np.nan))
    wall_type = run.scene.walls[run.script.dumped_mesh_walls[0]].type
    parts = []
    for dump, cols in ((run.pairs, run._pair_names), (run.walls, run._wall_names)):
        f = open_dump(dump.path).frame(k)
        part = {name: f.columns[tok] for name, tok in cols.items()}
        vec = {v: np.stack([part[f"{v}{x}"] for x in "xyz"], -1) for v in ("fn", "ft", "tq")}
        i1 = np.array([row[int(i)] for i in f.int_column(cols["id1"])], dtype=np.int64)
        if "id2" in cols:
            i2 = np.array([row[int(i)] for i in f.int_column(cols["id2"])], dtype=np.int64)
            towards, r2, m2, t2 = np.stack([part[f"{x}2"] for x in "xyz"], -1), radius[i2], mass[i2], types[i2]
            c2 = liquid[i2]
        else:
            towards = np.stack([part[f"wall_cp{x}"] for x in "xyz"], -1)
            r2, t2, c2 = np.full(len(i1), np.inf), np.full(len(i1), wall_type), np.zeros(len(i1))
            m2 = np.full(len(i1), np.inf)
        n = towards - np.stack([part[f"{x}1"] for x in "xyz"], -1)
        n /= np.linalg.norm(n, axis=1)[:, None]
        part.update(
            F=-np.einsum("ij,ij->i", vec["fn"], n),
            ft=vec["ft"],
            tq=vec["tq"],
            n=n,
            r1=radius[i1],
            r2=r2,
            m1=mass[i1],
            m2=m2,
            t1=types[i1],
            t2=t2,
            c1=liquid[i1],
            c2=c2,
        )
        parts.append(part)
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0] if key in parts[1]}


LIQUID = "f_surfaceLiquidContent"
_BRIDGES: dict[tuple[str, int], tuple[np.ndarray, np.ndarray]] = {}


def bridge_reference(name: str, run, k: int, x: dict) -> tuple[np.ndarray, np.ndarray]:
    """The capillary force (N) of every contact of frame k (:func:`raw_contacts` ``x``) by LIGGGHTS' C++ transcribed
    in liggghts_bridges.py, and its work from rupture, int_{-s_rup}^delta F (J), by adaptive Gauss-Kronrod quadrature
    (scipy's QUADPACK, relative tolerance 1e-13) of that force in mpmath's 20 digits.
    Touching, a contact holds a bridge; apart, an easo one where LIGGGHTS' flag (history value contflag) is 1 (it
    forms at contact), a washino one wherever the gap is below rupture (it forms on approach too). Cached per run
    and frame: two tests use it."""
    key = (str(run.script.path), k)
    if key not in _BRIDGES:
        props = run.script.coefficients
        model = BRIDGE_MODELS[0] if "easo" in name else BRIDGE_MODELS[1]
        ratio, angle = props["maxSeparationDistanceRatio"], props["contactAngle"]
        mpmath.mp.dps = 20
        force, work = np.zeros(len(x["delta"])), np.zeros(len(x["delta"]))
        for i, d in enumerate(x["delta"]):
            f, rupture = liggghts_capillary(
                model,
                x["r1"][i],
                None if np.isinf(x["r2"][i]) else x["r2"][i],
                x["c1"][i],
                x["c2"][i],
                angle[x["t1"][i] - 1],
                angle[x["t2"][i] - 1],
                props["surfaceTension"],
                ratio,
                ratio * 1.1,
            )
            if not (d > 0 or (x["liquid_bridge"][i] == 1 if model == BRIDGE_MODELS[0] else -d < rupture)):
                continue
            force[i] = f(d)
            bounds = [float(-rupture), *([0.0] if d > 0 else []), float(d)]
            work[i] = sum(
                quad(lambda s, f=f: float(f(s)), a, b, epsabs=0, epsrel=1e-13, limit=200)[0]
                for a, b in zip(bounds, bounds[1:])
            )
        _BRIDGES[key] = force, work
    return _BRIDGES[key]


def reference_energies(name: str, run, k: int, x: dict) -> dict[str, np.ndarray]:
    """Energies of every dumped contact of model ``name`` computed from LIGGGHTS' dumped forces, torques and history
    and the source's stiffnesses, without demsplit's laws (liggghts_reference.py); with a liquid bridge, here:
    u_n = (2/5) F_el delta with F_el the dumped force less the capillary one, u_t = |F_t|^2/(2 kt) and u_adh the
    capillary force's work (:func:`bridge_reference`), 0 apart but for u_adh."""
    if name.startswith("cohesion_") and name not in ("cohesion_sjkr", "cohesion_sjkr2"):
        props = run.script.coefficients
        E, nu = props["youngsModulus"], props["poissonsRatio"]
        a, b = x["t1"] - 1, x["t2"] - 1
        G = 1 / (2 * (2 - nu[a]) * (1 + nu[a]) / E[a] + 2 * (2 - nu[b]) * (1 + nu[b]) / E[b])
        R = 1 / (1 / x["r1"] + 1 / x["r2"])
        F, d = x["F"], x["delta"]
        ft2 = np.einsum("ij,ij->i", x["ft"], x["ft"])
        f_cap, u_adh = bridge_reference(name, run, k, x)
        touching = d > 0
        kt = 8 * G * np.sqrt(R * np.maximum(d, 0))
        return {
            "u_n": np.where(touching, 0.4 * (F - f_cap) * d, 0.0),
            "u_t": np.where(touching, ft2 / (2 * np.where(touching, kt, 1.0)), 0.0),
            "u_adh": u_adh,
        }
    return liggghts_reference.reference_energies(make_run.MODELS[name][0], run, x)


REFERENCED = sorted(
    name
    for name, (words, _, _) in make_run.MODELS.items()
    if has_reference(words) or submodels(words).get("cohesion") in BRIDGE_MODELS
)
"""The models with an independent reference: liggghts_reference.py's, and the liquid bridges' here (every model:
:func:`test_every_model_has_an_independent_reference`)."""


@pytest.fixture(scope="module", params=REFERENCED)
def referenced_run(request, tmp_path_factory) -> tuple[str, Path]:
    return liggghts_run(request.param, tmp_path_factory)


@pytest.mark.slow
def test_totals_equal_an_independent_recomputation(referenced_run):
    """Per frame and mode, demsplit's total over the dumped contacts equals the sum of :func:`reference_energies`
    to 1e-12."""
    name, script = referenced_run
    run = open_run(script)
    res = demsplit.analyze(script)
    dumped_walls = [-1, *run.script.dumped_mesh_walls]
    for k, step in enumerate(sorted(res.contacts["step"].unique())):
        ours = res.contacts[(res.contacts["step"] == step) & res.contacts["wall"].isin(dumped_walls)]
        reference = reference_energies(name, run, k, raw_contacts(run, k))
        assert len(ours) == len(reference["u_n"]) > at_least(name, 200)
        assert set(reference) == {m for m in ("u_n", "u_t", "u_r", "u_adh") if m in ours}
        for mode, u in reference.items():
            assert ours[mode].sum() == pytest.approx(u.sum(), rel=1e-12, abs=0), (name, step, mode)


BRIDGES = sorted(
    name for name, (words, _, _) in make_run.MODELS.items() if submodels(words).get("cohesion") in BRIDGE_MODELS
)
"""The models with a liquid bridge."""


@pytest.fixture(scope="module", params=BRIDGES)
def bridge_run(request, tmp_path_factory) -> tuple[str, Path]:
    return liggghts_run(request.param, tmp_path_factory)


def test_liquid_bridges_are_liggghts_own(bridge_run):
    """Liquid bridges: the pair dump holds bridges apart (negative overlap), the wall dump contacts apart with and
    without one; for every dumped contact the normal force is Hertz's plus the capillary force of LIGGGHTS' C++
    (transcribed in liggghts_bridges.py, with the atom dump's liquid content) to 1e-9, and demsplit's u_adh is that
    force's work from rupture by quadrature (:func:`bridge_reference`), touching and apart."""
    name, script = bridge_run
    run = open_run(script)
    law = run.scene.model.contact_law
    assert law.params["cohesion"] in BRIDGE_MODELS
    res = demsplit.analyze(script)
    dumped_walls = [-1, *run.script.dumped_mesh_walls]
    props = run.script.coefficients
    counts = {"pairs apart": 0, "wall rows apart": 0}
    for k, step in enumerate(sorted(res.contacts["step"].unique())):
        x = raw_contacts(run, k)
        f_cap, work = bridge_reference(name, run, k, x)
        E, nu = props["youngsModulus"], props["poissonsRatio"]
        a, b = x["t1"] - 1, x["t2"] - 1
        Y = 1 / ((1 - nu[a] ** 2) / E[a] + (1 - nu[b] ** 2) / E[b])
        hertz = 4 / 3 * Y * np.sqrt(1 / (1 / x["r1"] + 1 / x["r2"])) * np.maximum(x["delta"], 0) ** 1.5
        np.testing.assert_allclose(x["F"], hertz + f_cap, rtol=1e-9, atol=1e-12 * np.abs(x["F"]).max(), err_msg=name)
        apart = x["delta"] < 0
        pair = np.isfinite(x["r2"])
        assert np.all(x["liquid_bridge"][pair] == 1)  # LIGGGHTS lists a pair apart only while its bridge acts
        counts["pairs apart"] += int(np.count_nonzero(apart & pair))
        counts["wall rows apart"] += int(np.count_nonzero(apart & ~pair))
        ours = res.contacts[(res.contacts["step"] == step) & res.contacts["wall"].isin(dumped_walls)]
        np.testing.assert_array_equal(ours["delta"], x["delta"])  # the same contacts in the same order
        np.testing.assert_allclose(ours["u_adh"], work, rtol=1e-10, atol=1e-10 * np.abs(work).max(), err_msg=name)
        assert np.all(ours["u_n"][ours["delta"] < 0] == 0) and np.all(ours["u_t"][ours["delta"] < 0] == 0)
        assert np.all(ours["u_adh"][ours["delta"] < 0] <= 0) and np.any(ours["u_adh"][ours["delta"] < 0] < 0)
    assert counts["pairs apart"] > 100, counts


def test_a_gap_beyond_a_bridge_is_refused(bridge_run, tmp_path, capsys):
    """The bridges apart of a real run pass ``demsplit check``; a pair row apart beyond any bridge's reach (its dumped
    delta edited to -1 mm, with its history flag still 1) is a problem for ``check`` and refused by ``run``."""
    import shutil

    from demsplit.cli import main

    name, script = bridge_run
    assert open_run(script).scene.model.contact_law.params["cohesion"] in BRIDGE_MODELS
    copy = tmp_path / "run"
    shutil.copytree(script.parent, copy)
    assert main(["check", str(copy / script.name)]) == 0, capsys.readouterr().out
    lines = (copy / "pairs.txt").read_text().split("\n")
    apart = next(k for k, line in enumerate(lines) if len(line.split()) == 42 and float(line.split()[38]) < 0)
    words = lines[apart].split()
    words[38] = "-0.001"
    lines[apart] = " ".join(words) + " "
    (copy / "pairs.txt").write_text("\n".join(lines))
    capsys.readouterr()
    assert main(["check", str(copy / script.name)]) == 1
    assert "beyond the largest its law acts across" in capsys.readouterr().out
    assert main(["run", str(copy / script.name), "-o", str(tmp_path / "r.h5"), "-q"]) == 2
    assert "beyond its rupture distance" in capsys.readouterr().err


def test_every_model_has_an_independent_reference():
    """Every model of make_run.MODELS is in the totals test: none lacks a reference."""
    assert set(REFERENCED) == set(make_run.MODELS)


@pytest.mark.slow
def test_a_mesh_wall_with_its_own_model(tmp_path):
    """The mesh wall's fix without the pairs' rolling friction: LIGGGHTS accepts it, and its wall compute then
    writes 41 columns against the pairs' 44. demsplit reads both, the wall's contacts under the wall's own law
    (no rolling spring), the pairs' with theirs. It was refused, blaming the wall dump's header."""
    from conftest import require_program

    script = make_run.write_run("rolling_epsd2", tmp_path / "mixed")
    lines = script.read_text().splitlines()
    for k, line in enumerate(lines):
        if line.startswith("fix wfloor"):
            lines[k] = line.replace(" rolling_friction epsd2", "")
        elif line.startswith("dump dwall"):
            lines[k] = " ".join(t for t in line.split() if not (t.startswith("c_cwgl[") and int(t[7:-1]) > 41))
        elif line.startswith("dump_modify dwall"):
            lines[k] = 'dump_modify dwall format "' + " ".join(["%.17g"] * 41) + '"'
    script.write_text("\n".join(lines) + "\n")
    make_run.run(script, require_program("liggghts"))
    run = open_run(script)
    floor = [k for k, w in enumerate(run.scene.walls) if w.name == "floor"][0]
    assert run.scene.walls[floor].model.params["rolling"] == "off" and run.scene.model.params["rolling"] == "epsd2"
    c = demsplit.analyze(script).contacts
    on_floor, pairs = c["wall"] == floor, c["wall"] < 0
    assert on_floor.sum() > 50 and (c.loc[on_floor, "u_r"] == 0).all() and (c.loc[pairs, "u_r"] > 0).sum() > 100
    assert (c.loc[on_floor, "u_n"] > 0).all()
