"""The partition: every contact's elastic energy by its own law, split between its two bodies, summed per body.

:func:`contact_energies` groups the contacts by the law that acts on them
(the scene's law, or a wall's own law) and asks each law for the energy of
every mode it has (:mod:`demsplit.physics.laws`); :func:`partition` gives each
body its share of every mode by that mode's rule
(:mod:`demsplit.physics.modes`) and places the contact point;
:func:`per_particle` sums per particle and per wall. Energies are arrays of
shape (modes, contacts), row m the mode ``modes[m]`` of the scene (:func:`~demsplit.physics.modes.scene_modes`).

    u1 = sum_m s_m u_m,  u2 = sum_m (1 - s_m) u_m,  depth1 = s_n delta,  x_c = x1 + (r1 - depth1) n.

The per-contact work runs in compiled loops (:mod:`demsplit.kernels`, imported
when first needed, so ``import demsplit`` needs no numba); per-body sums add
each body's contributions in contact order, body-1 terms then body-2 terms.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ContactError
from ..frame import Table, table_length
from ..scene import ContactModel, Scene
from .bodies import FrameContacts, LawRows
from .modes import ADHESION_COLUMN, ADHESION_SHARE, ALWAYS, NOT_COMPUTED_BITS, Mode, scene_modes
from .shares import SPLITS, radius_share, springs_share


class _ByMode:
    """Attribute access to the rows of ``u`` (and ``shares``) by mode column: ``x.u_n``, ``x.share_t1``."""

    u: np.ndarray
    modes: tuple[Mode, ...]

    def __getattr__(self, name: str) -> np.ndarray:
        modes = self.__dict__.get("modes", ())
        for k, m in enumerate(modes):
            if name == m.column:
                return self.__dict__["u"][k]
            if name == m.share_column and "shares" in self.__dict__:
                return self.__dict__["shares"][k]
        raise AttributeError(f"{type(self).__name__!r} has no attribute {name!r}")


@dataclass
class ContactLawEnergy(_ByMode):
    """Elastic energy of every mode of every contact under the run's own law(s) (J), shape (modes, n),
    row k the mode ``modes[k]`` (also as ``u_n``, ``u_t``, ...); ``u_adh``: the cohesion work of
    every contact (J, signed), or None when no law of the scene has cohesion; ``skipped``: the modes
    a law does not have (0 is their true value), with why; ``missing``: the modes a law has but could
    not compute from the data given (their columns were not dumped), with why; ``not_computed``: per
    contact, the bits (:data:`~demsplit.physics.modes.NOT_COMPUTED_BITS`) of the modes whose value is
    unknown (``missing`` modes, and history-dependent modes of contacts whose history the simulator
    never wrote, flagged by the reader with the bits of those modes in the contact column ``history_unknown``;
    0: known). A law may
    decide itself which of its rows are unknown (``LawEnergy.unknown``), e.g. a liquid bridge apart from a
    primitive wall, whose state LIGGGHTS never writes, while the same contact touching holds one for certain.
    An unknown value is 0 in ``u`` and ``u_adh``, never an estimate."""

    u: np.ndarray
    skipped: dict[str, str] = field(default_factory=dict)
    modes: tuple[Mode, ...] = ALWAYS
    u_adh: np.ndarray | None = None
    missing: dict[str, str] = field(default_factory=dict)
    not_computed: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.not_computed is None:  # every value known
            self.not_computed = np.zeros(self.u.shape[-1], dtype=np.int32)


@dataclass
class ContactEnergy(_ByMode):
    """Per-contact results of :func:`partition`.

    ``u`` (J) and ``shares`` (fraction to body 1): shape (modes, n), row k the
    mode ``modes[k]``, also as ``u_n u_t`` and ``share_n1 share_t1``; ``u_adh``:
    cohesion work (J, signed; None without cohesion); ``u1``, ``u2`` (J): elastic energy of each
    body; ``depth1`` (m): approach of body 1; ``cp`` (m, shape (n, 3), stored by
    coordinate: ``cp[:, 0]`` is contiguous): contact point; ``separated``:
    contacts with delta < 0 (zero energy, kept and flagged); ``skipped``:
    quantities not computed and why; ``not_computed``: per contact, the bits of its unknown modes
    (:class:`ContactLawEnergy`).
    """

    u: np.ndarray
    shares: np.ndarray
    u1: np.ndarray
    u2: np.ndarray
    depth1: np.ndarray
    cp: np.ndarray
    separated: np.ndarray
    split: str = "material"
    skipped: dict[str, str] = field(default_factory=dict)
    modes: tuple[Mode, ...] = ALWAYS
    u_adh: np.ndarray | None = None
    missing: dict[str, str] = field(default_factory=dict)
    not_computed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))

    def table(self) -> Table:
        """The per-contact columns as a table: every mode's energy and share, ``u_adh`` when the scene
        has cohesion, ``u1 u2 depth1 cpx cpy cpz``, ``not_computed``."""
        out = {m.column: self.u[k] for k, m in enumerate(self.modes)}
        if self.u_adh is not None:
            out[ADHESION_COLUMN] = self.u_adh
        out.update({m.share_column: self.shares[k] for k, m in enumerate(self.modes)})
        out.update(u1=self.u1, u2=self.u2, depth1=self.depth1, cpx=self.cp[:, 0], cpy=self.cp[:, 1], cpz=self.cp[:, 2])
        out["not_computed"] = self.not_computed
        return out


def law_groups(
    contacts: Table, scene: Scene, types: tuple[np.ndarray, np.ndarray] | None = None
) -> list[tuple[ContactModel, slice | np.ndarray]]:
    """Rows of the contacts each law acts on: the scene's law, a wall's own law where it differs (LIGGGHTS
    ``fix wall/gran`` with another model), and the law of each pair of particle types that has its own
    (``Scene.pair_models``: then ``types``, the material types of body 1 and body 2 of every contact, are
    needed)."""
    wall = contacts["wall"]
    groups: list[tuple[ContactModel, np.ndarray]] = []
    default = np.ones(len(wall), dtype=bool)

    def add(model: ContactModel, mask: np.ndarray) -> None:
        nonlocal default
        default &= ~mask
        for known, other in groups:
            if known == model:
                other |= mask
                return
        groups.append((model, mask))

    for i, w in enumerate(scene.walls):
        if w.model is not None and w.model != scene.model:
            add(w.model, wall == i)
    if scene.pair_models and len(wall):
        t1, t2 = (np.asarray(t, dtype=np.int64) for t in types)
        lo, hi = np.minimum(t1, t2), np.maximum(t1, t2)
        for (a, b), model in scene.pair_models.items():
            if model != scene.model:
                add(model, (wall < 0) & (lo == a) & (hi == b))
    groups.append((scene.model, default))
    if len(groups) == 1:  # one law for every contact: a slice, so that x[rows] is a view, not a copy
        return [(scene.model, slice(None))] if len(wall) else []
    return [(m, np.flatnonzero(mask)) for m, mask in groups if mask.any()]


def contact_energies(
    contacts: Table, scene: Scene, particles: Table | None = None, *, compiled: bool = True
) -> ContactLawEnergy:
    """:func:`law_energies` of a contact table, its scene and its particles."""
    return law_energies(FrameContacts(contacts, scene, particles), compiled=compiled)


def law_energies(frame: FrameContacts, *, compiled: bool = True) -> ContactLawEnergy:
    """Elastic energy of every mode of every contact with the run's own law(s) (J), shape (modes, n).

    Each law computes the modes it has from the columns it declares
    (:mod:`demsplit.physics.laws`); a mode a law does not have is 0 and named in ``skipped`` with the
    reason; a mode it has but cannot compute from the columns given (its ``LawEnergy.skipped``) is 0 with
    the not-computed bit and named in ``missing``. Damping and friction work are never counted.
    """
    contacts, scene = frame.contacts, frame.scene
    n = len(frame)
    _refuse_rigid_pairs(frame)
    types = frame.types() if scene.pair_models else None
    models = scene.models()
    by_model = law_groups(contacts, scene, types)
    # every law of the scene, also one without a contact in this frame (rows: none), so that what its columns
    # lack is known from the first frame on, before particles touch (a run that inserts them): a refusal then
    # comes before any frame is stored, and every frame says the same
    for model in models:
        if not any(model == m for m, _ in by_model):
            by_model.append((model, np.empty(0, dtype=np.intp)))
    groups = [(model.contact_law, rows) for model, rows in by_model]
    # the modes of every law of the scene, whether or not this frame has contacts it acts on: every frame
    # of a run has the same columns (a frame without contacts had only u_n and u_t)
    laws = [model.contact_law for model in models]
    modes = scene_modes(c for law in laws for c in law.modes)
    u = np.zeros((len(modes), n))
    with_adhesion = any(ADHESION_COLUMN in law.modes for law in laws)
    u_adh = np.zeros(n) if with_adhesion else None
    skipped: dict[str, str] = {}
    missing: dict[str, str] = {}
    # the bits of the modes whose history the simulator never wrote, per contact
    unknown = np.asarray(contacts["history_unknown"]).astype(np.int32) if "history_unknown" in contacts else None
    not_computed = np.zeros(n, dtype=np.int32)
    several = any(m != scene.model for m in models)  # a wall with a law of its own: say whose law lacks a mode
    for (model, _), (law, rows) in zip(by_model, groups):
        result = law.energies(LawRows(frame, rows, law.key), compiled=compiled)
        whose = f" of {_served(model, scene)}" if several else ""
        for k, mode in enumerate(modes):
            if mode.column in result.modes:
                u[k, rows] = result.modes[mode.column]
            elif mode.column not in result.skipped:
                skipped.setdefault(
                    mode.column,
                    f"the contact law {law.key}{whose} has no {mode.name} energy (0 for "
                    f"{'these' if several else 'its'} contacts)",
                )
        if u_adh is not None:
            if ADHESION_COLUMN in result.modes:
                u_adh[rows] = result.modes[ADHESION_COLUMN]
            elif ADHESION_COLUMN not in result.skipped:
                others = _with_mode(models, laws, scene, ADHESION_COLUMN) if several else ""
                skipped.setdefault(
                    ADHESION_COLUMN,
                    f"the contact law {law.key}{whose} has no cohesion (0 for "
                    f"{'these' if several else 'its'} contacts)"
                    + (f"; the cohesion of {others} is computed" if others else ""),
                )
        missing.update(result.skipped)  # modes the law has, whose columns the data lacks
        bits = sum(NOT_COMPUTED_BITS[m] for m in result.skipped)
        bits_without_history = sum(
            NOT_COMPUTED_BITS[m] for m in law.mode_columns if m not in result.skipped and m not in result.unknown
        )
        decided = {m: mask for m, mask in result.unknown.items() if mask.any()}  # rows the law itself says are unknown
        for m, why in result.unknown_why.items():  # every law's reason, once
            if m in decided and why not in missing.get(m, ""):
                missing[m] = f"{missing[m]}; {why}" if m in missing else why
        if bits or decided or (unknown is not None and bits_without_history):
            not_computed[rows] |= bits
            if unknown is not None and bits_without_history:
                not_computed[rows] |= unknown[rows] & np.int32(bits_without_history)
            for m, mask in decided.items():
                not_computed[rows] |= np.where(mask, NOT_COMPUTED_BITS[m], 0).astype(np.int32)
    if not_computed.any():  # an unknown value is 0 with its bit, never what the law made of no data
        for k, mode in enumerate(modes):
            u[k][(not_computed & NOT_COMPUTED_BITS[mode.column]) != 0] = 0.0
        if u_adh is not None:
            u_adh[(not_computed & NOT_COMPUTED_BITS[ADHESION_COLUMN]) != 0] = 0.0
    return ContactLawEnergy(u, skipped, modes, u_adh, missing, not_computed)


def _served(model, scene: Scene) -> str:
    """Which contacts ``model`` acts on, for a message: the walls whose own law it is, or the particle pairs
    (and the walls without a law of their own) for the scene's law."""
    own = [w.name for w in scene.walls if w.model is not None and w.model == model and model != scene.model]
    if own:
        return f"wall{'s' if len(own) > 1 else ''} {', '.join(repr(n) for n in own)}"
    rest = [w.name for w in scene.walls if w.model is None or w.model == scene.model]
    return "the particle pairs" + (
        f" and wall{'s' if len(rest) > 1 else ''} {', '.join(map(repr, rest))}" if rest else ""
    )


def _with_mode(models, laws, scene: Scene, column: str) -> str:
    """The contacts whose law has the mode ``column`` (:func:`_served`), for a message; ``models`` and
    ``laws``: the scene's law then the walls' own, as :func:`law_energies` lists them."""
    served = dict.fromkeys(_served(m, scene) for m, law in zip(models, laws) if column in law.modes)
    return " and ".join(served)


def _refuse_rigid_pairs(frame: FrameContacts) -> None:
    """A contact between two rigid bodies (E = inf both) is an error: neither can store energy."""
    contacts = frame.contacts
    rigid_pair = np.broadcast_to(frame.bodies.rigid_pairs(), (len(frame),))
    if rigid_pair.any():
        i = int(np.flatnonzero(rigid_pair)[0])
        raise ContactError(
            f"{int(np.count_nonzero(rigid_pair))} contact(s) between two rigid bodies, e.g. "
            f"id1={int(contacts['id1'][i])}, id2={int(contacts['id2'][i])}, wall={int(contacts['wall'][i])}: "
            "neither body can store elastic energy.",
            fix="give one of the two materials a finite Young's modulus.",
        )


def _per_contact(x: ArrayLike) -> np.ndarray:
    """Per-contact values for a compiled loop as one row: the array itself, or its one value
    (length 1) when it is a constant broadcast to every contact."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1 and len(x) and x.strides[0] == 0:
        x = x[:1]
    return np.ascontiguousarray(np.atleast_1d(x))[None, :]


def comparison_shares(frame: FrameContacts, split: str) -> np.ndarray:
    """Share of body 1 under a comparison split, the same for every mode (shape (1, n) or (1, 1)):
    ``equal`` 1/2, ``radius`` r1/(r1 + r2), ``springs`` the series springs k_i = E_i r_i (see
    :data:`~demsplit.physics.shares.SPLITS`)."""
    contacts, bodies = frame.contacts, frame.bodies
    if split == "equal":
        return np.full((1, 1), 0.5)
    if split == "radius":
        return _per_contact(radius_share(contacts["r1"], contacts["r2"]))
    if split == "springs":
        n = table_length(contacts)
        return _per_contact(np.broadcast_to(springs_share(bodies.E1, contacts["r1"], bodies.E2, contacts["r2"]), (n,)))
    raise ValueError(f"unknown split {split!r}; use one of {SPLITS}")


def _material_shares(bodies, n: int, tangential_rule: str, modes: tuple[Mode, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Shares of body 1 of every mode under the material law, as ``(values, code)`` for the loops:
    one value per pair of types present (coded) in a multi-material scene, 1/2 in a single-material one."""
    from ..kernels import NO_CODE

    if bodies.single_material:
        return np.full((1, 1), 0.5), NO_CODE
    rows = [bodies.pair_values(mode.rule(tangential_rule)) for mode in modes]
    code = rows[0][1]
    if len(code):
        return np.stack([values for values, _ in rows]), code
    return np.concatenate(
        [_per_contact(np.broadcast_to(values, (n,)) if len(values) == 1 else values) for values, _ in rows]
    ), NO_CODE


def partition(
    contacts: Table,
    scene: Scene,
    particles: Table | None = None,
    *,
    split: str = "material",
    tangential_rule: str = "mindlin",
) -> ContactEnergy:
    """:func:`split_energies` of a contact table's :func:`law_energies`, with its scene and its particles."""
    frame = FrameContacts(contacts, scene, particles)
    return split_energies(frame, law_energies(frame), split=split, tangential_rule=tangential_rule)


def split_energies(
    frame: FrameContacts,
    energies: ContactLawEnergy,
    *,
    split: str = "material",
    tangential_rule: str = "mindlin",
    normal_shares: np.ndarray | None = None,
) -> ContactEnergy:
    """Split every contact's elastic energy between its two bodies and place the contact point.

    u1 = sum_m s_m u_m,  u2 = sum_m (1 - s_m) u_m,  depth1 = s_n delta,  x_c = x1 + (r1 - depth1) n,

    with s_m the share of body 1 of mode m under ``split`` (the material law:
    each mode's own rule; the comparison splits: one share for every mode) and
    ``energies`` the contacts' :func:`law_energies`. ``normal_shares`` (material
    split only): body 1's share of the normal mode per contact, replacing the law's c1/(c1 + c2) (the
    finite-body correction, :func:`~demsplit.physics.accuracy.corrected_share`); it also places the
    contact point.
    """
    contacts, bodies = frame.contacts, frame.bodies
    n = len(frame)
    from ..kernels import NO_CODE, split_contacts  # compiled: see the module docstring

    if split == "material":
        values, code = _material_shares(bodies, n, tangential_rule, energies.modes)
        if normal_shares is not None:  # one share per contact and mode: gather the coded or constant ones
            full = values[:, code] if len(code) else np.repeat(values, n, axis=1) if values.shape[1] == 1 else values
            full = np.array(np.repeat(full, len(energies.modes), axis=0) if len(full) == 1 else full, dtype=np.float64)
            full[0] = normal_shares
            values, code = full, NO_CODE
    else:
        values, code = comparison_shares(frame, split), NO_CODE
    delta = np.asarray(contacts["delta"], dtype=np.float64)
    shares, u1, u2, depth1, cp = split_contacts(
        values,
        code,
        energies.u,
        delta,
        *(np.asarray(contacts[c], dtype=np.float64) for c in ("x1", "y1", "z1", "nx", "ny", "nz", "r1")),
    )
    return ContactEnergy(
        energies.u,
        shares,
        u1,
        u2,
        depth1,
        cp.T,
        delta < 0,
        split,
        dict(energies.skipped),
        energies.modes,
        energies.u_adh,
        dict(energies.missing),
        energies.not_computed,
    )


def per_particle(contacts: Table, energy: ContactEnergy, particles: Table, n_walls: int = 0) -> tuple[Table, Table]:
    """:func:`body_tables` of a contact table and its particles."""
    return body_tables(FrameContacts(contacts, None, particles), energy, n_walls)


def body_tables(frame: FrameContacts, energy: ContactEnergy, n_walls: int = 0) -> tuple[Table, Table]:
    """Sum each body's energy over its contacts (one compiled pass, :func:`demsplit.kernels.body_sums`).

    Returns ``(particle_table, wall_table)``: per particle ``id type x y z radius u``,
    the energy of every mode (J), ``u_adh`` with cohesion, ``n_contacts``, ``not_computed`` (the bits of
    the modes any of its contacts could not give) and ``n_not_computed`` (those contacts), in the
    particles' row order; per wall ``wall u``, every mode, ``u_adh``, ``n_contacts``, ``not_computed``,
    ``n_not_computed``. ``u`` is the sum of the elastic modes, each the known part where a contact's
    value is not computed; ``u_adh`` gets half of each contact's cohesion work. Conservation: sum of
    particle u + sum of wall u = sum over contacts of every mode, to rounding.
    """
    from ..kernels import body_sums, max_wall  # compiled: see the module docstring

    particles = frame.particles
    rows1, rows2 = frame.rows
    n_walls = max(n_walls, int(max_wall(rows2)) + 1)
    pu, n_contacts, wu, w_contacts = body_sums(rows1, rows2, energy.shares, energy.u, table_length(particles), n_walls)
    columns = [m.column for m in energy.modes]
    ptable = {
        "id": np.asarray(particles["id"], dtype=np.int64),
        "type": np.asarray(particles["type"], dtype=np.int32),
        **{c: np.asarray(particles[c], dtype=np.float64) for c in ("x", "y", "z", "radius")},
        "u": _total(pu),
        **dict(zip(columns, pu)),
        "n_contacts": n_contacts,
    }
    wtable = {
        "wall": np.arange(n_walls, dtype=np.int64),
        "u": _total(wu),
        **dict(zip(columns, wu)),
        "n_contacts": w_contacts,
    }
    # a body is incomplete in every mode one of its contacts is; n_not_computed counts those contacts
    unknown = energy.not_computed != 0
    pair = rows2 >= 0
    pbits = np.zeros(table_length(particles), dtype=np.int32)
    wbits = np.zeros(n_walls, dtype=np.int32)
    np.bitwise_or.at(pbits, rows1, energy.not_computed)
    np.bitwise_or.at(pbits, rows2[pair], energy.not_computed[pair])
    np.bitwise_or.at(wbits, -1 - rows2[~pair], energy.not_computed[~pair])
    ptable["not_computed"] = pbits
    ptable["n_not_computed"] = np.bincount(rows1[unknown], minlength=len(pbits)) + np.bincount(
        rows2[pair & unknown], minlength=len(pbits)
    )
    wtable["not_computed"] = wbits
    wtable["n_not_computed"] = np.bincount(-1 - rows2[~pair & unknown], minlength=n_walls)
    if energy.u_adh is not None:  # the interface's work, half to each body
        half = np.full((1, len(energy.u_adh)), ADHESION_SHARE)
        p_adh, _, w_adh, _ = body_sums(rows1, rows2, half, energy.u_adh[None, :], table_length(particles), n_walls)
        ptable[ADHESION_COLUMN] = p_adh[0]
        wtable[ADHESION_COLUMN] = w_adh[0]
    return ptable, wtable


def _total(u: np.ndarray) -> np.ndarray:
    """Sum of the modes (rows of ``u``), added in mode order."""
    total = u[0]
    for row in u[1:]:
        total = total + row
    return total


def particle_energy(frame: FrameContacts, energies: ContactLawEnergy, split: str) -> np.ndarray:
    """Energy of every particle (J, particles' row order) under a comparison ``split``: the
    ``u`` column of :func:`body_tables` without the per-contact table."""
    from ..kernels import particle_sums  # compiled: see the module docstring

    rows1, rows2 = frame.rows
    return particle_sums(rows1, rows2, comparison_shares(frame, split), energies.u, table_length(frame.particles))
