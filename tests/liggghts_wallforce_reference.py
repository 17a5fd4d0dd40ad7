"""Wall contacts of a LIGGGHTS 3.8.0 run rebuilt from each wall fix's force, independently of demsplit, for the tests.

LIGGGHTS never dumps the contacts of ``fix wall/gran ... primitive`` walls, but ``store_force yes`` makes the fix
keep the force it applied to each particle in the step (``f_force_<fixID>[1..3]`` in a ``dump custom``). From that
force, the atom dump (``fx fy fz tqx tqy tqz`` included) and the pair dump with its history, this module rebuilds what
the wall contact's history would have held, transcribing the LIGGGHTS-PUBLIC 3.8.0 source (file:line below):

- the force: ``fix_wall_gran_base.h:205-206, 345-350`` stores f(after) - f(before) of the atom around the contact's
  evaluation in ``post_force`` (with ``computeflag``), summed over the fix's contacts of the particle;
  ``fix_wall_gran.cpp:803-808`` zeroes it at every evaluation, ``post_force_pgl`` (``compute wall/gran/local``
  at output) included, which adds nothing: a mesh fix's stored force reads 0 once its local dump has been written;
- the velocities of the step's force evaluation: Verlet integrates x and v by half a step before the force and v by
  the other half after it, so the dumped v, omega are the step's plus (dt/2) f/m and (dt/2) tau/I
  (``fix_nve_sphere.cpp:157-181``: I = 0.4 m r^2, ``dtf`` = dt/2 in SI); in a frame written at the setup of a ``run``
  no half step separates them (``fix_wall_gran.cpp:740``: ``shearupdate`` is 0 then, no history is updated). A dump
  writes at a run's setup only a step it has not written yet (``output.cpp:229-231``): its first frame when it is
  defined between runs, never the step where the previous run ended (written then, mid-run);
- the contact geometry: ``primitive_wall_definitions.h:133-191`` (plane, cylinder: the vector ``delta`` from the
  centre to the wall), ``fix_wall_gran_base.h:181-261`` (r = r_i - delta_n, e_n = -delta/r from the wall to the
  particle, R* = r_i, m* = m_i); pairs ``pair_gran_base.h:279-394`` (e_n = (x_i - x_j)/r, m* = m_i m_j/(m_i + m_j));
- the relative velocity at the contact: ``surface_model_default.h:150-203`` (wall: w_r = (r_i - delta/2) omega_i/r,
  pair: (c_i omega_i + c_j omega_j)/r, c = r - delta/2; v_tr = v_t - w_r x delta_vec);
- the normal model: ``normal_model_hertz.h:231-263`` (k_n = 4/3 Y* sqrt(R* d), k_t = 8 G* sqrt(R* d),
  gamma = -2 sqrt(5/6) beta sqrt(S m*), S_n = 2 Y* sqrt(R* d), S_t = k_t; beta = ln e/sqrt(ln^2 e + pi^2),
  ``global_properties.cpp:432, 463, 516, 539``), ``normal_model_hooke.h:269-292`` (k_n = 16/15 sqrt(R*) Y*
  (15 m* V^2/(16 sqrt(R*) Y*))^0.2, k_t = k_n, gamma_n = gamma_t = sqrt(4 m* k_n ln^2 e/(ln^2 e + pi^2))),
  ``normal_model_hooke_hysteresis.h:139-200`` (hooke's k_n and gamma_n, written sqrt(4 m* k_n/(1 + (pi/ln e)^2)),
  equal to rounding; k2 = k_n + (k2Max - k_n) dmax/dlim below
  dlim = k2Max/(k2Max - k_n) phiF 2 R*, else k2Max; f = k_n d loading, k2 (d - dmax) + k_n dmax unloading, >= -kc d;
  the applied normal force is f - gamma_n v_n in every model here (limitForce off));
- the tangential model ``tangential_model_history.h:147-228``: the history ``shear`` gets v_tr dt and loses its
  normal part, F_el = -k_t shear; if |F_el| > mu |F_n| (F_n the applied normal force) the applied force is F_el
  rescaled to mu |F_n| **without damping**, and the history is set to -F_t/k_t (only with ``shearupdate``); else
  F_t = F_el - gamma_t v_tr. So mid-run a capped contact's spring *is* its force, and an uncapped one's is
  F_t + gamma_t v_tr; at a setup frame a capped contact's history was not rescaled and its magnitude is lost;
- the rolling model ``rolling_model_epsd2.h:161-224``: M = M_hist + k_r w_t dt, k_r = k_t R*^2, capped at
  mu_r |F_n| R*, stored when ``shearupdate`` (mid-run the history *is* the applied torque), applied as -M on i
  (``:136-141``), w = omega_i - omega_j (a wall: the w_r above), w_t its part normal to e_n;
- the torques: -c_i e_n x F_t on i, -c_j e_n x F_t on j (``tangential_model_history.h:229-262``); with ``newton
  off`` a pair across a periodic boundary is evaluated from each side, with the other atom's image and each side's own
  copy of the history, applying the force to its own atom only (``pair_gran_base.h:421-429``); the pair dump lists
  one side.

On hooke/hysteresis's unloading line the elastic force f = k_n d + a dmax (d - dmax), a = (k2Max - k_n)/dlim, gives
dmax = (d + sqrt(d^2 - 4 (f - k_n d)/a))/2 (>= d; dmax = d on the loading line), hence k2 and u_n = f^2/(2 k2).

Per wall contact this gives the elastic normal force (checked against the model, or, for hooke/hysteresis, inverted
for the unloading stiffness), the tangential spring F_el with u_t = |F_el|^2/(2 k_t), and, from the particle's
torque balance (its dumped torque less the torques of its pair contacts as LIGGGHTS applied them in the step, rebuilt
from their history, and less the wall's tangential torque), the rolling torque with u_r = |M|^2/(2 k_r). Each
particle's dumped force (and torque, where no unknown rolling torque used it up) must equal m g plus the sum over its
contacts within a tolerance set by the printed precision (``tolerance``); where it does not, or where a value cannot
be determined, the contact's value is NaN with the reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

EPS = np.finfo(np.float64).eps
CLOSURE_ULPS = 64.0
"""The closure tolerance of a full-precision dump in units of eps times the sum of the magnitudes of the terms
(``tolerance``): the rounding of the force sum LIGGGHTS accumulates and of this module's recomputation."""
GHOST_RTOL = 1e-10
"""The allowance, relative to its tangential force and rolling torque, for a pair across a periodic boundary on the
side the pair dump does not list: that side integrates its own copy of the history, the negative of the dumped one to
the rounding accumulated over the contact's life (measured up to 4e-12). Its delta_max (hooke/hysteresis) is the
largest overlap it computed with its own periodic image, whose coordinates are rounded to the box length's spacing:
it gets k2Max times 4 such spacings."""
CAP_RTOL = 1e-9
"""How close |F_t| (or |M|) must be to the Coulomb (rolling) cap for the contact to count as capped: an uncapped
contact lands that close only by accident, and the balance of its pair partner would then not close."""


@dataclass(frozen=True)
class Law:
    """The contact law of the pair style and the wall fixes (the same words) and the run's settings; tables are
    indexed by atom type - 1."""

    normal: str  # hertz, hooke, hooke/hysteresis
    rolling: str | None  # epsd2 or None
    young: tuple[float, ...]
    poisson: tuple[float, ...]
    restitution: tuple[tuple[float, ...], ...]
    friction: tuple[tuple[float, ...], ...]
    timestep: float
    gravity: np.ndarray  # m/s^2, the acceleration of fix gravity (magnitude times the normalised vector)
    rolling_friction: tuple[tuple[float, ...], ...] | None = None
    characteristic_velocity: float | None = None
    max_elastic_stiffness: float | None = None  # hooke/hysteresis: k2Max/k_n
    plasticity_depth: float | None = None  # hooke/hysteresis: phiF
    adhesion_stiffness: float = 0.0  # hooke/hysteresis: kc/k_n

    def pair_table(self, name: str, t1: np.ndarray, t2: np.ndarray) -> np.ndarray:
        return np.asarray(getattr(self, name))[t1 - 1, t2 - 1]

    def effective_moduli(self, t1: np.ndarray, t2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Y* and G* (global_properties.cpp:432, 463)."""
        E, nu = np.asarray(self.young), np.asarray(self.poisson)
        e1, e2, n1, n2 = E[t1 - 1], E[t2 - 1], nu[t1 - 1], nu[t2 - 1]
        Y = 1.0 / ((1.0 - n1**2) / e1 + (1.0 - n2**2) / e2)
        G = 1.0 / (2.0 * (2.0 - n1) * (1.0 + n1) / e1 + 2.0 * (2.0 - n2) * (1.0 + n2) / e2)
        return Y, G

    def stiffness(self, t1, t2, R, meff, delta) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """k_n, k_t, gamma_n, gamma_t of the normal model (module docstring)."""
        Y, G = self.effective_moduli(t1, t2)
        log_e = np.log(self.pair_table("restitution", t1, t2))
        if self.normal == "hertz":
            sqrtval = np.sqrt(R * delta)
            beta = log_e / np.sqrt(log_e**2 + np.pi**2)
            Sn, St = 2.0 * Y * sqrtval, 8.0 * G * sqrtval
            gamman = -2.0 * np.sqrt(5.0 / 6.0) * beta * np.sqrt(Sn * meff)
            gammat = -2.0 * np.sqrt(5.0 / 6.0) * beta * np.sqrt(St * meff)
            return 4.0 / 3.0 * Y * sqrtval, St, gamman, gammat
        if self.normal in ("hooke", "hooke/hysteresis"):
            v, sqrtval = self.characteristic_velocity, np.sqrt(R)
            kn = 16.0 / 15.0 * sqrtval * Y * (15.0 * meff * v * v / (16.0 * sqrtval * Y)) ** 0.2
            gamman = np.sqrt(4.0 * meff * kn * log_e**2 / (log_e**2 + np.pi**2))
            return kn, kn, gamman, gamman
        raise ValueError(f"no reference for normal model {self.normal!r}")

    def hysteresis(self, kn: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """k2Max, kc and the overlap dlim beyond which k2 = k2Max (normal_model_hooke_hysteresis.h:150-163)."""
        k2max = kn * self.max_elastic_stiffness
        return k2max, kn * self.adhesion_stiffness, k2max / (k2max - kn) * self.plasticity_depth * 2.0 * R

    def elastic_normal(self, kn, R, delta, delta_max=None) -> np.ndarray:
        """The elastic normal force k_n delta, or hooke/hysteresis's f from the stored delta_max (after the step's
        update, >= delta; normal_model_hooke_hysteresis.h:156-195)."""
        if self.normal != "hooke/hysteresis":
            return kn * delta
        k2max, kc, dlim = self.hysteresis(kn, R)
        big = delta_max >= dlim
        k2 = np.where(big, k2max, kn + (k2max - kn) * delta_max / dlim)
        ftmp = np.where(big, k2max * (delta - dlim) + kn * dlim, k2 * (delta - delta_max) + kn * delta_max)
        f = np.where(~big & (ftmp >= kn * delta), kn * delta, ftmp)
        return np.where(f >= -kc * delta, f, -kc * delta)

    def unloading_stiffness(self, kn, R, delta_max) -> np.ndarray:
        """k2 of hooke/hysteresis at the given delta_max."""
        k2max, _, dlim = self.hysteresis(kn, R)
        return np.where(delta_max >= dlim, k2max, kn + (k2max - kn) * delta_max / dlim)

    def normal_energy(self, kn, R, delta, f, delta_max=None) -> np.ndarray:
        """u_n of the elastic normal force f: 1/2 f delta (hooke), 2/5 f delta (hertz), f^2/(2 k2) for
        hooke/hysteresis (the energy released unloading along the current k2 line)."""
        if self.normal == "hertz":
            return 0.4 * f * delta
        if self.normal == "hooke":
            return 0.5 * f * delta
        return f**2 / (2.0 * self.unloading_stiffness(kn, R, delta_max))


@dataclass(frozen=True)
class Wall:
    """A wall fix's geometry as LIGGGHTS resolves a primitive wall (primitive_wall_definitions.h:133-191): a plane
    ``axis = position`` or a cylinder of ``radius`` around ``axis`` through ``center`` (the two other coordinates in
    LIGGGHTS' cyclic order x -> (y, z), y -> (z, x), z -> (x, y)). Several Walls with the same ``fix`` stand for
    one fix with several surfaces (a mesh box): its force is then their sum."""

    fix: str
    type: int
    kind: str  # plane or cylinder
    axis: int
    position: float = 0.0
    radius: float = 0.0
    center: tuple[float, float] = (0.0, 0.0)

    def resolve(self, x: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """LIGGGHTS' ``deltan`` (distance to the wall surface minus r; <= 0 is a contact) and ``delta`` (the vector
        from the centre to the wall surface) of each centre."""
        delta = np.zeros_like(x)
        if self.kind == "plane":
            delta[:, self.axis] = self.position - x[:, self.axis]
            return np.abs(x[:, self.axis] - self.position) - r, delta
        a, b = (self.axis + 1) % 3, (self.axis + 2) % 3
        dy, dz = x[:, a] - self.center[0], x[:, b] - self.center[1]
        dist = np.sqrt(dy * dy + dz * dz)
        outside = dist > self.radius
        fact = np.where(outside, dist - self.radius, self.radius - dist) / dist
        sign = np.where(outside, -1.0, 1.0)
        delta[:, a], delta[:, b] = sign * dy * fact, sign * dz * fact
        return np.where(outside, dist - self.radius - r, self.radius - dist - r), delta


@dataclass
class Frame:
    """One frame of the run: the atom dump's columns (``sort id``: rows in id order) and the pair dump's columns
    by name (x1 ... tqz, the history by name: shearx.., rolling_torquex.., delta_max, then area delta cpx cpy cpz)."""

    atoms: dict[str, np.ndarray]
    pairs: dict[str, np.ndarray]
    setup: bool  # written at the setup of a run: the force used the dumped velocities, histories were not updated
    periodic: np.ndarray = field(default_factory=lambda: np.zeros(3))  # box length of each periodic axis, else 0


@dataclass
class WallContacts:
    """The rebuilt wall contacts: one row per (wall, particle) in contact; energies NaN where not computed, with
    the reasons (per mode, '' where computed)."""

    wall: np.ndarray  # index into the walls given
    id: np.ndarray
    delta: np.ndarray
    fn: np.ndarray  # the applied normal force (N, > 0 repulsive), F . e_n
    fn_model: np.ndarray  # the model's applied normal force (NaN for hooke/hysteresis, whose force is path dependent)
    kt: np.ndarray
    capped: np.ndarray  # the tangential force sat at the Coulomb cap
    u_n: np.ndarray
    u_t: np.ndarray
    u_r: np.ndarray
    reason_n: np.ndarray
    reason_t: np.ndarray
    reason_r: np.ndarray
    spring: np.ndarray  # F_el (n, 3)
    rolling_torque: np.ndarray  # M (n, 3)


@dataclass
class Closure:
    """Per atom: the residuals of the force and torque balance, their tolerances, and whether they close
    (torque: NaN residual where an unknown rolling torque was solved from it)."""

    id: np.ndarray
    force_residual: np.ndarray
    force_tolerance: np.ndarray
    torque_residual: np.ndarray
    torque_tolerance: np.ndarray

    @property
    def closes(self) -> np.ndarray:
        force = self.force_residual <= self.force_tolerance
        torque = np.isnan(self.torque_residual) | (self.torque_residual <= self.torque_tolerance)
        return force & torque


def tolerance(scale: np.ndarray, print_rtol: float) -> np.ndarray:
    """A balance closes to ``CLOSURE_ULPS`` eps (arithmetic) plus 4 ``print_rtol`` (the relative rounding of one
    printed value: 0 for %.17g, which round-trips, 5e-6 for %g's 6 digits) times the sum of the magnitudes of its
    terms."""
    return (CLOSURE_ULPS * EPS + 4.0 * print_rtol) * scale


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ij,ij->i", a, a))


def _vec(d: dict, names: str) -> np.ndarray:
    return np.stack([d[n] for n in names.split()], -1).astype(np.float64)


def step_velocities(law: Law, atoms: dict, setup: bool) -> tuple[np.ndarray, np.ndarray]:
    """v and omega of the step's force evaluation (module docstring; fix_nve_sphere.cpp:157-181)."""
    v, w = _vec(atoms, "vx vy vz"), _vec(atoms, "omegax omegay omegaz")
    if setup:
        return v, w
    m, r = atoms["mass"], atoms["radius"]
    dtf = 0.5 * law.timestep
    dtfm = dtf / m
    dtirotate = dtf / 0.4 / (r * r * m)
    return v - dtfm[:, None] * _vec(atoms, "fx fy fz"), w - dtirotate[:, None] * _vec(atoms, "tqx tqy tqz")


def _tangential_velocity(vr, en, wr, dvec) -> tuple[np.ndarray, np.ndarray]:
    """v_n and v_tr (surface_model_default.h:150-194)."""
    vn = np.einsum("ij,ij->i", vr, en)
    return vn, vr - vn[:, None] * en - np.cross(wr, dvec)


def _rolling_increment(law: Law, w, en, kr) -> np.ndarray:
    """k_r w_t dt of rolling_model_epsd2.h:183-195 (w without its part along e_n)."""
    wt = w - np.einsum("ij,ij->i", w, en)[:, None] * en
    return wt * (law.timestep * kr)[:, None]


def _capped(vec: np.ndarray, cap: np.ndarray) -> np.ndarray:
    mag = _norm(vec)
    return vec * np.where(mag > cap, cap / np.where(mag > 0, mag, 1.0), 1.0)[:, None]


def _pair_side(law: Law, frame: Frame, i, j, shear, rolling, delta_max, vh, wh, capped_as=None) -> dict:
    """The force on i and the torques on i and j of pair contacts evaluated from i's side, with j's image nearest
    to i (a periodic ghost: x_j plus the box length, as LIGGGHTS shifts it), rebuilt from the contact's history
    after the step (module docstring). ``capped_as``: (tangential, rolling) capped flags of the other side of the same
    contacts, whose history this side's approximates: a side capped there rescaled its own copy to its own cap."""
    a = frame.atoms
    x = _vec(a, "x y z")
    xj = x[j].copy()
    per = frame.periodic > 0
    xj[:, per] += frame.periodic[per] * np.round((x[i][:, per] - xj[:, per]) / frame.periodic[per])
    dvec = x[i] - xj
    rsq = dvec[:, 0] * dvec[:, 0] + dvec[:, 1] * dvec[:, 1] + dvec[:, 2] * dvec[:, 2]  # pair_gran_base.h:282
    ri, rj, mi, mj = a["radius"][i], a["radius"][j], a["mass"][i], a["mass"][j]
    r = np.sqrt(rsq)
    delta = (ri + rj) - r
    rinv = 1.0 / r
    en = dvec * rinv[:, None]
    R, meff = ri * rj / (ri + rj), mi * mj / (mi + mj)
    t1, t2 = a["type"][i].astype(np.int64), a["type"][j].astype(np.int64)
    kn, kt, gamman, gammat = law.stiffness(t1, t2, R, meff, delta)
    ci, cj = ri - 0.5 * delta, rj - 0.5 * delta
    wr = (ci[:, None] * wh[i] + cj[:, None] * wh[j]) * rinv[:, None]
    vn, vtr = _tangential_velocity(vh[i] - vh[j], en, wr, dvec)
    fn = law.elastic_normal(kn, R, delta, delta_max) - gamman * vn
    f_el = -kt[:, None] * shear
    cap = law.pair_table("friction", t1, t2) * np.abs(fn)
    if frame.setup:  # the history was not updated (nor rescaled): cap it here
        capped = _norm(f_el) > cap
        ft = np.where(capped[:, None], _capped(f_el, cap), f_el - gammat[:, None] * vtr)
    else:  # a capped history was rescaled to the applied force
        capped = _norm(f_el) >= cap * (1 - CAP_RTOL) if capped_as is None else capped_as[0]
        if capped_as is not None:
            f_el = np.where(capped[:, None], f_el * (cap / np.maximum(_norm(f_el), 1e-300))[:, None], f_el)
        ft = np.where(capped[:, None], f_el, f_el - gammat[:, None] * vtr)
    tor = np.cross(en, ft)
    tq_i, tq_j = -ci[:, None] * tor, -cj[:, None] * tor
    rolling_capped = np.zeros(len(i), dtype=bool)
    if law.rolling == "epsd2":
        cap_r = law.pair_table("rolling_friction", t1, t2) * np.abs(fn) * R
        if frame.setup:
            rolling = _capped(rolling + _rolling_increment(law, wh[i] - wh[j], en, kt * R * R), cap_r)
        elif capped_as is not None:
            rolling = np.where(
                capped_as[1][:, None], rolling * (cap_r / np.maximum(_norm(rolling), 1e-300))[:, None], rolling
            )
        rolling_capped = _norm(rolling) >= cap_r * (1 - CAP_RTOL)
        tq_i, tq_j = tq_i - rolling, tq_j + rolling
    # rounding: of the terms, and of the step's relative velocity from the atoms' velocities
    speeds = _norm(vh[i]) + _norm(vh[j]) + ci * _norm(wh[i]) + cj * _norm(wh[j])
    damping = gammat * speeds + gamman * speeds
    spacing = 4.0 * np.spacing(frame.periodic.max())
    ghost_normal = law.hysteresis(kn, R)[0] * spacing if law.normal == "hooke/hysteresis" else 0.0 * kn
    ghost_rolling = 0.0 if rolling is None else GHOST_RTOL * _norm(rolling)
    return {
        "force": fn[:, None] * en + ft,
        "tq_i": tq_i,
        "tq_j": tq_j,
        "force_scale": np.abs(fn) + _norm(ft) + damping,
        "torque_scale": _norm(tq_i) + _norm(tq_j) + ci * (_norm(ft) + damping),
        "ghost_force": GHOST_RTOL * _norm(ft) + ghost_normal,
        "ghost_torque": ci * (GHOST_RTOL * _norm(ft) + ghost_normal) + ghost_rolling,
        "capped": (capped, rolling_capped),
    }


def pair_forces(law: Law, frame: Frame, row: dict[int, int], vh, wh) -> list[tuple[np.ndarray, dict]]:
    """What the pair contacts applied to each atom in the step: (rows of the atoms, their forces and torques and the
    sums of magnitudes). With ``newton off`` a pair of owned atoms is evaluated once (id1's side: -F on id2); a pair
    across a periodic boundary (flag 1) once from each side, each with the other's periodic image and its own copy of
    the history (the negative of the dumped one), applying the force to its own atom only."""
    p = frame.pairs
    i = np.array([row[int(k)] for k in p["id1"]], dtype=np.int64)
    j = np.array([row[int(k)] for k in p["id2"]], dtype=np.int64)
    shear = _vec(p, "shearx sheary shearz")
    rolling = _vec(p, "rolling_torquex rolling_torquey rolling_torquez") if law.rolling else None
    dmax = p.get("delta_max")
    a = _pair_side(law, frame, i, j, shear, rolling, dmax, vh, wh)
    ghost = p["periodic"] == 1
    b = _pair_side(
        law,
        frame,
        j[ghost],
        i[ghost],
        -shear[ghost],
        None if rolling is None else -rolling[ghost],
        None if dmax is None else dmax[ghost],
        vh,
        wh,
        capped_as=tuple(c[ghost] for c in a["capped"]),
    )
    both, none = ~ghost, np.zeros(len(i))
    return [
        (
            i,
            {
                "force": a["force"],
                "torque": a["tq_i"],
                "force_scale": a["force_scale"],
                "torque_scale": a["torque_scale"],
                "force_allowance": none,
                "torque_allowance": none,
            },
        ),
        (
            j[both],
            {
                "force": -a["force"][both],
                "torque": a["tq_j"][both],
                "force_scale": a["force_scale"][both],
                "torque_scale": a["torque_scale"][both],
                "force_allowance": none[both],
                "torque_allowance": none[both],
            },
        ),
        (
            j[ghost],
            {
                "force": b["force"],
                "torque": b["tq_i"],
                "force_scale": b["force_scale"],
                "torque_scale": b["torque_scale"],
                "force_allowance": b["ghost_force"],
                "torque_allowance": b["ghost_torque"],
            },
        ),
    ]


def reconstruct(law: Law, walls: list[Wall], frame: Frame, print_rtol: float = 0.0) -> tuple[WallContacts, Closure]:
    """Every wall contact of the frame rebuilt from its wall fix's force, and the atoms' balance (module
    docstring)."""
    a = frame.atoms
    n_atoms = len(a["id"])
    row = {int(k): n for n, k in enumerate(a["id"])}
    x, r, m = _vec(a, "x y z"), a["radius"].astype(np.float64), a["mass"].astype(np.float64)
    vh, wh = step_velocities(law, a, frame.setup)
    f_atom, tq_atom = _vec(a, "fx fy fz"), _vec(a, "tqx tqy tqz")
    gravity = m[:, None] * law.gravity

    # the balance's known part: gravity and the pair contacts
    res_f, res_t = f_atom - gravity, tq_atom.copy()
    scale_f = _norm(f_atom) + _norm(gravity)
    scale_t = _norm(tq_atom)
    allow_f, allow_t = np.zeros(n_atoms), np.zeros(n_atoms)
    if len(frame.pairs.get("id1", [])):
        for rows, side in pair_forces(law, frame, row, vh, wh):
            np.add.at(res_f, rows, -side["force"])
            np.add.at(res_t, rows, -side["torque"])
            np.add.at(scale_f, rows, side["force_scale"])
            np.add.at(scale_t, rows, side["torque_scale"])
            np.add.at(allow_f, rows, side["force_allowance"])
            np.add.at(allow_t, rows, side["torque_allowance"])

    # the wall contacts: geometry, then the force each fix stored, split into its normal and tangential parts
    parts = []
    for k, wall in enumerate(walls):
        deltan, dvec_in = wall.resolve(x, r)
        hit = np.flatnonzero(deltan <= 0)
        parts.append((np.full(len(hit), k), hit, -deltan[hit], -dvec_in[hit]))
    wk, ip, delta_n, dvec = (np.concatenate(c) for c in zip(*parts)) if parts else ([],) * 4
    dvec = dvec.reshape(-1, 3)
    fixes = [walls[k].fix for k in wk]
    # a particle touching one fix more than once: the fix stored the sum of the forces
    key = [(f, int(i)) for f, i in zip(fixes, ip)]
    multiple = np.array([key.count(c) > 1 for c in key], dtype=bool)
    dist = r[ip] - delta_n  # sidata.r = radi - deltan (fix_wall_gran_base.h:181)
    en = dvec * (1.0 / dist)[:, None]
    t1 = a["type"][ip].astype(np.int64)
    t2 = np.array([walls[k].type for k in wk], dtype=np.int64)
    R, meff = r[ip], m[ip]
    kn, kt, gamman, gammat = law.stiffness(t1, t2, R, meff, delta_n)
    force = (
        np.stack([np.stack([a[f"f_force_{f}[{c}]"][i] for c in (1, 2, 3)]) for f, i in zip(fixes, ip)])
        if len(ip)
        else np.zeros((0, 3))
    )
    fn = np.einsum("ij,ij->i", force, en)
    ft = force - fn[:, None] * en
    cr = r[ip] - 0.5 * delta_n
    wr = cr[:, None] * wh[ip] * (1.0 / dist)[:, None]
    vn, vtr = _tangential_velocity(vh[ip], en, wr, dvec)
    f_el_n = fn + gamman * vn  # the elastic normal force: the applied one less the damping
    cap = law.pair_table("friction", t1, t2) * np.abs(fn)
    # the stored force is f(after) - f(before): rounded to the magnitude of the atom's other forces
    capped = np.abs(_norm(ft) - cap) <= CAP_RTOL * cap + tolerance(scale_f[ip], print_rtol)
    spring = np.where(capped[:, None], ft, ft + gammat[:, None] * vtr)
    tq_t = -cr[:, None] * np.cross(en, ft)
    # rounding: of the terms, and of the step's relative velocity from the atom's velocities
    fscale = _norm(force) + (gamman + gammat) * (_norm(vh[ip]) + cr * _norm(wh[ip]))
    np.add.at(res_f, ip, -force)
    np.add.at(res_t, ip, -tq_t)
    np.add.at(scale_f, ip, fscale)
    np.add.at(scale_t, ip, cr * fscale)

    # rolling: one unknown torque per particle is solved from its torque balance
    n = len(ip)
    rolling = np.full((n, 3), np.nan)
    torque_used = np.zeros(n_atoms, dtype=bool)
    reason_r = np.full(n, "", dtype=object)
    if law.rolling == "epsd2":
        count = np.bincount(ip, minlength=n_atoms)
        single = count[ip] == 1
        rolling[single] = -res_t[ip[single]]  # the torque on the particle is -M
        torque_used[ip] = True
        reason_r[~single] = "the particle has another wall contact with an unknown rolling torque"
    kr = kt * R * R
    cap_r = np.abs(fn) * R * (law.pair_table("rolling_friction", t1, t2) if law.rolling else 0.0)

    # normal: the model's force (hertz, hooke), or hooke/hysteresis's unloading line through the elastic force
    reason_n = np.full(n, "", dtype=object)
    if law.normal == "hooke/hysteresis":
        k2max, _, dlim = law.hysteresis(kn, R)
        slope = (k2max - kn) / dlim
        # f = k_n d + slope dmax (d - dmax) on the line of dmax <= dlim: dmax >= d is the larger root
        disc = delta_n**2 - 4.0 * (f_el_n - kn * delta_n) / slope
        delta_max = 0.5 * (delta_n + np.sqrt(np.maximum(disc, 0.0)))
        fn_model = np.full(n, np.nan)
        above = f_el_n > kn * delta_n + tolerance(fscale, print_rtol)
        reason_n[above] = "the normal force lies above the loading line k_n delta"
        reason_n[(f_el_n < -tolerance(fscale, print_rtol)) & ~above] = "negative elastic normal force (no adhesion)"
        u_n = law.normal_energy(kn, R, delta_n, np.maximum(f_el_n, 0.0), np.minimum(delta_max, dlim))
    else:
        fn_model = law.elastic_normal(kn, R, delta_n) - gamman * vn
        mismatch = np.abs(fn - fn_model) > tolerance(fscale, print_rtol)
        reason_n[mismatch] = "the normal force does not match the normal model"
        u_n = law.normal_energy(kn, R, delta_n, kn * delta_n)

    reason_t = np.full(n, "", dtype=object)
    if frame.setup:
        reason_t[capped] = "capped at a setup step: the history is not rescaled there, the spring is not in the force"
    over = ~capped & (_norm(spring) > cap * (1 + CAP_RTOL))
    reason_t[over] = "the spring rebuilt from the force exceeds the Coulomb cap"
    for reason in (reason_t, reason_r, reason_n):
        reason[multiple] = "the particle touches this wall fix more than once: the stored force is their sum"
    u_t = 0.5 * np.einsum("ij,ij->i", spring, spring) / kt

    # the balance: the force always; the torque unless an unknown rolling torque took it up
    tq_res = _norm(res_t)
    rolling_res = np.where(torque_used, np.nan, tq_res)
    closure = Closure(
        a["id"].astype(np.int64),
        _norm(res_f),
        tolerance(scale_f, print_rtol) + allow_f,
        rolling_res,
        tolerance(scale_t, print_rtol) + allow_t,
    )
    if law.rolling == "epsd2":
        ok = np.isfinite(rolling[:, 0])
        if frame.setup:
            at_cap = ok & (np.abs(_norm(np.nan_to_num(rolling)) - cap_r) <= CAP_RTOL * cap_r)
            reason_r[at_cap] = "rolling torque capped at a setup step: the stored torque is not in the balance"
            rolling[ok] -= _rolling_increment(law, wr[ok], en[ok], kr[ok])
        else:  # mid-run the stored torque is the applied one, within the step's cap
            beyond = ok & (_norm(np.nan_to_num(rolling)) > cap_r * (1 + CAP_RTOL) + tolerance(scale_t[ip], print_rtol))
            reason_r[beyond] = "the torque balance gives a rolling torque beyond the cap"
    u_r = 0.5 * np.einsum("ij,ij->i", rolling, rolling) / kr if law.rolling else np.full(n, np.nan)
    open_ = ~closure.closes[ip]
    why = "the particle's force or torque does not close against its contacts"
    for reason in (reason_n, reason_t, reason_r):
        reason[open_ & (reason == "")] = why
    if law.normal != "hooke/hysteresis":
        reason_n[:] = np.where(reason_n == why, "", reason_n)  # u_n of hertz, hooke rests on delta alone
    u_n = np.where(reason_n == "", u_n, np.nan)
    u_t = np.where(reason_t == "", u_t, np.nan)
    u_r = np.where(reason_r == "", u_r, np.nan) if law.rolling else u_r
    return WallContacts(
        wk.astype(np.int64),
        a["id"][ip].astype(np.int64),
        delta_n,
        fn,
        fn_model,
        kt,
        capped,
        u_n,
        u_t,
        u_r,
        reason_n,
        reason_t,
        reason_r,
        spring,
        rolling,
    ), closure


def from_history(law: Law, atoms: dict, walls: dict, wall_type: int) -> dict[str, np.ndarray]:
    """The energies of the mesh-wall contacts of a ``compute wall/gran/local`` dump (columns by name, as the pair
    dump's) from their history: u_n (hooke/hysteresis: f(delta, dmax)^2/(2 k2)), u_t = k_t |shear|^2/2, u_r =
    |M|^2/(2 k_r); per row, with the particle id."""
    row = {int(k): n for n, k in enumerate(atoms["id"])}
    ip = np.array([row[int(k)] for k in walls["id"]], dtype=np.int64)
    r, m, delta = atoms["radius"][ip], atoms["mass"][ip], walls["delta"]
    t1 = atoms["type"][ip].astype(np.int64)
    t2 = np.full(len(ip), wall_type)
    kn, kt, _, _ = law.stiffness(t1, t2, r, m, delta)
    dmax = walls.get("delta_max")
    f = law.elastic_normal(kn, r, delta, dmax)
    shear = _vec(walls, "shearx sheary shearz")
    out = {
        "id": atoms["id"][ip].astype(np.int64),
        "u_n": law.normal_energy(kn, r, delta, f, dmax),
        "u_t": 0.5 * kt * np.einsum("ij,ij->i", shear, shear),
    }
    if law.rolling == "epsd2":
        mr = _vec(walls, "rolling_torquex rolling_torquey rolling_torquez")
        out["u_r"] = 0.5 * np.einsum("ij,ij->i", mr, mr) / (kt * r * r)
    return out
