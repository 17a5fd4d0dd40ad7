"""A LIGGGHTS run: the input script plus its dumps, assembled into Frames.

:class:`LiggghtsRun` reads the script (:mod:`.liggghts_script`) for the
materials, the contact model, the walls and the meaning of every contact-dump
column, then joins per timestep

* the atom dump (``dump custom``: ids, types, positions, radii, masses),
* the pair contact dump (``dump local`` of ``compute pair/gran/local``),
* the mesh-wall contact dump (``dump local`` of ``compute wall/gran/local``),
* the primitive-wall contacts, rebuilt from positions (LIGGGHTS never dumps
  them; :mod:`demsplit.readers.liggghts_walls`),

into one :class:`~demsplit.frame.Frame` (the join: :mod:`demsplit.readers.liggghts_join`).

Dump files are the ones the script's ``dump`` lines write (a ``.gz``, ``.bz2``
or ``.xz`` copy is found too) unless given as ``atoms=``, ``contacts=``,
``walls=``. Column names of a contact dump come from its own header
(``c_ID[k]``) mapped through that compute's layout in the script.
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import DemsplitError, InputFormatError
from ..frame import Frame, describe_steps
from ..physics.laws import simulator_words
from ..scene import Material, Scene
from .base import ATOMS, CONTACTS, MATERIALS, OVERLAP_TOLERANCE, VARIABLES, Option, Run
from .dump_series import DumpSeries, series_files
from .lammps_dump import HEADER_LINES, DumpFile, DumpFrame, open_dump
from .liggghts_join import ATOM_COLUMNS, PRIMITIVE_HISTORY_UNKNOWN, StepJoin
from .liggghts_script import COMPRESSED_SUFFIXES, TANGENTIAL, DumpSpec, LiggghtsScript, read_script
from .liggghts_vtk import vtk_dump_note
from .liggghts_wallforce import BALANCE_COLUMNS, WallForce, stored_force_columns, wall_force_of

DEFAULT_OVERLAP_TOLERANCE = 1e-3
"""Largest accepted relative error bound of an overlap recomputed from printed positions."""

PREPARED_MARK = "# --- added by 'demsplit prepare'"
"""How the lines ``demsplit prepare`` adds to a script begin (:mod:`demsplit.prepare`): a script holding it is
prepared, and a missing dump of it is one LIGGGHTS has not written yet, not one to add."""
_LOCAL_TOKEN = re.compile(r"^c_(\w+)\[(\d+)\]$")


def existing_file(path: str | Path) -> Path | None:
    """``path`` if it exists, else its compressed copy (.gz/.bz2/.xz), else None."""
    path = Path(path)
    for candidate in (path, *(path.with_name(path.name + s) for s in COMPRESSED_SUFFIXES)):
        if candidate.is_file():
            return candidate
    return None


def scene_script(
    *,
    materials: dict[int, Material],
    contacts: Path,
    walls: Path | None = None,
    columns: str | None = None,
    wall_columns: str | None = None,
    wall_type: int | None = None,
    model: str = "hertz",
    tangential: str = "history",
    characteristic_velocity: float | None = None,
    boundary: str = "f f f",
) -> str:
    """The LIGGGHTS input script equivalent to a scene given on the command line.

    Without the run's own script, demsplit still needs its facts: the
    materials (``--material TYPE:E:NU``, types 1..N), the contact model, and
    the keywords of the computes whose ``dump local`` files are read
    (``--columns``, ``--wall-columns``, e.g. ``"pos id delta history"``). They
    are written as the script lines LIGGGHTS would have read, so the one script
    parser serves both ways in. Primitive walls cannot be given this way (their
    contacts are not rebuilt, and a note says so).
    """
    missing = []
    if not materials:
        missing.append("the materials (--material TYPE:E:NU for every type)")
    if columns is None:
        missing.append(f"the keywords of the compute pair/gran/local that wrote {contacts} (--columns)")
    if walls is not None and (wall_columns is None or wall_type is None):
        missing.append(
            f"the keywords of the compute wall/gran/local that wrote {walls} (--wall-columns) "
            "and the mesh walls' material type (--wall-type)"
        )
    if missing:
        raise InputFormatError(
            "without the run's input script demsplit cannot know " + "; ".join(missing) + ".",
            file=contacts,
            fix="pass the LIGGGHTS input script that made the run, or give those options.",
        )
    ntypes = max(max(materials), wall_type or 0)
    absent = sorted(set(range(1, ntypes + 1)) - set(materials))
    if absent:
        raise InputFormatError(
            f"types {absent} have no material (types run from 1 to {ntypes}).",
            fix="give --material TYPE:E:NU for every type, walls included.",
        )

    def compute_id(path: Path) -> str:
        token = next((t for t in open_dump(path).columns or [] if _LOCAL_TOKEN.match(t)), None)
        if token is None:
            raise InputFormatError(
                "the contact dump's header names no c_ID[k] column.",
                file=path,
                fix="dump the compute's columns (dump ID all local N FILE c_ID[1] ...).",
            )
        return _LOCAL_TOKEN.match(token).group(1)

    E = " ".join(repr(materials[t].E) for t in range(1, ntypes + 1))
    nu = " ".join(repr(materials[t].nu) for t in range(1, ntypes + 1))
    lines = [
        "# demsplit: the scene given on the command line, as the script lines LIGGGHTS reads",
        "units si",
        f"boundary {boundary}",
        f"create_box {ntypes} domain",
        f"fix m1 all property/global youngsModulus peratomtype {E}",
        f"fix m2 all property/global poissonsRatio peratomtype {nu}",
    ]
    if characteristic_velocity is not None:
        lines.append(f"fix m3 all property/global characteristicVelocity scalar {characteristic_velocity!r}")
    lines += [
        f"pair_style gran model {model} tangential {tangential}",
        f"compute {compute_id(contacts)} all pair/gran/local {columns}",
    ]
    if walls is not None:
        lines += [
            f"fix mesh all mesh/surface file mesh.stl type {wall_type}",
            f"fix wmesh all wall/gran model {model} tangential {tangential} mesh n_meshes 1 meshes mesh",
            f"compute {compute_id(walls)} all wall/gran/local {wall_columns}",
        ]
    return "\n".join(lines) + "\n"


MESH_WALL_NOT_DUMPED = (
    "no dump holds its contacts (LIGGGHTS writes them only with 'compute ID all wall/gran/local' placed after "
    "the wall's fix wall/gran and before the first run, and a 'dump local' of it). 'demsplit prepare SCRIPT' "
    "writes a copy of the script with these lines, split with write_restart/read_restart where the wall fix comes "
    "after a run; or add, e.g.: 'compute cwall all wall/gran/local id pos force delta history' and 'dump dwall "
    "all local N wall.txt c_cwall[1] c_cwall[2] ...' (docs/liggghts-output.md)"
)
"""Why a mesh wall's contacts are missing when the run has no wall dump (:attr:`demsplit.scene.Wall.missing`)."""

MESH_WALL_NOT_LAST = (
    "LIGGGHTS' compute wall/gran/local writes the contacts of the last mesh 'fix wall/gran' of the script only, "
    "and this wall belongs to an earlier one. Give all mesh walls to one fix wall/gran ('mesh n_meshes K meshes "
    "m1 m2 ...') so that one wall dump holds them all"
)
"""Why a mesh wall's contacts are missing when it is not in the last mesh ``fix wall/gran``."""


def _candidates(script: LiggghtsScript, kind: str) -> list:
    """The script's dumps of one kind, full precision first; of the atom dumps, those with more of the columns the
    rebuilding of the primitive walls' history reads (:func:`force_route_columns`) first among them."""
    if kind == "atoms":
        specs = [d for d in script.dumps if d.style == "custom" and all(c in d.keywords for c in ATOM_COLUMNS)]
        wanted = force_route_columns(script)
        return sorted(specs, key=lambda d: (not d.full_precision, -len(set(wanted) & set(d.keywords))))
    specs = [d for d in script.dumps if d.layout is not None and d.layout.kind == kind]
    return sorted(specs, key=lambda d: not d.full_precision)


def force_route_columns(script: LiggghtsScript) -> list[str]:
    """The atom-dump columns that let a run's primitive-wall contacts be rebuilt from their stored forces
    (:mod:`.liggghts_wallforce`): none without a primitive wall fix with ``store_force yes``."""
    if not script.stored_force:
        return []
    return [
        *BALANCE_COLUMNS,
        *(c for fix in dict.fromkeys(script.stored_force.values()) for c in stored_force_columns(fix)),
    ]


def _series(script: LiggghtsScript, spec) -> DumpSeries | None:
    """The dump of ``spec`` when it writes one file per timestep (``*``; see
    :mod:`demsplit.readers.dump_series`), None for a single file or when no file matches;
    one file per processor (``%``) is refused."""
    name = Path(spec.file).name
    if "%" in name:
        raise InputFormatError(
            f"dump {spec.id} writes one file per processor ({spec.file}), so each frame is split over "
            "several files; demsplit reads a frame from one file.",
            file=script.path,
            fix="write the dump without '%' in its file name (one file, or one per timestep with '*').",
        )
    if "*" not in name:
        return None
    files = series_files(spec.file)
    return DumpSeries(spec.file, files, columns=spec.keywords if spec.style == "custom" else None) if files else None


def _open_atoms(script: LiggghtsScript, given) -> tuple[DumpFile, DumpSpec | None]:
    """The atom dump, opened, and the script's dump line that writes it (None: a file given that no line
    of the script names)."""
    if given is not None:
        path = existing_file(given)
        if path is None:
            raise InputFormatError("atom dump not found.", file=given, fix="check the --atoms path.")
        spec = next((d for d in _candidates(script, "atoms") if existing_file(d.file) == path), None)
        return open_dump(path, columns=spec.keywords if spec else None), spec
    for spec in _candidates(script, "atoms"):
        if (series := _series(script, spec)) is not None:
            return series, spec
        path = existing_file(spec.file)
        if path is not None:
            return open_dump(path, columns=spec.keywords), spec
    if _candidates(script, "atoms"):
        raise _not_written(script, _candidates(script, "atoms"), "atoms")
    raise InputFormatError(
        "no atom dump found: the script has no 'dump ... custom' with id type x y z radius whose file exists."
        + vtk_dump_note(script.dumps),
        file=script.path,
        fix="'demsplit prepare SCRIPT' writes a copy of the script with the dumps demsplit reads; or add "
        "'dump D all custom N atoms.txt id type x y z radius mass' to the script, or pass --atoms FILE.",
    )


def _open_local(script: LiggghtsScript, given, kind: str) -> DumpFile | None:
    if given is not None:
        path = existing_file(given)
        if path is None:
            raise InputFormatError(
                f"{kind} contact dump not found.",
                file=given,
                fix=f"check the --{'contacts' if kind == 'pair' else 'walls'} path.",
            )
        return open_dump(path)
    for spec in _candidates(script, kind):
        if (series := _series(script, spec)) is not None:
            return series
        path = existing_file(spec.file)
        if path is not None:
            return open_dump(path)
    if kind == "pair" and _candidates(script, kind):
        raise _not_written(script, _candidates(script, kind), "contacts")
    if kind == "pair":
        raise InputFormatError(
            "no pair contact dump found: the script has no 'dump ... local' of a compute pair/gran/local "
            "whose file exists." + vtk_dump_note(script.dumps),
            file=script.path,
            fix="'demsplit prepare SCRIPT' writes a copy of the script with the dumps demsplit reads; or add "
            "'compute cpgl all pair/gran/local id pos delta history' and "
            "'dump dc all local N pairs.txt c_cpgl[1] ...' to the script, or pass --contacts FILE.",
        )
    return None


def _not_written(script: LiggghtsScript, specs: list[DumpSpec], option: str) -> InputFormatError:
    """The error of a script whose dump lines for a table exist but none of whose files does: LIGGGHTS has not
    run it here yet (a script ``demsplit prepare`` wrote, typically), so the fix is to run it, not to add dumps."""
    path = Path(script.path)
    files = ", ".join(f"{os.path.relpath(d.file, path.parent)} (dump {d.id})" for d in specs)
    prepared = PREPARED_MARK in path.read_text(encoding="utf-8", errors="replace")
    return InputFormatError(
        f"the script {'is prepared for demsplit' if prepared else 'has the dumps demsplit reads'} but its "
        f"{'atom' if option == 'atoms' else 'pair contact'} dump does not exist yet: {files} not found in "
        f"{path.parent}. LIGGGHTS has not run this script here.",
        file=path,
        fix=f"run it first (cd {path.parent} && liggghts -in {path.name}), then demsplit again; "
        f"or pass --{option} FILE where the dump was written elsewhere.",
    )


def _open_dumps(
    script: LiggghtsScript, atoms, contacts, walls
) -> tuple[DumpFile, DumpFile, DumpFile | None, DumpSpec | None]:
    """The atom, pair contact and mesh-wall contact dumps of the run (given, else the script's, full precision
    first), opened (their first headers read) but not indexed, and the atom dump's line in the script."""
    atom_dump, spec = _open_atoms(script, atoms)
    return atom_dump, _open_local(script, contacts, "pair"), _open_local(script, walls, "wall"), spec


def walls_present(script: LiggghtsScript, dump: DumpSpec | None, step: int) -> tuple[int, ...] | None:
    """The indices of the scene's walls that exist when ``dump`` (None: a dump from the first run on) wrote
    its frame of timestep ``step``; None when every wall exists in every run.

    A frame is written by the first run of the dump's (from the run before which the dump line stands)
    whose timesteps hold ``step``: a step at the end of one run and the start of the next was written at
    the end of the first, before the lines between them (a wall fix, an ``unfix``) took effect. A wall
    exists in the runs from its fix line to its ``unfix`` line."""
    if all(first == 0 and end is None for first, end in script.wall_runs):
        return None
    first = dump.first_run if dump is not None else 0
    runs = [k for k, (start, end) in enumerate(script.runs) if k >= first and start <= step <= end]
    if not runs:  # not a step of this script's runs: the walls of the last run
        runs = [len(script.runs) - 1]
    k = runs[0]
    return tuple(i for i, (start, end) in enumerate(script.wall_runs) if start <= k and (end is None or k < end))


def frame_kind(script: LiggghtsScript, dump: DumpSpec | None, step: int) -> tuple[bool | None, float | None]:
    """Whether ``dump`` (None: a dump from the first run on) wrote its frame of timestep ``step`` at the setup of a
    run, and that run's timestep (s); (None, the timestep) where the script cannot tell: a run after a
    ``read_restart``, whose timesteps the restart file sets.

    A dump writes at the setup of a run only a step it has not written yet (LIGGGHTS' ``output.cpp:229-231``): its
    first frame when it is defined between runs, or the first step of its first run; the step where one of its runs
    ends and the next starts was written at the end of the first (mid-run)."""
    first = dump.first_run if dump is not None else 0
    runs = [k for k, (start, end) in enumerate(script.runs) if k >= first and start <= step <= end]
    if not runs or (script.restart_run is not None and runs[0] >= script.restart_run):
        after = set(script.run_timesteps[script.restart_run or 0 :]) or {script.timestep}
        return None, after.pop() if len(after) == 1 else None
    k = runs[0]
    return step == script.runs[k][0], script.run_timesteps[k]


def _script(
    path: str | Path | None, *, variables, materials, atoms, contacts, walls, scene_options
) -> tuple[LiggghtsScript, str | None]:
    """The run's script, or without one the script equivalent to the scene given as options
    (:func:`scene_script`, whose text is returned too)."""
    if path is not None:
        if scene_options:
            raise InputFormatError(
                f"the scene options ({', '.join(sorted(scene_options))}) describe a run without "
                "its input script, and this run has one.",
                file=path,
                fix="leave them out: the script says what they would.",
            )
        return read_script(path, variables), None
    if atoms is None or contacts is None:
        raise InputFormatError(
            "without an input script, the atom and pair contact dumps must be given.",
            fix="pass --atoms FILE and --contacts FILE (or the input script).",
        )
    text = scene_script(
        materials=materials or {},
        contacts=Path(contacts),
        walls=None if walls is None else Path(walls),
        **(scene_options or {}),
    )
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "in.demsplit").write_text(text)
        return read_script(Path(tmp) / "in.demsplit"), text


class LiggghtsRun(Run):
    """A LIGGGHTS run opened for reading (see the module docstring)."""

    format_name = "liggghts"
    simulator = "liggghts"
    formats = (
        "a LIGGGHTS input script (its dumps found from its dump lines, or given as options)",
        "LIGGGHTS dumps given as options (atoms=, contacts=) with the scene as options",
    )
    priority = -10  # any text file that no other reader claims is taken for a script
    cli_group = "LIGGGHTS inputs (default: the files the script's dump lines write)"
    cli_options = (
        ATOMS,
        CONTACTS,
        Option("walls", ("--walls",), "mesh-wall contact dump (dump local of compute wall/gran/local)"),
        VARIABLES,
        MATERIALS,
        OVERLAP_TOLERANCE,
        Option(
            "force_positions",
            ("--force-positions",),
            "recompute overlaps from printed positions even above the tolerance (reported)",
            {"action": "store_true"},
        ),
        *(
            Option(
                name,
                flags,
                help,
                kwargs,
                into="scene_options",
                group="LIGGGHTS without an input script (the scene from these options)",
            )
            for name, flags, help, kwargs in (
                (
                    "columns",
                    ("--columns",),
                    'keywords of the compute pair/gran/local behind --contacts, e.g. "pos id delta history"',
                    {"metavar": "KEYWORDS"},
                ),
                (
                    "wall_columns",
                    ("--wall-columns",),
                    "keywords of the compute wall/gran/local behind --walls",
                    {"metavar": "KEYWORDS"},
                ),
                (
                    "wall_type",
                    ("--wall-type",),
                    "material type of the mesh walls (LIGGGHTS) or of the wall, facet and box bodies (YADE VTK)",
                    {"type": int, "metavar": "T"},
                ),
                (
                    "model",
                    ("--model",),
                    "pair_style gran model (default hertz)",
                    {"choices": tuple(simulator_words("liggghts"))},
                ),
                ("tangential", ("--tangential",), "tangential model (default history)", {"choices": TANGENTIAL}),
                (
                    "characteristic_velocity",
                    ("--characteristic-velocity",),
                    "for model hooke (m/s)",
                    {"type": float, "metavar": "V"},
                ),
                (
                    "boundary",
                    ("--boundary",),
                    'boundary as in the script, e.g. "p p f" (default "f f f")',
                    {"metavar": '"X Y Z"'},
                ),
            )
        ),
    )

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is None or (path.is_file() and b"\0" not in head and b"ITEM: TIMESTEP" not in head)

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """The script's scene and dumps, without reading the dumps."""
        script = read_script(path)
        scene = script.scene
        lines = [
            f"{path}: LIGGGHTS input script",
            f"  model:    {scene.model.describe()}",
            f"  timestep: {script.timestep} s; periodic {list(script.periodic)}",
            "  materials: " + ", ".join(f"{t}: E={m.E:g} Pa nu={m.nu:g}" for t, m in sorted(scene.materials.items())),
            "  walls:    " + (", ".join(f"{w.name} ({w.kind}, type {w.type})" for w in scene.walls) or "none"),
            "  dumps:",
        ]
        for d in script.dumps:
            what = d.layout.kind + " contacts" if d.layout is not None else d.style
            lines.append(
                f"    {d.id:<10} {what:<15} every {d.every:<7} {d.file}"
                f"  ({'full precision' if d.full_precision else 'printed precision'})"
            )
        lines += [f"  warning: {w}" for w in script.warnings]
        return "\n".join(lines)

    def __init__(
        self,
        script: str | Path | None,
        *,
        atoms: str | Path | None = None,
        contacts: str | Path | None = None,
        walls: str | Path | None = None,
        variables: dict[str, str] | None = None,
        materials: dict[int, Material] | None = None,
        overlap_tolerance: float | None = None,
        force_positions: bool = False,
        scene_options: dict | None = None,
    ) -> None:
        self.script, self.script_text = _script(
            script,
            variables=variables,
            materials=materials,
            atoms=atoms,
            contacts=contacts,
            walls=walls,
            scene_options=scene_options,
        )
        base = self.script.scene
        if materials and script is not None:  # without a script the materials are the scene's already
            base = Scene({**base.materials, **materials}, base.model, base.walls, base.units, base.source)
        self.overlap_tolerance = DEFAULT_OVERLAP_TOLERANCE if overlap_tolerance is None else overlap_tolerance
        self.force_positions = force_positions
        self.atoms, self.pairs, self.walls, self._atom_spec = _open_dumps(self.script, atoms, contacts, walls)
        self._pair_names = self._local_names(self.pairs, "pair")
        self._wall_names = self._local_names(self.walls, "wall")
        self.notes: list[str] = list(self.script.warnings)
        dumped = set(self.script.dumped_mesh_walls) if self.walls is not None else set()
        self.scene = replace(
            base,
            walls=[
                w
                if w.kind != "mesh" or i in dumped
                else replace(w, missing=MESH_WALL_NOT_DUMPED if self.walls is None else MESH_WALL_NOT_LAST)
                for i, w in enumerate(base.walls)
            ],
        )
        self._refuse_wall_columns_apart()
        if script is None:
            self.notes.append(
                "no input script: primitive walls (never dumped by LIGGGHTS) are unknown, "
                "so contacts with them are not included"
            )
        self.wall_force, primitive_note = self._wall_force(dumped)
        for dump in (self.atoms, self.pairs, self.walls):
            if dump is not None:
                _refuse_repeated_steps(dump)
        self.steps = np.asarray(self.atoms.steps, dtype=np.int64)
        self.damaged = self.atoms.damaged  # atom frames whose header is unreadable: frames len(steps)...
        self.sources = ([] if script is None else [self.script.path]) + [
            f for d in (self.atoms, self.pairs, self.walls) if d is not None for f in getattr(d, "files", [d.path])
        ]
        self.join = StepJoin(
            self.scene,
            self.script.periodic,
            self.script.timestep,
            self._atom_columns(),
            self._pair_names,
            self._wall_names,
            self._law_columns(),
            list(self.script.dumped_mesh_walls),
            self.walls is not None,
            self.overlap_tolerance,
            self.force_positions,
            self.wall_force,
            primitive_note,
        )

    def _wall_force(self, dumped: set[int]) -> tuple[WallForce | None, str]:
        """The rebuilding of the primitive walls' history from their stored forces (None where the run does not
        allow it) and the note that says what becomes of that history."""
        if self.script_text is not None:
            return None, PRIMITIVE_HISTORY_UNKNOWN
        route, why = wall_force_of(self.script, self.scene, dumped)
        columns = set(self.atoms.columns or [])
        if route is not None:  # a wall whose force the atom dump lacks stays unknown, as one without store_force
            route.stored = {k: fix for k, fix in route.stored.items() if set(stored_force_columns(fix)) <= columns}
            missing = [c for c in BALANCE_COLUMNS if c not in columns]
            if missing or not route.stored:
                route, why = None, f"the atom dump lacks the columns {missing or 'f_force_<ID>[1..3]'}"
        if route is None:
            return (
                None,
                f"{PRIMITIVE_HISTORY_UNKNOWN} Their fixes' stored forces cannot stand in for it: {why} "
                "('demsplit prepare' adds store_force yes and the columns; docs/liggghts-output.md).",
            )
        names = [self.scene.walls[k].name for k in route.stored]
        rest = [
            w.name for k, w in enumerate(self.scene.walls) if w.kind in ("plane", "cylinder") and k not in route.stored
        ]
        note = (
            f"the history of the primitive-wall contacts of {', '.join(names)} (tangential and rolling springs, "
            "elasto-plastic normal state) is rebuilt from each wall fix's stored force (store_force yes), checked "
            "by every particle's force and torque balance; where it cannot be, it is NOT COMPUTED and a note says "
            "why (docs/liggghts-output.md)"
        )
        if rest:
            note += (
                f"; the walls {', '.join(rest)} have no stored force in the atom dump (store_force yes and its "
                f"f_force_<ID> columns): {PRIMITIVE_HISTORY_UNKNOWN}"
            )
        return route, note

    @classmethod
    def first_frame_rows(
        cls,
        path: Path | None,
        *,
        atoms: str | Path | None = None,
        contacts: str | Path | None = None,
        walls: str | Path | None = None,
        variables: dict[str, str] | None = None,
        materials: dict[int, Material] | None = None,
        scene_options: dict | None = None,
        **_: object,
    ) -> tuple[int, int] | None:
        """The first frame's particles and contacts from the first header of each dump (the script read
        again, the dumps not indexed); None when they cannot be found (the opening says why)."""
        try:
            script, _text = _script(
                path,
                variables=variables,
                materials=materials,
                atoms=atoms,
                contacts=contacts,
                walls=walls,
                scene_options=scene_options,
            )
            dumps = _open_dumps(script, atoms, contacts, walls)
        except DemsplitError:
            return None
        return dumps[0].head_rows, sum(d.head_rows for d in dumps[1:3] if d is not None)

    def named_files(self) -> list[Path]:
        """The files read, and every other file the script names (:meth:`LiggghtsScript.named_files`)."""
        files = [Path(s) for s in self.sources]
        if self.script_text is not None:  # no script of the user's: the dumps given are the run
            return files
        return files + self.script.named_files()

    def _local_names(self, dump: DumpFile | None, kind: str) -> dict[str, str]:
        """Canonical name -> header token for every column of a local dump, from
        the header's ``c_ID[k]`` through compute ID's layout in the script."""
        if dump is None:
            return {}
        names: dict[str, str] = {}
        # the column names are those of the first frame's header (its line HEADER_LINES)
        where = {"file": dump.path, "step": int(dump.steps[0]) if len(dump.steps) else None, "line": HEADER_LINES}
        for token in dump.columns or []:
            m = _LOCAL_TOKEN.match(token)
            if m is None:
                continue  # 'index' or another non-compute column
            cid, k = m.group(1), int(m.group(2))
            layout = self.script.local_computes.get(cid)
            if layout is None:
                raise InputFormatError(
                    f"column {token} reads compute '{cid}', which the script does not define.",
                    **where,
                    fix="pass the input script that wrote this dump.",
                )
            if layout.kind != kind:
                raise InputFormatError(
                    f"this dump holds {layout.kind} contacts (compute {cid}), given as the {kind} contact dump.",
                    **where,
                    fix="swap --contacts and --walls.",
                )
            if k > len(layout.columns):
                raise InputFormatError(
                    f"column {token} is beyond the {len(layout.columns)} columns compute {cid} writes "
                    "with the keywords in the script.",
                    **where,
                    fix="pass the input script that wrote this dump (its compute keywords decide the columns).",
                )
            names[layout.columns[k - 1]] = token
        required = ("id1", "id2") if kind == "pair" else ("id1", "mesh_index")
        missing = [c for c in required if c not in names]
        if missing:
            raise InputFormatError(
                f"the {kind} contact dump lacks the columns {missing} (its compute needs the 'id' keyword).",
                **where,
                fix="add 'id' to the compute's keywords and dump all its columns.",
            )
        return names

    # -- frames ------------------------------------------------------------------------------

    def __len__(self) -> int:
        return len(self.steps) + len(self.damaged)

    def frame(self, k: int) -> Frame:
        """Frame ``k``: the k-th readable atom frame; ``k >= len(steps)`` raises the
        error of the (k - len(steps))-th damaged atom frame header, so that a
        damaged frame is stopped at or listed as skipped, never silently lost."""
        if k >= len(self.steps):
            raise self.damaged[k - len(self.steps)]
        step = int(self.steps[k])
        af = self.atoms.frame(k, columns=self._atom_columns())
        pf = self._local_at(self.pairs, step, self._pair_names)
        wf = self._local_at(self.walls, step, self._wall_names) if self.walls is not None else None
        return self.join.frame(
            af,
            pf,
            wf,
            walls_present(self.script, self._atom_spec, step),
            frame_kind(self.script, self._atom_spec, step),
        )

    def __iter__(self) -> Iterator[Frame]:
        """Stream the three dumps side by side (one decompression each)."""
        pairs = self._stream(self.pairs, self._pair_names)
        walls = self._stream(self.walls, self._wall_names) if self.walls is not None else None
        for af in self.atoms.frames(columns=self._atom_columns()):
            pf = self._advance(pairs, af.step, self.pairs)
            wf = self._advance(walls, af.step, self.walls) if walls is not None else None
            yield self.join.frame(
                af,
                pf,
                wf,
                walls_present(self.script, self._atom_spec, af.step),
                frame_kind(self.script, self._atom_spec, af.step),
            )

    def _atom_columns(self) -> list[str]:
        cols = list(ATOM_COLUMNS)
        models = [self.scene.model] + [w.model for w in self.scene.walls if w.model is not None]
        for model in models:  # what the laws need of the particles (mass for hooke, the liquid content of bridges)
            cols += [c for c in model.contact_law.particle_columns if c not in cols]
        if self.wall_force is not None:  # the particles' balance and the stored forces
            cols += [c for c in self.wall_force.particle_columns() if c not in cols]
        missing = [c for c in cols if c not in (self.atoms.columns or [])]
        if missing:
            raise InputFormatError(
                f"the atom dump lacks the columns {missing}.",
                file=self.atoms.path,
                fix="add them to the 'dump ... custom' line.",
            )
        return cols

    def _refuse_wall_columns_apart(self) -> None:
        """The mesh-wall contacts join the pair contacts in one table: a law column (a history) the pair dump
        holds, the law of a dumped mesh wall reads and the wall dump does not hold is refused, naming the wall
        dump's header (it was a KeyError). A column only the pairs' law reads (a mesh wall whose fix has no
        rolling friction, say) is not needed of the wall: :meth:`_mesh_walls` gives its rows 0 there."""
        if self.walls is None:
            return
        wall_reads = self._mesh_wall_law_columns()
        missing = [
            c for c in self._law_columns() if c in self._pair_names and c not in self._wall_names and c in wall_reads
        ]
        if missing:
            raise InputFormatError(
                f"the wall contact dump has no column for {', '.join(missing)}, which the law reads and the pair "
                f"dump holds: its header names {len(self.walls.columns or [])} columns, its compute's keywords "
                "differ from the pair compute's, or the header is damaged.",
                file=self.walls.path,
                step=int(self.walls.steps[0]) if len(self.walls.steps) else None,
                line=HEADER_LINES,
                fix="give the wall compute the pair compute's keywords and dump all its columns; check the header.",
            )

    def _mesh_wall_law_columns(self) -> set[str]:
        """Contact columns the laws of the dumped mesh walls read (each wall's own model, else the scene's)."""
        models = [self.scene.walls[i].model or self.scene.model for i in self.script.dumped_mesh_walls]
        return {c for model in models for c in model.contact_law.needs()}

    def _law_columns(self) -> list[str]:
        """Contact columns the scene's laws read (the tangential history, ...), in their order."""
        columns: list[str] = []
        for model in [self.scene.model] + [w.model for w in self.scene.walls if w.model is not None]:
            columns += [c for c in model.contact_law.needs() if c not in columns]
        return columns

    def _wanted(self, names: dict[str, str]) -> list[str]:
        """Dump tokens of the contact columns the join needs and the laws read."""
        keep = ["id1", "id2", "mesh_index", "tri_id", "delta", "cpx", "cpy", "cpz", "wall_cpx", "wall_cpy", "wall_cpz"]
        if self.wall_force is not None:  # a pair across a periodic boundary is applied from each side
            keep.append("periodic")
        keep += [c for c in self._law_columns() if c not in keep]
        return [names[c] for c in keep if c in names]

    def _local_at(self, dump: DumpFile, step: int, names: dict[str, str]) -> DumpFrame:
        if step not in set(int(s) for s in dump.steps):
            damaged = dump.damaged
            raise InputFormatError(
                f"the contact dump has no frame at timestep {step}, which the atom dump has"
                + (
                    f"; it has {len(damaged)} frame(s) with a damaged header, the first: {damaged[0]}"
                    if damaged
                    else "."
                ),
                file=dump.path,
                step=step,
                fix="write the atom and contact dumps every N steps with the same N (dump ... N ...)."
                if not damaged
                else "repair or rewrite the contact dump.",
            )
        return dump.frame_at_step(step, columns=self._wanted(names))

    def _stream(self, dump: DumpFile, names: dict[str, str]) -> Iterator[DumpFrame]:
        return iter(dump.frames(columns=self._wanted(names)))

    @staticmethod
    def _advance(stream: Iterator[DumpFrame], step: int, dump: DumpFile) -> DumpFrame:
        for f in stream:
            if f.step == step:
                return f
            if f.step > step:
                break
        raise InputFormatError(
            f"the contact dump has no frame at timestep {step}, which the atom dump has.",
            file=dump.path,
            step=step,
            fix="write the atom and contact dumps every N steps with the same N (dump ... N ...).",
        )

    # -- description -------------------------------------------------------------------------

    def describe(self) -> dict:
        """Files, kinds and precision, for provenance and ``demsplit check``."""

        def info(d):
            return None if d is None else {"path": str(d.path), "frames": len(d.steps)}

        return {
            "kind": "liggghts",
            "script": self.script_text or str(self.script.path),
            "atoms": info(self.atoms),
            "pairs": info(self.pairs),
            "walls": info(self.walls),
            "model": {"law": self.scene.model.law, "params": self.scene.model.params},
            "overlap_tolerance": self.overlap_tolerance,
            "force_positions": self.force_positions,
            "notes": self.notes,
        }

    def check_files(self, out: list[str]) -> list[str]:
        """The dumps, their frames, the timesteps the atom and contact dumps share, damaged headers."""
        problems = []
        for name, dump in (("atoms", self.atoms), ("pairs", self.pairs), ("walls", self.walls)):
            if dump is None:
                out.append(f"  {name + ':':<10} none")
                continue
            steps = dump.steps
            out.append(f"  {name + ':':<10} {dump.path} ({len(steps)} frames, steps {describe_steps(steps)})")
            if dump is not self.atoms:
                problems += [str(err) for err in dump.damaged]
                missing = np.setdiff1d(self.steps, steps)
                extra = np.setdiff1d(steps, self.steps)
                if len(missing):
                    problems.append(
                        str(
                            InputFormatError(
                                f"{len(missing)} timestep(s) of the atom dump have no frame here, e.g. "
                                f"{missing[:5].tolist()}.",
                                file=dump.path,
                                step=int(missing[0]),
                                fix="write the atom and contact dumps every N steps with the same N.",
                            )
                        )
                    )
                if len(extra):
                    problems.append(
                        str(
                            InputFormatError(
                                f"{len(extra)} frame(s) have no atom frame and would be ignored, e.g. steps "
                                f"{extra[:5].tolist()}.",
                                file=dump.path,
                                step=int(extra[0]),
                                fix="write the atom and contact dumps every N steps with the same N.",
                            )
                        )
                    )
        return problems

    def locate(self, frame: Frame, row: int) -> tuple[str | None, int | None]:
        """Contact rows are pair rows, then mesh-wall rows, then primitive-wall rows rebuilt from
        positions (those have the atom dump and no line)."""
        offset = 0
        for dump in (self.pairs, self.walls):
            if dump is None:
                continue
            k = int(np.flatnonzero(dump.steps == frame.step)[0])
            n = int(dump.rows[k])
            if row < offset + n:
                f = dump.frame(k, columns=dump.columns[:1])
                return str(dump.path), f.line_of(row - offset)
            offset += n
        return str(self.atoms.path), None


def _refuse_repeated_steps(dump: DumpFile) -> None:
    """A timestep written twice to one dump (a LIGGGHTS restart appending to it) is refused: which copy
    holds the run's state is the user's call, not a silent first-copy read."""
    values, counts = np.unique(dump.steps, return_counts=True)
    if np.any(counts > 1):
        raise InputFormatError(
            f"timestep(s) {values[counts > 1][:5].tolist()} appear more than once in this dump (a restart that "
            "appended to it writes its first step again).",
            file=dump.path,
            step=int(values[counts > 1][0]),
            fix="keep one copy of each timestep: cut the earlier or the later run out of the dump.",
        )
