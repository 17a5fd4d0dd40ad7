"""``demsplit prepare`` for a LAMMPS GRANULAR script: a copy that writes everything demsplit reads.

:func:`prepare_lammps_script` reads the script (:func:`demsplit.readers.lammps_script.read_lammps_script`) and
adds what it lacks (``docs/lammps-output.md``):

- ``contacts`` on every ``fix wall/gran`` and ``wall/gran/region`` line (at the end of its logical line, before a
  comment), so that the fix keeps each particle's contact in its array (the trajectory is unchanged: measured on
  the hertz_mindlin sample, every atom column identical);
- ``compute dsL all property/local patom1 patom2 ptype1 ptype2 cutoff radius`` and ``compute dsP all pair/local
  dist force fx fy fz p1 .. p12 cutoff radius`` (legacy styles: p1 .. p10) and their ``dump local`` at ``%.17g``;
- a ``%.17g`` atom dump sorted by id with ``id type x y z vx vy vz omegax omegay omegaz fx fy fz tqx tqy tqz radius
  mass`` and ``f_ID[1]`` .. ``f_ID[8]`` of every wall fix,

inserted just before the first ``run`` after the last wall fix (a dump naming a fix's columns must follow the
fix); runs before it are then not dumped, which prepare says.
"""

from __future__ import annotations

from pathlib import Path

from .errors import ScriptError
from .prepare import PREPARED_MARK, Prepared, _commands, output_interval
from .readers.lammps_input import logical_lines, read_text, strip_comment
from .readers.lammps_join import ATOM_COLUMNS
from .readers.lammps_script import LEGACY_STYLES, LammpsScript, read_lammps_script
from .readers.liggghts_script import DumpSpec

_WALL_STYLES = ("wall/gran", "wall/gran/region")


def _wall_fix_lines(path: Path) -> list[tuple[int, int, list[str]]]:
    """(first line, last physical line, words) of every wall fix command of the script file."""
    physical = path.read_text().split("\n")
    out = []
    for line, text in logical_lines(path):
        words = strip_comment(text).split()
        if len(words) > 3 and words[0] == "fix" and words[3] in _WALL_STYLES:
            last = line
            while physical[last - 1].rstrip().endswith("&"):
                last += 1
            out.append((line, last, words))
    return out


def _with_contacts(line: str) -> str:
    """A physical line with `` contacts`` after its last word (before a comment)."""
    body, hash_, comment = line.partition("#")
    return body.rstrip() + " contacts" + (" " + hash_ + comment if hash_ else "")


def _pair_dump_complete(script: LammpsScript) -> bool:
    """The script writes a full-precision pair dump of touching pairs with every quantity demsplit reads."""
    needed = {"patom1", "patom2", "dist", "force", *(f"p{k}" for k in range(1, _p_count(script) + 1))}
    for dump in script.dumps:
        if dump.style != "local" or not dump.full_precision:
            continue
        names = set()
        for token in dump.keywords:
            cid = token[2:].split("[")[0] if token.startswith("c_") else None
            compute = script.computes.get(cid)
            if compute is not None and compute.cutoff == "radius" and "[" in token:
                k = int(token.split("[")[1].rstrip("]"))
                names.add(compute.keywords[k - 1] if k <= len(compute.keywords) else "")
        if needed <= names:
            return True
    return False


def _p_count(script: LammpsScript) -> int:
    return 10 if script.pair_style in LEGACY_STYLES else 12


def _atom_columns(script: LammpsScript) -> list[str]:
    return [*ATOM_COLUMNS, *(f"f_{w.id}[{k}]" for w in script.walls for k in range(1, 9))]


def _full_atom_dump(script: LammpsScript) -> DumpSpec | None:
    """The script's full-precision atom dump with every column demsplit reads, if it has one (the pair dump
    must then be written at its timesteps)."""
    return next(
        (
            d
            for d in script.dumps
            if d.style == "custom" and d.full_precision and set(_atom_columns(script)) <= set(d.keywords)
        ),
        None,
    )


def prepare_lammps_script(path: str | Path, every: int | None = None) -> Prepared:
    """The script at ``path`` with the wall fixes' ``contacts``, the computes and the dumps demsplit needs
    (module docstring); the dumps it adds write every ``every`` steps (default: the interval of the script's
    own full-precision atom dump when it has one, else :func:`~demsplit.prepare.output_interval`)."""
    path = Path(path)
    script = read_lammps_script(path)
    lines = read_text(path).split("\n")
    runs = [line for line, text in logical_lines(path) if strip_comment(text).split()[:1] == ["run"]]
    if not runs:
        raise ScriptError(
            "the script has no 'run' command: there is nothing to dump.",
            file=path,
            fix="pass the script that runs the simulation.",
        )
    walls = _wall_fix_lines(path)
    notes, added = [], []
    for _, last, words in walls:
        if "contacts" not in words:
            lines[last - 1] = _with_contacts(lines[last - 1])
            added.append(lines[last - 1].strip())
            notes.append(
                f"walls: 'contacts' added to fix {words[1]} (its contacts array holds each particle's "
                "contact force and point)."
            )
    after = max((line for line, _, _ in walls), default=0)
    at = next((line for line in runs if line > after), None)
    if at is None:
        raise ScriptError(
            f"the wall fix on line {after} follows the last run: no run would dump its contacts.",
            file=path,
            fix="add the wall fix before a run.",
        )
    block = []
    own = _full_atom_dump(script)
    every = own.every if own is not None else output_interval(script, _commands(path), every)[0]
    if not _pair_dump_complete(script):
        p = _p_count(script)
        block += [
            "compute dsL all property/local patom1 patom2 ptype1 ptype2 cutoff radius",
            "compute dsP all pair/local dist force fx fy fz "
            + " ".join(f"p{k}" for k in range(1, p + 1))
            + " cutoff radius",
            f"dump dsPairs all local {every} ds_pairs.txt index c_dsL[1] c_dsL[2] c_dsL[3] c_dsL[4] "
            + " ".join(f"c_dsP[{k}]" for k in range(1, p + 6)),
            "dump_modify dsPairs format float %.17g",
        ]
        notes.append(
            f"pairs: computes dsL and dsP (touching pairs only) and their %.17g dump every {every} steps "
            "(ds_pairs.txt); change the interval to the output you want."
        )
    else:
        notes.append("pairs: the script's full-precision pair dump holds every quantity demsplit reads.")
    if own is None:
        block += [
            f"dump dsAtoms all custom {every} ds_atoms.txt {' '.join(_atom_columns(script))}",
            "dump_modify dsAtoms format float %.17g sort id",
        ]
        notes.append(
            f"atoms: a %.17g atom dump every {every} steps (ds_atoms.txt) with velocities, forces, torques "
            "and the wall fixes' contacts."
        )
    else:
        notes.append("atoms: the script's full-precision atom dump holds every column demsplit reads.")
    if block:
        earlier = [line for line in runs if line < at]
        if earlier:
            notes.append(
                f"the dumps start before the run on line {at}, after the last wall fix (line {after}); "
                f"the run{'s' if len(earlier) > 1 else ''} on line{'s' if len(earlier) > 1 else ''} "
                f"{', '.join(map(str, earlier))} {'are' if len(earlier) > 1 else 'is'} not dumped."
            )
        lines[at - 1 : at - 1] = [
            "",
            f"{PREPARED_MARK}: the contact output demsplit reads (docs/lammps-output.md) ---",
            *block,
            "# --- end of the lines added by demsplit ---",
            "",
        ]
        added += block
    if not added:
        return Prepared(
            read_text(path), [], notes + ["nothing to add: the script writes everything demsplit needs."], program="lmp"
        )
    text = "\n".join(lines)
    return Prepared(text if text.endswith("\n") else text + "\n", added, notes, program="lmp")
