"""The distribution law: who stores a contact's elastic energy, and where the contact point is.

Feng & Gao show that under the Hertz assumptions the energy stored in each
body is proportional to its compliance, whatever the radii (eqs. 14-15):

    S1/S2 = c1/c2,   c_i = (1 - nu_i^2)/E_i,   share1 = c1/(c1 + c2),

and that the same ratio splits the overlap (eq. 31): delta1 = share1 delta.
The tangential (Mindlin) energy splits by t_i = (2 - nu_i)/G_i (the paper's
eq. 22 factor (1 - 2 nu)/G is wrong; see ``docs/physics.md``).

This module holds the share functions, the contact point, :func:`partition`
(per-contact energies and shares) and :func:`per_particle` (sums per particle
and per wall). Everything works on plain arrays; see :mod:`demsplit.frame`
for the table columns.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from . import laws
from .errors import ContactError, InputFormatError
from .frame import ParticleIndex, Table, table_length
from .scene import ContactModel, Scene

SPLITS = ("material", "equal", "radius", "springs")
"""Distribution laws: ``material`` (Feng & Gao), ``equal`` (50/50: LAMMPS
``compute pe/atom``, Kratos), ``radius`` (share1 = r1/(r1 + r2), the split
implied by the radius-weighted contact point of LIGGGHTS and Aspherix),
``springs`` (share1 = E2 r2/(E1 r1 + E2 r2), the series springs k_i = E_i r_i
behind YADE's linear ``FrictPhys`` stiffness)."""

TANGENTIAL_RULES = ("mindlin", "paper")


def _scalar_or_array(x: np.ndarray) -> np.ndarray | np.float64:
    return x[()] if x.ndim == 0 else x


def share_from_compliances(c1: ArrayLike, c2: ArrayLike) -> np.ndarray:
    """Fraction c1/(c1 + c2) of a series-spring energy stored in body 1.

    The smaller of the two fractions is computed directly and the larger as
    its complement, so a rigid body (c = 0) gets exactly 0, its partner exactly
    1, equal compliances exactly 1/2, and the two shares add to 1 exactly.
    Both compliances 0 (two rigid bodies) is a :class:`ContactError`.
    """
    c1 = np.asarray(c1, dtype=np.float64)
    c2 = np.asarray(c2, dtype=np.float64)
    total = c1 + c2
    if np.any(total == 0):
        raise ContactError(
            "two rigid bodies are in contact: neither can store elastic energy.",
            fix="give at least one of the two bodies a finite Young's modulus.",
        )
    with np.errstate(invalid="ignore"):
        share = np.where(c1 <= c2, c1 / total, 1.0 - c2 / total)
    return _scalar_or_array(share)


def normal_share(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Fraction of the normal elastic energy stored in body 1 (eqs. 14-15).

    share1 = c1/(c1 + c2) = E*/E1',  c_i = (1 - nu_i^2)/E_i = 1/E_i'.

    Dimensionless, in [0, 1]; E = inf (rigid) gives exactly 0 and its partner 1.
    """
    return share_from_compliances(laws.plane_strain_compliance(E1, nu1),
                                  laws.plane_strain_compliance(E2, nu2))


def tangential_share(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike,
                     rule: str = "mindlin") -> np.ndarray:
    """Fraction of the tangential elastic energy stored in body 1.

    ``rule="mindlin"`` (default): share1 = t1/(t1 + t2), t_i = (2 - nu_i)/G_i.
    Under the full-stick Mindlin traction each half-space's tangential surface
    displacement is (2 - nu_i) Q/(8 G_i a), uniform over the contact, so the
    energy ½ Q u_i of body i is proportional to t_i. This is also the series
    split behind 1/G* = t1 + t2, the G* LIGGGHTS and YADE use.

    ``rule="paper"``: the paper's eq. (22), t_i = (1 - 2 nu_i)/G_i. That factor
    is the normal-tangential coupling compliance, not the tangential
    displacement; it predicts no tangential energy in an incompressible body
    (nu = 0.5), which the Mindlin solution contradicts. Offered for
    comparison. Where both factors vanish (nu1 = nu2 = 0.5, or nu = 0.5 against
    a rigid body) the result is the limit nu1 = nu2 -> 0.5 of the rule,
    share1 = (1/G1)/(1/G1 + 1/G2).
    """
    if rule == "mindlin":
        return share_from_compliances(laws.mindlin_compliance(E1, nu1), laws.mindlin_compliance(E2, nu2))
    if rule != "paper":
        raise ValueError(f"unknown tangential rule {rule!r}; use one of {TANGENTIAL_RULES}")
    t1 = laws.paper_tangential_compliance(E1, nu1)
    t2 = laws.paper_tangential_compliance(E2, nu2)
    # limit along nu1 = nu2 -> 0.5: the (1 - 2 nu) factors cancel, leaving 1/G = 2 (1 + nu)/E
    both_zero = (t1 + t2) == 0
    g1 = 2.0 * (1.0 + np.asarray(nu1, dtype=np.float64)) / np.asarray(E1, dtype=np.float64)
    g2 = 2.0 * (1.0 + np.asarray(nu2, dtype=np.float64)) / np.asarray(E2, dtype=np.float64)
    return share_from_compliances(np.where(both_zero, g1, t1), np.where(both_zero, g2, t2))


def radius_share(r1: ArrayLike, r2: ArrayLike) -> np.ndarray:
    """Radius-weighted share of body 1: r1/(r1 + r2).

    It is the overlap split implied by LIGGGHTS' ``contactPoint``
    (x1 r2 + x2 r1)/(r1 + r2) (and Aspherix's radius split): body 1 takes
    delta1 = r1 delta/(r1 + r2). Against a plane (r2 = inf) LIGGGHTS puts the
    contact point on the wall surface, i.e. the particle takes the whole
    overlap: share 1.
    """
    r1 = np.asarray(r1, dtype=np.float64)
    r2 = np.asarray(r2, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        share = np.where(np.isinf(r2), 1.0, r1 / (r1 + np.where(np.isinf(r2), 0.0, r2)))
    return _scalar_or_array(share)


def springs_share(E1: ArrayLike, r1: ArrayLike, E2: ArrayLike, r2: ArrayLike) -> np.ndarray:
    """Share of body 1 for two springs k_i = E_i r_i in series (YADE ``FrictPhys``):
    the energy F^2/(2 k_i) of each spring gives share1 = (1/k1)/(1/k1 + 1/k2)."""
    return share_from_compliances(1.0 / (np.asarray(E1, dtype=np.float64) * np.asarray(r1, dtype=np.float64)),
                                  1.0 / (np.asarray(E2, dtype=np.float64) * np.asarray(r2, dtype=np.float64)))


def overlap_depths(delta: ArrayLike, share1: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Approach of each body, delta1 = share1 delta and delta2 = delta - delta1 (m), eq. (31)."""
    delta = np.asarray(delta, dtype=np.float64)
    d1 = np.asarray(share1, dtype=np.float64) * delta
    return d1, delta - d1


def contact_point(x1: ArrayLike, n: ArrayLike, r1: ArrayLike, delta: ArrayLike,
                  share1: ArrayLike) -> np.ndarray:
    """Material-weighted contact point x_c = x1 + (r1 - share1 delta) n (m), eq. (31).

    x1 : centre of body 1, shape (..., 3) (m); n : unit normal from body 1 to
    body 2, shape (..., 3); r1 : radius of body 1 (m); delta : overlap (m).
    Equal materials give the middle of the overlap; a rigid partner
    (share1 = 1) puts the point on its surface.
    """
    depth1 = np.asarray(share1, dtype=np.float64) * np.asarray(delta, dtype=np.float64)
    arm = np.asarray(r1, dtype=np.float64) - depth1
    return np.asarray(x1, dtype=np.float64) + arm[..., None] * np.asarray(n, dtype=np.float64)


# --- Per-contact bodies: which material, radius and mass each side has ------------------------

@dataclass
class ContactBodies:
    """Material types and elastic constants of both sides of every contact.

    In a single-material scene ``E1 nu1 E2 nu2`` are scalars and no per-contact
    lookup is made.
    """

    type1: np.ndarray | None
    type2: np.ndarray | None
    E1: np.ndarray | float
    nu1: np.ndarray | float
    E2: np.ndarray | float
    nu2: np.ndarray | float
    single_material: bool
    scene: Scene | None = None
    _pairs: tuple | None = field(default=None, repr=False, compare=False)

    @classmethod
    def build(cls, contacts: Table, scene: Scene, particles: Table | None = None,
              index: ParticleIndex | None = None) -> "ContactBodies":
        if scene.single_material:
            m = next(iter(scene.materials.values()))
            return cls(None, None, m.E, m.nu, m.E, m.nu, True)
        type1, type2 = contact_types(contacts, scene, particles, index)
        E1, nu1 = scene.lookup(type1, what="particle")
        E2, nu2 = scene.lookup(type2, what="particle or wall")
        return cls(type1, type2, E1, nu1, E2, nu2, False, scene)

    def per_pair(self, f) -> np.ndarray | float:
        """``f(E1, nu1, E2, nu2)`` for every contact, evaluated once per pair of
        material types present and gathered (a few types, millions of contacts)."""
        if self.single_material or self.scene is None:
            return f(self.E1, self.nu1, self.E2, self.nu2)
        E, nu = self.scene.material_tables()
        n_types = len(E)
        if self._pairs is None:  # code of each contact's (type1, type2), and the codes present
            code = self.type1 * n_types + self.type2
            present = np.zeros(n_types * n_types, dtype=bool)
            present[code] = True
            self._pairs = (code, np.flatnonzero(present))
        code, pairs = self._pairs
        t1, t2 = pairs // n_types, pairs % n_types
        table = np.zeros(n_types * n_types)
        table[pairs] = f(E[t1], nu[t1], E[t2], nu[t2])
        return table.take(code)


def contact_types(contacts: Table, scene: Scene, particles: Table | None = None,
                  index: ParticleIndex | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Material type of body 1 and body 2 of each contact.

    Taken from the ``type1``/``type2`` columns when the reader set them,
    otherwise from the particles table (by id) and the wall list.
    """
    if "type1" in contacts and "type2" in contacts:
        return contacts["type1"].astype(np.int64), contacts["type2"].astype(np.int64)
    if particles is None:
        raise InputFormatError("contacts carry no material types and no particles table was given.",
                               fix="pass the frame's particles so types can be looked up by id.")
    index = index or ParticleIndex(particles["id"])
    ptype = np.asarray(particles["type"], dtype=np.int64)
    wall = contacts["wall"]
    is_wall = wall >= 0
    type1 = ptype[index.rows(contacts["id1"])]
    type2 = np.empty_like(type1)
    if (~is_wall).any():
        type2[~is_wall] = ptype[index.rows(contacts["id2"][~is_wall])]
    if is_wall.any():
        wall_types = scene.wall_types()
        if wall[is_wall].max() >= len(wall_types):
            raise ContactError(f"a wall contact names wall {int(wall[is_wall].max())} but the scene has "
                               f"{len(wall_types)} wall(s).",
                               fix="describe every wall of the run in the scene (input script).")
        type2[is_wall] = wall_types[wall[is_wall]]
    return type1, type2


# --- Energies by contact model -------------------------------------------------------------

def _column(contacts: Table, name: str, model: ContactModel) -> np.ndarray:
    if name not in contacts:
        raise InputFormatError(
            f"the {model.normal} contact model needs the contact column {name!r}, which the input does not have.",
            fix="dump it (see the reader's documentation for the column) or describe the model explicitly.",
        )
    return np.asarray(contacts[name], dtype=np.float64)


def _reduced_mass(contacts: Table, rows: np.ndarray, particles: Table | None,
                  index: ParticleIndex | None) -> np.ndarray:
    """m* of the contacts ``rows`` (kg), from ``m1 m2`` columns or the particles' ``mass``;
    a wall has infinite mass."""
    if "m1" in contacts and "m2" in contacts:
        return laws.reduced_mass(contacts["m1"][rows], contacts["m2"][rows])
    if particles is None or "mass" not in particles:
        raise InputFormatError("the hooke contact model needs particle masses, which the atom dump does not have.",
                               fix="add 'mass' to the dump custom columns.")
    index = index or ParticleIndex(particles["id"])
    mass = np.asarray(particles["mass"], dtype=np.float64)
    m1 = mass[index.rows(contacts["id1"][rows])]
    m2 = np.full_like(m1, np.inf)
    pair = contacts["wall"][rows] < 0
    m2[pair] = mass[index.rows(contacts["id2"][rows][pair])]
    return laws.reduced_mass(m1, m2)


@dataclass
class ContactLawEnergy:
    """Elastic energies of every contact under the run's own law (J), and what could not be computed."""

    u_n: np.ndarray
    u_t: np.ndarray
    skipped: dict[str, str] = field(default_factory=dict)


def _model_groups(contacts: Table, scene: Scene) -> list[tuple[ContactModel, np.ndarray]]:
    """Rows of the contacts each model acts on: the pair model, or a wall's own
    ``fix wall/gran`` model when it differs."""
    wall = contacts["wall"]
    groups: list[tuple[ContactModel, np.ndarray]] = []
    default = np.ones(len(wall), dtype=bool)
    for i, w in enumerate(scene.walls):
        if w.model is None or w.model == scene.model:
            continue
        mask = wall == i
        default &= ~mask
        for model, other in groups:
            if model == w.model:
                other |= mask
                break
        else:
            groups.append((w.model, mask))
    groups.append((scene.model, default))
    if len(groups) == 1:  # one law for every contact: a slice, so that x[rows] is a view, not a copy
        return [(scene.model, slice(None))] if len(wall) else []
    return [(m, np.flatnonzero(mask)) for m, mask in groups if mask.any()]


def contact_energies(contacts: Table, scene: Scene, particles: Table | None = None,
                     bodies: ContactBodies | None = None, index: ParticleIndex | None = None) -> ContactLawEnergy:
    """Normal and tangential elastic energy of every contact with the run's own law (J).

    normal ``hertz``: (2/5) kno delta^2.5 with YADE's stored ``kno`` when
    present, else (8/15) E* sqrt(R* delta) delta^2 from materials and radii
    (LIGGGHTS builds E*, R* that way). ``hooke``: ½ kn delta^2 with LIGGGHTS'
    kn(m*, V). ``linear``: ½ kn delta^2 with the stored ``kn``. ``power``:
    k delta^(n+1)/(n+1).

    tangential ``history``: ½ kt |shear|^2 with kt as the normal model builds
    it (hertz: 8 G* sqrt(R* delta); hooke: kt_to_kn kn). ``incremental``:
    ½ |F_t|^2/ks with the stored ``ks``. Damping forces are never used.
    Tangential energy without tangential data is 0 and named in ``skipped``.
    """
    n = table_length(contacts)
    bodies = bodies or ContactBodies.build(contacts, scene, particles, index)
    delta = np.asarray(contacts["delta"], dtype=np.float64)
    u_n = np.zeros(n)
    u_t = np.zeros(n)
    skipped: dict[str, str] = {}

    def pick(x, rows):
        return x if np.ndim(x) == 0 else x[rows]

    moduli: dict = {}

    def modulus(f):  # E* or G* of every contact, once per pair of types
        if f not in moduli:
            moduli[f] = bodies.per_pair(f)
        return moduli[f]

    for model, rows in _model_groups(contacts, scene):
        d = delta[rows]
        R_eff = laws.effective_radius(contacts["r1"][rows], contacts["r2"][rows])
        kn = None
        if model.normal == "hertz":
            if "kno" in contacts:
                u_n[rows] = laws.hertz_energy_from_kno(d, contacts["kno"][rows])
            else:
                u_n[rows] = laws.hertz_energy_from_moduli(d, R_eff, pick(modulus(laws.effective_modulus), rows))
        elif model.normal == "hooke":
            v = model.params.get("characteristic_velocity")
            if v is None:
                raise InputFormatError("model hooke needs characteristicVelocity, which the scene does not give.",
                                       fix="define 'fix ... property/global characteristicVelocity scalar V'.")
            kn = laws.liggghts_hooke_kn(R_eff, pick(modulus(laws.effective_modulus), rows),
                                        _reduced_mass(contacts, rows, particles, index), v)
            u_n[rows] = laws.hooke_energy(d, kn)
        elif model.normal == "linear":
            u_n[rows] = laws.hooke_energy(d, _column(contacts, "kn", model)[rows])
        elif model.normal == "power":
            u_n[rows] = laws.power_law_energy(d, model.params["k"], model.params["n"])

        if model.tangential == "history":
            if not all(c in contacts for c in ("shearx", "sheary", "shearz")):
                skipped["u_t"] = ("the contact data has no tangential spring history (shear), "
                                  "so tangential elastic energy is not computed (0)")
                continue
            if model.normal == "hertz":
                kt = laws.liggghts_hertz_kt(d, R_eff, pick(modulus(laws.effective_shear_modulus), rows))
            elif kn is not None:
                kt = model.params.get("kt_to_kn", 1.0) * kn
            else:
                raise InputFormatError(f"tangential history with normal model {model.normal!r} has no kt rule.")
            shear = np.stack([contacts["shearx"][rows], contacts["sheary"][rows], contacts["shearz"][rows]], axis=-1)
            u_t[rows] = np.where(d > 0, laws.shear_spring_energy(shear, kt), 0.0)
        elif model.tangential == "incremental":
            if not all(c in contacts for c in ("ftx", "fty", "ftz", "ks")):
                skipped["u_t"] = ("the contact data has no elastic shear force and shear stiffness, "
                                  "so tangential elastic energy is not computed (0)")
                continue
            ft = np.stack([contacts["ftx"][rows], contacts["fty"][rows], contacts["ftz"][rows]], axis=-1)
            u_t[rows] = np.where(d > 0, laws.tangential_spring_energy(ft, contacts["ks"][rows]), 0.0)
        else:
            skipped.setdefault("u_t", "the contact model has no tangential spring (0)")
    return ContactLawEnergy(u_n, u_t, skipped)


# --- The partition --------------------------------------------------------------------------

@dataclass
class ContactEnergy:
    """Per-contact results of :func:`partition`.

    ``u_n``, ``u_t`` (J): elastic energies; ``share_n1``, ``share_t1``: fraction
    to body 1; ``u1``, ``u2`` (J): energy of each body; ``depth1`` (m): approach
    of body 1; ``cp`` (m, shape (n, 3)): contact point; ``separated``: contacts
    with delta < 0 (zero energy, kept and flagged); ``skipped``: quantities not
    computed and why.
    """

    u_n: np.ndarray
    u_t: np.ndarray
    share_n1: np.ndarray
    share_t1: np.ndarray
    u1: np.ndarray
    u2: np.ndarray
    depth1: np.ndarray
    cp: np.ndarray
    separated: np.ndarray
    split: str = "material"
    skipped: dict[str, str] = field(default_factory=dict)

    def table(self) -> Table:
        """The per-contact columns as a table (``cpx cpy cpz`` for the point)."""
        out = {k: getattr(self, k) for k in ("u_n", "u_t", "share_n1", "share_t1", "u1", "u2", "depth1")}
        out.update(cpx=self.cp[:, 0], cpy=self.cp[:, 1], cpz=self.cp[:, 2])
        return out


def contact_shares(contacts: Table, bodies: ContactBodies, *, split: str = "material",
                   tangential_rule: str = "mindlin") -> tuple[np.ndarray, np.ndarray]:
    """Normal and tangential share of body 1 of every contact under ``split`` (see :data:`SPLITS`).

    The comparison splits (``equal``, ``radius``, ``springs``) do not tell
    normal from tangential, so they give both parts the same share.
    """
    n = table_length(contacts)
    if split == "material":
        if bodies.single_material:
            half = np.full(n, 0.5)
            return half, half
        return (np.broadcast_to(bodies.per_pair(normal_share), (n,)),
                np.broadcast_to(bodies.per_pair(lambda E1, nu1, E2, nu2: tangential_share(
                    E1, nu1, E2, nu2, rule=tangential_rule)), (n,)))
    if split == "equal":
        s = np.full(n, 0.5)
    elif split == "radius":
        s = radius_share(contacts["r1"], contacts["r2"])
    elif split == "springs":
        s = np.broadcast_to(springs_share(bodies.E1, contacts["r1"], bodies.E2, contacts["r2"]), (n,))
    else:
        raise ValueError(f"unknown split {split!r}; use one of {SPLITS}")
    return s, s


def partition(contacts: Table, scene: Scene, particles: Table | None = None, *,
              split: str = "material", tangential_rule: str = "mindlin",
              energies: ContactLawEnergy | None = None, bodies: ContactBodies | None = None,
              index: ParticleIndex | None = None) -> ContactEnergy:
    """Split every contact's elastic energy between its two bodies and place the contact point.

    u1 = share_n1 u_n + share_t1 u_t,  u2 = (1 - share_n1) u_n + (1 - share_t1) u_t,
    depth1 = share_n1 delta,  x_c = x1 + (r1 - depth1) n.

    ``energies`` and ``bodies`` may be passed in to reuse them across splits.
    """
    if index is None and particles is not None and not scene.single_material:
        index = ParticleIndex(particles["id"])
    bodies = bodies or ContactBodies.build(contacts, scene, particles, index)
    n = table_length(contacts)
    rigid_pair = np.broadcast_to(np.isinf(bodies.E1) & np.isinf(bodies.E2), (n,))
    if rigid_pair.any():
        i = int(np.flatnonzero(rigid_pair)[0])
        raise ContactError(
            f"{int(np.count_nonzero(rigid_pair))} contact(s) between two rigid bodies, e.g. "
            f"id1={int(contacts['id1'][i])}, id2={int(contacts['id2'][i])}, wall={int(contacts['wall'][i])}: "
            "neither body can store elastic energy.",
            fix="give one of the two materials a finite Young's modulus.",
        )
    energies = energies or contact_energies(contacts, scene, particles, bodies, index)
    s_n, s_t = contact_shares(contacts, bodies, split=split, tangential_rule=tangential_rule)
    u1 = s_n * energies.u_n + s_t * energies.u_t
    u2 = (1.0 - s_n) * energies.u_n + (1.0 - s_t) * energies.u_t
    delta = np.asarray(contacts["delta"], dtype=np.float64)
    depth1, _ = overlap_depths(delta, s_n)
    x1 = np.stack([contacts["x1"], contacts["y1"], contacts["z1"]], axis=-1)
    normal = np.stack([contacts["nx"], contacts["ny"], contacts["nz"]], axis=-1)
    cp = contact_point(x1, normal, contacts["r1"], delta, s_n)
    return ContactEnergy(energies.u_n, energies.u_t, np.asarray(s_n), np.asarray(s_t), u1, u2, depth1, cp,
                         delta < 0, split, dict(energies.skipped))


def per_particle(contacts: Table, energy: ContactEnergy, particles: Table, n_walls: int = 0,
                 index: ParticleIndex | None = None) -> tuple[Table, Table]:
    """Sum each body's energy over its contacts (np.bincount over a dense particle index).

    Returns ``(particle_table, wall_table)``: per particle ``id type radius u
    u_n u_t n_contacts`` (J), in the particles' row order; per wall ``wall u
    u_n u_t n_contacts``. Conservation: Σ particle u + Σ wall u = Σ contact
    (u_n + u_t) to rounding.
    """
    index = index or ParticleIndex(particles["id"])
    n = table_length(particles)
    wall = contacts["wall"]
    pair = wall < 0
    body_sum = _BodySum(contacts, index, n)
    un1 = energy.share_n1 * energy.u_n
    ut1 = energy.share_t1 * energy.u_t
    un2 = energy.u_n - un1
    ut2 = energy.u_t - ut1
    u_n = body_sum(un1, un2)
    u_t = body_sum(ut1, ut2)
    n_contacts = (np.bincount(body_sum.rows1, minlength=n)
                  + np.bincount(body_sum.rows2, minlength=n)).astype(np.int64)
    ptable = {
        "id": np.asarray(particles["id"], dtype=np.int64),
        "type": np.asarray(particles["type"], dtype=np.int32),
        "radius": np.asarray(particles["radius"], dtype=np.float64),
        "u": u_n + u_t, "u_n": u_n, "u_t": u_t, "n_contacts": n_contacts,
    }
    w = wall[~pair]
    n_walls = max(n_walls, int(w.max()) + 1 if len(w) else 0)
    wu_n = np.bincount(w, weights=un2[~pair], minlength=n_walls)
    wu_t = np.bincount(w, weights=ut2[~pair], minlength=n_walls)
    wtable = {"wall": np.arange(n_walls, dtype=np.int64), "u": wu_n + wu_t, "u_n": wu_n, "u_t": wu_t,
              "n_contacts": np.bincount(w, minlength=n_walls).astype(np.int64)}
    return ptable, wtable


class _BodySum:
    """Sums per particle over its contacts: weight w1 where it is body 1, w2 where it is
    body 2 of a particle-particle contact (np.bincount over the dense particle index)."""

    def __init__(self, contacts: Table, index: ParticleIndex, n: int) -> None:
        self.pair = contacts["wall"] < 0
        self.all_pairs = bool(self.pair.all())
        self.rows1 = index.rows(contacts["id1"])
        self.rows2 = index.rows(contacts["id2"] if self.all_pairs else contacts["id2"][self.pair])
        self.n = n

    def __call__(self, w1: np.ndarray, w2: np.ndarray) -> np.ndarray:
        return (np.bincount(self.rows1, weights=w1, minlength=self.n)
                + np.bincount(self.rows2, weights=w2 if self.all_pairs else w2[self.pair], minlength=self.n))


def particle_energy(contacts: Table, energies: ContactLawEnergy, bodies: ContactBodies, particles: Table, *,
                    split: str, index: ParticleIndex | None = None) -> np.ndarray:
    """Energy of every particle (J, particles' row order) under ``split``: the
    ``u`` column of :func:`per_particle` without the per-contact table, for the
    comparison splits. u1 = s_n u_n + s_t u_t, u2 = u_n + u_t - u1."""
    index = index or ParticleIndex(particles["id"])
    s_n, s_t = contact_shares(contacts, bodies, split=split)
    u1 = s_n * energies.u_n + s_t * energies.u_t
    return _BodySum(contacts, index, table_length(particles))(u1, energies.u_n + energies.u_t - u1)
