"""One frame's contacts and the two bodies of every contact: their rows, material types and elastic constants.

:class:`FrameContacts` is what every stage of the partition is given: the frame's contact table, its scene
and its particles, with what the stages derive from them (the particle index, the two bodies' rows, their
materials) computed once, on first use. :class:`ContactBodies` knows, for every contact of a frame, which material
each side is made of, without a per-contact lookup where it can avoid one: a
single-material scene has scalars, a multi-material scene codes every
contact by its pair of types (``type1 * n_types + type2``) and evaluates
moduli and shares once per pair present. :class:`LawRows` is the view of
these contacts that a contact law gets (:class:`demsplit.physics.laws.ContactRows`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np

from ..errors import ContactError, InputFormatError
from ..frame import ParticleIndex, Table, table_length
from ..scene import Scene
from .moduli import reduced_mass


class FrameContacts:
    """One frame's contacts (``contacts``, a table of :mod:`demsplit.frame`), the ``scene`` and the frame's
    ``particles`` (None where the contacts carry their bodies' types and no stage needs a particle column),
    with what the stages derive from them computed once: :attr:`index`, :attr:`rows`, :attr:`bodies`.
    ``index`` may be given when the caller has built it already."""

    def __init__(
        self, contacts: Table, scene: Scene, particles: Table | None = None, index: ParticleIndex | None = None
    ) -> None:
        self.contacts, self.scene, self.particles = contacts, scene, particles
        if index is not None:
            self.index = index

    @cached_property
    def index(self) -> ParticleIndex:
        """Row of every particle id (:class:`demsplit.frame.ParticleIndex`)."""
        if self.particles is None:
            raise InputFormatError(
                "contacts carry no material types and no particles table was given.",
                fix="pass the frame's particles so types can be looked up by id.",
            )
        return ParticleIndex(self.particles["id"])

    @cached_property
    def rows(self) -> tuple[np.ndarray, np.ndarray]:
        """The particle row of body 1 and of body 2 of every contact (body 2 of a wall contact: ``-1 - wall``,
        :meth:`demsplit.frame.ParticleIndex.contact_rows`)."""
        c = self.contacts
        return self.index.contact_rows(c["id1"], c["id2"], c["wall"])

    @cached_property
    def bodies(self) -> ContactBodies:
        """Material types and elastic constants of both bodies of every contact."""
        return ContactBodies.build(self)

    def __len__(self) -> int:
        return table_length(self.contacts)

    def types(self) -> tuple[np.ndarray, np.ndarray]:
        """The material types of body 1 and body 2 of every contact (a wall: its type), single material or not."""
        type1, type2 = self.bodies.type1, self.bodies.type2
        if type1 is None:  # a single-material scene: the types were not needed until now
            type1, type2, pairs = _contact_pairs(self)
            if type1 is None:
                type1, type2 = _types_of_codes(pairs[0], self.scene)
        return type1, type2

    def without(self, columns: Sequence[str]) -> None:
        """Drop contact ``columns`` nothing later reads (the caller's table keeps them: a new dict)."""
        self.contacts = {c: v for c, v in self.contacts.items() if c not in columns}


class ContactBodies:
    """Material types and elastic constants of both sides of every contact.

    In a single-material scene ``E1 nu1 E2 nu2`` are scalars and no per-contact
    lookup is made. Built from a multi-material scene, the per-contact constants
    ``E1 nu1 E2 nu2`` are gathered from the scene's tables on first use (the
    partition itself works from the types, once per pair of types).
    """

    def __init__(
        self,
        type1: np.ndarray | None,
        type2: np.ndarray | None,
        E1: np.ndarray | float | None,
        nu1: np.ndarray | float | None,
        E2: np.ndarray | float | None,
        nu2: np.ndarray | float | None,
        single_material: bool,
        scene: Scene | None = None,
        *,
        pairs: tuple | None = None,
    ) -> None:
        self._types = (type1, type2)
        self._constants = (E1, nu1, E2, nu2)
        self.single_material = single_material
        self.scene = scene
        self._pairs = pairs  # (code of every contact, codes present), see _pair_codes

    @classmethod
    def build(cls, frame: FrameContacts) -> ContactBodies:
        """The bodies of ``frame``'s contacts: scalars in a single-material scene, else their types (the
        contacts' ``type1 type2``, or gathered from the particles and the walls), checked against the
        scene's materials once per pair of types present."""
        scene = frame.scene
        if scene.single_material:
            m = next(iter(scene.materials.values()))
            return cls(None, None, m.E, m.nu, m.E, m.nu, True, scene)
        type1, type2, pairs = _contact_pairs(frame)
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

    def constants(self, lo: int, hi: int) -> tuple:
        """``(E1, nu1, E2, nu2)`` of contacts ``lo:hi`` (Pa, -, Pa, -): scalars in a single-material
        scene, else arrays of that range gathered from the types, without building the frame's
        per-contact arrays (4 float64 per contact) that the properties keep once asked for. Safe to call
        from several threads on disjoint ranges."""
        if self._constants[0] is not None or self.scene is None:
            return tuple(v[lo:hi] if np.ndim(v) else v for v in self._constants)
        E, nu = self.scene.material_tables()
        if self._types[0] is not None:
            t1, t2 = self._types[0][lo:hi], self._types[1][lo:hi]
        else:
            t1, t2 = _types_of_codes(self._pairs[0][lo:hi], self.scene)
        return E.take(t1), nu.take(t1), E.take(t2), nu.take(t2)

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
        from ..kernels import NO_CODE

        if self.single_material or self.scene is None:
            return np.atleast_1d(np.asarray(f(self.E1, self.nu1, self.E2, self.nu2), dtype=np.float64)), NO_CODE
        E, nu = self.scene.material_tables()
        n_types = len(E)
        code, pairs = self._pair_codes()
        t1, t2 = pairs // n_types, pairs % n_types
        table = np.zeros(n_types * n_types)
        table[pairs] = f(E[t1], nu[t1], E[t2], nu[t2])
        return table, code


def _types_of_codes(code: np.ndarray, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(type1, type2) of pair codes type1 * n_types + type2."""
    n_types = len(scene.material_tables()[0])
    code = code.astype(np.int64)
    return code // n_types, code % n_types


def _code_dtype(n_types: int) -> type:
    """Smallest integer type for the codes 0..n_types^2 - 1 (less to read per contact)."""
    return np.int8 if n_types**2 <= 127 else np.int16 if n_types**2 <= 32767 else np.int64


def _contact_pairs(frame: FrameContacts) -> tuple[np.ndarray | None, np.ndarray | None, tuple | None]:
    """The bodies' material types as ``(type1, type2, None)`` when the contacts carry
    them, else ``(None, None, (pair code of every contact, codes present))``."""
    contacts, scene, particles = frame.contacts, frame.scene, frame.particles
    if "type1" in contacts and "type2" in contacts:
        return contacts["type1"].astype(np.int64), contacts["type2"].astype(np.int64), None
    from ..kernels import contact_types as gather_types  # compiled: see the module docstring

    wall = contacts["wall"]
    rows1, rows2 = frame.rows
    wall_types = scene.wall_types()
    n_types = len(scene.material_tables()[0])
    ptype = np.asarray(particles["type"])
    code = np.empty(len(rows1), dtype=_code_dtype(n_types))
    present, bad_wall, bad_type = gather_types(rows1, rows2, ptype, wall_types, n_types, code)
    if bad_wall >= 0:
        raise ContactError(
            f"a wall contact names wall {int(wall.max())} but the scene has {len(wall_types)} wall(s).",
            fix="describe every wall of the run in the scene (input script).",
        )
    if bad_type >= 0:  # a type outside the material table: the lookup's error lists them
        scene.lookup(ptype[rows1], what="particle")
        pair = rows2 >= 0
        scene.lookup(ptype[rows2[pair]], what="particle")
        scene.lookup(wall_types[-1 - rows2[~pair]], what="wall")
    return None, None, (code, np.flatnonzero(present))


class LawRows:
    """The contacts ``rows`` (a slice or an index array) of a frame, as a contact law sees them
    (:class:`demsplit.physics.laws.ContactRows`): float64 columns of those rows, moduli per pair of
    types, reduced masses. ``law`` (its key) names the law in the errors of missing columns."""

    def __init__(self, frame: FrameContacts, rows: slice | np.ndarray, law: str) -> None:
        self.frame, self.rows, self.law = frame, rows, law
        self.contacts, self.bodies, self.particles = frame.contacts, frame.bodies, frame.particles
        self.delta = self.column("delta")
        self.r1 = self.column("r1")
        self.r2 = self.column("r2")

    def has(self, *names: str) -> bool:
        return all(c in self.contacts for c in names)

    def column(self, name: str) -> np.ndarray:
        if name not in self.contacts:
            raise InputFormatError(
                f"the contact law {self.law} needs the contact column {name!r}, which the input does not have.",
                fix="dump it (see the reader's documentation for the column) or describe the model explicitly.",
            )
        return np.asarray(self.contacts[name], dtype=np.float64)[self.rows]

    def per_pair(self, rule) -> np.ndarray | float:
        values = self.bodies.per_pair(rule)
        return values if np.ndim(values) == 0 else values[self.rows]

    def pair_values(self, rule) -> tuple[np.ndarray, np.ndarray]:
        values, code = self.bodies.pair_values(rule)
        if len(code):
            return values, code[self.rows]
        return (values[self.rows] if len(values) > 1 else values), code

    def type_pair(self, table: Sequence[Sequence[float]]) -> np.ndarray | float:
        """A per-type-pair property (``table[t1 - 1][t2 - 1]``, LIGGGHTS ``peratomtypepair``, types from 1)
        of every row; a scalar when the table holds one value."""
        values = np.asarray(table, dtype=np.float64)
        if np.all(values == values.flat[0]):
            return float(values.flat[0])
        type1, type2 = self.frame.types()
        t1, t2 = np.asarray(type1)[self.rows], np.asarray(type2)[self.rows]
        n = len(values)
        if np.any((t1 < 1) | (t1 > n) | (t2 < 1) | (t2 > n)):
            raise InputFormatError(
                f"the contact law {self.law} has a per-type-pair table for types 1..{n}, "
                f"but contacts have types {sorted(set(np.concatenate([t1, t2]).tolist()))}.",
                fix="give the property one value per pair of atom types, wall types included.",
            )
        return values[t1 - 1, t2 - 1]

    def reduced_mass(self) -> np.ndarray:
        c, rows = self.contacts, self.rows
        if "m1" in c and "m2" in c:
            return reduced_mass(c["m1"][rows], c["m2"][rows])
        m1, m2 = self.particle_column("mass")
        return reduced_mass(m1, np.where(c["wall"][rows] < 0, m2, np.inf))

    def particle_column(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        if self.particles is None or name not in self.particles:
            raise InputFormatError(
                f"the contact law {self.law} needs the particle column {name!r}, which the atom dump does not have.",
                fix=f"add '{name}' to the dump custom columns.",
            )
        c, rows = self.contacts, self.rows
        index = self.frame.index
        values = np.asarray(self.particles[name], dtype=np.float64)
        v1 = values[index.rows(c["id1"][rows])]
        v2 = np.full_like(v1, np.nan)
        pair = c["wall"][rows] < 0
        v2[pair] = values[index.rows(c["id2"][rows][pair])]
        return v1, v2
