"""What LIGGGHTS' sphere models share: the sub-models a normal model is composed with.

LIGGGHTS composes a contact from a normal model, which sets the normal and
tangential stiffnesses kn and kt of the contact (``sidata.kn``, ``sidata.kt``),
and sub-models that use them (``contact_models.h``):

- ``tangential history`` keeps a spring displacement ``shear`` (m) per contact
  with F_t = -kt shear (``tangential_model_history.h``): u_t = kt |shear|^2 / 2;
  ``tan_luding`` keeps the same history with the spring kT2kcMax kt
  (coeffFrictionStiffness, ``tangential_model_luding_tn.h``): u_t = kT2kcMax kt |shear|^2 / 2;
  ``no_history`` keeps none (no spring, u_t = 0);
- ``rolling_friction epsd|epsd2|epsd3|luding`` keeps the spring's rolling torque M_r
  (N m) per contact, M_r += kr w_t dt, capped at mu_r |F_n| R*: u_r = |M_r|^2/(2 kr)
  with kr = 2.25 kn mu_r^2 R*^2 (``rolling_model_epsd.h``), kt R*^2
  (``rolling_model_epsd2.h``), coeffRollStiffness kn mu_r^2 R*^2
  (``rolling_model_epsd3.h``) or kR2kcMax kt R*^2 (coeffRollingStiffness,
  ``rolling_model_luding.h``, whose cap is mu_r |F_n + kc delta - f0| R* and whose
  history holds 3 more values, the torsion torque, 0 without ``torsion on``);
  ``cdt`` is a constant torque without a spring;
- ``cohesion sjkr`` adds F = -k A with A the lens area of the two spheres,
  pi/4 (S^2 - d^2)(d^2 - D^2)/d^2 (S = r1 + r2, D = r1 - r2, d = S - delta), or
  pi (r1^2 - (r1 - delta)^2) on a wall (``cohesion_model_sjkr.h``); ``sjkr2``
  A = 4 pi R* delta (wall: 2 pi r1 delta, ``cohesion_model_sjkr2.h``). The normal
  force is the normal model's plus this one, so the elastic energy is unchanged
  and the cohesion work u_adh = -k int_0^delta A(s) ds (J, negative) is reported apart;
- ``cohesion easo/capillary/viscous|washino/capillary/viscous`` add a liquid bridge's capillary
  force, which also acts across a gap up to the bridge's rupture distance, and a viscous force
  (dissipative: no energy). u_adh is the capillary force's work from the current state to rupture,
  int_{-s_rup}^delta F (J, negative), from the per-atom liquid content ``f_surfaceLiquidContent``
  of the atom dump (:mod:`._liquid_bridge`). Their contacts apart (delta < 0) hold a bridge within
  its rupture distance, an easo bridge (formed when the bodies touched) only while the history
  value ``liquid_bridge`` (LIGGGHTS' ``contflag``) is 1.

Apart (delta <= 0) a contact has no normal, tangential or rolling energy: LIGGGHTS evaluates
those models only on touching bodies and resets the tangential and rolling histories of bodies
that part (``surfacesClose``).

A normal-model law derives from :class:`LiggghtsNormalModel` and gives its
normal (and tangential) energy and its kn, kt; this base adds the rolling and
cohesion modes. Not a law itself.
"""

from __future__ import annotations

from abc import abstractmethod
from typing import Any

import numpy as np

from ...errors import ContactError, InputFormatError, UnsupportedModelError
from ..elastic import history_spring_energy, overlap
from ..modes import NOT_COMPUTED_BITS
from ..moduli import effective_radius
from ._liquid_bridge import BRIDGE_MODELS, FORMED_ON_TOUCH, WASHINO_FRACTION, LiquidBridges
from .base import ContactLaw, ContactRows, LawEnergy

SHEAR = ("shearx", "sheary", "shearz")
"""Contact columns of the tangential spring history (m)."""
ROLLING_TORQUE = ("rolling_torquex", "rolling_torquey", "rolling_torquez")
"""Contact columns of the rolling spring history, the spring's torque M_r (N m)."""
TORSION_TORQUE = ("torsion_torquex", "torsion_torquey", "torsion_torquez")
"""Contact columns of ``rolling_friction luding``'s torsion-torque history (N m), after its rolling torque."""

TANGENTIAL_MODELS = {"history": True, "no_history": False, "tan_luding": True}
"""LIGGGHTS ``tangential`` model -> whether it keeps a spring (``shear`` history)."""
ROLLING_MODELS = {"off": False, "cdt": False, "epsd": True, "epsd2": True, "epsd3": True, "luding": True}
"""LIGGGHTS ``rolling_friction`` model -> whether it keeps a spring (rolling-torque history)."""
COHESION_MODELS = ("off", "sjkr", "sjkr2", *BRIDGE_MODELS)
"""LIGGGHTS ``cohesion`` models whose work demsplit computes."""
LIQUID_CONTENT = "f_surfaceLiquidContent"
"""Atom-dump column of the per-atom liquid content the liquid-bridge models read: the ``fix property/atom``
``surfaceLiquidContent`` LIGGGHTS creates for them (volume of liquid over the particle's volume)."""
BRIDGE_FLAG = "liquid_bridge"
"""Contact column of the liquid-bridge models' history value (``contflag``): 1 while the contact holds a bridge."""
LIQUID_TRANSFER_FIX = (
    "fix liquidtransfer all transportequation/scalar equation_id liquidtransfer quantity "
    "surfaceLiquidContent default_value {initial:e} flux_quantity liquidFlux source_quantity "
    "liquidSource capacity_quantity none"
)
"""The fix a liquid-bridge model creates when the first run starts (``cohesion_model_*_capillary_viscous.h``, with
its ``%e`` of surfaceLiquidContentInitial); it creates the ``surfaceLiquidContent`` property/atom."""


def _table(value: Any) -> Any:
    """A per-type-pair table as nested tuples (hashable, so that two models compare equal)."""
    if value is None or np.ndim(value) == 0:
        return value
    return tuple(tuple(float(v) for v in row) for row in np.asarray(value, dtype=np.float64))


def rolling_spring_energy(torque: np.ndarray, kr: np.ndarray | float) -> np.ndarray:
    """Energy of the rolling spring, |M_r|^2/(2 kr) (J): ``torque`` (n, 3) in N m, ``kr`` in N m/rad.
    A contact with kr = 0 (no overlap) holds no spring: 0."""
    m2 = np.einsum("ij,ij->i", torque, torque)
    kr = np.broadcast_to(np.asarray(kr, dtype=np.float64), m2.shape)
    return np.divide(m2, 2.0 * kr, out=np.zeros_like(m2), where=kr > 0)


def sjkr_area_integral(delta: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """int_0^delta A(s) ds (m^3) of LIGGGHTS ``sjkr``'s contact area A.

    Two spheres: A = pi/4 (S^2 - d^2)(d^2 - D^2)/d^2, d = S - s, whose integral is
    (pi/4) delta^2 [(4 r1 r2 - S delta)/(S - delta) - delta/3] (no cancellation for
    small delta); a wall (r2 = inf): A = pi (2 r1 s - s^2), integral pi (r1 delta^2 - delta^3/3).
    """
    d = overlap(delta)
    wall = np.isinf(r2)
    S = np.where(wall, 1.0, r1 + r2)
    pair = (np.pi / 4.0) * d * d * ((4.0 * r1 * np.where(wall, 1.0, r2) - S * d) / (S - d) - d / 3.0)
    plane = np.pi * (r1 * d * d - d**3 / 3.0)
    return np.where(wall, plane, pair)


def sjkr2_area_integral(delta: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """int_0^delta A(s) ds (m^3) of LIGGGHTS ``sjkr2``: A = 4 pi R* s, so 2 pi R* delta^2
    (a wall: A = 2 pi r1 s, so pi r1 delta^2)."""
    d = overlap(delta)
    return np.where(np.isinf(r2), np.pi * r1 * d * d, 2.0 * np.pi * effective_radius(r1, r2) * d * d)


def sjkr_area(delta: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """LIGGGHTS ``sjkr``'s contact area A (m^2): pi/4 (S^2 - d^2)(d^2 - D^2)/d^2 for two spheres, written
    as pi/4 delta (2 S - delta)(4 r1 r2 - 2 S delta + delta^2)/(S - delta)^2 (no cancellation); a wall:
    pi (2 r1 delta - delta^2)."""
    d = overlap(delta)
    wall = np.isinf(r2)
    S = np.where(wall, 1.0, r1 + r2)
    pair = (np.pi / 4.0) * d * (2.0 * S - d) * (4.0 * r1 * np.where(wall, 1.0, r2) - 2.0 * S * d + d * d) / (S - d) ** 2
    return np.where(wall, np.pi * (2.0 * r1 * d - d * d), pair)


def sjkr2_area(delta: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """LIGGGHTS ``sjkr2``'s area A = 4 pi R* delta (m^2); a wall: 2 pi r1 delta."""
    d = overlap(delta)
    return np.where(np.isinf(r2), 2.0 * np.pi * r1 * d, 4.0 * np.pi * effective_radius(r1, r2) * d)


_AREA_INTEGRAL = {"sjkr": sjkr_area_integral, "sjkr2": sjkr2_area_integral}
_AREA = {"sjkr": sjkr_area, "sjkr2": sjkr2_area}


class LiggghtsNormalModel(ContactLaw):
    """A LIGGGHTS normal model with its ``tangential``, ``rolling_friction`` and ``cohesion`` sub-models
    as parameters (module docstring). A subclass gives :meth:`normal_and_tangential`, :meth:`kn`
    and :meth:`kt`."""

    modes = ("u_n", "u_t")
    mode_columns = {"u_t": SHEAR, "u_r": ROLLING_TORQUE}
    parameters = {
        "tangential": ("history", "LIGGGHTS tangential model: history, no_history or tan_luding"),
        "rolling": ("off", "LIGGGHTS rolling_friction model: off, cdt, epsd, epsd2, epsd3 or luding"),
        "cohesion": ("off", "LIGGGHTS cohesion model: off, sjkr or sjkr2"),
        "rolling_friction": (None, "coefficientRollingFriction mu_r, per type pair (epsd, epsd3)"),
        "rolling_stiffness": (None, "coeffRollStiffness, scalar (epsd3)"),
        "cohesion_energy_density": (None, "cohesionEnergyDensity k (J/m^3), per type pair (sjkr, sjkr2)"),
        "friction_stiffness": (
            None,
            "coeffFrictionStiffness kT2kcMax, the tangential spring over kt, per type pair (tan_luding)",
        ),
        "rolling_stiffness_ratio": (None, "coeffRollingStiffness kR2kcMax, kr/(kt R*^2), per type pair (luding)"),
        "torsion": ("off", "the torsion setting of rolling_friction luding; only off is supported"),
        "surface_tension": (None, "surfaceTension gamma (N/m), scalar (liquid bridges)"),
        "contact_angle": (None, "contactAngle (degrees), per atom type (liquid bridges)"),
        "max_separation_ratio": (
            None,
            "maxSeparationDistanceRatio: a bridge breaks at a gap of (ratio - 1)(r1 + r2), scalar (liquid bridges)",
        ),
        "min_separation_ratio": (
            None,
            "minSeparationDistanceRatio, scalar: the viscous force's smallest gap over "
            "R* (liquid bridges; dissipative, no energy)",
        ),
        "fluid_viscosity": (
            None,
            "fluidViscosity (Pa s), scalar (liquid bridges; the viscous force is dissipative, no energy)",
        ),
        "liquid_content_initial": (
            None,
            "surfaceLiquidContentInitial, scalar: the liquid content every particle "
            "starts with (liquid bridges; the energy reads the atom dump's)",
        ),
        "bridge_volume_fraction": (
            None,
            "the share of the two particles' liquid in a washino bridge: lbVolumeFraction "
            f"with modifyLbVolume on (default {WASHINO_FRACTION})",
        ),
        "limit_liquid_content": ("off", "washino's limitLiquidContent setting; only off is supported"),
        "contact_distance_factor": (
            None,
            "neigh_modify contact_distance_factor (default 1); LIGGGHTS raises it to "
            "1.1 maxSeparationDistanceRatio (liquid bridges)",
        ),
    }
    simulator_parameters = {
        "characteristicVelocity": "characteristic_velocity",
        "coefficientRollingFriction": "rolling_friction",
        "rollingStiffness": "rolling_stiffness",
        "cohesionEnergyDensity": "cohesion_energy_density",
        "kn": "kn",
        "kt": "kt",
        "coefficientMaxElasticStiffness": "max_elastic_stiffness",
        "coefficientAdhesionStiffness": "adhesion_stiffness",
        "coefficientPlasticityDepth": "plasticity_depth",
        "LoadingStiffness": "loading_stiffness",
        "UnloadingStiffness": "unloading_stiffness",
        "pullOffForce": "pull_off_force",
        "overlapExponent": "overlap_exponent",
        "surfaceEnergy": "surface_energy",
        "coeffFrictionStiffness": "friction_stiffness",
        "coeffRollingStiffness": "rolling_stiffness_ratio",
        "surfaceTension": "surface_tension",
        "contactAngle": "contact_angle",
        "maxSeparationDistanceRatio": "max_separation_ratio",
        "minSeparationDistanceRatio": "min_separation_ratio",
        "fluidViscosity": "fluid_viscosity",
        "surfaceLiquidContentInitial": "liquid_content_initial",
    }
    """LIGGGHTS ``fix property/global`` names of the parameters of its normal models and sub-models: a normal
    model takes those of the parameters it declares."""
    simulator_settings = {"ktToKnUser": ("kt_to_kn", 2.0 / 7.0, 1.0), "torsion": ("torsion", "on", "off")}
    """Switches of the ``pair_style gran``/``fix wall/gran`` line and the parameters they set."""

    def check(self) -> None:
        p = self.params
        for name, allowed in (
            ("tangential", TANGENTIAL_MODELS),
            ("rolling", ROLLING_MODELS),
            ("cohesion", COHESION_MODELS),
        ):
            if p[name] not in allowed:
                raise UnsupportedModelError(
                    f"{self.key}: {name} model {p[name]!r} is not supported; it takes {', '.join(allowed)}."
                )
        if p["torsion"] != "off":
            raise UnsupportedModelError(
                f"{self.key}: rolling_friction luding with torsion on is not supported: LIGGGHTS 3.8 writes the "
                "torsion torque into the rolling torque's history values (rolling_model_luding.h, calcTorTorque), "
                "so the dump holds neither spring's state.",
                fix="analyse a run with torsion off, or leave it out.",
            )
        if p["limit_liquid_content"] != "off":
            raise UnsupportedModelError(
                f"{self.key}: cohesion washino/capillary/viscous with limitLiquidContent on is not supported: LIGGGHTS "
                "3.8 clips the particles' liquid content inside the force evaluation (after the atom dump wrote it) "
                "and replaces maxSeparationDistanceRatio by a value of its own, so the dump does not hold the "
                "bridges' state.",
                fix="analyse a run with limitLiquidContent off.",
            )
        bridge = p["cohesion"] in BRIDGE_MODELS
        needed = {
            "rolling_friction": p["rolling"] in ("epsd", "epsd3"),
            "rolling_stiffness": p["rolling"] == "epsd3",
            "rolling_stiffness_ratio": p["rolling"] == "luding",
            "friction_stiffness": p["tangential"] == "tan_luding",
            "cohesion_energy_density": p["cohesion"] in ("sjkr", "sjkr2"),
            **{
                name: bridge
                for name in (
                    "surface_tension",
                    "contact_angle",
                    "max_separation_ratio",
                    "min_separation_ratio",
                    "fluid_viscosity",
                    "liquid_content_initial",
                )
            },
        }
        for name, need in needed.items():
            if need and p[name] is None:
                raise UnsupportedModelError(
                    f"{self.key} with tangential {p['tangential']}, rolling_friction "
                    f"{p['rolling']} and cohesion {p['cohesion']} needs the parameter "
                    f"{name!r} ({self.parameters[name][1]}).",
                    fix="define it in the script with fix property/global, as the run did.",
                )
        for name in ("rolling_friction", "cohesion_energy_density", "friction_stiffness", "rolling_stiffness_ratio"):
            if p[name] is not None:
                p[name] = self.table(name)
        if "pull_off_force" in p:  # a normal model with a constant pull-off force f0 (luding, edinburgh)
            f0 = np.asarray(p["pull_off_force"], dtype=np.float64)
            if not np.all(np.isfinite(f0)):
                raise UnsupportedModelError(
                    f"{self.key}: pullOffForce must be finite, got {f0.tolist()!r}.",
                    fix="correct the fix property/global line of the script.",
                )
            p["pull_off_force"] = f0.item() if f0.ndim == 0 else tuple(map(tuple, f0.tolist()))
        self.modes = tuple(
            m
            for m, has in (
                ("u_n", True),
                ("u_t", TANGENTIAL_MODELS[p["tangential"]]),
                ("u_r", ROLLING_MODELS[p["rolling"]]),
                ("u_adh", p["cohesion"] != "off" or self.has_pull_off()),
            )
            if has
        )
        self.mode_columns = {m: cols for m, cols in type(self).mode_columns.items() if m in self.modes}
        if bridge:
            self._check_bridge()

    def _check_bridge(self) -> None:
        """The liquid-bridge parameters checked as LIGGGHTS does; the contact-angle table theta1 theta2/2 (rad, per
        type pair, LIGGGHTS 3.8.0: ``_liquid_bridge``), the liquid-content particle column and the bridge flag."""
        p = self.params
        for name in (
            "surface_tension",
            "max_separation_ratio",
            "min_separation_ratio",
            "fluid_viscosity",
            "liquid_content_initial",
            "bridge_volume_fraction",
            "contact_distance_factor",
        ):
            if p[name] is not None:
                p[name] = float(self.table(name))
        angles = np.atleast_1d(np.asarray(p["contact_angle"], dtype=np.float64))
        if angles.ndim != 1 or not np.all((angles >= 0) & (angles <= 180)):
            raise UnsupportedModelError(
                f"{self.key}: contactAngle must be one value per atom type in 0..180 degrees, got {angles.tolist()!r}.",
                fix="correct the fix property/global line of the script (LIGGGHTS refuses it too).",
            )
        p["contact_angle"] = angles.item() if np.ndim(p["contact_angle"]) == 0 else tuple(angles.tolist())
        theta = angles * np.pi / 180.0  # as LIGGGHTS converts it (global_properties.cpp)
        self._theta = _table(0.5 * np.outer(theta, theta)) if theta.size > 1 else 0.5 * float(theta[0]) ** 2
        self.particle_columns = (*type(self).particle_columns, LIQUID_CONTENT)
        if FORMED_ON_TOUCH[p["cohesion"]]:  # whether a bridge holds across a gap is in the history
            self.mode_columns = {**self.mode_columns, "u_adh": (BRIDGE_FLAG,)}
        else:  # read where dumped, to check it (a bridge LIGGGHTS holds beyond rupture is refused)
            self.contact_columns = (*type(self).contact_columns, BRIDGE_FLAG)

    def has_pull_off(self) -> bool:
        """Whether the normal model pulls the bodies with a nonzero constant force f0 (``pull_off_force``)."""
        return "pull_off_force" in self.params and bool(np.any(np.asarray(self.params["pull_off_force"]) != 0))

    def table(self, name: str) -> Any:
        """Parameter ``name`` as a per-type-pair table of nested tuples (or its scalar), checked finite and >= 0."""
        value = _table(self.params[name])
        if not np.all(np.isfinite(np.asarray(value, dtype=np.float64))) or np.any(np.asarray(value) < 0):
            raise UnsupportedModelError(
                f"{self.key}: parameter {name!r} must be finite and >= 0, got {value!r}.",
                fix="correct the fix property/global line of the script.",
            )
        return value

    # -- what a normal model gives ------------------------------------------------------------

    normal_history: tuple[str, ...] = ()
    """Contact columns of the normal model's own history values, in LIGGGHTS' order."""

    applied_force: bool = False
    """The law gives the damped force LIGGGHTS applies (:meth:`damping`), which lets a wall fix's stored force
    give back the springs of its contacts (:mod:`._liggghts_force`)."""

    def damping(self, rows: ContactRows, restitution: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """The damping coefficients gamma_n, gamma_t (kg/s) of every row, with the per-row coefficient of
        restitution ``restitution``: a law with :attr:`applied_force` gives them."""
        raise UnsupportedModelError(f"{self.key}: demsplit does not model the damped force this normal model applies.")

    def normal_history_of_force(self, rows: ContactRows, f: np.ndarray) -> dict[str, np.ndarray]:
        """The normal model's history columns (:attr:`normal_history`) of every row whose elastic normal force is
        ``f`` (N): none for a model whose force follows from the overlap alone."""
        return {}

    @abstractmethod
    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        """``u_n`` of every row (J)."""

    @abstractmethod
    def kn(self, rows: ContactRows) -> np.ndarray:
        """The normal stiffness LIGGGHTS sets for the sub-models, ``sidata.kn`` (N/m), per row."""

    @abstractmethod
    def kt(self, rows: ContactRows) -> np.ndarray:
        """The tangential stiffness LIGGGHTS sets, ``sidata.kt`` (N/m), per row."""

    def normal_and_tangential(self, rows: ContactRows, with_shear: bool, compiled: bool) -> dict[str, np.ndarray]:
        """``u_n`` and, with ``with_shear``, ``u_t`` = kt |shear|^2/2 of every row (J); a law with a faster
        joint evaluation overrides it."""
        modes = {"u_n": self.normal_energy(rows)}
        if with_shear:
            modes["u_t"] = history_spring_energy(rows.delta, self.shear(rows), self.kt(rows))
        return modes

    def history_columns(self) -> list[str]:
        """The contact history LIGGGHTS keeps for this model, as demsplit names its columns, in LIGGGHTS'
        order (sub-model construction order, ``contact_models.h``): surface (none for ``default``), normal,
        cohesion (none for sjkr, sjkr2; the bridge flag for the liquid bridges), tangential, rolling (``luding``:
        the rolling, then the torsion torque)."""
        rolling = (*ROLLING_TORQUE, *(TORSION_TORQUE if self.params["rolling"] == "luding" else ()))
        return [
            *self.normal_history,
            *((BRIDGE_FLAG,) if self.params["cohesion"] in BRIDGE_MODELS else ()),
            *(SHEAR if "u_t" in self.modes else ()),
            *(rolling if "u_r" in self.modes else ()),
        ]

    def describe(self) -> str:
        """The normal model's line, then the rolling and cohesion sub-models the contact has."""
        extra = []
        if "u_r" in self.modes:
            extra.append(f"rolling {self.params['rolling']} u_r = |M_r|^2/(2 kr)")
        if self.params["cohesion"] in BRIDGE_MODELS:
            extra.append(
                f"cohesion {self.params['cohesion']} work u_adh = int F_cap from rupture (liquid content "
                f"{LIQUID_CONTENT}; apart from u; its viscous force stores no energy)"
            )
        elif "u_adh" in self.modes:
            extra.append(f"cohesion {self.params['cohesion']} work u_adh = -k int A (apart from u)")
        return super().describe() + "".join(f"; {e}" for e in extra)

    # -- the composition ------------------------------------------------------------------------

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        skipped = {m: why for m in self.mode_columns if (why := self.missing_mode(rows, m))}
        with_shear = "u_t" in self.modes and "u_t" not in skipped
        if "u_n" in skipped:  # the normal model's history was not dumped
            modes = {"u_t": history_spring_energy(rows.delta, self.shear(rows), self.kt(rows))} if with_shear else {}
        else:
            modes = self.normal_and_tangential(rows, with_shear, compiled)
        if with_shear and self.params["tangential"] == "tan_luding":  # its spring is kT2kcMax kt: u_t scales
            modes["u_t"] = rows.type_pair(self.params["friction_stiffness"]) * modes["u_t"]
        if "u_r" in self.modes and "u_r" not in skipped:
            modes["u_r"] = rolling_spring_energy(self.vectors(rows, ROLLING_TORQUE), self.kr(rows))
        touching = rows.delta > 0
        if not touching.all():  # apart: no normal, tangential or rolling energy (module docstring)
            for m in ("u_n", "u_t", "u_r"):
                if m in modes:
                    modes[m] = np.where(touching, modes[m], 0.0)
        unknown = {}
        lost = rows.column("history_unknown").astype(np.int64) if rows.has("history_unknown") else None
        if lost is not None and lost.any():  # no history written: only a touching contact's history modes unknown
            unknown = {
                m: ((lost & NOT_COMPUTED_BITS[m]) != 0) & touching for m in self.mode_columns if m not in skipped
            }
        if self.params["cohesion"] != "off" and "u_adh" not in skipped:
            modes["u_adh"], unknown_adh = self._cohesion(rows, work=True)
            if lost is not None and lost.any():
                unknown["u_adh"] = ((lost & NOT_COMPUTED_BITS["u_adh"]) != 0) & unknown_adh
        if self.has_pull_off() and "u_adh" not in skipped:  # the constant pull-off force's work f0 delta
            work = rows.type_pair(self.params["pull_off_force"]) * overlap(rows.delta)
            modes["u_adh"] = modes.get("u_adh", 0.0) + work
        return LawEnergy(modes, skipped, unknown)

    def cohesion_force(self, rows: ContactRows) -> np.ndarray:
        """The cohesion model's normal force (N, negative: attractive), d(u_adh)/d(delta): -k A (sjkr, sjkr2), a
        liquid bridge's capillary force; 0 without one."""
        if self.params["cohesion"] == "off":
            return np.zeros_like(rows.delta)
        return self._cohesion(rows, work=False)[0]

    def _cohesion(self, rows: ContactRows, work: bool) -> tuple[np.ndarray, np.ndarray]:
        """The cohesion model's work u_adh (J, ``work``) or force (N) of every row, and the rows whose value the
        data cannot give without the contact's history: an easo bridge's contacts apart within rupture."""
        cohesion = self.params["cohesion"]
        none = np.zeros(rows.delta.shape, dtype=bool)
        if cohesion not in BRIDGE_MODELS:
            k = rows.type_pair(self.params["cohesion_energy_density"])
            area = (_AREA_INTEGRAL if work else _AREA)[cohesion](rows.delta, rows.r1, rows.r2)
            return -k * area, none
        bridges = self.bridges(rows)
        apart = ~(rows.delta > 0)
        acting = apart & bridges.present & (-rows.delta < bridges.rupture)
        value = bridges.work(rows.delta) if work else bridges.force(rows.delta)
        on_touch = FORMED_ON_TOUCH[cohesion]
        flag = rows.column(BRIDGE_FLAG) if on_touch or rows.has(BRIDGE_FLAG) else np.zeros_like(value)
        beyond = apart & (flag == 1) & (-rows.delta > bridges.rupture * (1.0 + 1e-12))
        if beyond.any():
            i = int(np.flatnonzero(beyond)[0])
            raise ContactError(
                f"{int(np.count_nonzero(beyond))} contact(s) hold a liquid bridge (history value {BRIDGE_FLAG} 1) at "
                f"a gap beyond its rupture distance, e.g. a gap of {float(-rows.delta[i]):g} m for a rupture "
                f"distance of {float(bridges.rupture[i]):g} m: LIGGGHTS breaks such a bridge, so the liquid contents "
                "or the positions are not those of the contact dump's step.",
                fix=f"dump {LIQUID_CONTENT} in the atom dump of the same run and steps as the contact dump.",
            )
        if not on_touch:  # a washino bridge acts wherever the gap is below rupture
            return value, none
        held = ~apart | (flag == 1)  # touching: LIGGGHTS always holds a bridge (surfacesIntersect sets contflag)
        return np.where(held, value, 0.0), acting

    def bridges(self, rows: ContactRows) -> LiquidBridges:
        """The liquid bridge of every row (:class:`._liquid_bridge.LiquidBridges`) with the particles' liquid content
        ``f_surfaceLiquidContent``."""
        p = self.params
        c1, c2 = rows.particle_column(LIQUID_CONTENT)
        wall = np.isinf(rows.r2)
        bad = ~(c1 >= 0) | (~wall & ~(c2 >= 0))
        if bad.any():
            value = c1[bad][0] if not (c1[bad][0] >= 0) else c2[bad][0]
            raise InputFormatError(
                f"the liquid content {LIQUID_CONTENT} of a particle is {float(value)!r}; it must be >= 0.",
                fix="check the atom dump's column (a damaged or foreign value).",
            )
        return LiquidBridges(
            p["cohesion"],
            rows.r1,
            rows.r2,
            c1,
            c2,
            rows.type_pair(self._theta),
            p["surface_tension"],
            p["max_separation_ratio"],
            self.contact_distance_factor(),
            WASHINO_FRACTION if p["bridge_volume_fraction"] is None else p["bridge_volume_fraction"],
        )

    def dump_setup(self) -> list[str]:
        """LIGGGHTS commands that, placed before the first run, let a ``dump custom`` write the law's particle columns
        (which LIGGGHTS checks when it reads the dump command): with a liquid bridge, the fix the model would
        create at the first run (:data:`LIQUID_TRANSFER_FIX`), created earlier, to the same effect."""
        if self.params["cohesion"] not in BRIDGE_MODELS:
            return []
        return [LIQUID_TRANSFER_FIX.format(initial=self.params["liquid_content_initial"])]

    def contact_distance_factor(self) -> float:
        """LIGGGHTS' contact distance factor with a liquid bridge: the larger of ``neigh_modify
        contact_distance_factor`` (1 by default) and 1.1 maxSeparationDistanceRatio (``neighbor.h``)."""
        given = self.params["contact_distance_factor"]
        return max(1.0 if given is None else given, self.params["max_separation_ratio"] * 1.1)

    def separation_limit(self, r1: np.ndarray | float, r2: np.ndarray | float) -> np.ndarray | float:
        """0 but with a liquid bridge: LIGGGHTS writes a pair apart only while its bridge acts, so below
        (maxSeparationDistanceRatio - 1)(r1 + r2), and a wall contact apart while it evaluates it, below
        (cdf - 1) r1 (``fix_wall_gran.cpp``; :meth:`contact_distance_factor`)."""
        if self.params["cohesion"] not in BRIDGE_MODELS:
            return 0.0
        r1, r2 = np.asarray(r1, dtype=np.float64), np.asarray(r2, dtype=np.float64)
        wall = np.isinf(r2)
        return np.where(
            wall,
            (self.contact_distance_factor() - 1.0) * r1,
            (self.params["max_separation_ratio"] - 1.0) * (r1 + np.where(wall, 0.0, r2)),
        )

    def kr(self, rows: ContactRows) -> np.ndarray:
        """Rolling stiffness of the ``rolling_friction`` model (N m/rad), per row (module docstring)."""
        R2 = effective_radius(rows.r1, rows.r2) ** 2
        rolling = self.params["rolling"]
        if rolling == "epsd2":
            return self.kt(rows) * R2
        if rolling == "luding":
            return rows.type_pair(self.params["rolling_stiffness_ratio"]) * self.kt(rows) * R2
        mu = rows.type_pair(self.params["rolling_friction"])
        factor = 2.25 if rolling == "epsd" else float(self.params["rolling_stiffness"])
        return factor * self.kn(rows) * mu * mu * R2

    @staticmethod
    def vectors(rows: ContactRows, columns: tuple[str, str, str]) -> np.ndarray:
        """Three contact columns of every row as one (n, 3) array."""
        return np.stack([rows.column(c) for c in columns], axis=-1)

    def shear(self, rows: ContactRows) -> np.ndarray:
        """The tangential spring displacement of every row, shape (n, 3) (m)."""
        return self.vectors(rows, SHEAR)
