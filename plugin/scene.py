"""What a run is made of: materials, contact model, walls.

A :class:`Scene` is built from the LIGGGHTS input script
(:func:`demsplit.readers.liggghts_script.read_script`), from a YADE snapshot's
metadata, or given explicitly. Materials are keyed by an integer *type*: the
LIGGGHTS atom type (walls use their ``type T``), or the YADE material id.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from .errors import MaterialError, UnsupportedModelError
from .physics import laws


@dataclass(frozen=True)
class Material:
    """Elastic constants of one material.

    E : Young's modulus (Pa); ``math.inf`` makes the body rigid.
    nu : Poisson's ratio, -1 < nu <= 0.5.
    name : the simulator's name of the material (YADE's material label), shown by the report; not
        part of the comparison.
    """

    E: float
    nu: float
    name: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not (self.E > 0):  # also rejects NaN
            raise MaterialError(
                f"Young's modulus must be > 0 (or inf for a rigid body), got E = {self.E!r}.",
                fix="correct youngsModulus in the input script or the --material option.",
            )
        if not (-1.0 < self.nu <= 0.5):
            raise MaterialError(
                f"Poisson's ratio must lie in (-1, 0.5], got nu = {self.nu!r}.",
                fix="correct poissonsRatio in the input script or the --material option.",
            )


@dataclass(frozen=True)
class ContactModel:
    """The contact law the run used: its registry key and its parameters.

    ``law`` is a key of the law registry (:mod:`demsplit.physics.laws`), the
    simulator's own name: ``liggghts:hertz``, ``liggghts:hooke``,
    ``yade:Law2_ScGeom_MindlinPhys_Mindlin``, ... ``params`` are the law's
    parameters (e.g. ``tangential``, ``characteristic_velocity`` (m/s)); the
    defaults the law declares are filled in, so two models of the same law
    compare equal whether a default was written or not. An unknown key or
    parameter is an :class:`~demsplit.errors.UnsupportedModelError` that lists
    what is supported.
    """

    law: str = laws.DEFAULT
    params: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        contact_law = laws.make(self.law, self.params)
        object.__setattr__(self, "params", dict(contact_law.params))
        object.__setattr__(self, "_contact_law", contact_law)

    @property
    def contact_law(self) -> laws.ContactLaw:
        """The law itself (:class:`demsplit.physics.laws.ContactLaw`), which computes the energies."""
        return self._contact_law

    def describe(self) -> str:
        """One line: the law, its parameters and what it computes."""
        return self.contact_law.describe()


UNITS = ("si", "lj")
"""A scene's units: SI, or LAMMPS' ``lj`` (mass, length and time of the run's own scales; energies in m sigma^2/tau^2),
which demsplit computes in as given and labels as such."""

WALL_KINDS = ("plane", "cylinder", "mesh", "yade_wall", "facet", "box")


@dataclass(frozen=True)
class Wall:
    """A body that is not a particle.

    kind : ``plane`` and ``cylinder`` (LIGGGHTS primitive walls, rebuilt from
        positions), ``mesh`` (LIGGGHTS mesh, contacts from the wall dump),
        ``yade_wall``, ``facet``, ``box`` (YADE bodies).
    type : material type of the wall.
    axis : 0, 1, 2 for x, y, z (plane normal, cylinder axis).
    position : plane coordinate along ``axis`` (m).
    radius : cylinder radius (m).
    center : cylinder centre in the two other axes, in LIGGGHTS's cyclic order
        (x: (y, z); y: (z, x); z: (x, y)) (m).
    model : the wall's own contact model when it differs from the pair model.
    file : mesh file of a ``mesh`` wall (LIGGGHTS ``fix mesh/surface file``).
    transforms : the mesh's ``scale``/``move``/``rotate`` operations in the
        order LIGGGHTS applies them (the order they appear on the fix line):
        ``("scale", (s,))``, ``("move", (dx, dy, dz))`` (m),
        ``("rotate", (ax, ay, az, angle_deg))``.
    missing : why the run's files do not hold this wall's contacts though the
        simulator could have written them, and how to write them (empty: they are
        there). A run with such a wall is refused unless the user lets it go on
        without it (``--allow-missing NAME``); its energy is then "not computed".
    """

    name: str
    kind: str
    type: int
    axis: int = 2
    position: float = 0.0
    radius: float = 0.0
    center: tuple[float, float] = (0.0, 0.0)
    model: ContactModel | None = None
    file: str | None = None
    transforms: tuple[tuple[str, tuple[float, ...]], ...] = ()
    missing: str = ""


@dataclass
class Scene:
    """Materials per type, the contact model and the walls of a run (``units``: :data:`UNITS`).

    ``pair_models``: the model of each pair of particle types ``(t1, t2)`` (t1 <= t2) whose model is not
    ``model`` (LAMMPS ``pair_coeff i j`` lines give each type pair its own); empty when one model acts on
    every pair of particles."""

    materials: dict[int, Material]
    model: ContactModel = field(default_factory=ContactModel)
    walls: list[Wall] = field(default_factory=list)
    units: str = "si"
    source: str = ""
    pair_models: dict[tuple[int, int], ContactModel] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.units not in UNITS:
            raise UnsupportedModelError(
                f"units {self.units!r} are not supported; demsplit works in SI (or in LAMMPS' lj units, as given).",
                fix="run the simulation with 'units si'.",
            )
        self._table_cache: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def single_material(self) -> bool:
        """True when every type (walls included) has the same E and nu, so
        every share is exactly 1/2 and no per-contact lookup is needed. A wall
        whose type has no material makes it False: the lookup then names it,
        instead of the wall getting the particles' half."""
        return len(set(self.materials.values())) == 1 and all(w.type in self.materials for w in self.walls)

    def material_tables(self) -> tuple[np.ndarray, np.ndarray]:
        """Dense lookup tables ``E[type]``, ``nu[type]`` (NaN where no material)."""
        if self._table_cache is None:
            n = max(self.materials, default=-1) + 1
            E = np.full(n, np.nan)
            nu = np.full(n, np.nan)
            for t, m in self.materials.items():
                if t < 0:
                    raise MaterialError(f"material type must be >= 0, got {t}.")
                E[t], nu[t] = m.E, m.nu
            self._table_cache = (E, nu)
        return self._table_cache

    def lookup(self, types: np.ndarray, *, what: str = "particle") -> tuple[np.ndarray, np.ndarray]:
        """E (Pa) and nu for each entry of ``types``; a type with no material is
        a :class:`MaterialError` that lists the missing types."""
        E_tab, nu_tab = self.material_tables()
        types = np.asarray(types, dtype=np.int64)
        inside = (types >= 0) & (types < len(E_tab))
        bad = ~inside
        if inside.any():
            bad[inside] = np.isnan(E_tab[types[inside]])
        if bad.any():
            missing = sorted(set(np.unique(types[bad]).tolist()))
            raise MaterialError(
                f"{what} type(s) {missing} have no material "
                f"(materials are defined for types {sorted(self.materials)}).",
                fix="define youngsModulus and poissonsRatio for every type in the input script, "
                "or pass --material TYPE:E:NU.",
            )
        return E_tab[types], nu_tab[types]

    def wall_types(self) -> np.ndarray:
        """Material type of each wall, indexed like ``walls``."""
        return np.array([w.type for w in self.walls], dtype=np.int64)

    def pair_model(self, t1: int, t2: int) -> ContactModel:
        """The model of contacts between particles of types ``t1`` and ``t2``."""
        return self.pair_models.get((min(t1, t2), max(t1, t2)), self.model)

    def models(self) -> list[ContactModel]:
        """Every model of the scene, once each: the pair model(s), then the walls' own."""
        out: list[ContactModel] = []
        for m in [self.model, *self.pair_models.values(), *(w.model for w in self.walls if w.model is not None)]:
            if m not in out:
                out.append(m)
        return out


def scene_to_dict(scene: Scene) -> dict:
    """The scene as plain JSON-ready data: ``materials`` (type -> E, nu, and name when it has one),
    ``model``, ``walls`` (every field), ``units``, ``source``, and ``pair_models`` (``"t1 t2"`` -> model)
    when the scene has them."""
    out = {
        "materials": {
            str(t): {k: v for k, v in asdict(m).items() if k != "name" or v} for t, m in sorted(scene.materials.items())
        },
        "model": asdict(scene.model),
        "walls": [asdict(w) for w in scene.walls],
        "units": scene.units,
        "source": scene.source,
    }
    if scene.pair_models:
        out["pair_models"] = {f"{t1} {t2}": asdict(m) for (t1, t2), m in sorted(scene.pair_models.items())}
    return out


def scene_from_dict(d: dict) -> Scene:
    """Inverse of :func:`scene_to_dict` (e.g. after a JSON round trip)."""

    def wall(w: dict) -> Wall:
        w = dict(w)
        w["center"] = tuple(w["center"])
        w["transforms"] = tuple((op, tuple(args)) for op, args in w["transforms"])
        w["model"] = None if w["model"] is None else ContactModel(**w["model"])
        return Wall(**w)

    pairs = {tuple(int(t) for t in key.split()): ContactModel(**m) for key, m in d.get("pair_models", {}).items()}
    return Scene(
        {int(t): Material(**m) for t, m in d["materials"].items()},
        ContactModel(**d["model"]),
        [wall(w) for w in d["walls"]],
        d["units"],
        d["source"],
        pairs,
    )
