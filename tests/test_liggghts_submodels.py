"""LIGGGHTS sub-models composed with a normal model: rolling springs (u_r), cohesion work (u_adh), the tan_luding
spring, liquid bridges (easo, washino: their work against 40-digit quadrature of LIGGGHTS' own capillary force,
contacts apart); and the normal models thornton_ning (its unloading branch at 40 digits) and edinburgh/stiffness.

The cohesion work is checked against LIGGGHTS' own contact area (``cohesion_model_sjkr.h``: the
lens area of two spheres, pi (r^2 - d^2) on a wall) by quadrature and by its derivative, the
cohesion force -k A; the rolling energy against |M_r|^2/(2 kr) with each model's kr; the modes
travel to the per-particle and per-wall tables with conservation.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from demsplit.physics.bodies import FrameContacts, LawRows
from demsplit.physics.laws import law_class, make, supported
from demsplit.physics.laws._liggghts import rolling_spring_energy, sjkr2_area_integral, sjkr_area, sjkr_area_integral
from demsplit.physics.modes import HISTORY_LOST
from demsplit.physics.partition import contact_energies, partition, per_particle
from demsplit.scene import ContactModel, Material, Scene, Wall
from liggghts_bridges import BRIDGE_MODELS, liggghts_capillary


def liggghts_sjkr_area(delta: np.ndarray, ri: np.ndarray, rj: np.ndarray) -> np.ndarray:
    """LIGGGHTS' ``Acont`` as written in cohesion_model_sjkr.h (r: the centre distance)."""
    if np.isinf(rj).all():
        r = ri - delta
        return (ri * ri - r * r) * np.pi
    r = ri + rj - delta
    return -np.pi / 4 * ((r - ri - rj) * (r + ri - rj) * (r - ri + rj) * (r + ri + rj)) / (r * r)


@pytest.mark.parametrize("rj", [0.7e-3, 2.5e-3, np.inf])
def test_sjkr_work_is_the_integral_of_liggghts_area(rj):
    ri = np.full(5, 1.3e-3)
    rj = np.full(5, rj)
    delta = np.array([1e-9, 1e-7, 1e-5, 1e-4, 3e-4])
    # LIGGGHTS' area integrated at 40 digits (in double precision its formula cancels for small delta)
    mpmath.mp.dps = 40
    a, b = mpmath.mpf(ri[0]), (mpmath.inf if np.isinf(rj[0]) else mpmath.mpf(rj[0]))

    def area(s):
        if b == mpmath.inf:
            return mpmath.pi * (a * a - (a - s) ** 2)
        r = a + b - s
        return -mpmath.pi / 4 * ((r - a - b) * (r + a - b) * (r - a + b) * (r + a + b)) / (r * r)

    quad = [float(mpmath.quad(area, [0, mpmath.mpf(d)])) for d in delta]
    np.testing.assert_allclose(sjkr_area_integral(delta, ri, rj), quad, rtol=1e-13)
    # and its derivative is the area itself (the cohesion force is -k A), which sjkr_area gives exactly
    h = delta * 1e-6
    slope = (sjkr_area_integral(delta + h, ri, rj) - sjkr_area_integral(delta - h, ri, rj)) / (2 * h)
    np.testing.assert_allclose(slope, sjkr_area(delta, ri, rj), rtol=1e-6)
    exact = [float(area(mpmath.mpf(d))) for d in delta]
    np.testing.assert_allclose(sjkr_area(delta, ri, rj), exact, rtol=1e-14)


def test_sjkr2_work():
    ri, rj, d = np.array([1e-3, 1e-3]), np.array([3e-3, np.inf]), np.array([2e-5, 2e-5])
    R = 1e-3 * 3e-3 / 4e-3
    np.testing.assert_allclose(
        sjkr2_area_integral(d, ri, rj), [2 * np.pi * R * d[0] ** 2, np.pi * 1e-3 * d[1] ** 2], rtol=1e-15
    )
    assert np.all(sjkr2_area_integral(-d, ri, rj) == 0)


def test_rolling_spring_energy_without_stiffness_is_zero():
    m = np.array([[1.0, 2.0, 2.0], [0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(rolling_spring_energy(m, np.array([2.0, 0.0])), [9.0 / 4.0, 0.0])


def scene(**params) -> Scene:
    return Scene(
        materials={1: Material(5e6, 0.45), 2: Material(7e7, 0.3)},
        model=ContactModel("liggghts:hertz", params),
        walls=[Wall("floor", "plane", 2)],
    )


def frame(n: int = 40, seed: int = 3):
    rng = np.random.default_rng(seed)
    particles = {
        "id": np.arange(1, 21),
        "type": rng.integers(1, 3, 20),
        "radius": rng.uniform(1e-3, 2e-3, 20),
        "x": rng.uniform(0, 1e-2, 20),
        "y": rng.uniform(0, 1e-2, 20),
        "z": rng.uniform(0, 1e-2, 20),
    }
    id1 = rng.integers(1, 21, n)
    id2 = np.where(np.arange(n) % 5 == 0, -1, (id1 % 20) + 1)
    wall = np.where(id2 < 0, 0, -1)
    r1 = particles["radius"][id1 - 1]
    r2 = np.where(id2 > 0, particles["radius"][np.maximum(id2, 1) - 1], np.inf)
    nvec = rng.normal(size=(n, 3))
    nvec /= np.linalg.norm(nvec, axis=1)[:, None]
    contacts = {
        "id1": id1,
        "id2": id2,
        "wall": wall,
        "delta": rng.uniform(-1e-6, 5e-5, n),
        "r1": r1,
        "r2": r2,
        "nx": nvec[:, 0],
        "ny": nvec[:, 1],
        "nz": nvec[:, 2],
        "x1": particles["x"][id1 - 1],
        "y1": particles["y"][id1 - 1],
        "z1": particles["z"][id1 - 1],
        **{f"shear{c}": rng.normal(0, 1e-6, n) for c in "xyz"},
        **{f"rolling_torque{c}": rng.normal(0, 1e-7, n) for c in "xyz"},
    }
    return particles, contacts


MU_R = ((0.1, 0.2), (0.2, 0.3))


@pytest.mark.slow
@pytest.mark.parametrize("rolling, factor", [("epsd", 2.25), ("epsd3", 0.7)])
def test_rolling_energy_uses_the_models_stiffness(rolling, factor):
    particles, contacts = frame()
    sc = scene(rolling=rolling, rolling_friction=MU_R, rolling_stiffness=0.7 if rolling == "epsd3" else None)
    e = contact_energies(contacts, sc, particles)
    assert [m.column for m in e.modes] == ["u_n", "u_t", "u_r"]
    law = sc.model.contact_law
    t1 = particles["type"][contacts["id1"] - 1]
    t2 = np.where(contacts["id2"] > 0, particles["type"][np.maximum(contacts["id2"], 1) - 1], 2)
    mu = np.asarray(MU_R)[t1 - 1, t2 - 1]
    r1, r2 = contacts["r1"], contacts["r2"]
    R = np.where(np.isinf(r2), r1, 1 / (1 / r1 + 1 / r2))
    E1 = np.where(t1 == 1, 5e6, 7e7)
    nu1 = np.where(t1 == 1, 0.45, 0.3)
    E2 = np.where(t2 == 1, 5e6, 7e7)
    nu2 = np.where(t2 == 1, 0.45, 0.3)
    Y = 1 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    kn = 4 / 3 * Y * np.sqrt(R * np.maximum(contacts["delta"], 0))
    kr = factor * kn * mu**2 * R**2
    m2 = sum(contacts[f"rolling_torque{c}"] ** 2 for c in "xyz")
    expected = np.where(kr > 0, m2 / (2 * np.where(kr > 0, kr, 1)), 0)
    np.testing.assert_allclose(e.u_r, expected, rtol=1e-12)
    assert law.describe().startswith("liggghts:hertz")


def test_rolling_mode_missing_history_is_said():
    particles, contacts = frame()
    for c in "xyz":
        del contacts[f"rolling_torque{c}"]
    e = contact_energies(contacts, scene(rolling="epsd2"), particles)
    assert "u_r" in e.missing and np.all(e.u_r == 0) and np.all(e.not_computed == 4)


def test_cohesion_work_is_signed_apart_and_conserved():
    particles, contacts = frame()
    k = ((1e5, 2e5), (2e5, 3e5))
    sc = scene(cohesion="sjkr", cohesion_energy_density=k)
    e = partition(contacts, sc, particles)
    assert e.u_adh is not None and np.all(e.u_adh <= 0) and np.any(e.u_adh < 0)
    assert np.all(e.u_adh[contacts["delta"] <= 0] == 0)
    pt, wt = per_particle(contacts, e, particles, n_walls=1)
    total = e.u_adh.sum()
    assert abs(pt["u_adh"].sum() + wt["u_adh"].sum() - total) <= 1e-12 * abs(total)
    # the elastic total leaves the cohesion work out
    np.testing.assert_allclose(pt["u"], pt["u_n"] + pt["u_t"], rtol=1e-15)
    assert "u_adh" in e.table() and "share_adh1" not in e.table()


def test_sub_model_words_are_checked():
    with pytest.raises(Exception, match="rolling model 'wobble'"):
        make("liggghts:hertz", {"rolling": "wobble"})
    with pytest.raises(Exception, match="rolling_stiffness"):
        make("liggghts:hertz", {"rolling": "epsd3", "rolling_friction": 0.1})


def hertz_kt_and_R(particles: dict, contacts: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """kt = 8 G* sqrt(R* delta) of LIGGGHTS' hertz for the scene of :func:`scene`, R*, and the two types."""
    t1 = particles["type"][contacts["id1"] - 1]
    t2 = np.where(contacts["id2"] > 0, particles["type"][np.maximum(contacts["id2"], 1) - 1], 2)
    E, nu = np.array([5e6, 7e7]), np.array([0.45, 0.3])
    G = 1 / (2 * (2 - nu[t1 - 1]) * (1 + nu[t1 - 1]) / E[t1 - 1] + 2 * (2 - nu[t2 - 1]) * (1 + nu[t2 - 1]) / E[t2 - 1])
    R = 1 / (1 / contacts["r1"] + 1 / contacts["r2"])
    return 8 * G * np.sqrt(R * np.maximum(contacts["delta"], 0)), R, t1, t2


def test_tan_luding_spring_is_kT2kcMax_kt():
    """tangential tan_luding: the spring is coeffFrictionStiffness kt (tangential_model_luding_tn.h)."""
    particles, contacts = frame()
    ratio = ((0.5, 0.25), (0.25, 2.0))
    e = contact_energies(contacts, scene(tangential="tan_luding", friction_stiffness=ratio), particles)
    kt, _, t1, t2 = hertz_kt_and_R(particles, contacts)
    s2 = sum(contacts[f"shear{c}"] ** 2 for c in "xyz")
    np.testing.assert_allclose(e.u_t, 0.5 * np.asarray(ratio)[t1 - 1, t2 - 1] * kt * s2, rtol=1e-12)
    assert np.any(e.u_t > 0)


def test_rolling_luding_stiffness_and_history():
    """rolling_friction luding: kr = coeffRollingStiffness kt R*^2 (rolling_model_luding.h); its history is the
    rolling torque, then the torsion torque; torsion on is refused (both share the rolling torque's values)."""
    particles, contacts = frame()
    ratio = ((0.3, 0.6), (0.6, 1.2))
    sc = scene(rolling="luding", rolling_stiffness_ratio=ratio)
    e = contact_energies(contacts, sc, particles)
    kt, R, t1, t2 = hertz_kt_and_R(particles, contacts)
    kr = np.asarray(ratio)[t1 - 1, t2 - 1] * kt * R**2
    m2 = sum(contacts[f"rolling_torque{c}"] ** 2 for c in "xyz")
    np.testing.assert_allclose(e.u_r, np.where(kr > 0, m2 / (2 * np.where(kr > 0, kr, 1)), 0), rtol=1e-12)
    assert sc.model.contact_law.history_columns()[3:] == [
        "rolling_torquex",
        "rolling_torquey",
        "rolling_torquez",
        "torsion_torquex",
        "torsion_torquey",
        "torsion_torquez",
    ]
    with pytest.raises(Exception, match="torsion on"):
        make("liggghts:hertz", {"rolling": "luding", "rolling_stiffness_ratio": 0.5, "torsion": "on"})


def thornton_ning(delta: np.ndarray, delta_h: np.ndarray, f_h: np.ndarray, **params) -> tuple[np.ndarray, ...]:
    """u_n and the normal force of liggghts:thornton_ning for pair contacts of radii 1 mm and 2 mm, types 1 and 2."""
    particles = {
        "id": np.array([1, 2]),
        "type": np.array([1, 2]),
        "radius": np.array([1e-3, 2e-3]),
        "x": np.zeros(2),
        "y": np.zeros(2),
        "z": np.array([0.0, 3e-3]),
    }
    n = len(delta)
    contacts = {
        "id1": np.ones(n, dtype=np.int64),
        "id2": np.full(n, 2),
        "wall": np.full(n, -1),
        "delta": delta,
        "r1": np.full(n, 1e-3),
        "r2": np.full(n, 2e-3),
        "nx": np.zeros(n),
        "ny": np.zeros(n),
        "nz": np.ones(n),
        "x1": np.zeros(n),
        "y1": np.zeros(n),
        "z1": np.zeros(n),
        "tn_delta_old": delta_h,
        "tn_force_old": f_h,
        **{f"shear{c}": np.zeros(n) for c in "xyz"},
    }
    sc = Scene(
        materials={1: Material(5e6, 0.45), 2: Material(7e7, 0.3)}, model=ContactModel("liggghts:thornton_ning", params)
    )
    e = contact_energies(contacts, sc, particles)
    rows = LawRows(FrameContacts(contacts, sc, particles), slice(None), sc.model.law)
    return e.u_n, sc.model.contact_law.normal_force(rows)


def test_thornton_ning_energy_is_the_integral_of_its_unloading_branch():
    """u_n = int_s0^delta (f_h + k (s^1.5 - delta_h^1.5)) ds (LIGGGHTS' Hertzian slope 2 E* sqrt(R* s) on
    unloading), at 40 digits, from a force at the Hertz curve (f = k delta^1.5), above it (the first step's
    overshoot: the branch reaches delta = 0 with a force), below it (yielded, nearly unloaded) and 0 (detached)."""
    R = 1e-3 * 2e-3 / 3e-3
    Y = 1 / ((1 - 0.45**2) / 5e6 + (1 - 0.3**2) / 7e7)
    k = 4 / 3 * Y * np.sqrt(R)
    d = np.array([2e-5, 2e-5, 3e-5, 3e-5, 4e-5, 4e-5])
    f = k * d**1.5 * np.array([1.0, 1.2, 0.3, 1e-6, 0.0, 0.7])
    u, force = thornton_ning(d, d, f)
    mpmath.mp.dps = 40
    for i in range(len(d)):
        kk, dh, fh = mpmath.mpf(k), mpmath.mpf(d[i]), mpmath.mpf(f[i])
        s0 = max(dh**1.5 - fh / kk, 0) ** (mpmath.mpf(2) / 3)
        exact = mpmath.quad(lambda s, kk=kk, dh=dh, fh=fh: fh + kk * (s**1.5 - dh**1.5), [s0, dh])
        assert u[i] == pytest.approx(float(exact), rel=1e-13, abs=1e-30), i
    assert u[4] == 0.0 and np.all(u[:4] > 0)
    np.testing.assert_array_equal(force, f)  # at the stored point the branch's force is the stored one
    # the derivative along the branch (delta_h, f_h fixed) is the branch's force (not across its zero-force
    # point, which lies within the step of the nearly unloaded and the detached contact: 3 and 4)
    h = 1e-6 * d
    up, f_up = thornton_ning(d + h, d, f)
    down, _ = thornton_ning(d - h, d, f)
    smooth = [0, 1, 2, 5]
    np.testing.assert_allclose(((up - down) / (2 * h))[smooth], f[smooth], rtol=1e-6)
    assert np.all(f_up[:4] > f[:4])  # loading along the branch raises the force with the Hertzian slope


def test_thornton_ning_refuses_what_it_cannot_rebuild():
    with pytest.raises(Exception, match="surfaceEnergy > 0"):
        make("liggghts:thornton_ning", {"surface_energy": 0.05})
    with pytest.raises(Exception, match="sets no normal stiffness"):
        make("liggghts:thornton_ning", {"rolling": "epsd3", "rolling_friction": 0.1, "rolling_stiffness": 1.0})
    assert make("liggghts:thornton_ning", {"rolling": "epsd2"}).modes == ("u_n", "u_t", "u_r")


def test_edinburgh_stiffness_uses_the_given_stiffness():
    """edinburgh/stiffness: k1 = LoadingStiffness, k2 = k1 UnloadingStiffness, kt = k1
    (normal_model_edinburgh_stiffness.h)."""
    law = make(
        "liggghts:edinburgh/stiffness", {"overlap_exponent": 1.0, "unloading_stiffness": 4.0, "loading_stiffness": 3e3}
    )
    assert law.history_columns() == [
        "delta_p_max",
        "edinburgh_old_delta",
        "edinburgh_kc",
        "edinburgh_fo",
        "shearx",
        "sheary",
        "shearz",
    ]
    particles, contacts = frame()
    contacts["delta_p_max"] = np.maximum(contacts["delta"], 0) * 0.4
    sc = Scene(
        materials={1: Material(5e6, 0.45), 2: Material(7e7, 0.3)},
        model=ContactModel(law.key, law.params),
        walls=[Wall("floor", "plane", 2)],
    )
    e = contact_energies(contacts, sc, particles)
    d = np.maximum(contacts["delta"], 0)
    np.testing.assert_allclose(e.u_n, 0.5 * 4 * 3e3 * (d - 0.4 * d) ** 2, rtol=1e-12, atol=1e-30)
    s2 = sum(contacts[f"shear{c}"] ** 2 for c in "xyz")
    np.testing.assert_allclose(e.u_t, np.where(d > 0, 0.5 * 3e3 * s2, 0), rtol=1e-12)


# ------------------------------------------------------------------ liquid bridges (easo, washino)


@pytest.mark.parametrize("model", BRIDGE_MODELS)
@pytest.mark.parametrize(
    "rj, ci, cj", [(1.6e-3, 0.01, 0.004), (0.7e-3, 2e-5, 0.03), (None, 0.01, 0.0), (None, 3e-6, 0.0)]
)
@pytest.mark.slow
def test_bridge_work_is_the_integral_of_liggghts_capillary_force(model, rj, ci, cj):
    """u_adh(delta) = int_{-s_rup}^delta F of LIGGGHTS' own force, by 40-digit quadrature of its transcription,
    touching and apart; its derivative is the force, which equals LIGGGHTS'; 0 from rupture on."""
    from demsplit.physics.laws._liquid_bridge import LiquidBridges

    ri, angles, gamma, max_ratio, cdf = 1.2e-3, (20.0, 35.0), 0.072, 1.1, 1.21
    mpmath.mp.dps = 40
    force, rupture = liggghts_capillary(model, ri, rj, ci, cj, *angles, gamma, max_ratio, cdf)
    s_rup = float(rupture)
    delta = np.array(
        [
            3e-5,
            1e-6,
            1e-9,
            0.0,
            -1e-9 * s_rup,
            -0.1 * s_rup,
            -0.5 * s_rup,
            -0.9 * s_rup,
            -0.999 * s_rup,
            -1.0001 * s_rup,
            -1.5 * s_rup,
        ]
    )
    n = len(delta)
    theta = 0.5 * np.radians(angles[0]) * np.radians(angles[1])
    b = LiquidBridges(
        model,
        np.full(n, ri),
        np.full(n, np.inf if rj is None else rj),
        np.full(n, ci),
        np.full(n, cj),
        theta,
        gamma,
        max_ratio,
        cdf,
    )
    assert b.rupture[0] == pytest.approx(s_rup, rel=1e-14)
    # at delta = 0 exactly washino's apart branch is 0/0 in LIGGGHTS (NaN); demsplit gives its limit
    exact_force = [float(force(d if d != 0 else -1e-40)) for d in delta]
    np.testing.assert_allclose(b.force(delta), exact_force, rtol=1e-13, atol=0)
    for d, w in zip(delta, b.work(delta)):
        if -d >= s_rup:
            assert w == 0.0
            continue
        exact = mpmath.quad(force, [-rupture, *([0] if d > 0 else []), mpmath.mpf(d)])
        assert w == pytest.approx(float(exact), rel=1e-12, abs=0), d
    assert np.all(b.work(delta)[:-2] < 0)  # the bridge holds the bodies together
    h = 1e-7 * s_rup
    for d in (2e-6, -0.3 * s_rup):  # d(u_adh)/d(delta) = F, touching and apart
        slope = (b.work(np.full(n, d + h)) - b.work(np.full(n, d - h)))[0] / (2 * h)
        assert slope == pytest.approx(float(force(d)), rel=1e-6)


def bridge_scene(model: str = BRIDGE_MODELS[0], **extra) -> Scene:
    params = {
        **dict(
            cohesion=model,
            surface_tension=0.072,
            contact_angle=(20.0, 35.0),
            max_separation_ratio=1.1,
            min_separation_ratio=1.01,
            fluid_viscosity=0.0,
            liquid_content_initial=0.01,
        ),
        **extra,
    }
    return Scene(
        materials={1: Material(5e6, 0.45), 2: Material(7e7, 0.3)},
        model=ContactModel("liggghts:hertz", params),
        walls=[Wall("floor", "plane", 2)],
    )


def bridge_contacts(delta: list[float], id2: list[int], flag: list[float], lost: list[int]) -> tuple[dict, dict]:
    """Particles 1 (r 1 mm, type 1) and 2 (r 1.5 mm, type 2) with their liquid; contacts of 1 with 2 or the wall."""
    particles = {
        "id": np.array([1, 2]),
        "type": np.array([1, 2]),
        "radius": np.array([1e-3, 1.5e-3]),
        "x": np.zeros(2),
        "y": np.zeros(2),
        "z": np.array([0.0, 3e-3]),
        "f_surfaceLiquidContent": np.array([0.01, 0.02]),
    }
    n = len(delta)
    id2 = np.array(id2)
    contacts = {
        "id1": np.ones(n, dtype=np.int64),
        "id2": id2,
        "wall": np.where(id2 < 0, 0, -1),
        "delta": np.array(delta),
        "r1": np.full(n, 1e-3),
        "r2": np.where(id2 < 0, np.inf, 1.5e-3),
        "nx": np.zeros(n),
        "ny": np.zeros(n),
        "nz": np.ones(n),
        "x1": np.zeros(n),
        "y1": np.zeros(n),
        "z1": np.zeros(n),
        "liquid_bridge": np.array(flag, dtype=float),
        "history_unknown": np.array(lost, dtype=np.int8) * np.int8(HISTORY_LOST),
        **{f"shear{c}": np.full(n, 1e-6) for c in "xyz"},
    }
    return particles, contacts


def test_bridge_law_apart_holds_only_its_bridge():
    """Apart (delta < 0) a contact has no elastic energy (LIGGGHTS resets the shear there) and a bridge's work while
    its flag is 1; a primitive-wall contact apart within rupture, whose flag LIGGGHTS never writes, is not computed
    (bit 16), while touching it holds a bridge for certain; a flag of 1 beyond rupture is refused."""
    from demsplit.errors import ContactError

    sc = bridge_scene()
    law = sc.model.contact_law
    assert law.history_columns() == ["liquid_bridge", "shearx", "sheary", "shearz"]
    assert law.particle_columns == ("f_surfaceLiquidContent",) and law.mode_columns["u_adh"] == ("liquid_bridge",)
    particles, contacts = bridge_contacts(
        [2e-5, -3e-5, -3e-5, 2e-5, -2e-5, -5e-4], [2, 2, 2, -1, -1, -1], [1, 1, 0, 0, 0, 0], [0, 0, 0, 1, 1, 1]
    )
    e = contact_energies(contacts, sc, particles)
    assert e.u_n[0] > 0 and e.u_t[0] > 0 and np.all(e.u_n[[1, 2, 4, 5]] == 0) and np.all(e.u_t[[1, 2, 4, 5]] == 0)
    assert e.u_adh[0] < e.u_adh[1] < 0 and e.u_adh[2] == 0 and e.u_adh[3] < 0
    assert e.u_adh[4] == 0 and e.u_adh[5] == 0  # unknown (flagged), and beyond any bridge's reach (known 0)
    assert e.not_computed.tolist() == [0, 0, 0, 2, 16, 0]
    contacts["liquid_bridge"][5] = 1  # a bridge LIGGGHTS would have broken
    contacts["history_unknown"][5] = 0
    with pytest.raises(ContactError, match="beyond its rupture distance"):
        contact_energies(contacts, sc, particles)
    # LIGGGHTS writes a pair apart while its bridge may act, a wall contact within (cdf - 1) r1
    np.testing.assert_allclose(
        law.separation_limit(np.array([1e-3, 1e-3]), np.array([1.5e-3, np.inf])),
        [0.1 * 2.5e-3, (1.21 - 1) * 1e-3],
        rtol=1e-12,
    )
    assert make("liggghts:hertz").separation_limit(1e-3, np.inf) == 0.0


def test_a_washino_bridge_forms_across_a_gap_without_history():
    """washino's bridge also forms on approach, wherever the gap is below rupture: apart it needs no history
    value, so a primitive-wall contact apart is computed, not flagged."""
    sc = bridge_scene(BRIDGE_MODELS[1])
    assert "u_adh" not in sc.model.contact_law.mode_columns
    particles, contacts = bridge_contacts([-3e-5, -2e-5, -5e-4], [2, -1, -1], [0, 0, 0], [0, 1, 1])
    e = contact_energies(contacts, sc, particles)
    assert e.u_adh[0] < 0 and e.u_adh[1] < 0 and e.u_adh[2] == 0
    assert e.not_computed is None or not np.any(e.not_computed & 16)


def test_bridge_law_parameters():
    law = bridge_scene(BRIDGE_MODELS[1], bridge_volume_fraction=0.1, contact_distance_factor=1.5).model.contact_law
    assert law.contact_distance_factor() == 1.5  # the larger of neigh_modify's and 1.1 maxSeparationDistanceRatio
    assert law.dump_setup() == [
        "fix liquidtransfer all transportequation/scalar equation_id liquidtransfer quantity "
        "surfaceLiquidContent default_value 1.000000e-02 flux_quantity liquidFlux "
        "source_quantity liquidSource capacity_quantity none"
    ]
    assert "liquid content f_surfaceLiquidContent" in law.describe()
    with pytest.raises(Exception, match="limitLiquidContent"):
        bridge_scene(BRIDGE_MODELS[1], limit_liquid_content="on")
    with pytest.raises(Exception, match="contactAngle"):
        bridge_scene(contact_angle=(20.0, 190.0))
    with pytest.raises(Exception, match="fluid_viscosity"):
        make(
            "liggghts:hertz",
            {
                "cohesion": BRIDGE_MODELS[0],
                "surface_tension": 0.07,
                "contact_angle": 30.0,
                "max_separation_ratio": 1.1,
                "min_separation_ratio": 1.01,
                "liquid_content_initial": 0.01,
            },
        )
    particles, contacts = bridge_contacts([2e-5], [2], [1], [0])
    particles["f_surfaceLiquidContent"][1] = -0.01
    with pytest.raises(Exception, match="must be >= 0"):
        contact_energies(contacts, bridge_scene(), particles)


@pytest.mark.parametrize("model", BRIDGE_MODELS)
@pytest.mark.parametrize("key", [k for k in supported() if k.startswith("liggghts:")])
def test_every_liggghts_normal_model_takes_a_bridge(key, model):
    """Any normal model composes with a liquid bridge: apart no elastic energy, u_adh the bridge's work whatever
    the normal model (it adds the pull-off work of luding and edinburgh only where they touch), and the model
    survives the scene's dict (its contact angles as a list)."""
    from demsplit.scene import scene_from_dict, scene_to_dict

    params = {
        **law_class(key).example_params,
        "cohesion": model,
        "surface_tension": 0.072,
        "contact_angle": (20.0, 35.0),
        "max_separation_ratio": 1.1,
        "min_separation_ratio": 1.01,
        "fluid_viscosity": 0.0,
        "liquid_content_initial": 0.01,
    }
    sc = Scene(
        materials={1: Material(5e6, 0.45), 2: Material(7e7, 0.3)},
        model=ContactModel(key, params),
        walls=[Wall("floor", "plane", 2)],
    )
    assert scene_from_dict(scene_to_dict(sc)).model == sc.model
    particles, contacts = bridge_contacts([2e-5, -3e-5, -2e-5], [2, 2, -1], [1, 1, 1], [0, 0, 0])
    particles["mass"] = np.array([1e-5, 2e-5])
    for column in sc.model.contact_law.needs():  # the normal model's own history, as at a first touch
        contacts.setdefault(column, np.where(contacts["delta"] > 0, contacts["delta"], 0.0))
    e = contact_energies(contacts, sc, particles)
    reference = contact_energies(contacts, bridge_scene(model), particles)
    assert np.all(e.u[:, 1:] == 0) and np.all(np.isfinite(e.u))
    np.testing.assert_array_equal(e.u_adh[1:], reference.u_adh[1:])
