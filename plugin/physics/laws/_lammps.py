"""What LAMMPS' granular contact models share (Debian's LAMMPS 29 Sep 2021, GRANULAR package).

A LAMMPS granular contact is a normal model composed with sub-models, set per type pair by a
``pair_coeff i j`` line of ``pair_style granular`` (``pair_granular.cpp``) or per wall by the words of a
``fix wall/gran ... granular`` (``fix_wall_gran.cpp``); the legacy styles ``gran/hooke``,
``gran/hooke/history`` and ``gran/hertz/history`` are one model for every pair. Line numbers below are
of that version's files.

Notation: delta the overlap, R the effective radius (r_i r_j/(r_i + r_j); a wall: r_i, or
r_i r_w/(r_i + r_w) with the wall's curvature radius r_w), a the contact radius, m* the reduced mass
(a wall: m_i), kn the normal coefficient of the model (N/m or N/m^(3/2)).

- damping (pair_granular.cpp:363-377): F_n = F_ne - eta_n v_n with eta_n = damp times 1 (``velocity``), m*
  (``mass_velocity``), a m* (``viscoelastic``, the default) or sqrt(m* kn_fac) (``tsuji``, damp = alpha(e)
  of the line's e, applied once for a pair and once per ``run`` for a wall, fix_wall_gran.cpp:535-540);
  ``limit_damping`` clips F_n < 0 to 0.
- Coulomb limit (:412-421): mu F_ncrit with F_ncrit = |F_ne + 6 pi gamma R| (jkr), |F_ne + 8 pi gamma R| (dmt, as
  documented: the code reads an unset variable, so a dmt spring at its limit is unknown), |F_n| (others).
- tangential (:423-546): eta_t = x_gammat eta_n; the spring k_t (``linear_history``) or k_t a (``mindlin``,
  ``mindlin_rescale``, ``*/force``) holds an elastic force F_el, whose energy is u_t = |F_el|^2/(2 k);
  ``linear_nohistory`` keeps none (u_t = 0). k_t NULL: 2E/((2 - nu)(1 + nu)) (:1021-1024), a wall
  E/4 (2 - nu)(1 + nu) (fix_wall_gran.cpp:248, measured).
- rolling ``sds`` (:550-616): k_r, gamma_r, mu_r; the pseudo-force's elastic part F_r,el, u_r = |F_r,el|^2/(2 k_r),
  its limit mu_r F_ncrit, v_r = R (omega_i - omega_j) x n, the torque R n x F_r.
- twisting ``sds`` (k_tw, gamma_tw, mu_tw) or ``marshall`` (k_tw = k a^2/2 with k the tangential spring,
  :620-646): u_tw = tau_el^2/(2 k_tw). No dump holds the twisting spring (``compute pair/local p9`` is the
  torque only where single() capped it).

A wall's model uses kn = 4/3 E/(2(1 - nu)) for the material models (fix_wall_gran.cpp:160, :171, :183; not
1 - nu^2), m* = m_i and the torque -r_i n x F_t (full radius).

The springs are rebuilt from what LAMMPS dumps (:meth:`LammpsModel.rebuild`): ``compute pair/local`` writes
single()'s forces, F_el plus the damping at the velocities then held (full step for the owned atom i, half
step for a ghost j); the step applied F_el plus the damping at the half-step velocities, capped at the
step's limit with the spring reset there. :func:`unsliding` removes the damping. A spring single() found at
its limit lies where the step's limit puts it (:func:`unsliding`'s capped root) unless the step was not
capped; the reader checks those against the atoms' force and torque balance.

Energies are of the rebuilt springs, which the reader writes as the contact columns
``ftx_el fty_el ftz_el`` (the tangential spring's force on body 1, N), ``frx_el fry_el frz_el`` (the
rolling spring's pseudo-force, N) and, were it known, ``tw_el`` (the twisting spring's torque, N m).
"""

from __future__ import annotations

import math
from abc import abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...errors import UnsupportedModelError
from ..modes import NOT_COMPUTED_BITS
from ..moduli import f64
from .base import ContactLaw, ContactRows, LawEnergy

SPRING_T = ("ftx_el", "fty_el", "ftz_el")
"""Contact columns of the rebuilt tangential spring: its elastic force on body 1 (N)."""
SPRING_R = ("frx_el", "fry_el", "frz_el")
"""Contact columns of the rebuilt rolling spring: its elastic pseudo-force (N)."""
SPRING_TW = ("tw_el",)
"""Contact column of the twisting spring's elastic torque (N m): no LAMMPS dump holds it."""
CURVATURE = "wall_curvature"
"""Contact column 1/r_w (1/m) of a curved wall's curvature as LAMMPS uses it (0: flat, or a pair)."""

VELOCITIES = tuple(f"{q}{c}_{w}" for q in ("dv", "ws", "wr") for w in ("s", "h") for c in "xyz")
"""Contact columns of the velocities the rebuild removes the damping with, at the dumped force's velocities
(``_s``) and the step's (``_h``): ``dv`` v_1 - v_2 (a wall: its velocity), ``ws`` r_1 omega_1 + r_2 omega_2
(a wall: r_1 omega_1), ``wr`` omega_1 - omega_2 (a wall: omega_1)."""
DUMPED = ("fn_dumped", "ftx_dumped", "fty_dumped", "ftz_dumped", "frx_dumped", "fry_dumped", "frz_dumped")
"""Contact columns of what LAMMPS wrote of a contact's force: the normal force on body 1 along n_L, the
tangential force, the rolling pseudo-force (a wall: 0, not dumped)."""
T_BIT, R_BIT = NOT_COMPUTED_BITS["u_t"], NOT_COMPUTED_BITS["u_r"]
UNKNOWN_MODES, UNKNOWN_WHY = "unknown_modes", "unknown_why"
"""Contact columns the reader writes where it could not rebuild a spring: the bits of the modes, and the
:data:`REASONS` code of why."""
DUMP_ROW = "dump_row"
"""Contact column: the row of a pair in its frame of the local dump (a wall contact: -1)."""

TANGENTIAL_MODELS = {
    "linear_nohistory": False,
    "linear_history": True,
    "mindlin": True,
    "mindlin_rescale": True,
    "mindlin/force": True,
    "mindlin_rescale/force": True,
}
"""LAMMPS ``tangential`` models -> whether they keep a spring."""
DAMPING_MODELS = ("velocity", "mass_velocity", "viscoelastic", "tsuji")
ROLLING_MODELS = ("none", "sds")
TWISTING_MODELS = ("none", "sds", "marshall")

REASONS = {
    1: "LAMMPS' single() writes all zeros for a jkr pair closer than its pull-off distance (pair_granular.cpp"
    ":1423-1437), so its tangential and rolling springs are in no dump",
    2: "dmt's Coulomb limit reads a variable only jkr sets (pair_granular.cpp:416, :1589): the first pair row of "
    "a frame and any row at that limit hold a spring no dump gives",
    3: "single() found the spring at its Coulomb limit but the step did not (the step's damping differs), so "
    "the spring lies in an interval that the atoms' force and torque balance did not pin",
    4: "a particle touches two surfaces of a wall/gran/region region and the fix's contacts array keeps the last "
    "one only (fix_wall_gran_region.cpp:244-254): the other contact's tangential spring is in no dump",
    5: "a jkr pair apart by less than its pull-off distance may still hold its neck: whether it does (its touch "
    "flag) is in no dump, and compute pair/local's cutoff radius rows list touching pairs only",
    6: "an atom of the contact does not close its force or torque balance with the rebuilt springs (a term of the "
    "step is not what the dumps and the script say), so the springs of its contacts are not trusted",
}
"""Why the reader could not rebuild a spring or a contact: the code it writes in the contact column ``unknown_why``
(beside the modes' bits in ``unknown_modes``) -> the reason."""


def tsuji_alpha(e: float) -> float:
    """The tsuji damping coefficient alpha(e) of a coefficient of restitution e (pair_granular.cpp:986-993)."""
    return 1.2728 - 4.2783 * e + 11.087 * e**2 - 22.348 * e**3 + 27.467 * e**4 - 18.022 * e**5 + 4.8218 * e**6


def lammps_radius(rows: ContactRows) -> np.ndarray:
    """R = 1/(1/r_1 + 1/r_2 + 1/r_w) (m): r_1 r_2/(r_1 + r_2) of a pair, r_1 of a flat wall, r_1 r_w/(r_1 + r_w)
    of a wall whose curvature 1/r_w is the contact column ``wall_curvature`` (fix_wall_gran.cpp:662)."""
    k = 1.0 / rows.r1 + 1.0 / rows.r2
    if rows.has(CURVATURE):
        k = k + rows.column(CURVATURE)
    return 1.0 / k


def vectors(rows: ContactRows, columns: tuple[str, ...]) -> np.ndarray:
    """Three contact columns as one (n, 3) array."""
    return np.stack([rows.column(c) for c in columns], axis=-1)


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a . b of (n, 3) arrays."""
    return np.einsum("ij,ij->i", a, b)


def norm(a: np.ndarray) -> np.ndarray:
    """Row-wise |a| of an (n, 3) array."""
    return np.sqrt(dot(a, a))


def spring_energy_of_force(force: np.ndarray, k: np.ndarray | float) -> np.ndarray:
    """|F|^2/(2 k) (J) of a spring of stiffness k (N/m, or N m/rad for a torque) holding the force F (rows of
    an (n, 3) array, or a magnitude); 0 where k = 0."""
    f2 = dot(force, force) if force.ndim == 2 else force * force
    k = np.broadcast_to(f64(k), f2.shape)
    return np.divide(f2, 2.0 * k, out=np.zeros_like(f2), where=k > 0)


def tangential_velocity(dv: np.ndarray, n: np.ndarray, ws: np.ndarray) -> np.ndarray:
    """The relative tangential velocity at the contact (m/s), v_t - (r_i omega_i + r_j omega_j) x n
    (pair_granular.cpp:392-403): ``dv`` v_i - v_j, ``ws`` r_i omega_i + r_j omega_j, ``n`` from j to i."""
    return dv - dot(dv, n)[:, None] * n - np.cross(ws, n)


def unsliding(
    p: np.ndarray, visc_s: np.ndarray, visc_h: np.ndarray, crit_s: np.ndarray, crit_h: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The elastic force F_el of a spring (N) from the force p = F_el + visc_s that single() wrote, capped at
    crit_s, when the step applied F_el + visc_h capped at crit_h and reset the spring to its limit
    (pair_granular.cpp:510-536); visc_s, visc_h the damping forces at single()'s and the step's velocities.

    Not capped in single() (|p| < crit_s): F_el = p - visc_s. Capped: F_el = L w - visc_s, w = p/|p|, with
    L the larger root of |L w - D| = crit_h, D = visc_s - visc_h (the step capped too; were it not, L lies in
    (crit_s, that root]). A zero limit in the step (F_n clipped by ``limit_damping``) left F_el = -visc_h.
    Returns F_el, the capped-in-single flag, the flag of a capped row no capped step explains, and L."""
    mag = norm(p)
    zero = crit_s == 0
    capped = ((mag >= crit_s * (1.0 - 1e-10)) & (mag > 0)) | zero
    w = p / np.where(mag > 0, mag, 1.0)[:, None]
    D = visc_s - visc_h
    wD = dot(w, D)
    disc = wD * wD - dot(D, D) + crit_h * crit_h
    L = wD + np.sqrt(np.maximum(disc, 0.0))
    bad = capped & (crit_h > 0) & (zero | (disc < 0) | (L < crit_s * (1.0 - 1e-10)))
    F_el = np.where(capped[:, None], L[:, None] * w - visc_s, p - visc_s)
    F_el = np.where((crit_h == 0)[:, None], -visc_h, F_el)
    return F_el, capped, bad, L


def viscous_limited(eta: np.ndarray, vt: np.ndarray, crit: np.ndarray) -> np.ndarray:
    """A tangential force without spring, -min(crit, eta |v_t|) v_t/|v_t| (N) (pair_gran_hooke.cpp:172-183,
    ``linear_nohistory`` alone)."""
    vmag = norm(vt)
    f = np.minimum(crit, eta * vmag) / np.where(vmag > 0, vmag, 1.0)
    return -f[:, None] * vt


@dataclass
class Rebuilt:
    """A contact's springs and step forces rebuilt from the dump (:meth:`LammpsModel.rebuild`), per row.

    spring_t, spring_r : the tangential spring's elastic force on body 1 and the rolling spring's
        pseudo-force (N, (n, 3)); 0 where the model has none.
    force : the force on body 1 in the step (N, (n, 3)); torque1, torque2 : the torques on the two bodies in
        the step (N m), twisting left out.
    fn_rebuilt, fn_scale : the dumped normal force as the model gives it, and its scale |F_ne| + |damping| (N).
    unknown : bits (:data:`demsplit.physics.modes.NOT_COMPUTED_BITS`) of the modes whose spring the dump does
        not give; why : per row, the :data:`REASONS` code (0: none).
    interval_t, interval_r : capped in single(), the step's cap assumed (:func:`unsliding`): checked by the
        reader against the atoms' balance; direction_t : single()'s tangential force direction w;
        limit_t, spring_limit_t : single()'s tangential limit crit_s and the force L assumed (N);
        arm1, arm2 : the lever arms of the tangential force on each body (m).
    twisting : rows whose twisting torque tau n (on body 1; -tau n on body 2) no dump gives.
    """

    spring_t: np.ndarray
    spring_r: np.ndarray
    force: np.ndarray
    torque1: np.ndarray
    torque2: np.ndarray
    fn_rebuilt: np.ndarray
    fn_scale: np.ndarray
    unknown: np.ndarray
    why: np.ndarray
    interval_t: np.ndarray
    interval_r: np.ndarray
    direction_t: np.ndarray
    limit_t: np.ndarray
    spring_limit_t: np.ndarray
    arm1: np.ndarray
    arm2: np.ndarray
    twisting: np.ndarray


class LammpsModel(ContactLaw):
    """A LAMMPS granular contact model (module docstring): a normal model with its damping, tangential,
    rolling and twisting sub-models as parameters. A subclass gives the normal model: :meth:`contact_radius`,
    :meth:`elastic_normal_force`, :meth:`normal_energy` and the stiffness :attr:`kn`."""

    mode_columns = {"u_t": SPRING_T, "u_r": SPRING_R, "u_tw": SPRING_TW}
    line_coefficients: ClassVar[tuple[str, ...]] = ()
    """The numbers after the normal model's name on a ``pair_coeff`` (or wall fix) line, in LAMMPS' order: the
    parameters they set (pair_granular.cpp coeff())."""
    parameters: ClassVar[dict[str, tuple[Any, str]]] = {
        "damp": (ContactLaw.REQUIRED, "the normal damping coefficient (e for tsuji)"),
        "damping": ("viscoelastic", "damping model: velocity, mass_velocity, viscoelastic or tsuji"),
        "tangential": (
            ContactLaw.REQUIRED,
            "tangential model: linear_nohistory, linear_history, mindlin, "
            "mindlin_rescale, mindlin/force or mindlin_rescale/force",
        ),
        "kt": (None, "tangential stiffness k_t (N/m, mindlin: N/m^(3/2)); None: NULL, from E and nu"),
        "xgammat": (0.0, "tangential damping over normal damping x_gammat"),
        "mu": (0.0, "tangential friction coefficient"),
        "rolling": ("none", "rolling model: none or sds"),
        "kr": (0.0, "rolling stiffness k_r (N/m)"),
        "gammar": (0.0, "rolling damping gamma_r (N s/m)"),
        "mur": (0.0, "rolling friction coefficient"),
        "twisting": ("none", "twisting model: none, sds or marshall"),
        "ktw": (0.0, "twisting stiffness k_tw (N m/rad)"),
        "gammatw": (0.0, "twisting damping gamma_tw (N m s/rad)"),
        "mutw": (0.0, "twisting friction coefficient"),
        "limit_damping": (False, "limit_damping: a negative normal force is clipped to 0"),
        "history": (
            False,
            "whether another model of the pair style keeps a tangential history (LAMMPS' global "
            "flag: linear_nohistory beside it runs the history branch with k_t = 0)",
        ),
        "wall": (False, "the model of a wall fix (its kn, k_t and torque formulas)"),
    }
    example_params: ClassVar[dict[str, Any]] = {
        "damp": 0.5,
        "tangential": "mindlin",
        "xgammat": 1.0,
        "mu": 0.5,
        "rolling": "sds",
        "kr": 20.0,
        "gammar": 0.002,
        "mur": 0.1,
        "twisting": "marshall",
    }

    def check(self) -> None:
        p = self.params
        for name, allowed in (
            ("damping", DAMPING_MODELS),
            ("tangential", TANGENTIAL_MODELS),
            ("rolling", ROLLING_MODELS),
            ("twisting", TWISTING_MODELS),
        ):
            if p[name] not in allowed:
                raise UnsupportedModelError(
                    f"{self.key}: {name} model {p[name]!r} is not supported; it takes {', '.join(allowed)}."
                )
        self.kn = self.normal_coefficient()
        self.has_spring = TANGENTIAL_MODELS[p["tangential"]]
        if p["kt"] is None and self.has_spring and not self.has_material():
            raise UnsupportedModelError(
                f"{self.key}: tangential k_t NULL needs a material model (E, nu).",
                fix="give k_t on the line, as LAMMPS requires.",
            )
        self.kt = float(p["kt"]) if p["kt"] is not None else self.null_kt() if self.has_spring else 0.0
        self.history_branch = not self.has_spring and bool(p["history"])
        self.rolling, self.twisting = p["rolling"] != "none", p["twisting"] != "none"
        self.set_modes()

    def set_modes(self) -> None:
        """The modes the model has, and their columns, from :attr:`has_spring`, :attr:`rolling`, :attr:`twisting`."""
        self.modes = tuple(
            m
            for m, has in (
                ("u_n", True),
                ("u_t", self.has_spring),
                ("u_r", self.rolling),
                ("u_tw", self.twisting),
                ("u_adh", self.adhesive),
            )
            if has
        )
        self.mode_columns = {m: cols for m, cols in type(self).mode_columns.items() if m in self.modes}

    # -- the normal model ---------------------------------------------------------------------

    adhesive: ClassVar[bool] = False
    """Whether the normal model has a cohesion work u_adh."""

    def has_material(self) -> bool:
        """Whether the model carries E and nu (hertz/material, dmt, jkr)."""
        return "E" in self.params

    def material(self) -> tuple[float, float] | None:
        """(E, nu) of the line, or None for a model without them."""
        return (float(self.params["E"]), float(self.params["nu"])) if self.has_material() else None

    def material_kn(self) -> float:
        """kn = 4/3 E/(2(1 - nu^2)) of a pair line (pair_granular.cpp:1006-1016), 4/3 E/(2(1 - nu)) of a wall's
        (fix_wall_gran.cpp:160)."""
        E, nu = self.material()
        return 4.0 / 3.0 * E / (2.0 * (1.0 - nu)) if self.params["wall"] else 4.0 / 3.0 * E / (2.0 * (1.0 - nu * nu))

    def null_kt(self) -> float:
        """k_t NULL: 2E/((2 - nu)(1 + nu)) for a pair (pair_granular.cpp:1021-1024), E/4 (2 - nu)(1 + nu) for a
        wall (fix_wall_gran.cpp:248)."""
        E, nu = self.material()
        return E / 4.0 * (2.0 - nu) * (1.0 + nu) if self.params["wall"] else 2.0 * E / ((2.0 - nu) * (1.0 + nu))

    @abstractmethod
    def normal_coefficient(self) -> float:
        """kn of the model (N/m, N/m^(3/2))."""

    def contact_radius(self, delta: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The contact radius a = sqrt(R delta) (m); jkr has its own."""
        return np.sqrt(R * np.maximum(delta, 0.0))

    @abstractmethod
    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne (N), the normal force without damping (pair_granular.cpp:328-358)."""

    @abstractmethod
    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n (J) of contacts in overlap."""

    def adhesion_work(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_adh (J, negative) of contacts in overlap; 0 without cohesion."""
        return np.zeros_like(delta)

    def damping_stiffness(self, a: np.ndarray) -> np.ndarray:
        """kn_fac of tsuji damping: kn a (hooke: kn) (N/m)."""
        return self.kn * a

    def coulomb_force(self, F_ne: np.ndarray, F_n: np.ndarray, R: np.ndarray) -> np.ndarray:
        """F_ncrit (N): |F_n| (pair_granular.cpp:419); jkr and dmt their own."""
        return np.abs(F_n)

    def stale_limit(self, rows: ContactRows, capped: np.ndarray) -> np.ndarray:
        """Rows whose Coulomb limit is not what the code meant to compute (dmt), given the rows ``capped`` at
        it in single(): their springs are unknown."""
        return np.zeros(len(capped), dtype=bool)

    def reach(self, R: np.ndarray) -> np.ndarray:
        """The largest gap (m) across which a pair of effective radius R may still act: 0 but for jkr, whose neck
        holds until pull-off; such a pair is in no ``cutoff radius`` row (it does not touch)."""
        return np.zeros_like(R)

    def unwritten(self, rows: ContactRows, R: np.ndarray) -> np.ndarray:
        """Rows single() wrote as zeros though the pair touches (jkr); none for the other models."""
        return np.zeros(len(R), dtype=bool)

    # -- sub-models --------------------------------------------------------------------------

    def tangential_stiffness(self, a: np.ndarray) -> np.ndarray:
        """The tangential spring k (N/m): k_t (linear_history), k_t a (mindlin*), 0 without a spring."""
        if not self.has_spring:
            return np.zeros_like(a)
        return self.kt * a if self.params["tangential"].startswith("mindlin") else np.full_like(a, self.kt)

    def rolling_stiffness(self) -> float:
        """k_r of rolling sds (N/m)."""
        return float(self.params["kr"])

    def twisting_stiffness(self, a: np.ndarray) -> np.ndarray:
        """k_tw (N m/rad): sds's k_tw, marshall's k a^2/2 with k the tangential spring (pair_granular.cpp:623)."""
        if self.params["twisting"] == "marshall":
            return 0.5 * self.tangential_stiffness(a) * a * a
        return np.full_like(a, float(self.params["ktw"]))

    def damp(self, inits: int) -> float:
        """The damping coefficient as the code holds it: the line's, or tsuji's alpha(e) applied ``inits`` times
        (a pair: once at its pair_coeff; a wall: once per run since its fix was defined)."""
        d = float(self.params["damp"])
        if self.params["damping"] == "tsuji":
            for _ in range(inits):
                d = tsuji_alpha(d)
        return d

    def normal_damping(self, a: np.ndarray, meff: np.ndarray, inits: int) -> np.ndarray:
        """eta_n (N s/m) of the damping model (pair_granular.cpp:363-373)."""
        factor = {
            "velocity": lambda: np.ones_like(a),
            "mass_velocity": lambda: meff,
            "viscoelastic": lambda: a * meff,
            "tsuji": lambda: np.sqrt(meff * self.damping_stiffness(a)),
        }[self.params["damping"]]()
        return self.damp(inits) * factor

    def tangential_damping(self, eta_n: np.ndarray, a: np.ndarray, meff: np.ndarray) -> np.ndarray:
        """eta_t = x_gammat eta_n (N s/m), pair_granular.cpp:427-428."""
        return float(self.params["xgammat"]) * eta_n

    def damped_normal_force(self, F_ne: np.ndarray, eta_n: np.ndarray, vn: np.ndarray) -> np.ndarray:
        """F_n = F_ne - eta_n v_n, clipped at 0 with limit_damping (pair_granular.cpp:376-377)."""
        F = F_ne - eta_n * vn
        return np.maximum(F, 0.0) if self.params["limit_damping"] else F

    def tangential_arms(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray]:
        """Lever arms of the tangential force: r_i - delta/2 and r_j - delta/2 (pair_granular.cpp:649-693); a
        wall's: r_i (fix_wall_gran.cpp:1512)."""
        if self.params["wall"]:
            return rows.r1, np.zeros_like(rows.r1)
        return rows.r1 - 0.5 * rows.delta, rows.r2 - 0.5 * rows.delta

    # -- energies ----------------------------------------------------------------------------

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        touching = rows.delta > 0
        delta, R = np.where(touching, rows.delta, 0.0), lammps_radius(rows)
        a = np.where(touching, self.contact_radius(delta, R), 0.0)
        modes = {"u_n": np.where(touching, self.normal_energy(delta, R, a), 0.0)}
        skipped = {m: why for m in self.mode_columns if (why := self.missing_mode(rows, m))}
        if "u_t" in self.modes and "u_t" not in skipped:
            modes["u_t"] = np.where(
                touching, spring_energy_of_force(vectors(rows, SPRING_T), self.tangential_stiffness(a)), 0.0
            )
        if "u_r" in self.modes and "u_r" not in skipped:
            modes["u_r"] = np.where(
                touching, spring_energy_of_force(vectors(rows, SPRING_R), self.rolling_stiffness()), 0.0
            )
        if "u_tw" in self.modes and "u_tw" not in skipped:
            modes["u_tw"] = np.where(
                touching, spring_energy_of_force(rows.column(SPRING_TW[0]), self.twisting_stiffness(a)), 0.0
            )
        if self.adhesive:
            modes["u_adh"] = np.where(touching, self.adhesion_work(delta, R, a), 0.0)
        unknown, why = self.unrebuilt(rows, [m for m in modes if m not in skipped])
        return LawEnergy(modes, skipped, unknown, why)

    def unrebuilt(self, rows: ContactRows, modes: list[str]) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """The rows of each mode whose spring the reader could not rebuild (contact columns ``unknown_modes``,
        bits, and ``unknown_why``, a :data:`REASONS` code), and why."""
        if not rows.has(UNKNOWN_MODES, UNKNOWN_WHY):
            return {}, {}
        bits = rows.column(UNKNOWN_MODES).astype(np.int64)
        codes = rows.column(UNKNOWN_WHY).astype(np.int64)
        unknown, why = {}, {}
        for mode in modes:
            mask = (bits & NOT_COMPUTED_BITS[mode]) != 0
            if mask.any():
                unknown[mode] = mask
                reasons = "; ".join(REASONS[c] for c in np.unique(codes[mask]) if c in REASONS)
                why[mode] = f"the {mode} energy of some contacts of {self.key} is not computed: {reasons}"
        return unknown, why

    def missing_mode(self, rows: ContactRows, mode: str) -> str | None:
        """A wall's rolling and twisting springs are in no file (its fix's contacts array holds forces only);
        a pair's twisting spring neither (single() writes the torque only where it capped it)."""
        if self.params["wall"] and mode in ("u_r", "u_tw"):
            sub = self.params["rolling" if mode == "u_r" else "twisting"]
            return (
                f"the {mode} energy of wall contacts ({self.key}, {sub}) is not computed: a LAMMPS wall fix's "
                "contacts array holds the contact's force only, never its rolling or twisting spring"
            )
        if mode == "u_tw" and not rows.has(*SPRING_TW):
            return (
                f"the u_tw energy of {self.key} (twisting {self.params['twisting']}) is not computed: LAMMPS "
                "keeps the twisting spring in the pair's history, which no compute dumps (pair/local's p9 is "
                "the torque only where single() capped it)"
            )
        return super().missing_mode(rows, mode)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        """dU_n/d(delta) (N): the elastic normal force without the cohesion's part."""
        touching = rows.delta > 0
        delta, R = np.where(touching, rows.delta, 0.0), lammps_radius(rows)
        a = self.contact_radius(delta, R)
        return np.where(touching, self.elastic_normal_force(delta, R, a) - self.adhesion_force(delta, R, a), 0.0)

    def adhesion_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """d(u_adh)/d(delta) (N); 0 without cohesion."""
        return np.zeros_like(delta)

    def describe(self) -> str:
        """The normal model's line, with its sub-models."""
        p = self.params
        wall = (
            ""
            if not p["wall"]
            else " (wall)"
            if not self.has_material()
            else " (wall: k_n = 4/3 E/(2(1 - nu)), k_t NULL = E/4 (2 - nu)(1 + nu))"
        )
        parts = [
            f"{self.key}{wall}: {self.summary}",
            f"damping {p['damping']}",
            f"tangential {p['tangential']}"
            + (
                f" u_t = |F_el|^2/(2 k), k = {self.kt:g}{' a' if p['tangential'].startswith('mindlin') else ''}"
                if self.has_spring
                else ""
            ),
        ]
        if p["rolling"] != "none":
            parts.append(f"rolling sds u_r = |F_r,el|^2/(2 k_r), k_r = {float(p['kr']):g}")
        if p["twisting"] != "none":
            parts.append(f"twisting {p['twisting']} u_tw = tau_el^2/(2 k_tw)")
        return "; ".join(parts)

    # -- the rebuild from the dumps -----------------------------------------------------------

    def rebuild(self, rows: ContactRows, *, inits: int = 1) -> Rebuilt:
        """The springs and the step's forces of the contacts ``rows`` from what LAMMPS dumped (module docstring):
        the contact columns :data:`VELOCITIES`, :data:`DUMPED`, :data:`DUMP_ROW`, ``m1 m2`` and the geometry.
        ``inits``: how many times a wall fix's init() converted tsuji's e (the runs since the fix was defined)."""
        n_L = -vectors(rows, ("nx", "ny", "nz"))  # LAMMPS' n, from body 2 to body 1
        delta, R = rows.delta, lammps_radius(rows)
        meff = rows.reduced_mass()
        a = self.contact_radius(delta, R)
        F_ne = self.elastic_normal_force(delta, R, a)
        eta_n = self.normal_damping(a, meff, inits)
        vel = {
            k: vectors(rows, tuple(f"{q}{c}_{k[-1]}" for c in "xyz"))
            for q in ("dv", "ws", "wr")
            for k in (f"{q}_s", f"{q}_h")
        }
        vn_s, vn_h = dot(vel["dv_s"], n_L), dot(vel["dv_h"], n_L)
        F_n_s, F_n_h = self.damped_normal_force(F_ne, eta_n, vn_s), self.damped_normal_force(F_ne, eta_n, vn_h)
        crit_s = float(self.params["mu"]) * self.coulomb_force(F_ne, F_n_s, R)
        crit_h = float(self.params["mu"]) * self.coulomb_force(F_ne, F_n_h, R)
        eta_t = self.tangential_damping(eta_n, a, meff)
        vt_s = tangential_velocity(vel["dv_s"], n_L, vel["ws_s"])
        vt_h = tangential_velocity(vel["dv_h"], n_L, vel["ws_h"])
        p_t = vectors(rows, ("ftx_dumped", "fty_dumped", "ftz_dumped"))
        n = len(delta)
        zeros = np.zeros((n, 3))
        unknown, why = np.zeros(n, dtype=np.int8), np.zeros(n, dtype=np.int8)
        interval_t = np.zeros(n, dtype=bool)
        capped_any = np.zeros(n, dtype=bool)
        L_t = np.zeros(n)
        if self.has_spring:
            spring_t, capped, bad, L_t = unsliding(p_t, -eta_t[:, None] * vt_s, -eta_t[:, None] * vt_h, crit_s, crit_h)
            F_t = spring_t - eta_t[:, None] * vt_h
            interval_t = capped & ~bad & np.any(vt_s != vt_h, axis=1)
            capped_any |= capped
            unknown[bad] |= T_BIT
            why[bad] = 3
        elif self.history_branch:  # beside a history model: k_t = 0 (:530-535)
            spring_t = zeros
            F_t = -eta_t[:, None] * vt_h
            F_t = np.where((norm(F_t) > crit_h)[:, None], 0.0, F_t)
        else:
            spring_t = zeros
            F_t = viscous_limited(eta_t, vt_h, crit_h)
        # where the dump holds the step's own force (a wall's contacts array; any row of a frame written at a run's
        # setup), it is the step's tangential force as written, not a round trip through the damping
        of_step = np.all(np.stack([np.all(vel[f"{q}_s"] == vel[f"{q}_h"], axis=1) for q in ("dv", "ws")]), axis=0)
        F_t = np.where(of_step[:, None], p_t, F_t)
        spring_r, F_r = zeros, zeros
        interval_r = np.zeros(n, dtype=bool)
        if self.rolling:
            p_r = vectors(rows, ("frx_dumped", "fry_dumped", "frz_dumped"))
            gr, mu_ratio = float(self.params["gammar"]), self.rolling_limit_ratio()
            vr_s = R[:, None] * np.cross(vel["wr_s"], n_L)
            vr_h = R[:, None] * np.cross(vel["wr_h"], n_L)
            if self.params["wall"]:  # the wall fix dumps no rolling force: the spring is unknown
                F_r = np.full((n, 3), np.nan)
            else:
                spring_r, capped_r, bad_r, _ = unsliding(
                    p_r, -gr * vr_s, -gr * vr_h, mu_ratio * crit_s, mu_ratio * crit_h
                )
                F_r = spring_r - gr * vr_h
                interval_r = capped_r & ~bad_r & np.any(vr_s != vr_h, axis=1)
                capped_any |= capped_r
                unknown[bad_r] |= R_BIT
                why[bad_r] = 3
        springs = (T_BIT if self.has_spring else 0) | (R_BIT if self.rolling else 0)
        for code, rows_of in ((2, self.stale_limit(rows, capped_any)), (1, self.unwritten(rows, R))):
            if rows_of.any():  # dmt: the limit itself is unknown; jkr: nothing written
                unknown[rows_of] |= springs
                why[rows_of] = code
        lost = why != 0  # the step's tangential and rolling forces of these rows are unknown too
        interval_t &= ~lost
        interval_r &= ~lost
        F_t = np.where(lost[:, None], np.nan, F_t)
        F_r = np.where(lost[:, None], np.nan, F_r)
        F_n_s = np.where(why == 1, np.nan, F_n_s)  # single() wrote nothing to compare with
        arm1, arm2 = self.tangential_arms(rows)
        nxft = np.cross(n_L, F_t)
        nxfr = R[:, None] * np.cross(n_L, F_r)
        force = F_n_h[:, None] * n_L + F_t
        w_t = p_t / np.where(norm(p_t) > 0, norm(p_t), 1.0)[:, None]
        return Rebuilt(
            spring_t,
            spring_r,
            force,
            -arm1[:, None] * nxft + nxfr,
            -arm2[:, None] * nxft - nxfr,
            F_n_s,
            np.abs(F_ne) + np.abs(F_n_s - F_ne),
            unknown,
            why,
            interval_t,
            interval_r,
            w_t,
            crit_s,
            L_t,
            arm1,
            arm2,
            np.full(n, self.twisting),
        )

    def rolling_limit_ratio(self) -> float:
        """mu_r/mu: the rolling limit is mu_r F_ncrit (pair_granular.cpp:585)."""
        mu = float(self.params["mu"])
        return float(self.params["mur"]) / mu if mu else 0.0


class LammpsMaterialModel(LammpsModel):
    """A normal model whose line carries E and nu (hertz/material, dmt, jkr): kn from them."""

    parameters = {
        "E": (ContactLaw.REQUIRED, "Young's modulus E of the line (Pa)"),
        "nu": (ContactLaw.REQUIRED, "Poisson's ratio nu of the line"),
        **LammpsModel.parameters,
    }
    example_params = {"E": 7e9, "nu": 0.3, **LammpsModel.example_params}

    def normal_coefficient(self) -> float:
        return self.material_kn()


class LammpsAdhesiveModel(LammpsMaterialModel):
    """dmt and jkr: E, nu and the surface energy gamma (J/m^2)."""

    adhesive = True
    parameters = {**LammpsMaterialModel.parameters, "cohesion": (ContactLaw.REQUIRED, "surface energy gamma (J/m^2)")}
    example_params = {**LammpsMaterialModel.example_params, "cohesion": 0.05}


def hertz_energy(kn: float, delta: np.ndarray, a: np.ndarray) -> np.ndarray:
    """u_n = 2/5 kn a delta^2 (J) of F_ne = kn a delta, a = sqrt(R delta) (hertz, hertz/material, dmt)."""
    return 0.4 * kn * a * delta * delta


def pi_gamma_R(gamma: float, R: np.ndarray) -> np.ndarray:
    """pi gamma R (N), the unit of dmt's and jkr's adhesive forces."""
    return math.pi * gamma * R


class LammpsLegacyModel(LammpsModel):
    """The legacy styles ``gran/hooke``, ``gran/hooke/history`` and ``gran/hertz/history`` (and their wall fixes)
    with ``kn kt gamman gammat xmu dampflag [limit_damping]`` (pair_gran_hooke_history.cpp:244-380).

    With p = 1 (hooke) or sqrt(R delta) (hertz): F_n = p (k_n delta - m* gamma_n v_n), the tangential spring
    p k_t (history styles) with F_t = -(p k_t xi + p m* gamma_t v_t) limited to mu |F_n|; ``gran/hooke`` keeps no
    spring (-min(mu |F_n|, m* gamma_t |v_t|) along v_t). k_t NULL = 2/7 k_n, gamma_t NULL = gamma_n/2, dampflag 0:
    gamma_t = 0. Torques -r n x F_t with the full radii. No rolling, no twisting."""

    parameters = {
        "kn": (ContactLaw.REQUIRED, "normal stiffness k_n (hooke: N/m; hertz: N/m^(3/2))"),
        "kt": (None, "tangential stiffness k_t; None: NULL, 2/7 k_n"),
        "gamman": (ContactLaw.REQUIRED, "normal damping gamma_n (1/s)"),
        "gammat": (None, "tangential damping gamma_t (1/s); None: NULL, gamma_n/2"),
        "mu": (ContactLaw.REQUIRED, "friction coefficient xmu"),
        "dampflag": (1, "1: tangential damping on, 0: off"),
        "limit_damping": (False, "limit_damping: a negative normal force is clipped to 0"),
        "wall": (False, "the model of a wall fix"),
    }
    example_params = {"kn": 2e5, "gamman": 50.0, "mu": 0.5}
    hertzian: ClassVar[bool] = False
    """p = sqrt(R delta) (gran/hertz/history) rather than 1."""

    def check(self) -> None:
        p = self.params
        self.kn = float(p["kn"])
        self.kt = 2.0 / 7.0 * self.kn if p["kt"] is None else float(p["kt"])
        gamman = float(p["gamman"])
        self.gammat = 0.0 if int(p["dampflag"]) == 0 else 0.5 * gamman if p["gammat"] is None else float(p["gammat"])
        self.history_branch, self.rolling, self.twisting = False, False, False
        self.set_modes()

    def normal_coefficient(self) -> float:
        return self.kn

    def contact_radius(self, delta: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The factor p: sqrt(R delta) (hertz) or 1 (m or -)."""
        return np.sqrt(R * np.maximum(delta, 0.0)) if self.hertzian else np.ones_like(delta)

    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne = p k_n delta (N)."""
        return a * self.kn * delta

    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n = k_n delta^2/2 (hooke) or 2/5 k_n sqrt(R) delta^(5/2) = 2/5 p k_n delta^2 (hertz) (J)."""
        return (0.4 if self.hertzian else 0.5) * a * self.kn * delta * delta

    def normal_damping(self, a: np.ndarray, meff: np.ndarray, inits: int) -> np.ndarray:
        """eta_n = p m* gamma_n (N s/m)."""
        return a * meff * float(self.params["gamman"])

    def tangential_damping(self, eta_n: np.ndarray, a: np.ndarray, meff: np.ndarray) -> np.ndarray:
        """eta_t = p m* gamma_t (N s/m)."""
        return a * meff * self.gammat

    def tangential_stiffness(self, a: np.ndarray) -> np.ndarray:
        """The spring p k_t (N/m); 0 for gran/hooke."""
        return self.kt * a if self.has_spring else np.zeros_like(a)

    def tangential_arms(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray]:
        """The full radii r_i, r_j (pair_gran_hooke_history.cpp:321-330; a wall: r_i)."""
        return rows.r1, (np.zeros_like(rows.r1) if self.params["wall"] else rows.r2)

    def describe(self) -> str:
        return (
            f"{self.key}{' (wall)' if self.params['wall'] else ''}: {self.summary} (k_n = {self.kn:g}, "
            f"k_t = {self.kt:g}, gamma_t = {self.gammat:g})"
        )
