"""``demsplit prepare``: a copy of a LIGGGHTS input script that writes everything demsplit needs.

demsplit analyses a run from its dumps; a script written without demsplit in
mind rarely dumps the contact history at full precision, and LIGGGHTS accepts
the contact computes only in one place. :func:`prepare_script` reads the script
(:func:`demsplit.readers.liggghts_script.read_script`), decides what is missing
and inserts, just before the first ``run`` (after every wall fix, as LIGGGHTS
requires of the contact computes):

- ``compute dsPair all pair/gran/local ...`` with ``history`` when the contact law
  keeps one (LIGGGHTS refuses it otherwise) and ``delta``, and its ``dump local``
  with the compute's full column list (its width follows the law's history,
  :func:`~demsplit.readers.liggghts_script.local_layout`) at ``%.17g``;
- ``compute dsWall all wall/gran/local ...`` and its dump only when the run has mesh
  walls (LIGGGHTS stops on it with primitive walls only);
- a full-precision atom dump with the columns the laws read of the particles (the liquid
  content ``f_surfaceLiquidContent`` of a liquid-bridge cohesion model), unless the script
  already writes one; LIGGGHTS checks a ``f_`` column when it reads the dump command, so the
  fix behind it, which a liquid-bridge model creates only when the first run starts, is
  created just before (:meth:`~demsplit.physics.laws._liggghts.LiggghtsNormalModel.dump_setup`;
  checked in Debian's LIGGGHTS: the trajectory is bit for bit the same);
- for primitive walls, whose contact history LIGGGHTS never writes: ``store_force yes`` on every
  primitive ``fix wall/gran`` (appended to its line), and in the atom dump the torques ``tqx tqy tqz``
  and each such fix's stored force ``f_force_<ID>[1] [2] [3]``, from which the reader rebuilds that
  history (:mod:`demsplit.readers.liggghts_wallforce`; ``store_force`` leaves the trajectory bit for
  bit the same: sample_dumps/liggghts/walls/measure.py --packing). A fix defined after the part's
  first run, or removed by ``unfix`` (LIGGGHTS stops a dump that names a removed fix's column), gets
  no column: its contacts' history stays not computed, and a note says so.

A mesh wall fix placed after a ``run`` cannot get its contact compute in the
same LIGGGHTS session (LIGGGHTS accepts ``wall/gran/local`` only before the
first run). prepare then splits the script there, which keeps the physics:
part 1 is the script up to that fix, ending with ``write_restart``; part 2
starts with the settings LIGGGHTS does not keep in a restart file (the
script's commands before the fix, less those that create or move atoms, run,
or write once), then ``read_restart`` and the rest of the script. Fixes keep
their IDs, so the restart restores their state (contact histories, insertion
counters). Each part gets its own demsplit dumps; the script's own dumps are
declared again in part 2 writing to ``NAME.part2.EXT`` (a ``*`` file name is
kept), so part 1's files are not overwritten. Checked in Debian's LIGGGHTS:
the split run's trajectory is bit for bit the unsplit one
(``tests/test_prepare.py``). Scripts whose commands before the split include
other files or loop (``include``, ``jump``, ``if``...) are refused with the
steps to split them by hand.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from pathlib import Path

from .errors import ScriptError
from .physics.laws import ContactLaw
from .readers.lammps_input import logical_lines, read_text, strip_comment
from .readers.liggghts import PREPARED_MARK
from .readers.liggghts_script import DumpSpec, LiggghtsScript, local_layout, read_script
from .readers.liggghts_wallforce import BALANCE_COLUMNS, stored_force_columns

KEYWORDS = [
    "pos",
    "vel",
    "id",
    "force",
    "force_normal",
    "force_tangential",
    "torque",
    "history",
    "contactArea",
    "delta",
    "contactPoint",
]
"""Keywords of the contact computes prepare adds (``history`` dropped when the law keeps none)."""
ATOM_COLUMNS = "id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass"
STORE_FORCE = "store_force yes"
GIVEN = "as given (--every)"
"""Why the added dumps have the interval they have when the user gave it."""
FRAMES_WITHOUT_OUTPUT = 100
"""Frames over the script's runs when it writes no output whose interval the added dumps could follow."""
RESTART = "ds_split{k}.restart"
"""The restart file between part k and part k + 1 of a split script."""
BEFORE_READ_RESTART = frozenset(
    {
        "units",
        "atom_style",
        "atom_modify",
        "boundary",
        "newton",
        "communicate",
        "comm_modify",
        "processors",
        "dimension",
    }
)
"""Commands that must precede ``read_restart`` (they define how the box and atoms are read)."""
NOT_REPEATED = frozenset(
    {
        "create_box",
        "create_atoms",
        "read_data",
        "read_dump",
        "read_restart",
        "set",
        "velocity",
        "delete_atoms",
        "displace_atoms",
        "change_box",
        "replicate",
        "reset_timestep",
        "run",
        "rerun",
        "minimize",
        "write_restart",
        "write_data",
        "write_dump",
        "print",
        "shell",
        "log",
        "clear",
    }
)
"""Commands of part 1 not repeated in part 2: they create, move or change atoms (the restart holds the
result), run, or write once (they would overwrite part 1's files)."""
NOT_SPLITTABLE = frozenset({"include", "jump", "label", "next", "if", "python"})
"""Commands before a split point that prepare cannot carry into part 2 by itself."""


@dataclass
class Prepared:
    """The prepared script's text, the lines added, and what prepare decided (one line each)."""

    text: str
    added: list[str]
    notes: list[str]
    part2: Prepared | None = None
    """When the script was split at a mesh wall fix after a run, the rest of it (this is then part 1)."""
    program: str = "liggghts"
    """The simulator's program that runs the prepared script."""

    @property
    def data(self) -> bytes:
        """The prepared script's bytes: the original's own bytes (:func:`~demsplit.readers.lammps_input.read_text`)
        where it is not changed."""
        return self.text.encode("utf-8", errors="surrogateescape")

    def diff(self, original: str, name: str) -> str:
        """A unified diff from the original script to the prepared one (to each part in turn when split), for
        the terminal: a byte that is not UTF-8 shows as ``\\xNN``."""
        out, part, k = [], self, 1
        while part is not None:
            label = f"{name} (prepared by demsplit" + (f", part {k})" if self.part2 is not None else ")")
            out += difflib.unified_diff(
                original.splitlines(True), part.text.splitlines(True), fromfile=name, tofile=label
            )
            part, k = part.part2, k + 1
        return "".join(out).encode("utf-8", errors="surrogateescape").decode("utf-8", errors="backslashreplace")


def _commands(path: Path) -> list[tuple[int, list[str]]]:
    """(line, words) of every command of the script file itself (not of the files it includes)."""
    out = []
    for line, text in logical_lines(path):
        words = strip_comment(text).split()
        if words:
            out.append((line, words))
    return out


def _full_atom_dump(script: LiggghtsScript, declared: set[str], needed: list[str]) -> DumpSpec | None:
    """A full-precision atom dump (among the dump ids ``declared``) with what demsplit reads (``id type x y z
    radius`` and the ``needed`` columns of the laws), or None."""
    for d in script.dumps:
        if (
            d.id in declared
            and d.style == "custom"
            and d.full_precision
            and {"id", "type", "x", "y", "z", "radius", *needed} <= set(d.keywords)
        ):
            return d
    return None


def _laws(script: LiggghtsScript) -> list[ContactLaw]:
    """The contact laws of the script's pair style and walls."""
    return [m.contact_law for m in [script.scene.model] + [w.model for w in script.scene.walls if w.model is not None]]


def _has_local_dump(script: LiggghtsScript, declared: set[str], kind: str, needed: set[str]) -> bool:
    """A full-precision ``dump local`` (among the dump ids ``declared``) of a ``kind`` compute holding the
    ``needed`` columns."""
    return any(
        d.id in declared
        and d.layout is not None
        and d.layout.kind == kind
        and d.full_precision
        and needed <= set(d.layout.columns)
        for d in script.dumps
    )


def _is_mesh_wall_fix(words: list[str]) -> bool:
    return words[0] == "fix" and len(words) > 3 and words[3] == "wall/gran" and "mesh" in words


def _mesh_names(words: list[str]) -> list[str]:
    """The meshes a ``fix wall/gran ... mesh n_meshes N meshes A B ...`` command names."""
    if "meshes" not in words or "n_meshes" not in words:
        return [words[1]]
    try:
        n = int(words[words.index("n_meshes") + 1])
    except ValueError:
        return [words[1]]
    at = words.index("meshes") + 1
    return words[at : at + n]


def _is_primitive_wall_fix(words: list[str]) -> bool:
    return words[0] == "fix" and len(words) > 3 and words[3] == "wall/gran" and "primitive" in words


def _stores_force(words: list[str]) -> bool:
    return any(a == "store_force" and b == "yes" for a, b in zip(words, words[1:]))


def _store_forces(lines: list[str], commands: list[tuple[int, list[str]]]) -> tuple[list[str], list[str]]:
    """``store_force yes`` appended to every primitive ``fix wall/gran`` command that lacks it (its last physical
    line, before a comment), in ``lines`` and in ``commands`` (in place); the fix ids changed."""
    changed = []
    for k, (line, words) in enumerate(commands):
        if not _is_primitive_wall_fix(words) or _stores_force(words):
            continue
        last = line - 1
        while lines[last].rstrip().endswith("&"):
            last += 1
        code = strip_comment(lines[last]).rstrip()
        lines[last] = code + f" {STORE_FORCE}" + lines[last][len(code) :]
        commands[k] = (line, [*words, *STORE_FORCE.split()])
        changed.append(words[1])
    return lines, changed


def _stored_force_fixes(commands: list[tuple[int, list[str]]], at: int) -> tuple[list[str], list[str]]:
    """The primitive wall fixes with ``store_force yes`` whose force an atom dump placed before line ``at`` may name
    (defined before it: earlier parts' fixes are replayed; and never removed by ``unfix``), and those it may not."""
    unfixed = {words[1] for _, words in commands if words[0] == "unfix" and len(words) > 1}
    fixes = [(line, words[1]) for line, words in commands if _is_primitive_wall_fix(words) and _stores_force(words)]
    dumped = [fid for line, fid in fixes if line < at and fid not in unfixed]
    return list(dict.fromkeys(dumped)), [fid for _, fid in fixes if fid not in dumped]


def split_points(commands: list[tuple[int, list[str]]]) -> list[int]:
    """Lines of the mesh wall fixes where the script must be split: each one that follows a ``run``
    of the part it would otherwise belong to (module docstring)."""
    points, ran = [], False
    for line, words in commands:
        if words[0] == "run":
            ran = True
        elif ran and _is_mesh_wall_fix(words):
            points.append(line)
            ran = False
    return points


def output_interval(
    script: LiggghtsScript, commands: list[tuple[int, list[str]]], every: int | None = None
) -> tuple[int, str]:
    """The interval (timesteps) of the dumps prepare adds, and why: ``every`` when given; else the script's
    own output, the smallest interval of its dumps, else of its ``thermo`` lines (a run whose output the user
    sized should not get frames far more often, which costs disk and time in proportion); else
    :data:`FRAMES_WITHOUT_OUTPUT` frames over its runs."""
    if every is not None:
        return every, GIVEN
    if script.dumps:
        d = min(script.dumps, key=lambda d: d.every)
        return d.every, f"the interval of the script's own dump {d.id}"
    thermo = [
        int(words[1])
        for _, words in commands
        if words[0] == "thermo" and len(words) > 1 and words[1].isdigit() and int(words[1]) > 0
    ]
    if thermo:
        return min(thermo), "the interval of the script's thermo output"
    steps = sum(end - start for start, end in script.runs)
    return max(1, -(-steps // FRAMES_WITHOUT_OUTPUT)), (
        f"{FRAMES_WITHOUT_OUTPUT} frames over the script's {steps} steps of runs (it writes no output to follow)"
    )


def prepare_script(path: str | Path, every: int | None = None) -> Prepared:
    """The script at ``path`` with the computes and dumps demsplit needs, split where a mesh wall fix
    follows a run (module docstring); the dumps it adds write every ``every`` steps (default: the script's own
    output interval, :func:`output_interval`)."""
    path = Path(path)
    script = read_script(path)
    law = script.scene.model.contact_law
    # the history each compute writes: the pair and the mesh-wall model's own, computeElasticPotential's too
    histories = {kind: script.local_histories.get(kind, law.history_columns()) for kind in ("pair", "wall")}
    commands = _commands(path)
    if not any(words[0] == "run" for _, words in commands):
        raise ScriptError(
            "the script has no 'run' command: there is nothing to dump.",
            file=path,
            fix="pass the script that runs the simulation.",
        )
    lines, stored = _store_forces(read_text(path).split("\n"), commands)
    points = split_points(commands)
    interval = output_interval(script, commands, every)
    if points:
        _check_splittable(path, commands, points)
    bounds = [1, *points, len(lines) + 1]
    parts = []
    for k in range(len(bounds) - 1):
        start, end = bounds[k], bounds[k + 1]
        last = k == len(bounds) - 2
        header = _replayed(commands, start, k + 1)
        footer = [] if last else ["", f"write_restart {RESTART.format(k=k + 1)}"]
        parts.append(
            _prepare_part(
                path, script, histories, commands, lines, start, end, k + 1 if points else 0, header, footer, interval
            )
        )
    for part, after in zip(parts, parts[1:]):
        part.part2 = after
    if stored:
        parts[0].notes.insert(
            0,
            f"primitive walls: store_force yes added to the fix{'es' if len(stored) > 1 else ''} "
            f"{', '.join(stored)}: the force each applies, dumped with the torques, gives back "
            "their contacts' history (the trajectory is the same).",
        )
    if points:
        parts[0].notes.insert(
            0,
            f"split: the mesh wall fix{'es' if len(points) > 1 else ''} on line"
            f"{'s' if len(points) > 1 else ''} {', '.join(map(str, points))} come"
            f"{'' if len(points) > 1 else 's'} after a 'run', where LIGGGHTS cannot dump "
            f"{'their' if len(points) > 1 else 'its'} contacts; the script is split there into "
            f"{len(parts)} parts joined by write_restart/read_restart (the same physics), run "
            "one after the other in the same directory.",
        )
    return parts[0]


def _check_splittable(path: Path, commands: list[tuple[int, list[str]]], points: list[int]) -> None:
    """Refuse a split whose part 1 holds commands prepare cannot carry into part 2."""
    for line, words in commands:
        if line < points[-1] and words[0] in NOT_SPLITTABLE:
            raise ScriptError(
                f"the mesh wall fix on line {points[0]} comes after a 'run', so the script must be split there "
                f"(LIGGGHTS dumps a mesh wall's contacts only when its compute comes before the first run), but "
                f"line {line} ('{words[0]}') includes another file or branches, which prepare cannot carry into "
                "the second part.",
                file=path,
                line=line,
                fix="split it by hand: end the first part with 'write_restart part1.restart'; start the second "
                "with the settings (units, atom_style, boundary...), 'read_restart part1.restart', the fixes, "
                "pair_style and computes again (same IDs), then the wall fix; run 'demsplit prepare' on each.",
            )


def _replayed(commands: list[tuple[int, list[str]]], start: int, k: int) -> list[str]:
    """The head of part ``k`` (> 1): the commands before line ``start`` that a restart file does not keep,
    around ``read_restart`` (module docstring); the script's own dumps write to ``.part{k}`` files."""
    if k == 1:
        return []
    before = [words for line, words in commands if line < start and words[0] not in NOT_REPEATED]
    head = [" ".join(w) for w in before if w[0] in BEFORE_READ_RESTART]
    rest = [" ".join(_renamed_dump(w, k)) for w in before if w[0] not in BEFORE_READ_RESTART]
    return [
        f"# --- part {k} of the script split by 'demsplit prepare': the settings a restart file does not "
        "keep, then the state of the previous part ---",
        *head,
        f"read_restart {RESTART.format(k=k - 1)}",
        *rest,
        "# --- the script continues ---",
    ]


def _renamed_dump(words: list[str], k: int) -> list[str]:
    """A ``dump`` command of an earlier part, writing to ``NAME.part{k}.EXT`` (a ``*`` name is kept: its
    files are per timestep)."""
    if words[0] != "dump" or len(words) < 6 or "*" in words[5]:
        return words
    stem, dot, ext = words[5].rpartition(".")
    renamed = f"{stem}.part{k}.{ext}" if dot and "/" not in ext else f"{words[5]}.part{k}"
    return [*words[:5], renamed, *words[6:]]


def _prepare_part(
    path: Path,
    script: LiggghtsScript,
    histories: dict[str, list[str]],
    commands: list[tuple[int, list[str]]],
    lines: list[str],
    start: int,
    end: int,
    k: int,
    header: list[str],
    footer: list[str],
    interval: tuple[int, str],
) -> Prepared:
    """Lines ``start``..``end - 1`` of the script (part ``k``; 0 when not split) with ``header`` and
    ``footer`` and, before the part's first run, the computes and dumps it lacks; ``histories``: the
    history columns of the pair and the wall compute (``'pair'``, ``'wall'``); ``interval``: the added dumps'
    interval and why (:func:`output_interval`)."""
    suffix = f".part{k}" if k > 1 else ""
    label = f"part {k}: " if k else ""
    original = read_text(path).split("\n")
    law = script.scene.model.contact_law
    keywords = {kind: [w for w in KEYWORDS if w != "history" or history] for kind, history in histories.items()}
    needed = {"id1", "id2", "delta", *law.needs()}
    declared = {words[1] for line, words in commands if line < end and words[0] == "dump" and len(words) > 1}
    mesh = [name for line, words in commands if line < end and _is_mesh_wall_fix(words) for name in _mesh_names(words)]
    runs = [line for line, words in commands if start <= line < end and words[0] == "run"]
    body = lines[start - 1 : end - 1]
    notes, block = [], []
    laws = _laws(script)
    extra = list(dict.fromkeys(c for law in laws for c in law.particle_columns if c not in ATOM_COLUMNS.split()))
    own = _full_atom_dump(script, declared, extra)
    forces, undumped = _stored_force_fixes(commands, runs[0] if runs else end)
    place = None
    if forces and own is not None:  # a dump beside the script's own: its interval, its place, so its frames
        place = max(line for line, words in commands if words[:2] == ["dump", own.id] and line < end)
        if place >= start:
            forces, undumped = _stored_force_fixes(commands, place)
        else:
            place = None
    wall_columns = [*BALANCE_COLUMNS, *(c for fid in forces for c in stored_force_columns(fid))] if forces else []
    extra = list(dict.fromkeys(c for c in [*extra, *wall_columns] if c not in ATOM_COLUMNS.split()))
    if undumped:
        notes.append(
            f"{label}primitive walls {', '.join(undumped)}: defined after the atom dump, or removed by "
            "unfix, so no atom dump holds their stored force: their contacts' history stays not computed."
        )
    beside: list[str] = []
    if own is not None and set(wall_columns) <= set(own.keywords):
        every = own.every
        notes.append(
            f"{label}atoms: the script's full-precision atom dump (every {every} steps) is used, and the "
            "contact dumps follow its interval"
            + (
                f" (--every {interval[0]} does not apply: the contacts are read at the atom dump's timesteps)."
                if interval[1] == GIVEN and interval[0] != every
                else "."
            )
        )
    elif place is not None:
        every = own.every
        columns = " ".join([ATOM_COLUMNS, *extra])
        beside = [
            f"dump dsAtoms all custom {every} ds_atoms{suffix}.txt {columns}",
            'dump_modify dsAtoms format "%d %d' + " %.17g" * (len(columns.split()) - 2) + '" sort id',
        ]
        notes.append(
            f"{label}atoms: a full-precision atom dump with the torques and the primitive walls' stored "
            f"forces beside the script's own {own.id} (every {every} steps, ds_atoms{suffix}.txt)."
        )
    else:
        every, why = interval
        columns = " ".join([ATOM_COLUMNS, *extra])
        fixes = {words[1] for line, words in commands if line < end and words[0] == "fix" and len(words) > 1}
        setup = [c for c in dict.fromkeys(c for law in laws for c in law.dump_setup()) if c.split()[1] not in fixes]
        block += [
            *setup,
            f"dump dsAtoms all custom {every} ds_atoms{suffix}.txt {columns}",
            'dump_modify dsAtoms format "%d %d' + " %.17g" * (len(columns.split()) - 2) + '" sort id',
        ]
        notes.append(
            f"{label}atoms: a full-precision atom dump every {every} steps ({why}; another with --every N) "
            f"in ds_atoms{suffix}.txt."
        )
        if setup:
            notes.append(
                f"{label}atoms: {' and '.join(extra)} from the fix the cohesion model creates at the first "
                "run, created just before the dump (LIGGGHTS checks a dump's f_ columns when it reads "
                "it); the run is the same."
            )
    if _has_local_dump(script, declared, "pair", needed):
        notes.append(f"{label}pairs: the script's full-precision pair dump holds every column the law needs.")
    else:
        block += _local("pair", "dsPair", keywords["pair"], histories["pair"], every, suffix)
        width = len(local_layout("pair", keywords["pair"], len(histories["pair"]), history=histories["pair"]))
        notes.append(
            f"{label}pairs: compute dsPair and a full-precision dump of its {width} columns (ds_pairs{suffix}.txt)."
        )
    if mesh and not _has_local_dump(script, declared, "wall", needed - {"id2"}):
        block += _local("wall", "dsWall", keywords["wall"], histories["wall"], every, suffix)
        notes.append(
            f"{label}mesh walls ({', '.join(mesh)}): compute dsWall and its full-precision dump (ds_walls{suffix}.txt)."
        )
    elif not mesh:
        notes.append(
            f"{label}walls: no mesh wall, so no wall/gran/local compute (LIGGGHTS refuses it with "
            "primitive walls only); primitive-wall contacts are rebuilt from positions, their history from "
            "the walls' stored forces."
        )
    if not runs:
        block, beside = [], []
        notes.append(f"{label}no 'run': nothing to dump.")
    if not block and not beside and not header and not footer and body == original[start - 1 : end - 1]:
        return Prepared(path.read_text(), [], notes + ["nothing to add: the script writes everything demsplit needs."])
    at = runs[0] - start if block else len(body)  # just before the part's first run: after every fix so far
    insertions = [(at, _added(block))]
    if beside:  # right after the script's own atom dump (its last physical line)
        last = place - 1
        while lines[last].rstrip().endswith("&"):
            last += 1
        insertions.append((last + 1 - (start - 1), _added(beside)))
    for position, added in sorted(insertions, key=lambda x: x[0], reverse=True):
        body = body[:position] + added + body[position:]
    text = "\n".join(header + body + footer)
    return Prepared(text if text.endswith("\n") else text + "\n", header + beside + block + footer, notes)


def _added(block: list[str]) -> list[str]:
    """Lines prepare adds, between the comments that mark them."""
    return (
        [
            "",
            f"{PREPARED_MARK}: the contact output demsplit reads (docs/liggghts-output.md) ---",
            *block,
            "# --- end of the lines added by demsplit ---",
            "",
        ]
        if block
        else []
    )


def _local(kind: str, cid: str, keywords: list[str], history: list[str], every: int, suffix: str = "") -> list[str]:
    """A granular local compute and the full-precision ``dump local`` of all its columns."""
    width = len(local_layout(kind, keywords, len(history), history=history))
    name = f"ds_pairs{suffix}.txt" if kind == "pair" else f"ds_walls{suffix}.txt"
    columns = " ".join(f"c_{cid}[{k}]" for k in range(1, width + 1))
    return [
        f"compute {cid} all {kind}/gran/local {' '.join(keywords)}",
        f"dump d{cid} all local {every} {name} {columns}",
        f'dump_modify d{cid} format "{" ".join(["%.17g"] * width)}"',
    ]
