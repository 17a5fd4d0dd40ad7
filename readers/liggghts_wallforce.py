"""Primitive-wall contacts of a LIGGGHTS run rebuilt from each wall fix's stored force (``store_force yes``).

LIGGGHTS never writes the history of a ``fix wall/gran ... primitive`` contact, but with ``store_force yes`` the fix
keeps the force it applied to each particle in the step, ``f_force_<ID>[1..3]`` in a ``dump custom``. A particle
touches a primitive wall fix at most once (``fix_wall_gran.cpp:1024-1110`` resolves one distance per particle and
fix), so that force is the contact's. With the velocities of the step's force evaluation (the dumped ones less half a
step of the dumped force and torque, or the dumped ones in a frame written at the setup of a run), it gives back
the springs the history would hold (:mod:`demsplit.physics.laws._liggghts_force`):

- u_t: the tangential spring, F_t itself for a contact sliding at the Coulomb cap mid-run, F_t + gamma_t v_tr
  otherwise; in a frame written at the setup of a run the spring of a contact at the cap is not known (its history
  was not rescaled there);
- u_r (``rolling_friction epsd2``): the rolling torque from the particle's torque balance, its dumped torque less
  the torques of every other contact as LIGGGHTS applied them in the step (pairs and mesh walls rebuilt from their
  dumped history) and less the wall's own tangential torque, for a particle with one such unknown; at a setup frame
  a torque at its cap is not known;
- the normal model's history (``hooke/hysteresis``'s delta_max) from the elastic normal force F_n + gamma_n v_n.

Every particle's dumped force (and torque, unless a rolling torque was solved from it) must equal m g plus all its
contacts as applied in the step, within :func:`~demsplit.physics.laws._liggghts_force.closure_tolerance` of the
printed precision, and the normal force must be one the normal model gives: where not, the particle's primitive-wall
contacts keep their history unknown, with the reason (:data:`REASONS`). The rebuilt history goes into the contact
columns the laws read (``shearx``..., ``rolling_torquex``..., ``delta_max``), so the energies come from the laws
themselves; ``history_unknown`` keeps the bits of the modes still unknown.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..frame import Box, ParticleIndex, Table
from ..physics.bodies import FrameContacts, LawRows
from ..physics.laws._liggghts import ROLLING_TORQUE, SHEAR, LiggghtsNormalModel
from ..physics.laws._liggghts_force import (
    CAP_RTOL,
    applied_rolling_torque,
    applied_tangential_force,
    closure_tolerance,
    contact_torque,
    contact_velocity,
    half_step_velocities,
    magnitude,
    rolling_increment,
    tangential_spring,
)
from ..physics.modes import HISTORY_LOST, NOT_COMPUTED_BITS
from ..physics.moduli import effective_radius
from ..scene import ContactModel, Scene
from .liggghts_script import LiggghtsScript

GHOST_RTOL = 1e-10
"""The allowance, relative to its tangential force and rolling torque, for the side of a pair across a periodic
boundary that the pair dump does not list: that side integrates its own copy of the history, the negative of the
dumped one to the rounding accumulated over the contact's life (measured up to 4e-12). A normal history (delta_max)
of that side is its own largest overlap, from its own periodic image: it gets the force's change over
:data:`GHOST_SPACINGS` spacings of the box length."""
GHOST_SPACINGS = 4.0
MESH_OVERLAP_ULPS = 4.0
"""A mesh-wall overlap rebuilt from the centre and the dumped contact point (no ``delta`` column) differs from
LIGGGHTS' own by the rounding of that distance: its force gets k_n times this many eps times the radius."""

REASONS = {
    "capped_at_setup": "u_t of a primitive-wall contact sliding at the Coulomb cap in a frame written at the setup of "
    "a run is NOT COMPUTED: LIGGGHTS does not rescale the spring there, so the stored force gives "
    "its direction, not its magnitude",
    "rolling_capped_at_setup": "u_r of a primitive-wall contact whose rolling torque sits at its cap in a frame "
    "written at the setup of a run is NOT COMPUTED: the history is not rescaled there",
    "two_rolling": "u_r of the primitive-wall contacts of a particle touching two or more walls whose rolling "
    "torque is unknown is NOT COMPUTED: one torque balance cannot give several torques",
    "open_balance": "the history of the primitive-wall contacts of a particle whose dumped force or torque does not "
    "close against its contacts (within the printed precision) is NOT COMPUTED",
    "unstored_wall": "the history of the primitive-wall contacts of a particle that also touches a primitive wall "
    "whose force the atom dump does not hold (no store_force yes, or no f_force column) is NOT "
    "COMPUTED: that wall's force is unknown, so the balance cannot be checked",
    "normal_off_model": "the history of a primitive-wall contact whose normal force the normal model does not give "
    "with the step's velocities is NOT COMPUTED",
    "spring_beyond_cap": "u_t of a primitive-wall contact whose spring, rebuilt from the force, exceeds the Coulomb "
    "cap is NOT COMPUTED",
    "rolling_beyond_cap": "u_r of a primitive-wall contact whose rolling torque, from the torque balance, exceeds "
    "its cap is NOT COMPUTED",
    "frame_kind": "the history of a primitive-wall contact is NOT COMPUTED where the frame may have been written at "
    "the setup of a run or mid-run (a run after read_restart) and the two readings disagree",
}
"""Why a primitive-wall contact's history stays unknown: the notes of a frame name the reasons that occurred."""


@dataclass(frozen=True)
class ForceSettings:
    """What one contact model's applied force needs beyond its law: LIGGGHTS' per-type-pair coefficients
    (``coefficientRestitution``, ``coefficientFriction``, ``coefficientRollingFriction``, (N, N) arrays by type - 1)
    and the model line's switches ``tangential_damping`` (on unless set off) and ``limitForce``."""

    restitution: np.ndarray
    friction: np.ndarray
    rolling_friction: np.ndarray | None
    tangential_damping: bool = True
    limit_force: bool = False


SUPPORTED = (
    "hertz, hooke (ktToKnUser allowed) or hooke/hysteresis with tangential history, rolling_friction off or "
    "epsd2 and no cohesion; viscous, disableNormalWhenBonded and torsionTorque off"
)


def settings_problem(model: ContactModel, settings: dict[str, str]) -> str | None:
    """Why the force of a contact model cannot be rebuilt (:data:`SUPPORTED`), or None."""
    law = model.contact_law
    if not isinstance(law, LiggghtsNormalModel) or not law.applied_force:
        return f"its normal model {model.law} is not one whose applied force demsplit models"
    p = law.params
    if p["tangential"] != "history" or p["rolling"] not in ("off", "epsd2") or p["cohesion"] != "off":
        return f"tangential {p['tangential']}, rolling_friction {p['rolling']} and cohesion {p['cohesion']}"
    on = [name for name in ("viscous", "disableNormalWhenBonded", "torsionTorque") if settings.get(name) == "on"]
    return f"{' and '.join(on)} on" if on else None


def force_settings(model: ContactModel, settings: dict[str, str], coefficients: dict) -> ForceSettings | str:
    """The :class:`ForceSettings` of a model from the script's ``fix property/global`` values and the model line's
    switches, or why not."""
    law = model.contact_law
    need = ["coefficientRestitution", "coefficientFriction"]
    if law.params["rolling"] == "epsd2":
        need.append("coefficientRollingFriction")
    missing = [name for name in need if np.ndim(coefficients.get(name)) != 2]
    if missing:
        return f"the script defines no per-type-pair {' and '.join(missing)}"
    return ForceSettings(
        np.asarray(coefficients["coefficientRestitution"], dtype=np.float64),
        np.asarray(coefficients["coefficientFriction"], dtype=np.float64),
        np.asarray(coefficients["coefficientRollingFriction"], dtype=np.float64)
        if law.params["rolling"] == "epsd2"
        else None,
        tangential_damping=settings.get("tangential_damping", "on") != "off",
        limit_force=settings.get("limitForce", "off") == "on",
    )


def stored_force_columns(fix: str) -> list[str]:
    """The atom-dump columns of a wall fix's stored force."""
    return [f"f_force_{fix}[{k}]" for k in (1, 2, 3)]


BALANCE_COLUMNS = ("mass", "vx", "vy", "vz", "omegax", "omegay", "omegaz", "fx", "fy", "fz", "tqx", "tqy", "tqz")
"""The atom-dump columns of every particle's balance, besides ``id type x y z radius`` and the stored forces."""


@dataclass
class Rebuilt:
    """The primitive-wall rows' rebuilt history columns, their ``history_unknown`` bits, the reasons (keys of
    :data:`REASONS`) of the modes still unknown with how many contacts each, and the largest residual of a
    particle's balance over its tolerance (the torque's where no rolling torque was solved from it)."""

    columns: dict[str, np.ndarray]
    unknown: np.ndarray
    reasons: dict[str, int] = field(default_factory=dict)
    closure: float = 0.0


@dataclass
class _Terms:
    """One side of a set of contacts as LIGGGHTS applied them in the step: the force on body 1 (N), the torques on
    body 1 and body 2 (N m), the sums of the magnitudes of the terms (the scales of the tolerance) and the allowances
    added to it."""

    force: np.ndarray
    torque1: np.ndarray
    torque2: np.ndarray
    force_scale: np.ndarray
    torque_scale: np.ndarray
    force_allowance: np.ndarray
    torque_allowance: np.ndarray


@dataclass
class WallForce:
    """The rebuilding of a run's primitive-wall contacts from their fixes' stored forces (module docstring).

    scene : the run's scene. stored : index in ``scene.walls`` of each primitive wall with a stored force -> its fix.
    pair_settings, wall_settings : the :class:`ForceSettings` of the pair style and of each wall (None: a wall whose
    force is not needed, a mesh wall without a dump). gravity : m/s^2.
    """

    scene: Scene
    stored: dict[int, str]
    pair_settings: ForceSettings
    wall_settings: list[ForceSettings | None]
    gravity: np.ndarray

    def particle_columns(self) -> list[str]:
        """The atom-dump columns the rebuilding reads, besides ``id type x y z radius``."""
        return [*BALANCE_COLUMNS, *(c for fix in self.stored.values() for c in stored_force_columns(fix))]

    # -- one frame -----------------------------------------------------------------------------

    def rebuild(
        self,
        particles: Table,
        pairs: Table,
        mesh: Table | None,
        primitive: Table,
        box: Box,
        setup: bool | None,
        dt: float,
        print_rtol: float,
        mesh_delta_dumped: bool,
    ) -> Rebuilt:
        """The history of the touching rows of ``primitive`` (the join's primitive-wall contacts, one per particle
        and wall) from the stored forces, with the pair contacts ``pairs`` (their ``periodic`` flag included) and the
        mesh-wall contacts ``mesh`` (None: none dumped) of the frame. ``setup``: the frame was written at the setup
        of a run (None: the script cannot tell; both readings are made, :data:`REASONS` ``frame_kind``); ``dt`` the
        run's timestep (s); ``print_rtol`` the relative rounding of the printed values (0 at full precision)."""
        if setup is not None:
            return self._rebuild(particles, pairs, mesh, primitive, box, setup, dt, print_rtol, mesh_delta_dumped)[0]
        readings = [
            self._rebuild(particles, pairs, mesh, primitive, box, kind, dt, print_rtol, mesh_delta_dumped)
            for kind in (False, True)
        ]
        consistent = [r for r, sound in readings if sound]
        if len(consistent) == 1:
            return consistent[0]
        mid, start = (r for r, _ in readings)
        if not consistent:  # neither reading closes: the mid-run one says where
            return mid
        return _agreeing(mid, start)

    def _rebuild(
        self,
        particles: Table,
        pairs: Table,
        mesh: Table | None,
        primitive: Table,
        box: Box,
        setup: bool,
        dt: float,
        print_rtol: float,
        mesh_delta_dumped: bool,
    ) -> tuple[Rebuilt, bool]:
        """:meth:`rebuild` for one reading of the frame, and whether it is sound (every balance closes, every normal
        force is the model's)."""
        n_atoms = len(particles["id"])
        vec = _vectors(particles)
        mass = np.asarray(particles["mass"], dtype=np.float64)
        radius = np.asarray(particles["radius"], dtype=np.float64)
        v, w = (
            (vec["v"], vec["omega"])
            if setup
            else half_step_velocities(vec["v"], vec["omega"], vec["f"], vec["tq"], mass, radius, dt)
        )
        weight = mass[:, None] * self.gravity
        res_f, res_t = vec["f"] - weight, vec["tq"].copy()
        scale_f, scale_t = magnitude(vec["f"]) + magnitude(weight), magnitude(vec["tq"])
        allow_f, allow_t = np.zeros(n_atoms), np.zeros(n_atoms)
        index = ParticleIndex(particles["id"])

        def add(rows: np.ndarray, terms: _Terms) -> None:
            """What contacts applied to their body 1, the particles ``rows``, out of those particles' balance."""
            np.add.at(res_f, rows, -terms.force)
            np.add.at(res_t, rows, -terms.torque1)
            np.add.at(scale_f, rows, terms.force_scale)
            np.add.at(scale_t, rows, terms.torque_scale)
            np.add.at(allow_f, rows, terms.force_allowance)
            np.add.at(allow_t, rows, terms.torque_allowance)

        # the pairs: one side each, both sides of a pair across a periodic boundary (each with its own image)
        if len(pairs.get("id1", ())):
            i, j = index.rows(pairs["id1"]), index.rows(pairs["id2"])
            ghost = np.asarray(pairs["periodic"]) == 1
            lengths = np.where(box.periodic, box.lengths, 0.0)
            listed = self._pair_terms(particles, pairs, i, j, slice(None), 1.0, lengths, v, w, setup, dt)
            add(i, listed)
            add(j[~ghost], _side2(listed, ~ghost))
            if ghost.any():
                add(
                    j[ghost],
                    self._pair_terms(particles, pairs, j[ghost], i[ghost], ghost, -1.0, lengths, v, w, setup, dt),
                )
        # the mesh walls, from their dumped history
        if mesh is not None and len(mesh.get("id1", ())):
            rows = index.rows(mesh["id1"])
            touching = np.asarray(mesh["delta"]) > 0
            add(rows[touching], self._mesh_terms(particles, mesh, rows, touching, v, w, setup, dt, mesh_delta_dumped))
        # every stored force, whether or not a contact was found for it
        for fix in self.stored.values():
            force = np.stack([np.asarray(particles[c], dtype=np.float64) for c in stored_force_columns(fix)], -1)
            res_f -= force
            scale_f += magnitude(force)

        touch = np.flatnonzero(np.asarray(primitive["delta"]) > 0)
        n = len(touch)
        unknown = np.full(len(primitive["delta"]), HISTORY_LOST, dtype=np.int8)
        columns: dict[str, np.ndarray] = {}
        reasons: dict[str, np.ndarray] = {}
        if n == 0:
            return Rebuilt(columns, unknown), True
        wall = np.asarray(primitive["wall"])[touch]
        ip = index.rows(np.asarray(primitive["id1"])[touch])
        table = {c: np.asarray(primitive[c])[touch] for c in ("id1", "id2", "wall", "delta", "r1", "r2")}
        delta, r1 = table["delta"], table["r1"]
        en = -np.stack([np.asarray(primitive[c])[touch] for c in ("nx", "ny", "nz")], -1)
        dist = r1 - delta
        lever = r1 - 0.5 * delta
        stored = np.isin(wall, list(self.stored))
        force = np.zeros((n, 3))
        for k, fix in self.stored.items():
            at = wall == k
            force[at] = np.stack(
                [np.asarray(particles[c], dtype=np.float64)[ip[at]] for c in stored_force_columns(fix)], -1
            )
        fn = np.einsum("ij,ij->i", force, en)
        ft = force - fn[:, None] * en
        w_r = (lever / dist)[:, None] * w[ip]
        vn, vtr = contact_velocity(v[ip], en, w_r, dist)
        frame = FrameContacts(table, self.scene, particles)
        law: dict[int, LiggghtsNormalModel] = {}
        kt, gamma_n, gamma_t, mu, mu_r, kr = (np.zeros(n) for _ in range(6))
        rolls = np.zeros(n, dtype=bool)
        bits = np.zeros(n, dtype=np.int8)  # the modes each row's law reads a history for
        for k in np.unique(wall):
            at = wall == k
            contact_law = law[k] = (self.scene.walls[k].model or self.scene.model).contact_law
            bits[at] = sum(NOT_COMPUTED_BITS[m] for m in contact_law.mode_columns)
            settings = self.wall_settings[k]
            if settings is None:
                continue
            rows = LawRows(frame, np.flatnonzero(at), contact_law.key)
            kt[at] = contact_law.kt(rows)
            gamma_n[at], gamma_t[at] = _damping(contact_law, rows, settings)
            mu[at] = rows.type_pair(settings.friction)
            if contact_law.params["rolling"] == "epsd2":
                rolls[at] = True
                kr[at] = contact_law.kr(rows)
                mu_r[at] = rows.type_pair(settings.rolling_friction)
        speed = magnitude(v[ip]) + lever * magnitude(w[ip])
        fscale = magnitude(force) + (gamma_n + gamma_t) * speed
        scale_f[ip] += (gamma_n + gamma_t) * speed
        tolerance = closure_tolerance(fscale, print_rtol)
        cap = mu * np.abs(fn)
        spring, capped = tangential_spring(ft, cap, gamma_t, vtr, closure_tolerance(scale_f[ip], print_rtol))
        np.add.at(res_t, ip[stored], -contact_torque(lever[stored], en[stored], ft[stored]))
        np.add.at(scale_t, ip, lever * fscale)

        # the normal model's history from the elastic normal force, and the check that the model gives it back
        elastic = fn + gamma_n * vn
        off_model = np.zeros(n, dtype=bool)
        for k in np.unique(wall[stored]):
            at = np.flatnonzero(wall == k)
            contact_law = law[k]
            rows = LawRows(frame, at, contact_law.key)
            history = contact_law.normal_history_of_force(rows, elastic[at])
            for c, values in history.items():
                table.setdefault(c, np.zeros(n))[at] = values
                columns.setdefault(c, np.zeros(len(primitive["delta"])))[touch[at]] = values
            model_force = contact_law.normal_force(
                LawRows(FrameContacts(table, self.scene, particles), at, contact_law.key)
            )
            off_model[at] = np.abs(model_force - elastic[at]) > tolerance[at]

        # the rolling torques: one unknown per particle from its torque balance
        unstored = np.zeros(n_atoms, dtype=bool)
        unstored[ip[~stored]] = True
        solving = rolls & stored
        count = np.bincount(ip[rolls], minlength=n_atoms)
        single = solving & (count[ip] == 1)
        torque_used = np.zeros(n_atoms, dtype=bool)
        torque_used[ip[rolls]] = True
        rolling = np.zeros((n, 3))
        rolling[single] = -res_t[ip[single]]  # the torque on the particle is -M
        force_ratio = _closure_ratio(res_f, scale_f, allow_f, print_rtol)
        torque_ratio = np.where(torque_used, 0.0, _closure_ratio(res_t, scale_t, allow_t, print_rtol))
        closes = (force_ratio <= 1.0) & (torque_ratio <= 1.0)

        modes = ("u_n", "u_t", "u_r")
        known = {m: stored.copy() for m in modes}

        def flag(mask: np.ndarray, reason: str, which: tuple[str, ...]) -> None:
            mask = mask & stored
            if mask.any():
                reasons[reason] = reasons.get(reason, np.zeros(n, dtype=bool)) | mask
                for m in which:
                    known[m] &= ~mask

        flag(capped & setup, "capped_at_setup", ("u_t",))
        flag(~capped & (magnitude(spring) > cap * (1.0 + CAP_RTOL) + tolerance), "spring_beyond_cap", ("u_t",))
        flag(rolls & ~single, "two_rolling", ("u_r",))
        cap_r = mu_r * np.abs(fn) * effective_radius(r1, table["r2"])
        m_mag = magnitude(rolling)
        if setup:
            flag(single & (np.abs(m_mag - cap_r) <= CAP_RTOL * cap_r), "rolling_capped_at_setup", ("u_r",))
            rolling[single] -= rolling_increment(w_r[single], en[single], kr[single], dt)
        else:
            flag(
                single & (m_mag > cap_r * (1.0 + CAP_RTOL) + closure_tolerance(scale_t[ip], print_rtol)),
                "rolling_beyond_cap",
                ("u_r",),
            )
        flag(off_model, "normal_off_model", modes)
        flag(unstored[ip], "unstored_wall", modes)
        flag(~closes[ip], "open_balance", modes)

        shear = -spring / np.where(kt > 0, kt, 1.0)[:, None]
        for c, values in zip(SHEAR, shear.T):
            columns[c] = np.zeros(len(primitive["delta"]))
            columns[c][touch] = np.where(known["u_t"], values, 0.0)
        if rolls.any():
            for c, values in zip(ROLLING_TORQUE, rolling.T):
                columns[c] = np.zeros(len(primitive["delta"]))
                columns[c][touch] = np.where(known["u_r"], values, 0.0)
        still = bits.copy()
        for m in modes:
            still &= ~np.where(known[m], NOT_COMPUTED_BITS[m], 0).astype(np.int8)
        unknown[touch] = still
        sound = bool(closes.all() and not (off_model & stored).any())
        return Rebuilt(
            columns,
            unknown,
            {r: int(mask.sum()) for r, mask in reasons.items()},
            float(max(force_ratio.max(), torque_ratio.max())),
        ), sound

    # -- the contacts whose history is dumped --------------------------------------------------

    def _pair_terms(
        self,
        particles: Table,
        pairs: Table,
        i: np.ndarray,
        j: np.ndarray,
        which,
        sign: float,
        lengths: np.ndarray,
        v: np.ndarray,
        w: np.ndarray,
        setup: bool,
        dt: float,
    ) -> _Terms:
        """The pair contacts ``which`` of ``pairs`` evaluated from the side of atoms ``i`` (LIGGGHTS' arithmetic:
        j's periodic image nearest to i, x_j + k L; d = x_i - x_j, r = sqrt(d.d), e_n = d (1/r),
        delta = r_i + r_j - r), with that side's history (``sign`` -1: the unlisted side of a periodic pair,
        whose copy is the negative of the dumped one)."""
        x = np.stack([np.asarray(particles[c], dtype=np.float64) for c in ("x", "y", "z")], -1)
        radius = np.asarray(particles["radius"], dtype=np.float64)
        xj = x[j].copy()
        per = lengths > 0
        xj[:, per] += lengths[per] * np.round((x[i][:, per] - xj[:, per]) / lengths[per])
        d = x[i] - xj
        rsq = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2]
        r = np.sqrt(rsq)
        en = d * (1.0 / r)[:, None]
        delta = (radius[i] + radius[j]) - r
        ids = np.asarray(particles["id"])
        law = self.scene.model.contact_law
        table = {
            "id1": ids[i],
            "id2": ids[j],
            "wall": np.full(len(i), -1, np.int64),
            "delta": delta,
            "r1": radius[i],
            "r2": radius[j],
        }
        for c in law.history_columns():
            if c in pairs:
                value = np.asarray(pairs[c], dtype=np.float64)[which]
                table[c] = sign * value if c in SHEAR or c in ROLLING_TORQUE else value
        c1, c2 = radius[i] - 0.5 * delta, radius[j] - 0.5 * delta
        w_r = (c1[:, None] * w[i] + c2[:, None] * w[j]) / r[:, None]
        vn, vtr = contact_velocity(v[i] - v[j], en, w_r, r)
        speed = magnitude(v[i]) + magnitude(v[j]) + c1 * magnitude(w[i]) + c2 * magnitude(w[j])
        ghost = GHOST_SPACINGS * np.spacing(lengths.max()) if sign < 0 else None
        return self._applied(
            table, particles, self.pair_settings, en, vn, vtr, w[i] - w[j], c1, c2, setup, dt, speed, ghost=ghost
        )

    def _mesh_terms(
        self,
        particles: Table,
        mesh: Table,
        rows: np.ndarray,
        touching: np.ndarray,
        v: np.ndarray,
        w: np.ndarray,
        setup: bool,
        dt: float,
        delta_dumped: bool,
    ) -> _Terms:
        """The touching mesh-wall contacts as applied in the step, from their dumped history (wall at rest)."""
        table = {c: np.asarray(values)[touching] for c, values in mesh.items()}
        rows = rows[touching]
        en = -np.stack([table[c] for c in ("nx", "ny", "nz")], -1)
        delta, r1 = np.asarray(table["delta"], dtype=np.float64), np.asarray(table["r1"], dtype=np.float64)
        dist = r1 - delta
        lever = r1 - 0.5 * delta
        w_r = (lever / dist)[:, None] * w[rows]
        vn, vtr = contact_velocity(v[rows], en, w_r, dist)
        speed = magnitude(v[rows]) + lever * magnitude(w[rows])
        rounding = None if delta_dumped else MESH_OVERLAP_ULPS * np.finfo(np.float64).eps * r1
        wall = np.asarray(table["wall"])
        n = len(rows)
        out = _Terms(*(np.zeros((n, 3)) for _ in range(3)), *(np.zeros(n) for _ in range(4)))
        for k in np.unique(wall):
            at = np.flatnonzero(wall == k)
            part = {c: values[at] for c, values in table.items()}
            terms = self._applied(
                part,
                particles,
                self.wall_settings[k],
                en[at],
                vn[at],
                vtr[at],
                w_r[at],
                lever[at],
                np.zeros(len(at)),
                setup,
                dt,
                speed[at],
                overlap_rounding=None if rounding is None else rounding[at],
            )
            for name in (
                "force",
                "torque1",
                "torque2",
                "force_scale",
                "torque_scale",
                "force_allowance",
                "torque_allowance",
            ):
                getattr(out, name)[at] = getattr(terms, name)
        return out

    def _applied(
        self,
        table: Table,
        particles: Table,
        settings: ForceSettings,
        en: np.ndarray,
        vn: np.ndarray,
        vtr: np.ndarray,
        w_roll: np.ndarray,
        c1: np.ndarray,
        c2: np.ndarray,
        setup: bool,
        dt: float,
        speed: np.ndarray,
        ghost: float | None = None,
        overlap_rounding: np.ndarray | None = None,
    ) -> _Terms:
        """What contacts of one law applied in the step from their history (:mod:`._liggghts_force`): the force on
        body 1, the torques on both bodies, and the scales of their rounding. ``w_roll``: the relative rotational
        velocity of the rolling model (omega_1 - omega_2; w_r on a wall); ``speed``: the sum of the bodies' speeds
        at the contact, whose rounding the relative velocity carries. ``ghost``: the unlisted side of pairs across a
        periodic boundary, with the shift (m) of its normal history (:data:`GHOST_RTOL`); ``overlap_rounding``: how
        far (m) the overlaps may be from LIGGGHTS' own (:data:`MESH_OVERLAP_ULPS`)."""
        wall = np.asarray(table["wall"])
        model = self.scene.model if wall[0] < 0 else (self.scene.walls[int(wall[0])].model or self.scene.model)
        law = model.contact_law
        rows = LawRows(FrameContacts(table, self.scene, particles), slice(None), law.key)
        kt = law.kt(rows)
        gamma_n, gamma_t = _damping(law, rows, settings)
        fn = law.normal_force(rows) - gamma_n * vn
        if settings.limit_force:
            fn = np.maximum(fn, 0.0)
        cap = rows.type_pair(settings.friction) * np.abs(fn)
        spring = -kt[:, None] * np.stack([table[c] for c in SHEAR], -1)
        ft, _ = applied_tangential_force(spring, np.broadcast_to(cap, fn.shape), gamma_t, vtr, setup)
        torque1, torque2 = contact_torque(c1, en, ft), contact_torque(c2, en, ft)
        rolling = np.zeros_like(ft)
        if law.params["rolling"] == "epsd2":
            kr = law.kr(rows)
            cap_r = rows.type_pair(settings.rolling_friction) * np.abs(fn) * effective_radius(rows.r1, rows.r2)
            history = np.stack([table[c] for c in ROLLING_TORQUE], -1)
            rolling = applied_rolling_torque(
                history, rolling_increment(w_roll, en, kr, dt), np.broadcast_to(cap_r, fn.shape), setup
            )
            torque1, torque2 = torque1 - rolling, torque2 + rolling
        apart = ~(rows.delta > 0)  # LIGGGHTS applies nothing between bodies that do not overlap
        if apart.any():
            fn, ft, torque1, torque2, rolling = (
                np.where(apart if a.ndim == 1 else apart[:, None], 0.0, a) for a in (fn, ft, torque1, torque2, rolling)
            )
        damping = (gamma_n + gamma_t) * speed
        ft_mag = magnitude(ft)
        force_allowance, rolling_allowance = np.zeros(len(fn)), np.zeros(len(fn))
        if ghost is not None:  # its own history copy and, for a normal history, its own image
            force_allowance = GHOST_RTOL * ft_mag
            rolling_allowance = GHOST_RTOL * magnitude(rolling)
            if law.normal_history:
                shifted = {**table, **{c: table[c] + ghost for c in law.normal_history}}
                moved = LawRows(FrameContacts(shifted, self.scene, particles), slice(None), law.key)
                force_allowance = force_allowance + np.abs(law.normal_force(moved) - law.normal_force(rows))
        if overlap_rounding is not None:  # d(k_n delta)/d(delta) is at most 1.5 k_n (hertz)
            force_allowance = force_allowance + 2.0 * law.kn(rows) * overlap_rounding
        return _Terms(
            fn[:, None] * en + ft,
            torque1,
            torque2,
            np.abs(fn) + ft_mag + damping,
            magnitude(torque1) + magnitude(torque2) + c1 * (ft_mag + damping),
            force_allowance,
            c1 * force_allowance + rolling_allowance,
        )


def wall_force_of(script: LiggghtsScript, scene: Scene, dumped_mesh_walls: set[int]) -> tuple[WallForce | None, str]:
    """The rebuilding of the primitive-wall contacts of a run (a :class:`~.liggghts_script.LiggghtsScript` and its
    scene, the mesh walls whose contacts a dump holds), or None and why not."""
    primitive = [k for k, w in enumerate(scene.walls) if w.kind in ("plane", "cylinder")]
    if not primitive:
        return None, "the run has no primitive wall"
    if not script.stored_force:
        return None, "no primitive 'fix wall/gran' has 'store_force yes'"
    if script.unmodelled_forces:
        return (
            None,
            f"{', '.join(script.unmodelled_forces)} changes the particles' forces or their integration "
            "beyond the contacts, fix gravity and fix nve/sphere, so their balance cannot be checked",
        )
    if script.moving_walls:
        moving = ", ".join(f"{scene.walls[k].name} ({word})" for k, word in script.moving_walls.items())
        return None, f"the walls {moving} move"
    if any(t is None for t in script.run_timesteps) or not script.run_timesteps:
        return None, "the script sets no timestep before its runs"
    problem = settings_problem(scene.model, script.pair_settings)
    if problem is not None:
        return None, f"the pair style: {problem} (supported: {SUPPORTED})"
    pair = force_settings(scene.model, script.pair_settings, script.coefficients)
    if isinstance(pair, str):
        return None, pair
    walls: list[ForceSettings | None] = []
    for k, wall in enumerate(scene.walls):
        if k not in primitive and k not in dumped_mesh_walls:
            walls.append(None)
            continue
        model, settings = wall.model or scene.model, script.wall_settings[k]
        problem = settings_problem(model, settings)
        if problem is not None:
            return None, f"wall {wall.name}: {problem} (supported: {SUPPORTED})"
        found = force_settings(model, settings, script.coefficients)
        if isinstance(found, str):
            return None, found
        walls.append(found)
    gravity = np.zeros(3) if script.gravity is None else np.asarray(script.gravity, dtype=np.float64)
    stored = {k: fix for k, fix in script.stored_force.items() if k in primitive}
    return WallForce(scene, stored, pair, walls, gravity), ""


def _vectors(particles: Table) -> dict[str, np.ndarray]:
    """Velocity, angular velocity, force and torque of every particle, (n, 3)."""

    def stack(names: str) -> np.ndarray:
        return np.stack([np.asarray(particles[c], dtype=np.float64) for c in names.split()], -1)

    return {
        "v": stack("vx vy vz"),
        "omega": stack("omegax omegay omegaz"),
        "f": stack("fx fy fz"),
        "tq": stack("tqx tqy tqz"),
    }


def _side2(terms: _Terms, rows: np.ndarray) -> _Terms:
    """The other side of the contacts ``rows`` of ``terms``: the opposite force and body 2's torque."""
    return _Terms(
        -terms.force[rows],
        terms.torque2[rows],
        terms.torque1[rows],
        terms.force_scale[rows],
        terms.torque_scale[rows],
        terms.force_allowance[rows],
        terms.torque_allowance[rows],
    )


def _damping(law: LiggghtsNormalModel, rows: LawRows, settings: ForceSettings) -> tuple[np.ndarray, np.ndarray]:
    """gamma_n, gamma_t of every row (gamma_t 0 with ``tangential_damping off``)."""
    gamma_n, gamma_t = law.damping(rows, rows.type_pair(settings.restitution))
    n = len(rows.delta)
    gamma_n = np.broadcast_to(gamma_n, (n,))
    return gamma_n, (np.broadcast_to(gamma_t, (n,)) if settings.tangential_damping else np.zeros(n))


def _closure_ratio(residual: np.ndarray, scale: np.ndarray, allowance: np.ndarray, print_rtol: float) -> np.ndarray:
    """Each particle's |residual| over its tolerance (that of its scale plus its allowance): it closes at <= 1."""
    bound = closure_tolerance(scale, print_rtol) + allowance
    mag = magnitude(residual)
    return np.divide(mag, bound, out=np.where(mag > 0, np.inf, 0.0), where=bound > 0)


def _agreeing(a: Rebuilt, b: Rebuilt) -> Rebuilt:
    """Of two readings of a frame that both close, the values where both know them and agree to 1e-9; the rest
    unknown (:data:`REASONS` ``frame_kind``)."""
    columns = {}
    differ = np.zeros(len(a.unknown), dtype=bool)
    for c, values in a.columns.items():
        other = b.columns.get(c, np.zeros_like(values))
        differ |= ~(np.abs(values - other) <= 1e-9 * np.maximum(np.abs(values), np.abs(other)))
        columns[c] = values
    unknown = a.unknown | b.unknown
    unknown = np.where(differ, HISTORY_LOST, unknown).astype(np.int8)
    reasons = {r: max(a.reasons.get(r, 0), b.reasons.get(r, 0)) for r in {*a.reasons, *b.reasons}}
    if differ.any():
        reasons["frame_kind"] = int(differ.sum())
    return Rebuilt(columns, unknown, reasons, max(a.closure, b.closure))
