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
- a full-precision atom dump, unless the script already writes one.

A mesh wall fix placed after the first ``run`` cannot get its contact compute
(LIGGGHTS needs it before the first run): that is an error naming the line and
the way out (split the script there with ``write_restart``/``read_restart``).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from pathlib import Path

from .errors import ScriptError
from .readers.lammps_input import logical_lines, strip_comment
from .readers.liggghts_script import LiggghtsScript, local_layout, read_script

KEYWORDS = ["pos", "vel", "id", "force", "force_normal", "force_tangential", "torque", "history", "contactArea",
            "delta", "contactPoint"]
"""Keywords of the contact computes prepare adds (``history`` dropped when the law keeps none)."""
ATOM_COLUMNS = "id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass"
DEFAULT_EVERY = 1000


@dataclass
class Prepared:
    """The prepared script's text, the lines added, and what prepare decided (one line each)."""

    text: str
    added: list[str]
    notes: list[str]

    def diff(self, original: str, name: str) -> str:
        """A unified diff from the original script to the prepared one."""
        return "".join(difflib.unified_diff(original.splitlines(True), self.text.splitlines(True),
                                            fromfile=name, tofile=f"{name} (prepared by demsplit)"))


def _commands(path: Path) -> list[tuple[int, list[str]]]:
    """(line, words) of every command of the script file itself (not of the files it includes)."""
    out = []
    for line, text in logical_lines(path):
        words = strip_comment(text).split()
        if words:
            out.append((line, words))
    return out


def _has_full_atom_dump(script: LiggghtsScript) -> int | None:
    """The ``every`` of a full-precision atom dump with what demsplit reads, or None."""
    for d in script.dumps:
        if d.style == "custom" and d.full_precision and {"id", "type", "x", "y", "z", "radius"} <= set(d.keywords):
            return d.every
    return None


def _has_local_dump(script: LiggghtsScript, kind: str, needed: set[str]) -> bool:
    """A full-precision ``dump local`` of a ``kind`` compute holding the ``needed`` columns."""
    return any(d.layout is not None and d.layout.kind == kind and d.full_precision and needed <= set(d.layout.columns)
               for d in script.dumps)


def prepare_script(path: str | Path) -> Prepared:
    """The script at ``path`` with the computes and dumps demsplit needs (module docstring)."""
    path = Path(path)
    script = read_script(path)
    scene = script.scene
    law = scene.model.contact_law
    history = law.history_columns()  # a LIGGGHTS law (the script reader maps only LIGGGHTS models)
    keywords = [k for k in KEYWORDS if k != "history" or history]
    needed = {"id1", "id2", "delta", *law.needs()}
    mesh = [w for w in scene.walls if w.kind == "mesh"]
    commands = _commands(path)
    runs = [line for line, words in commands if words[0] == "run"]
    if not runs:
        raise ScriptError("the script has no 'run' command: there is nothing to dump.", file=path,
                          fix="pass the script that runs the simulation.")
    first_run = runs[0]
    wall_fixes = [line for line, words in commands
                  if words[0] == "fix" and len(words) > 3 and words[3] == "wall/gran" and "mesh" in words]
    late = [line for line in wall_fixes if line > first_run]
    if late:
        raise ScriptError(
            f"the mesh wall fix on line {late[0]} comes after the first 'run' (line {first_run}); LIGGGHTS accepts "
            "'compute wall/gran/local' only after the wall's fix and before the first run, so this run cannot dump "
            "its mesh-wall contacts as written.", file=path, line=late[0],
            fix="split the script at that fix: end the first part with 'write_restart part1.restart'; start the "
                "second with 'read_restart part1.restart', the same settings (pair_style, property/global fixes, "
                "mesh and wall fixes), then the wall fix and 'demsplit prepare' the second part.")
    notes, block = [], []
    every = _has_full_atom_dump(script)
    if every is None:
        every = DEFAULT_EVERY
        block += [f"dump dsAtoms all custom {every} ds_atoms.txt {ATOM_COLUMNS}",
                  'dump_modify dsAtoms format "%d %d' + " %.17g" * (len(ATOM_COLUMNS.split()) - 2) + '" sort id']
        notes.append(f"atoms: a full-precision atom dump every {every} steps (ds_atoms.txt); change the interval "
                     "to the output you want.")
    else:
        notes.append(f"atoms: the script's full-precision atom dump (every {every} steps) is used.")
    if _has_local_dump(script, "pair", needed):
        notes.append("pairs: the script's full-precision pair dump holds every column the law needs.")
    else:
        block += _local("pair", "dsPair", keywords, history, every)
        width = len(local_layout("pair", keywords, len(history), history=history))
        notes.append(f"pairs: compute dsPair and a full-precision dump of its {width} columns (ds_pairs.txt).")
    if mesh and not _has_local_dump(script, "wall", needed - {"id2"}):
        block += _local("wall", "dsWall", keywords, history, every)
        notes.append(f"mesh walls ({', '.join(w.name for w in mesh)}): compute dsWall and its full-precision dump "
                     "(ds_walls.txt).")
    elif not mesh:
        notes.append("walls: no mesh wall, so no wall/gran/local compute (LIGGGHTS refuses it with primitive walls "
                     "only); primitive-wall contacts are rebuilt from positions.")
    if not block:
        return Prepared(path.read_text(), [], notes + ["nothing to add: the script writes everything demsplit needs."])
    lines = path.read_text().split("\n")
    end = first_run - 1  # just before the first run: after every fix the run has so far
    added = ["", "# --- added by 'demsplit prepare': the contact output demsplit reads (docs/liggghts-output.md) ---",
             *block, "# --- end of the lines added by demsplit ---", ""]
    text = "\n".join(lines[:end] + added + lines[end:])
    return Prepared(text, block, notes)


def _local(kind: str, cid: str, keywords: list[str], history: list[str], every: int) -> list[str]:
    """A granular local compute and the full-precision ``dump local`` of all its columns."""
    width = len(local_layout(kind, keywords, len(history), history=history))
    name = "ds_pairs.txt" if kind == "pair" else "ds_walls.txt"
    columns = " ".join(f"c_{cid}[{k}]" for k in range(1, width + 1))
    return [f"compute {cid} all {kind}/gran/local {' '.join(keywords)}",
            f"dump d{cid} all local {every} {name} {columns}",
            f'dump_modify d{cid} format "{" ".join(["%.17g"] * width)}"']

