"""``demsplit info FILE`` and ``demsplit check RUN``: look at inputs without computing energies.

:func:`describe_file` says what one file is and holds: a LAMMPS/LIGGGHTS dump
(kind, label, frames, steps, columns with their printed digits, rows per
frame, compression), a demsplit result store (frames, tables, provenance), a
VTK file that is part of a run (points, fields), or whatever a run reader
reads, described by that reader (``Run.describe_file``: a LIGGGHTS input
script's materials, model, walls and dumps; a ``demsplit.yade`` snapshot
file's snapshots, iterations, bodies, interactions and functors; ...).

:func:`check_run` opens a run the way ``demsplit run`` does and validates
every frame: the readers' own checks (counts, numbers, ids, duplicates,
unknown particles, contacts listed twice, printed precision) plus the
consistency of the dumps' timesteps, the overlap range 0 < delta <= min(r1, r2)
and a material for every type. It ends with what ``run`` would compute from
which columns. Every problem names its file, timestep and line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import ContactError, DemsplitError, InputFormatError, MaterialError, PrecisionError
from .fingerprint import DIGEST
from .frame import Frame, describe_steps

MAX_LISTED = 20
"""Problems listed by ``check_run`` before the rest is only counted."""


# --------------------------------------------------------------------------- info


def describe_file(path: str | Path) -> str:
    """A human-readable description of ``path`` (see the module docstring): a result store, a dump or a
    VTK file that is part of a run (none of which is a run), else what the reader that reads it says
    (``Run.describe_file``)."""
    from .readers import read_head, reader_for, readers
    from .readers.lammps_dump import describe_dump, looks_like_dump
    from .readers.liggghts_vtk import describe_vtk_dump, is_liggghts_vtk
    from .readers.yade_export import describe_vtk, is_vtk_part

    path = Path(path)
    head = read_head(path)
    if path.is_dir() or not path.exists():  # a directory or a glob: only a reader of several files takes it
        return reader_for(path).describe_file(path)
    if not head:
        raise InputFormatError("the file is empty.", file=path, fix="check that the program that writes it ran.")
    if _is_store(path, head):
        return _describe_store(path)
    for cls in readers():  # readers that know their files by a signature (YADE states are compressed like dumps)
        if cls.priority > 0 and cls.detect(path, head):
            return cls.describe_file(path)
    for looks_like, describe in (
        (looks_like_dump, describe_dump),
        (is_liggghts_vtk, describe_vtk_dump),
        (is_vtk_part, describe_vtk),
    ):
        if looks_like(path, head):
            return describe(path)
    return reader_for(path).describe_file(path)


def _is_store(path: Path, head: bytes) -> bool:
    """True for an HDF5 file whose ``format`` attribute says it is a result store."""
    from .results.store import STORE

    return STORE.ours(path)


def _describe_store(path: Path) -> str:
    """The store's frames, tables, model, inputs, options and notes, from its checked layout
    (:func:`~demsplit.results.store.open_store`)."""
    from .results.store import open_store

    h5, layout = open_store(path)
    with h5:
        prov = layout.provenance
        steps = layout.steps
        lines = [
            f"{path}: demsplit result store (format version {int(h5.attrs['format_version'])}, "
            f"written by demsplit {_plain_text(h5.attrs.get('demsplit_version', '?'))})",
            f"  frames:   {len(steps)}, steps {describe_steps(steps)}",
            "  tables:",
        ]
        for name in ("particles", "contacts", "walls", "frames"):
            cols = layout.columns[name]
            lines.append(f"    {name:<10} {int(layout.offsets[name][-1]):>9} rows  {' '.join(cols)}")
    model = prov.get("model") or {}
    lines.append(f"  model:    {model.get('law')} {model.get('params', {})}")
    for f in prov.get("inputs") or []:
        # stores written before the fingerprint became BLAKE3 hold sha256 digests
        algo = next((a for a in (DIGEST, "sha256") if a in f), DIGEST)
        lines.append(f"  input:    {f.get('path')}  ({f.get('size')} bytes, {algo} {str(f.get(algo))[:12]}...)")
    options = prov.get("options") or {}
    if options:
        lines.append("  options:  " + ", ".join(f"{k}={v}" for k, v in options.items()))
    bad = prov.get("bad_frames") or []
    lines.append(f"  bad frames skipped: {len(bad)}")
    for b in bad:
        lines.append(f"    frame {b.get('frame')} (step {b.get('step')}): {b.get('error')}")
    for note in prov.get("notes") or []:
        lines.append(f"  note: {note}")
    return "\n".join(lines)


def _plain_text(value) -> str:
    """An attribute's text as a message shows it: bounded and printable."""
    from .readers.lammps_input import excerpt

    return excerpt(value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value))[1:-1]


def _walls(scene) -> str:
    return ", ".join(f"{w.name} ({w.kind}, type {w.type})" for w in scene.walls) or "none"


# --------------------------------------------------------------------------- check


def check_run(input: str | Path, **reader_options) -> tuple[str, bool]:
    """Validate the run ``input`` (a LIGGGHTS script or a YADE snapshot file)
    without computing energies. Returns the report and whether it found no problem."""
    from .readers import open_run

    out = [f"demsplit check {input}"]
    problems: list[str] = []
    try:
        run = open_run(input, **reader_options)
    except DemsplitError as exc:
        return _finish(out, [str(exc)])
    try:
        scene = run.scene
        out.append(f"  model:     {scene.model.describe()}")
        out.append(
            "  materials: " + ", ".join(f"{t}: E={m.E:g} Pa nu={m.nu:g}" for t, m in sorted(scene.materials.items()))
        )
        out.append(f"  walls:     {_walls(scene)}")
        problems += run.check_files(out)
        problems += [
            f"wall {w.name!r} ({w.kind}): {w.missing}; 'demsplit run' refuses the run unless given "
            f"--allow-missing {w.name}"
            for w in scene.walls
            if w.missing
        ]
        types: set[int] = set()
        first: Frame | None = None  # the first frame with contacts, else the first readable one
        notes: list[str] = []  # every frame's, once (what a frame could not give, and why)
        sources: dict[str, int] = {}  # overlap source -> frames with contacts that use it
        imprecise = 0  # frames refused because their printed positions are too coarse for the overlaps
        out.append("  frame  step        particles  contacts  wall contacts  overlap bound")
        for k in range(len(run)):
            try:
                frame = run.frame(k)
            except DemsplitError as exc:
                out.append(f"  {k:>5}  unreadable: see problems")
                problems.append(str(exc))
                imprecise += isinstance(exc, PrecisionError)
                continue
            if first is None or (first.n_contacts == 0 and frame.n_contacts > 0):
                first = frame
            if frame.n_contacts:
                sources[frame.overlap_source] = sources.get(frame.overlap_source, 0) + 1
            notes += [note for note in frame.notes if note not in notes]
            types.update(np.unique(frame.particles["type"]).tolist())
            bound = frame.overlap_error
            out.append(
                f"  {k:>5}  {frame.step:<10}  {frame.n_particles:>9}  {frame.n_contacts:>8}  "
                f"{int(np.count_nonzero(frame.contacts['wall'] >= 0)):>13}  "
                + ("exact" if bound is None or len(bound) == 0 else f"{np.max(bound):.2g}")
            )
            problems += _check_overlaps(run, frame)
        problems += _check_materials(scene, types)
        if first is not None:
            lines, missing = _what_run_computes(run, first, sources, imprecise, notes)
            out += lines
            problems += missing
    finally:
        run.close()
    return _finish(out, problems)


def _finish(out: list[str], problems: list[str]) -> tuple[str, bool]:
    if problems:
        out.append(f"{len(problems)} problem(s):")
        out += [f"  - {p}" for p in problems[:MAX_LISTED]]
        if len(problems) > MAX_LISTED:
            out.append(f"  ... and {len(problems) - MAX_LISTED} more")
    else:
        out.append("OK: no problem found")
    return "\n".join(out), not problems


def _check_overlaps(run, frame: Frame) -> list[str]:
    """-limit < delta <= its law's largest overlap for every contact (first offending row of each kind), with
    limit the largest gap at which the contact's law acts (0: delta > 0, ``ContactLaw.separation_limit``) and
    the largest overlap as the validation has it (:func:`demsplit.validate.overlap_limit`)."""
    from .physics.bodies import FrameContacts
    from .physics.partition import law_groups
    from .validate import overlap_limit

    c = frame.contacts
    delta = c["delta"]
    limit = np.zeros(len(delta))
    types = FrameContacts(c, run.scene, frame.particles).types() if run.scene.pair_models and len(delta) else None
    for model, rows in law_groups(c, run.scene, types):
        limit[rows] = model.contact_law.separation_limit(c["r1"][rows], c["r2"][rows])
    problems = []
    for bad, what in (
        (
            ~(delta > -limit),
            "overlap delta <= 0 (not in contact)"
            if not limit.any()
            else "a gap -delta at or beyond the largest its law acts across (0 but for a liquid bridge)",
        ),
        (
            delta > overlap_limit(c, run.scene, frame.particles),
            "overlap larger than the smaller radius (or the largest its law allows)",
        ),
    ):
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            who = (
                f"particles {int(c['id1'][row])}-{int(c['id2'][row])}"
                if c["wall"][row] < 0
                else f"particle {int(c['id1'][row])} on wall {run.scene.walls[int(c['wall'][row])].name}"
            )
            file, line = run.locate(frame, row)
            problems.append(
                str(
                    ContactError(
                        f"{int(np.count_nonzero(bad))} contact(s) with {what}, the first {who} with delta = "
                        f"{float(delta[row])!r} (r1 = {c['r1'][row]:g}, r2 = {c['r2'][row]:g}).",
                        file=file,
                        step=frame.step,
                        line=line,
                        fix="check that the contact and atom dumps belong to the same run and timestep, and that the "
                        "run is physically sound (timestep, stiffness).",
                    )
                )
            )
    return problems


def _check_materials(scene, types: set[int]) -> list[str]:
    problems = []
    for what, t in (("particle", sorted(types)), ("wall", scene.wall_types().tolist())):
        try:
            scene.lookup(np.asarray(t, dtype=np.int64), what=what)
        except MaterialError as exc:
            problems.append(str(exc.located(file=scene.source or None)))
    return problems


def _what_run_computes(
    run, frame: Frame, sources: dict[str, int], imprecise: int, notes: list[str]
) -> tuple[list[str], list[str]]:
    """What ``demsplit run`` would compute from which columns (from ``frame``, the first readable frame with
    contacts: a frame without any, e.g. before particles are inserted, shows no column a contact needs): where
    the overlaps come from in the frames with contacts (``sources``: source -> frames; ``imprecise``: frames
    refused for printed positions too coarse), each law's one-line description, the modes a law does not have
    (0), and, as problems, the modes the run has but whose columns were not dumped (``run`` refuses them without
    ``--allow-missing``); the run's notes and every frame's ``notes``."""
    from .physics.partition import contact_energies

    scene = run.scene
    shown = [
        f"{source} ({n} frame{'s' if n > 1 else ''})" if len(sources) > 1 or imprecise else source
        for source, n in sources.items()
        if source
    ]
    if imprecise:
        shown.append(
            f"positions printed with too few digits ({imprecise} frame{'s' if imprecise > 1 else ''} "
            "refused: see the problems)"
        )
    lines = [
        "run would compute:",
        f"  overlaps:    {'; '.join(shown) or frame.overlap_source or 'as the reader gives them'}",
    ]
    lines += [f"  law:         {model.describe()}" for model in scene.models()]
    problems = []
    try:  # the partition's own verdict on what the columns allow (one frame)
        energies = contact_energies(frame.contacts, scene, frame.particles)
        for what, why in energies.skipped.items():
            lines.append(f"  {what} is 0:     {why}")
        for what, why in energies.missing.items():
            lines.append(f"  NOT COMPUTED: {what}: {why}")
            problems.append(
                f"{what}: {why}; dump its columns, or let 'demsplit run' go on without it with "
                f"--allow-missing {what} (its values are then marked not computed)."
            )
    except DemsplitError as exc:
        problems.append(str(exc))
    for note in run.notes + [n for n in notes if n not in run.notes]:
        lines.append(f"  note: {note}")
    lines.append(f"  walls:       {len(scene.walls)} ({_walls(scene)})")
    return lines, problems
