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

The per-contact work runs in compiled loops (:mod:`demsplit.kernels`, imported
when first needed, so ``import demsplit`` needs no numba): one pass gathers,
applies the law, splits and places the contact point, one pass sums per body.
Those loops call the formulas defined here and in :mod:`demsplit.laws`
(:func:`body_energies`, :func:`contact_point_coordinate`, ...), compiled:
one definition of the physics. Per-body sums add each body's contributions in
contact order, body-1 terms then body-2 terms, as ``np.bincount`` did; results
are those of the numpy formulation to rounding (``tests/test_kernels.py``).
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
    plane = np.isinf(r2)
    with np.errstate(invalid="ignore"):
        share = np.asarray(r1 / (r1 + r2), dtype=np.float64)
    share[plane] = 1.0
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


def contact_point_coordinate(x1, n, r1, depth1):
    """One coordinate of the contact point, x1 + (r1 - depth1) n (m): formula on
    float64 arrays or scalars (compiled by :mod:`demsplit.kernels`)."""
    return x1 + (r1 - depth1) * n


def body_energies(s_n, s_t, u_n, u_t):
    """Energy of body 1 and body 2 of a contact (J): u1 = s_n u_n + s_t u_t,
    u2 = (1 - s_n) u_n + (1 - s_t) u_t. Formula on float64 arrays or scalars."""
    return s_n * u_n + s_t * u_t, (1.0 - s_n) * u_n + (1.0 - s_t) * u_t


def contact_point(x1: ArrayLike, n: ArrayLike, r1: ArrayLike, delta: ArrayLike,
                  share1: ArrayLike) -> np.ndarray:
    """Material-weighted contact point x_c = x1 + (r1 - share1 delta) n (m), eq. (31).

    x1 : centre of body 1, shape (..., 3) (m); n : unit normal from body 1 to
    body 2, shape (..., 3); r1 : radius of body 1 (m); delta : overlap (m).
    Equal materials give the middle of the overlap; a rigid partner
    (share1 = 1) puts the point on its surface.
    """
    depth1, _ = overlap_depths(delta, share1)
    return contact_point_coordinate(np.asarray(x1, dtype=np.float64), np.asarray(n, dtype=np.float64),
                                    np.asarray(r1, dtype=np.float64)[..., None], depth1[..., None])


# --- Per-contact bodies: which material, radius and mass each side has ------------------------

class ContactBodies:
    """Material types and elastic constants of both sides of every contact.

    In a single-material scene ``E1 nu1 E2 nu2`` are scalars and no per-contact
    lookup is made. Built from a multi-material scene, the per-contact constants
    ``E1 nu1 E2 nu2`` are gathered from the scene's tables on first use (the
    partition itself works from the types, once per pair of types).
    """

    def __init__(self, type1: np.ndarray | None, type2: np.ndarray | None, E1: np.ndarray | float | None,
                 nu1: np.ndarray | float | None, E2: np.ndarray | float | None, nu2: np.ndarray | float | None,
                 single_material: bool, scene: Scene | None = None, *, pairs: tuple | None = None) -> None:
        self._types = (type1, type2)
        self._constants = (E1, nu1, E2, nu2)
        self.single_material = single_material
        self.scene = scene
        self._pairs = pairs  # (code of every contact, codes present), see _pair_codes

    @classmethod
    def build(cls, contacts: Table, scene: Scene, particles: Table | None = None,
              index: ParticleIndex | None = None) -> "ContactBodies":
        if scene.single_material:
            m = next(iter(scene.materials.values()))
            return cls(None, None, m.E, m.nu, m.E, m.nu, True)
        type1, type2, pairs = _contact_pairs(contacts, scene, particles, index)
        bodies = cls(type1, type2, None, None, None, None, False, scene, pairs=pairs)
        code, pairs = bodies._pair_codes()
        n_types = len(scene.material_tables()[0])
        # every type present has a material (checked once per pair of types present)
        scene.lookup(pairs // n_types, what="particle")
        scene.lookup(pairs % n_types, what="particle or wall")
        return bodies

    def _constant(self, k: int) -> np.ndarray | float:
        if self._constants[k] is None:
            E, nu = self.scene.material_tables()
            self._constants = (E.take(self.type1), nu.take(self.type1), E.take(self.type2), nu.take(self.type2))
        return self._constants[k]

    def _type(self, k: int) -> np.ndarray | None:
        if self._types[k] is None and self._pairs is not None:
            self._types = _types_of_codes(self._pairs[0], self.scene)
        return self._types[k]

    type1 = property(lambda self: self._type(0), doc="material type of body 1 (None: single material)")
    type2 = property(lambda self: self._type(1), doc="material type of body 2 (None: single material)")
    E1 = property(lambda self: self._constant(0), doc="Young's modulus of body 1 (Pa)")
    nu1 = property(lambda self: self._constant(1), doc="Poisson's ratio of body 1")
    E2 = property(lambda self: self._constant(2), doc="Young's modulus of body 2 (Pa)")
    nu2 = property(lambda self: self._constant(3), doc="Poisson's ratio of body 2")

    def _pair_codes(self) -> tuple[np.ndarray, np.ndarray]:
        """Code type1 * n_types + type2 of every contact, and the codes present."""
        if self._pairs is None:
            n_types = len(self.scene.material_tables()[0])
            inside = (self.type1 >= 0) & (self.type1 < n_types) & (self.type2 >= 0) & (self.type2 < n_types)
            if not inside.all():  # a type beyond the table: the lookup's error names it
                self.scene.lookup(self.type1, what="particle")
                self.scene.lookup(self.type2, what="particle or wall")
            code = self.type1 * n_types + self.type2
            present = np.zeros(n_types * n_types, dtype=bool)
            present[code] = True
            self._pairs = (code, np.flatnonzero(present))
        return self._pairs

    def rigid_pairs(self) -> np.ndarray:
        """Contacts between two rigid bodies (E1 = E2 = inf): a boolean array, or a
        boolean scalar when every contact has the same two bodies' materials."""
        if self.single_material or self.scene is None:
            return np.isinf(self.E1) & np.isinf(self.E2)
        code, pairs = self._pair_codes()
        E = self.scene.material_tables()[0]
        n_types = len(E)
        rigid = np.isinf(E[pairs // n_types]) & np.isinf(E[pairs % n_types])
        if not rigid.any():
            return np.False_
        return np.isin(code, pairs[rigid])

    def per_pair(self, f) -> np.ndarray | float:
        """``f(E1, nu1, E2, nu2)`` for every contact, evaluated once per pair of
        material types present and gathered (a few types, millions of contacts)."""
        values, code = self.pair_values(f)
        return values.take(code) if len(code) else f(self.E1, self.nu1, self.E2, self.nu2)

    def pair_values(self, f) -> tuple[np.ndarray, np.ndarray]:
        """``f(E1, nu1, E2, nu2)`` for the compiled loops, as ``(values, code)`` (see
        :mod:`demsplit.kernels`): ``values`` per pair of types present and the pair
        code of every contact, or (no code) the values per contact or one for all."""
        from .kernels import NO_CODE

        if self.single_material or self.scene is None:
            return np.atleast_1d(np.asarray(f(self.E1, self.nu1, self.E2, self.nu2), dtype=np.float64)), NO_CODE
        E, nu = self.scene.material_tables()
        n_types = len(E)
        code, pairs = self._pair_codes()
        t1, t2 = pairs // n_types, pairs % n_types
        table = np.zeros(n_types * n_types)
        table[pairs] = f(E[t1], nu[t1], E[t2], nu[t2])
        return table, code


def contact_types(contacts: Table, scene: Scene, particles: Table | None = None,
                  index: ParticleIndex | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Material type of body 1 and body 2 of each contact.

    Taken from the ``type1``/``type2`` columns when the reader set them,
    otherwise from the particles table (by id) and the wall list.
    """
    type1, type2, pairs = _contact_pairs(contacts, scene, particles, index)
    return (type1, type2) if type1 is not None else _types_of_codes(pairs[0], scene)


def _types_of_codes(code: np.ndarray, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(type1, type2) of pair codes type1 * n_types + type2."""
    n_types = len(scene.material_tables()[0])
    code = code.astype(np.int64)
    return code // n_types, code % n_types


def _code_dtype(n_types: int) -> type:
    """Smallest integer type for the codes 0..n_types^2 - 1 (less to read per contact)."""
    return np.int8 if n_types**2 <= 127 else np.int16 if n_types**2 <= 32767 else np.int64


def _contact_pairs(contacts: Table, scene: Scene, particles: Table | None,
                   index: ParticleIndex | None) -> tuple[np.ndarray | None, np.ndarray | None, tuple | None]:
    """The bodies' material types as ``(type1, type2, None)`` when the contacts carry
    them, else ``(None, None, (pair code of every contact, codes present))``."""
    if "type1" in contacts and "type2" in contacts:
        return contacts["type1"].astype(np.int64), contacts["type2"].astype(np.int64), None
    if particles is None:
        raise InputFormatError("contacts carry no material types and no particles table was given.",
                               fix="pass the frame's particles so types can be looked up by id.")
    from .kernels import contact_types as gather_types  # compiled: see the module docstring

    index = index or ParticleIndex(particles["id"])
    wall = contacts["wall"]
    rows1, rows2 = index.contact_rows(contacts["id1"], contacts["id2"], wall)
    wall_types = scene.wall_types()
    n_types = len(scene.material_tables()[0])
    ptype = np.asarray(particles["type"])
    code = np.empty(len(rows1), dtype=_code_dtype(n_types))
    present, bad_wall, bad_type = gather_types(rows1, rows2, ptype, wall_types, n_types, code)
    if bad_wall >= 0:
        raise ContactError(f"a wall contact names wall {int(wall.max())} but the scene has "
                           f"{len(wall_types)} wall(s).",
                           fix="describe every wall of the run in the scene (input script).")
    if bad_type >= 0:  # a type outside the material table: the lookup's error lists them
        scene.lookup(ptype[rows1], what="particle")
        pair = rows2 >= 0
        scene.lookup(ptype[rows2[pair]], what="particle")
        scene.lookup(wall_types[-1 - rows2[~pair]], what="wall")
    return None, None, (code, np.flatnonzero(present))


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

    def pair_values(f, rows):  # E* or G* for the compiled loop: values per pair of types and codes
        values, code = bodies.pair_values(f)
        if len(code):
            return values, code[rows]
        return (values[rows] if len(values) > 1 else values), code

    has_shear = all(c in contacts for c in ("shearx", "sheary", "shearz"))
    for model, rows in _model_groups(contacts, scene):
        d = delta[rows]
        if model.normal == "hertz" and "kno" not in contacts:  # LIGGGHTS hertz: one compiled pass
            from .kernels import hertz_history_energies

            history = model.tangential == "history" and has_shear
            shear = [_f64(contacts[c])[rows] for c in ("shearx", "sheary", "shearz")] if history else [d, d, d]
            E_eff, code = pair_values(laws.effective_modulus, rows)
            G_eff = pair_values(laws.effective_shear_modulus, rows)[0] if history else E_eff
            u_n_rows, u_t_rows, bad = hertz_history_energies(d, _f64(contacts["r1"][rows]), _f64(contacts["r2"][rows]),
                                                             E_eff, G_eff, code, *shear, history)
            if bad >= 0:
                raise laws.curvature_error()
            if isinstance(rows, slice):  # every contact: the loop's arrays are the result
                u_n = u_n_rows
            else:
                u_n[rows] = u_n_rows
            if history:
                if isinstance(rows, slice):
                    u_t = u_t_rows
                else:
                    u_t[rows] = u_t_rows
                continue
        R_eff = laws.effective_radius(contacts["r1"][rows], contacts["r2"][rows])
        kn = None
        if model.normal == "hertz":
            if "kno" in contacts:
                u_n[rows] = laws.hertz_energy_from_kno(d, contacts["kno"][rows])
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
            if not has_shear:
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
    of body 1; ``cp`` (m, shape (n, 3), stored by coordinate: ``cp[:, 0]`` is
    contiguous): contact point; ``separated``: contacts
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
            half = np.broadcast_to(0.5, (n,))
            return half, half
        return (np.broadcast_to(bodies.per_pair(normal_share), (n,)),
                np.broadcast_to(bodies.per_pair(lambda E1, nu1, E2, nu2: tangential_share(
                    E1, nu1, E2, nu2, rule=tangential_rule)), (n,)))
    if split == "equal":
        s = np.broadcast_to(0.5, (n,))
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
    rigid_pair = np.broadcast_to(bodies.rigid_pairs(), (n,))
    if rigid_pair.any():
        i = int(np.flatnonzero(rigid_pair)[0])
        raise ContactError(
            f"{int(np.count_nonzero(rigid_pair))} contact(s) between two rigid bodies, e.g. "
            f"id1={int(contacts['id1'][i])}, id2={int(contacts['id2'][i])}, wall={int(contacts['wall'][i])}: "
            "neither body can store elastic energy.",
            fix="give one of the two materials a finite Young's modulus.",
        )
    energies = energies or contact_energies(contacts, scene, particles, bodies, index)
    from .kernels import NO_CODE, split_contacts  # compiled: see the module docstring

    if split == "material" and not bodies.single_material:  # shares per pair of types, not per contact
        shares = (*bodies.pair_values(normal_share),
                  *bodies.pair_values(lambda E1, nu1, E2, nu2: tangential_share(E1, nu1, E2, nu2,
                                                                                 rule=tangential_rule)))
    else:
        s_n, s_t = contact_shares(contacts, bodies, split=split, tangential_rule=tangential_rule)
        shares = (_values(s_n), NO_CODE, _values(s_t), NO_CODE)
    delta = np.asarray(contacts["delta"], dtype=np.float64)
    s_n, s_t, u1, u2, depth1, cp = split_contacts(
        *shares, energies.u_n, energies.u_t, delta,
        *(_f64(contacts[c]) for c in ("x1", "y1", "z1", "nx", "ny", "nz", "r1")))
    return ContactEnergy(energies.u_n, energies.u_t, s_n, s_t, u1, u2, depth1, cp.T, delta < 0, split,
                         dict(energies.skipped))


def _f64(x: ArrayLike) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def _values(x: ArrayLike) -> np.ndarray:
    """Per-contact values for a compiled loop: the array itself, or its one value
    (length 1) when it is a constant broadcast to every contact."""
    x = _f64(x)
    if x.ndim == 1 and len(x) and x.strides[0] == 0:
        return x[:1]
    return np.atleast_1d(x)


def per_particle(contacts: Table, energy: ContactEnergy, particles: Table, n_walls: int = 0,
                 index: ParticleIndex | None = None) -> tuple[Table, Table]:
    """Sum each body's energy over its contacts (one compiled pass, :func:`demsplit.kernels.body_sums`).

    Returns ``(particle_table, wall_table)``: per particle ``id type radius u
    u_n u_t n_contacts`` (J), in the particles' row order; per wall ``wall u
    u_n u_t n_contacts``. Conservation: Σ particle u + Σ wall u = Σ contact
    (u_n + u_t) to rounding.
    """
    from .kernels import body_sums, max_wall  # compiled: see the module docstring

    index = index or ParticleIndex(particles["id"])
    wall = contacts["wall"]
    rows1, rows2 = index.contact_rows(contacts["id1"], contacts["id2"], wall)
    n_walls = max(n_walls, int(max_wall(rows2)) + 1)
    u_n, u_t, n_contacts, wu_n, wu_t, w_contacts = body_sums(
        rows1, rows2, _values(energy.share_n1), _values(energy.share_t1), energy.u_n, energy.u_t,
        table_length(particles), n_walls)
    ptable = {
        "id": np.asarray(particles["id"], dtype=np.int64),
        "type": np.asarray(particles["type"], dtype=np.int32),
        "radius": np.asarray(particles["radius"], dtype=np.float64),
        "u": u_n + u_t, "u_n": u_n, "u_t": u_t, "n_contacts": n_contacts,
    }
    wtable = {"wall": np.arange(n_walls, dtype=np.int64), "u": wu_n + wu_t, "u_n": wu_n, "u_t": wu_t,
              "n_contacts": w_contacts}
    return ptable, wtable


def particle_energy(contacts: Table, energies: ContactLawEnergy, bodies: ContactBodies, particles: Table, *,
                    split: str, index: ParticleIndex | None = None) -> np.ndarray:
    """Energy of every particle (J, particles' row order) under ``split``: the
    ``u`` column of :func:`per_particle` without the per-contact table, for the
    comparison splits. u1 = s_n u_n + s_t u_t, u2 = u_n + u_t - u1."""
    from .kernels import particle_sums  # compiled: see the module docstring

    index = index or ParticleIndex(particles["id"])
    wall = contacts["wall"]
    rows1, rows2 = index.contact_rows(contacts["id1"], contacts["id2"], wall)
    s_n, s_t = contact_shares(contacts, bodies, split=split)
    return particle_sums(rows1, rows2, _values(s_n), _values(s_t), energies.u_n, energies.u_t,
                         table_length(particles))
