"""The whole computation for one frame: a Frame and its Scene in, the store's tables out.

:func:`frame_tables` is a pure function of a :class:`~demsplit.frame.Frame`, a
:class:`~demsplit.scene.Scene` and the :class:`Options`: it validates the frame, computes every contact's
energy with the run's laws, splits it between the bodies, sums it per particle and per wall, adds the
comparison splits and the accuracy columns, and returns one frame's ``particles``, ``contacts``, ``walls``
and ``frames`` tables. The stages share one :class:`~demsplit.physics.bodies.FrameContacts`, so the
particle index, the bodies' rows and their materials are derived once per frame.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .errors import DemsplitError, IncompleteRunError
from .frame import CONTACT_REQUIRED, PARTICLE_REQUIRED, Frame, ParticleIndex, Table, require_columns
from .physics.accuracy import contact_radius_ratios, corrected_share, expected_share_error
from .physics.bodies import FrameContacts
from .physics.modes import ADHESION_COLUMN, NOT_COMPUTED_BITS
from .physics.partition import ContactEnergy, body_tables, law_energies, particle_energy, split_energies
from .results.schema import UNBOUNDED, UNKNOWN
from .runtime import threads
from .scene import Scene, Wall
from .validate import check_finite_energies, validated_frame

Tables = dict[str, dict[str, np.ndarray]]
"""One frame's tables, as the store takes them: table name -> column -> values."""


@dataclass(frozen=True)
class Options:
    """What to compute.

    tangential_rule : ``"mindlin"`` (default) or ``"paper"`` (see
        :func:`demsplit.physics.shares.tangential_share`).
    compare : also compute the 50/50 (``u_equal``) and radius-weighted
        (``u_radius``) splits per particle, and YADE's series-spring split
        (``u_springs``) for its linear law.
    contacts : keep the per-contact table (the largest table by far).
    allow_missing : what the run may go on without (``--allow-missing``): energy modes
        (``u_t``, ``u_r``, ...) whose columns were not dumped, and walls (by name) whose contacts
        were not dumped; their values are then marked "not computed" (never 0), else the run is
        refused. ``all`` allows everything.
    accuracy : add the expected error of the split (``a_over_r1 a_over_r2 share_n1_error`` per
        contact, ``u_n_error`` per particle) from the finite-element error model (docs/accuracy.md).
    split : ``"material"`` (the law, default) or ``"corrected"``: the normal energy split by the
        law corrected for finite bodies (:func:`demsplit.physics.accuracy.corrected_share`), an option
        until the evidence makes it the default (docs/accuracy.md).
    """

    tangential_rule: str = "mindlin"
    compare: bool = True
    contacts: bool = True
    allow_missing: tuple[str, ...] = ()
    accuracy: bool = True
    split: str = "material"

    def allows(self, name: str) -> bool:
        """True when the run may go on without ``name`` (a mode column or a wall name)."""
        return name in self.allow_missing or "all" in self.allow_missing


DEFAULT_OPTIONS = Options()
"""What :func:`frame_tables` computes unless told otherwise."""


def comparison_splits(scene: Scene) -> tuple[str, ...]:
    """The naive splits reported beside the distribution law for this scene (the scene's law says which)."""
    return scene.model.contact_law.comparison_splits


def frame_tables(frame: Frame, scene: Scene, options: Options = DEFAULT_OPTIONS) -> Tables:
    """Everything demsplit computes for one frame, as the store's tables.

    ``particles``: per-particle energies under the distribution law (``u
    u_n u_t``) and, with ``options.compare``, under the comparison splits;
    ``contacts``: per-contact energies, shares, depth and contact points
    (``cp*_sim``: the simulator's own point, when the input has it);
    ``walls``: energy stored in each wall that exists at the step; ``frames``: one row of totals (contact
    energies, and the sums over particles and walls that the energy balance
    compares them with).
    """
    source = frame.source[0] if frame.source else None
    require_columns(frame.particles, PARTICLE_REQUIRED, "particles", file=source, step=frame.step)
    require_columns(frame.contacts, CONTACT_REQUIRED, "contacts", file=source, step=frame.step)
    frame = validated_frame(frame, scene)  # canonical dtypes; every number finite, in range and plausible
    particles = frame.particles
    contacts = FrameContacts(
        frame.contacts, scene, particles, ParticleIndex(particles["id"], file=source, step=frame.step)
    )
    try:
        energies = law_energies(contacts)
        check_finite_energies(
            energies.u, contacts.contacts, file=frame.source[-1] if frame.source else None, step=frame.step
        )
        ratios = (
            _radius_ratios(contacts.contacts) if options.accuracy or options.split == "corrected" else None
        )  # a/R1, a/R2, once for both
        corrected = None
        if options.split == "corrected":
            x1, x2 = ratios
            bodies = contacts.bodies
            corrected = np.broadcast_to(corrected_share(x1, x2, bodies.nu1, bodies.nu2, bodies.E1, bodies.E2), x1.shape)
        main = split_energies(
            contacts, energies, split="material", tangential_rule=options.tangential_rule, normal_shares=corrected
        )
        contacts.without(_used_up(scene))  # what the partition used up: freed before the tables
        frame = replace(frame, contacts=contacts.contacts)  # (when the caller handed over its only reference)
        ptable, wtable = body_tables(contacts, main, n_walls=len(scene.walls))
        if "clump" in particles:  # YADE clump membership, for per-clump sums
            ptable["clump"] = np.asarray(particles["clump"], dtype=np.int64)
        if options.compare:
            for split in comparison_splits(scene):
                ptable[f"u_{split}"] = particle_energy(contacts, energies, split)
    except DemsplitError as exc:
        raise exc.located(file=source, step=frame.step) from None
    refused = {mode: why for mode, why in main.missing.items() if not options.allows(mode)}
    if refused:
        mode, why = next(iter(refused.items()))
        raise IncompleteRunError(
            f"{why}. The run has this energy but its files do not hold it"
            + (f" (also missing: {', '.join(list(refused)[1:])})" if len(refused) > 1 else "")
            + ".",
            file=source,
            step=frame.step,
            fix=f"dump the columns it needs where a dump can hold them (docs/liggghts-output.md and "
            f"docs/lammps-output.md list them per model; 'demsplit check' names the lines), or go on without it "
            f"with --allow-missing {mode}: its values are then marked not computed.",
        )
    for what, why in main.skipped.items():
        note = f"{what} is 0: {why}"
        if note not in frame.notes:
            frame.notes.append(note)
    for what, why in main.missing.items():
        note = f"{what} NOT COMPUTED (--allow-missing {what}): {why}"
        if note not in frame.notes:
            frame.notes.append(note)
    n = len(contacts)
    step = np.int64(frame.step)
    _mark_missing_walls(scene, main, wtable)
    if frame.walls is not None:  # a wall that does not exist at this step has no row
        present = np.isin(wtable["wall"], np.asarray(frame.walls, dtype=np.int64))
        wtable = {c: v[present] for c, v in wtable.items()}
    accuracy = _accuracy(contacts, ratios, main, ptable) if options.accuracy else {}
    tables: Tables = {
        "particles": {"step": np.full(len(ptable["id"]), step), **ptable},
        "walls": {"step": np.full(len(wtable["wall"]), step), **wtable},
    }
    if options.contacts:
        if frame.box is not None and frame.box.any_periodic:
            main.cp = frame.box.wrap(main.cp)  # contact points of contacts across a boundary, back in the box
        c = contacts.contacts
        ctable = {
            "step": np.full(n, step),
            "id1": c["id1"],
            "id2": c["id2"],
            "wall": c["wall"],
            "delta": c["delta"],
            **main.table(),
            **accuracy,
        }
        if "cpx" in c:
            ctable.update(cpx_sim=c["cpx"], cpy_sim=c["cpy"], cpz_sim=c["cpz"])
        tables["contacts"] = ctable
    err = frame.overlap_error
    tables["frames"] = {
        "step": np.array([step]),
        "time": np.array([UNKNOWN if frame.time is None else frame.time]),
        "n_particles": np.array([len(ptable["id"])], dtype=np.int64),
        "n_contacts": np.array([n], dtype=np.int64),
        "n_wall_contacts": np.array([int(np.count_nonzero(contacts.contacts["wall"] >= 0))], dtype=np.int64),
        "n_not_computed": np.array([int(np.count_nonzero(main.not_computed))], dtype=np.int64),
        **{mode.column: np.array([main.u[k].sum()]) for k, mode in enumerate(main.modes)},
        **({ADHESION_COLUMN: np.array([main.u_adh.sum()])} if main.u_adh is not None else {}),
        "u_particles": np.array([ptable["u"].sum()]),
        "u_walls": np.array([wtable["u"].sum()]),
        "overlap_max_rel_error": np.array(
            [UNKNOWN if err is None or len(err) == 0 else min(float(np.max(err)), UNBOUNDED)]
        ),
    }
    if frame.box is not None:  # the simulation box: where the VTK export draws primitive walls (m)
        for k, axis in enumerate("xyz"):
            tables["frames"][f"box_{axis}lo"] = np.array([frame.box.lo[k]])
            tables["frames"][f"box_{axis}hi"] = np.array([frame.box.hi[k]])
    return tables


_KEPT = ("id1", "id2", "wall", "delta", "r1", "r2", "cpx", "cpy", "cpz", "history_unknown")
"""Contact columns read after the partition: the contacts table, the comparison splits (the radii) and the
accuracy columns."""


def _used_up(scene: Scene) -> tuple[str, ...]:
    """Contact columns nothing after the partition reads: body 1's centre and the normal (which gave the
    contact point) and the laws' own columns (their histories, which gave the energies)."""
    own = [c for model in scene.models() for c in model.contact_law.needs()]
    return tuple(dict.fromkeys(c for c in ("x1", "y1", "z1", "nx", "ny", "nz", *own) if c not in _KEPT))


def _radius_ratios(contacts: Table) -> tuple[np.ndarray, np.ndarray]:
    """a/R1 and a/R2 of every contact (:func:`~demsplit.physics.accuracy.contact_radius_ratios`), in pieces
    of ``ACCURACY_ROWS`` contacts on the pool's threads."""
    n = len(contacts["delta"])
    x1, x2 = np.empty(n), np.empty(n)

    def piece(lo: int, hi: int) -> None:
        x1[lo:hi], x2[lo:hi] = contact_radius_ratios(*(contacts[c][lo:hi] for c in ("delta", "r1", "r2")))

    threads.map_ranges(piece, n, max_rows=ACCURACY_ROWS)
    return x1, x2


ACCURACY_ROWS = 1 << 16
"""Contacts per piece of the error model's evaluation: its two dozen temporaries stay a few MB a thread."""


def _accuracy(
    contacts: FrameContacts, ratios: tuple[np.ndarray, np.ndarray], main: ContactEnergy, ptable: Table
) -> Table:
    """How far the split can be trusted, from the fitted finite-element error model
    (:mod:`demsplit.physics.accuracy`, docs/accuracy.md): per contact ``a_over_r1 a_over_r2`` (the Hertz
    contact radius over each radius) and ``share_n1_error`` (expected FE share minus the law's share of
    body 1's normal energy), returned; per particle ``u_n_error`` (J), the expected error of its normal
    energy, the sum over its contacts of +-share_n1_error u_n, added to ``ptable``. ``ratios``: a/R1, a/R2
    (:func:`~demsplit.physics.accuracy.contact_radius_ratios`)."""
    x1, x2 = ratios
    err = np.empty(x1.shape)

    def piece(lo: int, hi: int) -> None:  # numpy releases the GIL: pieces of the contacts on every core
        E1, nu1, E2, nu2 = contacts.bodies.constants(lo, hi)
        err[lo:hi] = expected_share_error(x1[lo:hi], x2[lo:hi], nu1, nu2, E1, E2)

    threads.map_ranges(piece, len(err), max_rows=ACCURACY_ROWS)
    from .kernels import signed_particle_sums  # compiled, lazily

    rows1, rows2 = contacts.rows
    ptable["u_n_error"] = signed_particle_sums(rows1, rows2, err, main.u[0], len(ptable["id"]))
    return {"a_over_r1": x1, "a_over_r2": x2, "share_n1_error": err}


def missing_walls(scene: Scene) -> list[tuple[int, Wall]]:
    """The walls whose contacts the run's files lack (``Wall.missing``), with their indices."""
    return [(i, w) for i, w in enumerate(scene.walls) if w.missing]


def refuse_missing_walls(scene: Scene, options: Options) -> None:
    """Raise :class:`IncompleteRunError` for the first wall whose contacts the files lack and which
    the user did not let go (``--allow-missing NAME``)."""
    refused = [w for _, w in missing_walls(scene) if not options.allows(w.name)]
    if refused:
        w = refused[0]
        others = f" (and {', '.join(x.name for x in refused[1:])})" if len(refused) > 1 else ""
        raise IncompleteRunError(
            f"the {w.kind} wall {w.name!r}{others} is part of this run, but {w.missing}",
            file=scene.source or None,
            fix=f"write its contacts as said above and rerun the simulation, or go on without them with "
            f"--allow-missing {w.name}: the wall's energy is then marked not computed.",
        )


def _mark_missing_walls(scene: Scene, main: ContactEnergy, wtable: Table) -> None:
    """Set every mode's bit on the walls whose contacts are missing (their contacts, unread, are unknown)."""
    walls = missing_walls(scene)
    if not walls:
        return
    every = sum(NOT_COMPUTED_BITS[m.column] for m in main.modes) + (
        NOT_COMPUTED_BITS[ADHESION_COLUMN] if main.u_adh is not None else 0
    )
    for i, _ in walls:
        wtable["not_computed"][i] |= every
