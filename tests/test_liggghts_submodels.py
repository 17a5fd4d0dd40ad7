"""LIGGGHTS sub-models composed with a normal model: rolling springs (u_r) and cohesion work (u_adh).

The cohesion work is checked against LIGGGHTS' own contact area (``cohesion_model_sjkr.h``: the
lens area of two spheres, pi (r^2 - d^2) on a wall) by quadrature and by its derivative, the
cohesion force -k A; the rolling energy against |M_r|^2/(2 kr) with each model's kr; the modes
travel to the per-particle and per-wall tables with conservation.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from demsplit.physics.laws import make
from demsplit.physics.laws._liggghts import (rolling_spring_energy, sjkr2_area_integral, sjkr_area,
                                              sjkr_area_integral)
from demsplit.physics.partition import contact_energies, partition, per_particle
from demsplit.scene import ContactModel, Material, Scene, Wall


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
    np.testing.assert_allclose(sjkr2_area_integral(d, ri, rj), [2 * np.pi * R * d[0] ** 2, np.pi * 1e-3 * d[1] ** 2],
                               rtol=1e-15)
    assert np.all(sjkr2_area_integral(-d, ri, rj) == 0)


def test_rolling_spring_energy_without_stiffness_is_zero():
    m = np.array([[1.0, 2.0, 2.0], [0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(rolling_spring_energy(m, np.array([2.0, 0.0])), [9.0 / 4.0, 0.0])


def scene(**params) -> Scene:
    return Scene(materials={1: Material(5e6, 0.45), 2: Material(7e7, 0.3)},
                 model=ContactModel("liggghts:hertz", params), walls=[Wall("floor", "plane", 2)])


def frame(n: int = 40, seed: int = 3):
    rng = np.random.default_rng(seed)
    particles = {"id": np.arange(1, 21), "type": rng.integers(1, 3, 20), "radius": rng.uniform(1e-3, 2e-3, 20),
                 "x": rng.uniform(0, 1e-2, 20), "y": rng.uniform(0, 1e-2, 20), "z": rng.uniform(0, 1e-2, 20)}
    id1 = rng.integers(1, 21, n)
    id2 = np.where(np.arange(n) % 5 == 0, -1, (id1 % 20) + 1)
    wall = np.where(id2 < 0, 0, -1)
    r1 = particles["radius"][id1 - 1]
    r2 = np.where(id2 > 0, particles["radius"][np.maximum(id2, 1) - 1], np.inf)
    nvec = rng.normal(size=(n, 3))
    nvec /= np.linalg.norm(nvec, axis=1)[:, None]
    contacts = {"id1": id1, "id2": id2, "wall": wall, "delta": rng.uniform(-1e-6, 5e-5, n), "r1": r1, "r2": r2,
                "nx": nvec[:, 0], "ny": nvec[:, 1], "nz": nvec[:, 2], "x1": particles["x"][id1 - 1],
                "y1": particles["y"][id1 - 1], "z1": particles["z"][id1 - 1],
                **{f"shear{c}": rng.normal(0, 1e-6, n) for c in "xyz"},
                **{f"rolling_torque{c}": rng.normal(0, 1e-7, n) for c in "xyz"}}
    return particles, contacts


MU_R = ((0.1, 0.2), (0.2, 0.3))


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
