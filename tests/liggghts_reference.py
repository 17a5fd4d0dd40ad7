"""An independent recomputation of the contact energies of a LIGGGHTS run, for the tests.

Each energy is computed here from what LIGGGHTS dumped (the normal force, the tangential force, the torque, the
history columns, the overlap) and the script's properties, with the stiffnesses and force laws read from the
LIGGGHTS-PUBLIC source (``src/normal_model_*.h``, ``tangential_model_*.h``, ``rolling_model_*.h``,
``cohesion_model_*.h``), never with demsplit's law code. Per contact model of the ``pair_style gran`` words:

normal (u_n, from the dumped normal force F and overlap delta):
- ``hertz``, ``hertz/stiffness``: F = kn delta^1.5, u_n = 2/5 F delta;
- ``hooke``, ``hooke/stiffness``: F = kn delta, u_n = F delta / 2;
- ``hooke/hysteresis``, ``luding``: u_n = F^2/(2 k2), released along the current unloading line, k2 from the
  stored delta_max (k1 = hooke's kn or LoadingStiffness);
- ``edinburgh``: u_n = integral of k2 (s^n - dp^n) from dp to delta, dp^n = delta^n - F/k2 (the unloading
  branch through the current force), k2 = UnloadingStiffness k1, k1 = 4/3 Y* sqrt(R*) (n = 1.5);
- ``edinburgh/stiffness`` (overlapExponent 1): u_n = F^2/(2 k2), k2 = UnloadingStiffness LoadingStiffness;
- ``thornton_ning``: the Hertzian unloading branch F(s) = F + k (s^1.5 - delta^1.5) from its zero to delta;

tangential (u_t = |F_t|^2/(2 kt), F_t the dumped tangential force): kt = 8 G* sqrt(R* delta) (hertz, edinburgh,
thornton_ning), the property kt (hooke/stiffness), kt sqrt(R* delta) (hertz/stiffness), hooke's kn (hooke,
hooke/hysteresis), LoadingStiffness (luding, edinburgh/stiffness), coeffFrictionStiffness LoadingStiffness
(``tangential tan_luding``);

rolling (u_r = |M_r|^2/(2 kr)): ``epsd`` kr = 2.25 kn mu_r^2 R*^2, ``epsd2`` kr = kt R*^2, ``epsd3`` kr =
rollingStiffness kn mu_r^2 R*^2 (kn, kt the Hertz stiffnesses at delta; M_r the dumped rolling history),
``luding`` kr = coeffRollingStiffness LoadingStiffness R*^2 (M_r the applied torque: the dumped torque minus the
moment of the tangential force);

cohesion (u_adh, signed): the dumped normal force is the elastic one plus -k A(delta), k the
cohesionEnergyDensity; u_adh = -k * integral of A from 0 to delta, in closed form: ``sjkr`` A = pi/4 s (2 r1 - s)
(2 r2 - s) (2 L - s)/(L - s)^2 between spheres (L = r1 + r2), pi (2 r1 s - s^2) at a wall; ``sjkr2`` A = 2 pi
(2 r1 r2/L) s between spheres, 2 pi r1 s at a wall; u_n is then that of the normal model from F + k A.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


class Contacts:
    """The dumped contacts of one frame with the script's properties per contact (type pair) and the effective
    radius R*, mass m* (pair_gran_base.h, fix_wall_gran_base.h: a wall's is the particle's), Y* and G*
    (global_properties.cpp createYeff, createGeff)."""

    def __init__(self, run, x: dict):
        self.run, self.x = run, x
        self.props = run.script.coefficients
        self.pair = (x["t1"] - 1, x["t2"] - 1)
        E, nu = self.props["youngsModulus"], self.props["poissonsRatio"]
        a, b = self.pair
        self.Y = 1 / ((1 - nu[a] ** 2) / E[a] + (1 - nu[b] ** 2) / E[b])
        self.G = 1 / (2 * (2 - nu[a]) * (1 + nu[a]) / E[a] + 2 * (2 - nu[b]) * (1 + nu[b]) / E[b])
        self.R = 1 / (1 / x["r1"] + 1 / x["r2"])
        self.meff = 1 / (1 / x["m1"] + 1 / x["m2"])
        self.delta = x["delta"]

    def prop(self, name: str) -> np.ndarray:
        """A peratomtypepair property per contact."""
        return np.asarray(self.props[name])[self.pair]

    def hertz_kn(self) -> np.ndarray:
        return 4 / 3 * self.Y * np.sqrt(self.R * self.delta)

    def hertz_kt(self) -> np.ndarray:
        return 8 * self.G * np.sqrt(self.R * self.delta)

    def hooke_kn(self) -> np.ndarray:
        """normal_model_hooke.h: 16/15 sqrt(R*) Y* (15 m* v^2/(16 sqrt(R*) Y*))^0.2, v the characteristicVelocity."""
        v, sqrtval = self.props["characteristicVelocity"], np.sqrt(self.R)
        return 16 / 15 * sqrtval * self.Y * (15 * self.meff * v * v / (16 * sqrtval * self.Y)) ** 0.2


# A normal model: (contacts, the elastic normal force F) -> (u_n, kn, kt), kn and kt the stiffnesses the model
# passes on to the tangential and rolling models.
Normal = Callable[[Contacts, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def hysteresis_k2(c: Contacts, k1: np.ndarray, k2max: np.ndarray) -> np.ndarray:
    """The unloading stiffness of normal_model_luding.h and normal_model_hooke_hysteresis.h from the stored
    delta_max: k2Max beyond delta_lim = k2Max/(k2Max - k1) coefficientPlasticityDepth 2 R*, else
    k1 + (k2Max - k1) delta_max/delta_lim."""
    lim = k2max / (k2max - k1) * c.prop("coefficientPlasticityDepth") * 2 * c.R
    return np.where(c.x["delta_max"] >= lim, k2max, k1 + (k2max - k1) * c.x["delta_max"] / lim)


def _hertz(c: Contacts, F: np.ndarray):
    return 0.4 * F * c.delta, c.hertz_kn(), c.hertz_kt()


def _hertz_stiffness(c: Contacts, F: np.ndarray):
    poly = np.sqrt(c.R * c.delta)
    return 0.4 * F * c.delta, poly * c.prop("kn"), poly * c.prop("kt")


def _hooke(c: Contacts, F: np.ndarray):
    kn = c.hooke_kn()
    return 0.5 * F * c.delta, kn, kn


def _hooke_stiffness(c: Contacts, F: np.ndarray):
    return 0.5 * F * c.delta, c.prop("kn"), c.prop("kt")


def _hooke_hysteresis(c: Contacts, F: np.ndarray):
    k1 = c.hooke_kn()
    return F**2 / (2 * hysteresis_k2(c, k1, k1 * c.prop("coefficientMaxElasticStiffness"))), k1, k1


def _luding(c: Contacts, F: np.ndarray):
    k1 = c.prop("LoadingStiffness")
    return F**2 / (2 * hysteresis_k2(c, k1, k1 * c.prop("UnloadingStiffness"))), k1, k1


def _edinburgh(c: Contacts, F: np.ndarray):
    """normal_model_edinburgh.h, overlapExponent n != 1: k1 = 4/3 Y* sqrt(R*), F = k1 delta^n loading,
    k2 (delta^n - dp^n) unloading; the branch through the current (delta, F) has dp^n = delta^n - F/k2 (on the
    loading branch too: dp = lambda delta, lambda^n = 1 - k1/k2)."""
    n = np.longdouble(c.props["overlapExponent"])
    assert n != 1  # the linear variant has k1 = 2 Y* R* and kt = 2 Y* sqrt(R* delta)
    k1 = 4 / 3 * c.Y * np.sqrt(c.R)
    k2 = (k1 * c.prop("UnloadingStiffness")).astype(np.longdouble)
    d, f = c.delta.astype(np.longdouble), F.astype(np.longdouble)
    dpn = np.maximum(d**n - f / k2, 0)
    dp = dpn ** (1 / n)
    u_n = k2 * ((d ** (n + 1) - dp ** (n + 1)) / (n + 1) - dpn * (d - dp))
    return u_n.astype(np.float64), k1, c.hertz_kt()


def _edinburgh_stiffness(c: Contacts, F: np.ndarray):
    """overlapExponent 1: F = k2 (delta - dp) on unloading, k1 delta = k2 (delta - lambda delta) on loading:
    F^2/(2 k2) either way."""
    assert c.props["overlapExponent"] == 1
    k1 = c.prop("LoadingStiffness")
    return F**2 / (2 * k1 * c.prop("UnloadingStiffness")), k1, k1


def _thornton_ning(c: Contacts, F: np.ndarray):
    """F(s) = F + k (s^1.5 - delta^1.5) from s0, where it is 0 (or 0), to delta, in long double."""
    k = (4 / 3 * c.Y * np.sqrt(c.R)).astype(np.longdouble)
    f, d = F.astype(np.longdouble), c.delta.astype(np.longdouble)
    C = f - k * d**1.5
    s0 = np.minimum(np.maximum(-C / k, 0) ** (np.longdouble(2) / 3), d)
    u_n = C * (d - s0) + k * (d**2.5 - s0**2.5) / np.longdouble(2.5)
    return u_n.astype(np.float64), c.hertz_kn(), c.hertz_kt()


NORMAL: dict[str, Normal] = {
    "hertz": _hertz,
    "hertz/stiffness": _hertz_stiffness,
    "hooke": _hooke,
    "hooke/stiffness": _hooke_stiffness,
    "hooke/hysteresis": _hooke_hysteresis,
    "luding": _luding,
    "edinburgh": _edinburgh,
    "edinburgh/stiffness": _edinburgh_stiffness,
    "thornton_ning": _thornton_ning,
}

# A tangential model: (contacts, kt of the normal model) -> u_t.
TANGENTIAL: dict[str, Callable[[Contacts, np.ndarray], np.ndarray]] = {
    "history": lambda c, kt: np.einsum("ij,ij->i", c.x["ft"], c.x["ft"]) / (2 * kt),
    "tan_luding": lambda c, kt: (
        np.einsum("ij,ij->i", c.x["ft"], c.x["ft"])
        / (2 * c.prop("coeffFrictionStiffness") * c.prop("LoadingStiffness"))
    ),
    "no_history": lambda c, kt: np.zeros(len(c.x["F"])),  # no spring (its force is viscous only)
}


def _stored_torque(c: Contacts) -> np.ndarray:
    """|M_r|^2 of the rolling torque in the dumped history."""
    m = np.stack([c.x[f"rolling_torque{x}"] for x in "xyz"], -1)
    return np.einsum("ij,ij->i", m, m)


def _applied_torque(c: Contacts) -> np.ndarray:
    """|M_r|^2 of the rolling torque LIGGGHTS applied: the dumped torque minus the moment -(r1 - delta/2) e_n x F_t
    of the tangential force (e_n from body 2 to body 1)."""
    x = c.x
    m = -(x["tq"] + (x["r1"] - c.delta / 2)[:, None] * np.cross(-x["n"], x["ft"]))
    return np.einsum("ij,ij->i", m, m)


# A rolling model: (contacts, kn, kt of the normal model) -> u_r.
ROLLING: dict[str, Callable[[Contacts, np.ndarray, np.ndarray], np.ndarray] | None] = {
    "epsd": lambda c, kn, kt: _stored_torque(c) / (2 * 2.25 * kn * c.prop("coefficientRollingFriction") ** 2 * c.R**2),
    "epsd2": lambda c, kn, kt: _stored_torque(c) / (2 * kt * c.R**2),
    "epsd3": lambda c, kn, kt: (
        _stored_torque(c) / (2 * c.props["rollingStiffness"] * kn * c.prop("coefficientRollingFriction") ** 2 * c.R**2)
    ),
    "luding": lambda c, kn, kt: (
        _applied_torque(c) / (2 * c.prop("coeffRollingStiffness") * c.prop("LoadingStiffness") * c.R**2)
    ),
    "cdt": None,  # a constant torque mu_r |F_n| R*: no spring, no energy (rolling_model_cdt.h)
}


def _sjkr(c: Contacts) -> tuple[np.ndarray, np.ndarray]:
    """cohesion_model_sjkr.h: (the integral of A from 0 to delta, A(delta))."""
    r1, r2, d = c.x["r1"], c.x["r2"], c.delta
    wall = np.isinf(r2)
    L = np.where(wall, 1, r1 + r2)  # between spheres, with r = L - s: A = pi/4 (L^2 - r^2)(r^2 - (r1 - r2)^2)/r^2
    d12 = np.where(wall, 0, r1 - r2) ** 2
    pair_int = np.pi / 4 * (L * d**2 - d**3 / 3 - d12 * d**2 / (L - d))
    pair_a = np.pi / 4 * d * (2 * r1 - d) * (2 * np.where(wall, 1, r2) - d) * (2 * L - d) / (L - d) ** 2
    return (
        np.where(wall, np.pi * (r1 * d**2 - d**3 / 3), pair_int),
        np.where(wall, np.pi * (2 * r1 * d - d**2), pair_a),
    )


def _sjkr2(c: Contacts) -> tuple[np.ndarray, np.ndarray]:
    """cohesion_model_sjkr2.h: A = 2 pi (2 r1 r2/(r1 + r2)) s between spheres (4 pi R* s), 2 pi r1 s at a wall."""
    factor = np.where(np.isinf(c.x["r2"]), np.pi * c.x["r1"], 2 * np.pi * c.R)
    return factor * c.delta**2, 2 * factor * c.delta


# A cohesion model: contacts -> (integral of the contact area A from 0 to delta, A(delta)); the work is
# -cohesionEnergyDensity times the integral, the force -cohesionEnergyDensity A.
COHESION: dict[str, Callable[[Contacts], tuple[np.ndarray, np.ndarray]]] = {"sjkr": _sjkr, "sjkr2": _sjkr2}


def submodels(words: str) -> dict[str, str]:
    """The ``pair_style gran`` words as {model: ..., tangential: ..., rolling_friction: ..., cohesion: ...}."""
    w = words.split()
    return dict(zip(w[::2], w[1::2]))


def has_reference(words: str) -> bool:
    """Whether every submodel of these words has a reference here."""
    tables = {"model": NORMAL, "tangential": TANGENTIAL, "rolling_friction": ROLLING, "cohesion": COHESION}
    return all(key in tables and value in tables[key] for key, value in submodels(words).items())


def reference_energies(words: str, run, x: dict) -> dict[str, np.ndarray]:
    """Energies of every dumped contact of a run with ``pair_style gran`` ``words``, computed from LIGGGHTS' dumped
    forces, torques and history and the source's stiffnesses (module docstring). ``x``: per contact the normal
    force F (> 0 repulsive), delta, the tangential force ft and torque tq on body 1 (rows of 3), the normal n from
    body 1 to body 2, the radii r1, r2, masses m1, m2 (a wall: r2 = m2 = inf) and types t1, t2 of both bodies, and
    the dumped history columns by name (delta_max, rolling_torquex, ...)."""
    models = submodels(words)
    c = Contacts(run, x)
    F, out = x["F"], {}
    if "cohesion" in models:
        integral, area = COHESION[models["cohesion"]](c)
        k = c.prop("cohesionEnergyDensity")
        out["u_adh"] = -k * integral
        F = F + k * area  # the elastic force: the dumped one less the cohesion force -k A
    out["u_n"], kn, kt = NORMAL[models["model"]](c, F)
    out["u_t"] = TANGENTIAL[models["tangential"]](c, kt)
    if ROLLING.get(models.get("rolling_friction")) is not None:
        out["u_r"] = ROLLING[models["rolling_friction"]](c, kn, kt)
    return out
