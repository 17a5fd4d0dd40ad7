"""A LIGGGHTS run: the input script plus its dumps, assembled into Frames.

:class:`LiggghtsRun` reads the script (:mod:`.liggghts_script`) for the
materials, the contact model, the walls and the meaning of every contact-dump
column, then joins per timestep

* the atom dump (``dump custom``: ids, types, positions, radii, masses),
* the pair contact dump (``dump local`` of ``compute pair/gran/local``),
* the mesh-wall contact dump (``dump local`` of ``compute wall/gran/local``),
* the primitive-wall contacts, rebuilt from positions (LIGGGHTS never dumps
  them; :mod:`demsplit.readers.liggghts_walls`),

into one :class:`~demsplit.frame.Frame`. Geometry comes from the atom dump
(minimum image across periodic boundaries); the overlap from the best source
the run offers, chosen per run and reported (``overlap_source``):

1. the dumped ``delta`` column (%g keeps it to 5e-6 relative);
2. positions at full precision (``%.17g`` format or a binary dump);
3. positions at printed precision, only when the error bound
   sqrt(3) h / delta (h = the printed step of the coordinates) stays below
   ``overlap_tolerance`` for every contact, or when ``force_positions`` is set
   (the bound is then reported per contact); else :class:`PrecisionError`.

Dump files are the ones the script's ``dump`` lines write (a ``.gz``, ``.bz2``
or ``.xz`` copy is found too) unless given as ``atoms=``, ``contacts=``,
``walls=``. Column names of a contact dump come from its own header
(``c_ID[k]``) mapped through that compute's layout in the script.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import threads
from ..errors import ContactError, InputFormatError, MaterialError, PrecisionError
from ..frame import Box, Frame, ParticleIndex, Table, describe_steps
from ..physics.shares import contact_point
from ..scene import Material, Scene
from .base import Run, announce_first_frame
from .dump_series import DumpSeries, series_files
from .lammps_dump import HEADER_LINES, DumpFile, DumpFrame, open_dump
from .liggghts_script import read_script
from .liggghts_vtk import vtk_dump_note
from .liggghts_walls import primitive_wall_contacts
from .precision import position_error, printed_step, relative_rounding

DEFAULT_OVERLAP_TOLERANCE = 1e-3
"""Largest accepted relative error bound of an overlap recomputed from printed positions."""

ATOM_COLUMNS = ("id", "type", "x", "y", "z", "radius")
_COMPRESSED = (".gz", ".bz2", ".xz")
_LOCAL_TOKEN = re.compile(r"^c_(\w+)\[(\d+)\]$")


def existing_file(path: str | Path) -> Path | None:
    """``path`` if it exists, else its compressed copy (.gz/.bz2/.xz), else None."""
    path = Path(path)
    for candidate in (path, *(path.with_name(path.name + s) for s in _COMPRESSED)):
        if candidate.is_file():
            return candidate
    return None


def scene_script(*, materials: dict[int, Material], contacts: Path, walls: Path | None = None,
                 columns: str | None = None, wall_columns: str | None = None, wall_type: int | None = None,
                 model: str = "hertz", tangential: str = "history", characteristic_velocity: float | None = None,
                 boundary: str = "f f f") -> str:
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
        missing.append(f"the keywords of the compute wall/gran/local that wrote {walls} (--wall-columns) "
                       "and the mesh walls' material type (--wall-type)")
    if missing:
        raise InputFormatError(
            "without the run's input script demsplit cannot know " + "; ".join(missing) + ".",
            file=contacts, fix="pass the LIGGGHTS input script that made the run, or give those options.")
    ntypes = max(max(materials), wall_type or 0)
    absent = sorted(set(range(1, ntypes + 1)) - set(materials))
    if absent:
        raise InputFormatError(f"types {absent} have no material (types run from 1 to {ntypes}).",
                               fix="give --material TYPE:E:NU for every type, walls included.")

    def compute_id(path: Path) -> str:
        token = next((t for t in open_dump(path).columns or [] if _LOCAL_TOKEN.match(t)), None)
        if token is None:
            raise InputFormatError("the contact dump's header names no c_ID[k] column.", file=path,
                                   fix="dump the compute's columns (dump ID all local N FILE c_ID[1] ...).")
        return _LOCAL_TOKEN.match(token).group(1)

    E = " ".join(repr(materials[t].E) for t in range(1, ntypes + 1))
    nu = " ".join(repr(materials[t].nu) for t in range(1, ntypes + 1))
    lines = ["# demsplit: the scene given on the command line, as the script lines LIGGGHTS reads",
             "units si", f"boundary {boundary}", f"create_box {ntypes} domain",
             f"fix m1 all property/global youngsModulus peratomtype {E}",
             f"fix m2 all property/global poissonsRatio peratomtype {nu}"]
    if characteristic_velocity is not None:
        lines.append(f"fix m3 all property/global characteristicVelocity scalar {characteristic_velocity!r}")
    lines += [f"pair_style gran model {model} tangential {tangential}",
              f"compute {compute_id(contacts)} all pair/gran/local {columns}"]
    if walls is not None:
        lines += [f"fix mesh all mesh/surface file mesh.stl type {wall_type}",
                  f"fix wmesh all wall/gran model {model} tangential {tangential} mesh n_meshes 1 meshes mesh",
                  f"compute {compute_id(walls)} all wall/gran/local {wall_columns}"]
    return "\n".join(lines) + "\n"


PRIMITIVE_HISTORY_UNKNOWN = (
    "the energies that depend on a contact's history (tangential and rolling springs, elasto-plastic normal "
    "state, an easo liquid bridge across a gap) of primitive-wall contacts are NOT COMPUTED: LIGGGHTS never writes "
    "the history of primitive-wall contacts (their rows carry not_computed bits). An equivalent mesh wall (fix "
    "mesh/surface of the same plane or cylinder, with compute wall/gran/local) would give them.")
"""The note of a run whose law reads a history and which has primitive walls."""

MESH_WALL_NOT_DUMPED = (
    "no dump holds its contacts (LIGGGHTS writes them only with 'compute ID all wall/gran/local' placed after "
    "the wall's fix wall/gran and before the first run, and a 'dump local' of it). 'demsplit prepare SCRIPT' "
    "writes a copy of the script with these lines, split with write_restart/read_restart where the wall fix comes "
    "after a run; or add, e.g.: 'compute cwall all wall/gran/local id pos force delta history' and 'dump dwall "
    "all local N wall.txt c_cwall[1] c_cwall[2] ...' (docs/liggghts-output.md)")
"""Why a mesh wall's contacts are missing when the run has no wall dump (:attr:`demsplit.scene.Wall.missing`)."""

MESH_WALL_NOT_LAST = (
    "LIGGGHTS' compute wall/gran/local writes the contacts of the last mesh 'fix wall/gran' of the script only, "
    "and this wall belongs to an earlier one. Give all mesh walls to one fix wall/gran ('mesh n_meshes K meshes "
    "m1 m2 ...') so that one wall dump holds them all")
"""Why a mesh wall's contacts are missing when it is not in the last mesh ``fix wall/gran``."""


class LiggghtsRun(Run):
    """A LIGGGHTS run opened for reading (see the module docstring)."""

    format_name = "liggghts"
    formats = ("a LIGGGHTS input script (its dumps found from its dump lines, or given as options)",
               "LIGGGHTS dumps given as options (atoms=, contacts=) with the scene as options")
    priority = -10  # any text file that no other reader claims is taken for a script

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is None or (path.is_file() and b"\0" not in head and b"ITEM: TIMESTEP" not in head)

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """The script's scene and dumps, without reading the dumps."""
        script = read_script(path)
        scene = script.scene
        lines = [f"{path}: LIGGGHTS input script",
                 f"  model:    {scene.model.describe()}",
                 f"  timestep: {script.timestep} s; periodic {list(script.periodic)}",
                 "  materials: " + ", ".join(f"{t}: E={m.E:g} Pa nu={m.nu:g}"
                                             for t, m in sorted(scene.materials.items())),
                 "  walls:    " + (", ".join(f"{w.name} ({w.kind}, type {w.type})" for w in scene.walls) or "none"),
                 "  dumps:"]
        for d in script.dumps:
            what = d.layout.kind + " contacts" if d.layout is not None else d.style
            lines.append(f"    {d.id:<10} {what:<15} every {d.every:<7} {d.file}"
                         f"  ({'full precision' if d.full_precision else 'printed precision'})")
        lines += [f"  warning: {w}" for w in script.warnings]
        return "\n".join(lines)

    def __init__(self, script: str | Path | None, *, atoms: str | Path | None = None,
                 contacts: str | Path | None = None, walls: str | Path | None = None,
                 variables: dict[str, str] | None = None, materials: dict[int, Material] | None = None,
                 overlap_tolerance: float | None = None, force_positions: bool = False,
                 scene_options: dict | None = None) -> None:
        self.script_text = None
        if script is None:  # the scene comes from the command line (scene_script)
            if atoms is None or contacts is None:
                raise InputFormatError("without an input script, the atom and pair contact dumps must be given.",
                                       fix="pass --atoms FILE and --contacts FILE (or the input script).")
            self.script_text = scene_script(materials=materials or {}, contacts=Path(contacts),
                                            walls=None if walls is None else Path(walls), **(scene_options or {}))
            with tempfile.TemporaryDirectory() as tmp:
                (Path(tmp) / "in.demsplit").write_text(self.script_text)
                self.script = read_script(Path(tmp) / "in.demsplit")
            materials = None
        else:
            self.script = read_script(script, variables)
        base = self.script.scene
        self.scene = Scene({**base.materials, **(materials or {})}, base.model, base.walls, base.units,
                           base.source) if materials else base
        self.overlap_tolerance = DEFAULT_OVERLAP_TOLERANCE if overlap_tolerance is None else overlap_tolerance
        self.force_positions = force_positions
        self.atoms = self._open_atoms(atoms)
        self.pairs = self._open_local(contacts, "pair")
        self.walls = self._open_local(walls, "wall")
        announce_first_frame(self.atoms.head_rows,  # before the dumps are indexed below
                             sum(d.head_rows for d in (self.pairs, self.walls) if d is not None))
        self._pair_names = self._local_names(self.pairs, "pair")
        self._wall_names = self._local_names(self.walls, "wall")
        self._refuse_wall_columns_apart()
        self.notes: list[str] = list(self.script.warnings)
        dumped = set(self.script.dumped_mesh_walls) if self.walls is not None else set()
        self.scene = replace(self.scene, walls=[
            w if w.kind != "mesh" or i in dumped else
            replace(w, missing=MESH_WALL_NOT_DUMPED if self.walls is None else MESH_WALL_NOT_LAST)
            for i, w in enumerate(self.scene.walls)])
        if script is None:
            self.notes.append("no input script: primitive walls (never dumped by LIGGGHTS) are unknown, "
                              "so contacts with them are not included")
        for dump in (self.atoms, self.pairs, self.walls):
            if dump is not None:
                _refuse_repeated_steps(dump)
        self.steps = np.asarray(self.atoms.steps, dtype=np.int64)
        self.damaged = self.atoms.damaged  # atom frames whose header is unreadable: frames len(steps)...
        self.sources = ([] if script is None else [self.script.path]) + [
            f for d in (self.atoms, self.pairs, self.walls) if d is not None for f in getattr(d, "files", [d.path])]

    def named_files(self) -> list[Path]:
        """The files read, and every other file the script names: its includes, its mesh files and the
        file (and compressed copies) of every dump it writes, a per-step or per-processor pattern's
        existing files included."""
        files = [Path(s) for s in self.sources]
        if self.script_text is not None:  # no script of the user's: the dumps given are the run
            return files
        files += self.script.included
        files += [Path(w.file) for w in self.script.scene.walls if w.kind == "mesh" and w.file]
        for dump in self.script.dumps:
            name = Path(dump.file)
            if "*" in name.name or "%" in name.name:
                pattern = name.name.replace("%", "*")
                files += [p for suffix in ("", *_COMPRESSED) for p in name.parent.glob(pattern + suffix)]
            else:
                files += [name, *(name.with_name(name.name + suffix) for suffix in _COMPRESSED)]
        return files

    # -- finding and opening the dumps -----------------------------------------------------

    def _candidates(self, kind: str) -> list:
        """The script's dumps of one kind, full precision first."""
        if kind == "atoms":
            specs = [d for d in self.script.dumps
                     if d.style == "custom" and all(c in d.keywords for c in ATOM_COLUMNS)]
        else:
            specs = [d for d in self.script.dumps if d.layout is not None and d.layout.kind == kind]
        return sorted(specs, key=lambda d: not d.full_precision)

    def _series(self, spec) -> DumpSeries | None:
        """The dump of ``spec`` when it writes one file per timestep (``*``; see
        :mod:`demsplit.readers.dump_series`), None for a single file or when no file matches;
        one file per processor (``%``) is refused."""
        name = Path(spec.file).name
        if "%" in name:
            raise InputFormatError(
                f"dump {spec.id} writes one file per processor ({spec.file}), so each frame is split over "
                "several files; demsplit reads a frame from one file.", file=self.script.path,
                fix="write the dump without '%' in its file name (one file, or one per timestep with '*').")
        if "*" not in name:
            return None
        files = series_files(spec.file)
        return DumpSeries(spec.file, files, columns=spec.keywords if spec.style == "custom" else None) \
            if files else None

    def _open_atoms(self, given) -> DumpFile:
        if given is not None:
            path = existing_file(given)
            if path is None:
                raise InputFormatError("atom dump not found.", file=given, fix="check the --atoms path.")
            spec = next((d for d in self._candidates("atoms") if existing_file(d.file) == path), None)
            return open_dump(path, columns=spec.keywords if spec else None)
        for spec in self._candidates("atoms"):
            if (series := self._series(spec)) is not None:
                return series
            path = existing_file(spec.file)
            if path is not None:
                return open_dump(path, columns=spec.keywords)
        raise InputFormatError(
            "no atom dump found: the script has no 'dump ... custom' with id type x y z radius whose file exists."
            + vtk_dump_note(self.script.dumps), file=self.script.path,
            fix="'demsplit prepare SCRIPT' writes a copy of the script with the dumps demsplit reads; or add "
                "'dump D all custom N atoms.txt id type x y z radius mass' to the script, or pass --atoms FILE.")

    def _open_local(self, given, kind: str) -> DumpFile | None:
        if given is not None:
            path = existing_file(given)
            if path is None:
                raise InputFormatError(f"{kind} contact dump not found.", file=given,
                                       fix=f"check the --{'contacts' if kind == 'pair' else 'walls'} path.")
            return open_dump(path)
        for spec in self._candidates(kind):
            if (series := self._series(spec)) is not None:
                return series
            path = existing_file(spec.file)
            if path is not None:
                return open_dump(path)
        if kind == "pair":
            raise InputFormatError(
                "no pair contact dump found: the script has no 'dump ... local' of a compute pair/gran/local "
                "whose file exists." + vtk_dump_note(self.script.dumps), file=self.script.path,
                fix="'demsplit prepare SCRIPT' writes a copy of the script with the dumps demsplit reads; or add "
                    "'compute cpgl all pair/gran/local id pos delta history' and "
                    "'dump dc all local N pairs.txt c_cpgl[1] ...' to the script, or pass --contacts FILE.")
        return None

    def _local_names(self, dump: DumpFile | None, kind: str) -> dict[str, str]:
        """Canonical name -> header token for every column of a local dump, from
        the header's ``c_ID[k]`` through compute ID's layout in the script."""
        if dump is None:
            return {}
        names: dict[str, str] = {}
        # the column names are those of the first frame's header (its line HEADER_LINES)
        where = {"file": dump.path, "step": int(dump.steps[0]) if len(dump.steps) else None,
                 "line": HEADER_LINES}
        for token in dump.columns or []:
            m = _LOCAL_TOKEN.match(token)
            if m is None:
                continue  # 'index' or another non-compute column
            cid, k = m.group(1), int(m.group(2))
            layout = self.script.local_computes.get(cid)
            if layout is None:
                raise InputFormatError(
                    f"column {token} reads compute '{cid}', which the script does not define.",
                    **where, fix="pass the input script that wrote this dump.")
            if layout.kind != kind:
                raise InputFormatError(
                    f"this dump holds {layout.kind} contacts (compute {cid}), given as the {kind} contact dump.",
                    **where, fix="swap --contacts and --walls.")
            if k > len(layout.columns):
                raise InputFormatError(
                    f"column {token} is beyond the {len(layout.columns)} columns compute {cid} writes "
                    "with the keywords in the script.", **where,
                    fix="pass the input script that wrote this dump (its compute keywords decide the columns).")
            names[layout.columns[k - 1]] = token
        required = ("id1", "id2") if kind == "pair" else ("id1", "mesh_index")
        missing = [c for c in required if c not in names]
        if missing:
            raise InputFormatError(
                f"the {kind} contact dump lacks the columns {missing} (its compute needs the 'id' keyword).",
                **where, fix="add 'id' to the compute's keywords and dump all its columns.")
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
        return self._assemble(af, pf, wf)

    def __iter__(self) -> Iterator[Frame]:
        """Stream the three dumps side by side (one decompression each)."""
        pairs = self._stream(self.pairs, self._pair_names)
        walls = self._stream(self.walls, self._wall_names) if self.walls is not None else None
        for af in self.atoms.frames(columns=self._atom_columns()):
            pf = self._advance(pairs, af.step, self.pairs)
            wf = self._advance(walls, af.step, self.walls) if walls is not None else None
            yield self._assemble(af, pf, wf)

    def _atom_columns(self) -> list[str]:
        cols = list(ATOM_COLUMNS)
        models = [self.scene.model] + [w.model for w in self.scene.walls if w.model is not None]
        for model in models:  # what the laws need of the particles (mass for hooke, the liquid content of bridges)
            cols += [c for c in model.contact_law.particle_columns if c not in cols]
        missing = [c for c in cols if c not in (self.atoms.columns or [])]
        if missing:
            raise InputFormatError(f"the atom dump lacks the columns {missing}.", file=self.atoms.path,
                                   fix="add them to the 'dump ... custom' line.")
        return cols

    def _refuse_wall_columns_apart(self) -> None:
        """The mesh-wall contacts join the pair contacts in one table: a law column (a history) the pair dump
        holds, the law of a dumped mesh wall reads and the wall dump does not hold is refused, naming the wall
        dump's header (it was a KeyError). A column only the pairs' law reads (a mesh wall whose fix has no
        rolling friction, say) is not needed of the wall: :meth:`_mesh_walls` gives its rows 0 there."""
        if self.walls is None:
            return
        wall_reads = self._mesh_wall_law_columns()
        missing = [c for c in self._law_columns()
                   if c in self._pair_names and c not in self._wall_names and c in wall_reads]
        if missing:
            raise InputFormatError(
                f"the wall contact dump has no column for {', '.join(missing)}, which the law reads and the pair "
                f"dump holds: its header names {len(self.walls.columns or [])} columns, its compute's keywords "
                "differ from the pair compute's, or the header is damaged.", file=self.walls.path,
                step=int(self.walls.steps[0]) if len(self.walls.steps) else None, line=HEADER_LINES,
                fix="give the wall compute the pair compute's keywords and dump all its columns; check the header.")

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
        keep += [c for c in self._law_columns() if c not in keep]
        return [names[c] for c in keep if c in names]

    def _local_at(self, dump: DumpFile, step: int, names: dict[str, str]) -> DumpFrame:
        if step not in set(int(s) for s in dump.steps):
            damaged = dump.damaged
            raise InputFormatError(
                f"the contact dump has no frame at timestep {step}, which the atom dump has"
                + (f"; it has {len(damaged)} frame(s) with a damaged header, the first: {damaged[0]}"
                   if damaged else "."),
                file=dump.path, step=step,
                fix="write the atom and contact dumps every N steps with the same N (dump ... N ...)."
                if not damaged else "repair or rewrite the contact dump.")
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
            file=dump.path, step=step,
            fix="write the atom and contact dumps every N steps with the same N (dump ... N ...).")

    # -- assembly ----------------------------------------------------------------------------

    def _assemble(self, af: DumpFrame, pf: DumpFrame, wf: DumpFrame | None) -> Frame:
        step = af.step
        box = Box(af.box.lo, af.box.hi, tuple(p or q for p, q in zip(af.box.periodic, self.script.periodic)),
                  af.box.tilt)
        particles: Table = {"id": af.int_column("id"), "type": af.int_column("type").astype(np.int32),
                            "x": af.columns["x"], "y": af.columns["y"], "z": af.columns["z"],
                            "radius": af.columns["radius"]}
        particles.update({c: af.columns[c] for c in self._atom_columns()[len(ATOM_COLUMNS):]})
        if np.any(~(particles["radius"] > 0)):
            row = int(np.flatnonzero(~(particles["radius"] > 0))[0])
            raise InputFormatError(f"particle radius must be > 0, found {float(particles['radius'][row])!r}.",
                                   file=af.file, step=step, line=af.line_of(row),
                                   fix="check the atom dump's radius column.")
        unknown = ~np.isin(particles["type"], list(self.scene.materials))
        if unknown.any():
            row = int(np.flatnonzero(unknown)[0])
            raise MaterialError(f"particle type {int(particles['type'][row])} has no material (materials are "
                                f"defined for types {sorted(self.scene.materials)}).",
                                file=af.file, step=step, line=af.line_of(row),
                                fix="define youngsModulus and poissonsRatio for every type in the input script, "
                                    "or pass --material TYPE:E:NU.")
        try:
            index = ParticleIndex(particles["id"], file=af.file, step=step)
        except InputFormatError as exc:  # duplicated ids: name the line of the first repeat
            first = np.zeros(len(particles["id"]), bool)
            first[np.unique(particles["id"], return_index=True)[1]] = True
            raise exc.located(line=af.line_of(int(np.flatnonzero(~first)[0]))) from None
        # centre and radius of each particle in one row: the join fetches one cache line per body
        xyzr = np.stack([particles["x"], particles["y"], particles["z"], particles["radius"]], axis=-1)
        xyz = xyzr[:, :3]
        has_primitive = any(w.kind in ("plane", "cylinder") for w in self.scene.walls)
        # printed step of every particle's coordinates (0 at full precision): where positions make overlaps,
        # and where a dumped overlap is checked against them
        h = _largest_printed_step([particles[c] for c in ("x", "y", "z")], [af.digits.get(c) for c in ("x", "y", "z")])
        parts = [self._pairs(pf, index, xyzr, h, box)]
        if wf is not None:
            parts.append(self._mesh_walls(wf, particles, index, xyz, h))
        # printed positions can hide a contact: keep those within their uncertainty (bound inf); and those apart
        # that the wall's law still acts across (a liquid bridge), as LIGGGHTS evaluates them
        reach = [(w.model or self.scene.model).contact_law.separation_limit(particles["radius"], np.inf)
                 for w in self.scene.walls]
        primitive = primitive_wall_contacts(particles, self.scene.walls, margin=np.sqrt(3.0) * h, reach=reach) \
            if has_primitive else {}
        notes = []
        # the law reads a contact history, which LIGGGHTS never writes for primitive walls: every frame's
        # contacts say which rows lack it (history_unknown), so that their modes are "not computed"
        history = [c for c in self._law_columns() if c in parts[0]] if has_primitive else []
        if history:
            for part in parts:
                part["history_unknown"] = np.zeros(len(part["delta"]), dtype=np.int8)
        if primitive:
            rows = index.rows(primitive["id1"])
            # a contact apart beyond the positions' uncertainty (a liquid bridge's): the bound of its gap
            gap = -primitive["delta"]
            primitive["bound"] = np.where(gap >= np.sqrt(3.0) * h[rows], position_error(h[rows], gap),
                                          position_error(h[rows], primitive["delta"]))
            # LIGGGHTS' own point for a wall contact is on the wall: the particle takes the whole overlap
            primitive["cpx"], primitive["cpy"], primitive["cpz"] = contact_point(
                np.stack([primitive[c] for c in ("x1", "y1", "z1")], -1),
                np.stack([primitive[c] for c in ("nx", "ny", "nz")], -1),
                primitive["r1"], primitive["delta"], 1.0).T
            for c in history:  # columns every part must have; the flag below says they are unknown here
                primitive[c] = np.zeros(len(primitive["delta"]))
            if history:
                primitive["history_unknown"] = np.ones(len(primitive["delta"]), dtype=np.int8)
            parts.append(primitive)
        if history:
            notes.append(PRIMITIVE_HISTORY_UNKNOWN)
        contacts = {c: np.concatenate([p[c] for p in parts]) if len(parts) > 1 else parts[0][c] for c in parts[0]}
        source, error = self._overlap_policy(contacts, contacts.pop("bound"), af, pf, step)
        time = None if self.script.timestep is None else step * self.script.timestep
        return Frame(step=step, particles=particles, contacts=contacts, box=box, time=time,
                     source=(str(af.file), str(pf.file)) + ((str(wf.file),) if wf is not None else ()),
                     overlap_source=source, overlap_error=error, notes=notes)

    def _pairs(self, pf: DumpFrame, index: ParticleIndex, xyzr: np.ndarray, h: np.ndarray | None,
               box: Box) -> Table:
        from demsplit.kernels import pair_geometry  # compiled, lazily
        from demsplit.kernels import repeated_pair as repeated_rows

        names = self._pair_names
        col = {c: pf.columns[t] for c, t in names.items() if t in pf.columns}
        id1, id2 = pf.int_column(names["id1"]), pf.int_column(names["id2"])
        wall = np.full(len(id1), -1, np.int64)
        rows1, rows2 = self._pair_rows(index, pf, id1, id2, wall)
        first, repeat = repeated_rows(rows1, rows2, len(index.ids))
        if repeat >= 0:
            raise ContactError(
                f"particle {int(id1[first])} is paired with itself." if first == repeat else
                f"the contact of particles {int(id1[repeat])} and {int(id2[repeat])} is listed twice in this frame "
                f"(rows {first + 1} and {repeat + 1}, lines {pf.line_of(first)} and {pf.line_of(repeat)}).",
                file=pf.file, step=pf.step, line=pf.line_of(repeat),
                fix="each contact must appear once per frame: check that the dump is not the concatenation of "
                    "two runs or of two MPI ranks' output for the same step.")
        dumped_cp = all(c in col for c in ("cpx", "cpy", "cpz"))
        nx, ny, nz, x1, y1, z1, r1, r2, gap, hmax, cp = pair_geometry(
            rows1, rows2, xyzr, np.zeros(0) if h is None else h, box.lengths, box.tilt, box.periodic, not dumped_cp)
        if "delta" in col and len(hmax):
            _refuse_overlaps_off_positions(pf, names["delta"], col["delta"], gap, hmax, r1 + r2, id1, id2)
        out: Table = {"id1": id1, "id2": id2, "wall": wall, "delta": col["delta"] if "delta" in col else gap,
                      "nx": nx, "ny": ny, "nz": nz, "x1": x1, "y1": y1, "z1": z1, "r1": r1, "r2": r2}
        out["bound"] = self._delta_error(pf, names, hmax, gap)
        out.update({c: col[c] for c in self._law_columns() if c in col})
        # the dumped point, else LIGGGHTS' own radius-weighted point, (x1 r2 + x2 r1)/(r1 + r2), from the join
        cpx, cpy, cpz = (col["cpx"], col["cpy"], col["cpz"]) if dumped_cp else cp
        if box.any_periodic:
            cpx, cpy, cpz = box.wrap(np.stack([cpx, cpy, cpz], axis=-1)).T
        out.update(cpx=cpx, cpy=cpy, cpz=cpz)
        return out

    def _mesh_walls(self, wf: DumpFrame, particles: Table, index: ParticleIndex, xyz: np.ndarray,
                    h: np.ndarray) -> Table:
        names = self._wall_names
        col = {c: wf.columns[t] for c, t in names.items() if t in wf.columns}
        pid = wf.int_column(names["id1"])
        mesh = wf.int_column(names["mesh_index"])
        wall_of_mesh = np.asarray(self.script.dumped_mesh_walls, dtype=np.int64)
        if len(mesh) and (mesh.min() < 0 or mesh.max() >= len(wall_of_mesh)):
            row = int(np.flatnonzero((mesh < 0) | (mesh >= len(wall_of_mesh)))[0])
            raise InputFormatError(
                f"mesh index {int(mesh[row])} is not one of the {len(wall_of_mesh)} meshes of the script's "
                "last mesh 'fix wall/gran'.", file=wf.file, step=wf.step, line=wf.line_of(row),
                fix="pass the input script that wrote this dump.")
        self._refuse_repeated_wall_contacts(wf, pid, mesh, col)
        (rows,) = self._rows(index, wf, pid)
        r = particles["radius"][rows]
        if all(c in col for c in ("wall_cpx", "wall_cpy", "wall_cpz")):
            on_wall = np.stack([col["wall_cpx"], col["wall_cpy"], col["wall_cpz"]], axis=-1)
        else:
            raise InputFormatError("the wall contact dump lacks the 'pos' columns, so the wall normal is unknown.",
                                   file=wf.file, step=wf.step,
                                   fix="add 'pos' to the compute wall/gran/local keywords.")
        d = on_wall - xyz[rows]
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        n = d / np.where(dist > 0, dist, 1.0)[:, None]
        out: Table = {"id1": pid, "id2": np.full(len(pid), -1, np.int64), "wall": wall_of_mesh[mesh],
                      "delta": col["delta"] if "delta" in col else r - dist,
                      "nx": n[:, 0], "ny": n[:, 1], "nz": n[:, 2],
                      "x1": xyz[rows, 0], "y1": xyz[rows, 1], "z1": xyz[rows, 2],
                      "r1": r, "r2": np.full(len(pid), np.inf)}
        wall_digits = min((wf.digits.get(names[c]) or 17) for c in ("wall_cpx", "wall_cpy", "wall_cpz"))
        h_wall = np.max(printed_step(on_wall, wall_digits), axis=1)
        out["bound"] = self._delta_error(wf, names, np.maximum(h[rows], h_wall), r - dist)
        out.update({c: col[c] if c in col else np.zeros(len(pid)) for c in self._law_columns()
                    if c in col or c in self._pair_names})  # 0: a column only the pairs' law reads
        out.update(cpx=on_wall[:, 0], cpy=on_wall[:, 1], cpz=on_wall[:, 2])
        return out

    def _refuse_repeated_wall_contacts(self, wf: DumpFrame, pid: np.ndarray, mesh: np.ndarray, col: Table) -> None:
        """A mesh-wall contact (particle, mesh, triangle; without ``tri_id`` the whole row) listed twice in a
        frame would be counted twice: a ContactError naming both lines."""
        if len(pid) < 2:
            return
        keys = [pid, mesh] + ([wf.int_column(self._wall_names["tri_id"])] if "tri_id" in self._wall_names
                              else [col[c] for c in ("delta", "wall_cpx", "wall_cpy", "wall_cpz") if c in col])
        order = np.lexsort(keys[::-1])
        same = np.ones(len(pid) - 1, dtype=bool)
        for k in keys:
            same &= k[order][1:] == k[order][:-1]
        if same.any():
            at = int(np.flatnonzero(same)[0])
            first, repeat = sorted((int(order[at]), int(order[at + 1])))
            raise ContactError(
                f"the contact of particle {int(pid[repeat])} with mesh {int(mesh[repeat])} is listed twice in this "
                f"frame (lines {wf.line_of(first)} and {wf.line_of(repeat)}).", file=wf.file, step=wf.step,
                line=wf.line_of(repeat), fix="each contact must appear once per frame: check that the dump is "
                "not the concatenation of two runs or of two MPI ranks' output for the same step.")

    @staticmethod
    def _pair_rows(index: ParticleIndex, f: DumpFrame, id1: np.ndarray, id2: np.ndarray,
                   wall: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`ParticleIndex.contact_rows` of the particle pairs of contact dump frame
        ``f``; an unknown id is a ContactError naming the dump and the line of its first row."""
        try:
            return index.contact_rows(id1, id2, wall)
        except ContactError:
            LiggghtsRun._rows(index, f, id1, id2)  # raises, with the line
            raise

    @staticmethod
    def _rows(index: ParticleIndex, f: DumpFrame, *ids: np.ndarray) -> list[np.ndarray]:
        """Particle rows of each id column of contact dump frame ``f``; an unknown id is a
        ContactError naming the contact dump and the line of its first row."""
        try:
            return [index.rows(i) for i in ids]
        except ContactError as exc:
            known = np.logical_and.reduce([np.isin(i, index.ids) for i in ids])
            row = int(np.flatnonzero(~known)[0])
            raise ContactError(exc.message, file=f.file, step=f.step, line=f.line_of(row), fix=exc.fix) from None

    @staticmethod
    def _delta_error(f: DumpFrame, names: dict[str, str], h: np.ndarray,
                     delta_from_positions: np.ndarray) -> np.ndarray:
        """Relative error bound of each contact's overlap: the rounding of the
        dumped ``delta`` column, or the position bound when there is none."""
        token = names.get("delta")
        if token is not None:
            return np.full(len(delta_from_positions), relative_rounding(f.digits.get(token)))
        return position_error(h, delta_from_positions)

    def _overlap_policy(self, contacts: Table, error: np.ndarray, af: DumpFrame, pf: DumpFrame,
                        step: int) -> tuple[str, np.ndarray | None]:
        """Where the overlaps come from, their per-contact relative error bound,
        and refusal when overlaps recomputed from printed positions are too imprecise."""
        delta = self._pair_names.get("delta")
        digits = af.digits.get("x")
        positions = "full precision" if relative_rounding(digits) == 0 else f"printed precision ({digits} digits)"
        parts = [f"pairs: {'dumped delta' if delta else 'positions, ' + positions}"]
        if self.walls is not None:
            parts.append(f"mesh walls: {'dumped delta' if 'delta' in self._wall_names else 'positions'}")
        if any(w.kind in ("plane", "cylinder") for w in self.scene.walls):
            parts.append(f"primitive walls: positions, {positions}")
        source = "; ".join(parts)
        if not np.any(error > 0):
            return source, None
        worst = error > self.overlap_tolerance
        if worst.any() and not self.force_positions:
            k = int(np.count_nonzero(worst))
            raise PrecisionError(
                f"{k} of {len(error)} overlaps have an error bound above the tolerance {self.overlap_tolerance:g} "
                f"(median {np.median(error):.2g}, max {np.max(error):.2g}): they were recomputed from positions "
                f"printed with {digits} significant digits ({source}); their energies would be unreliable.",
                file=af.file, step=step,
                fix="dump the overlap ('delta' keyword of compute pair/gran/local and wall/gran/local), or write "
                    "positions at full precision (dump_modify ID format with %.17g, or a binary .bin atom dump); "
                    "primitive-wall overlaps always come from positions. Or raise --overlap-tolerance, or use "
                    "--force-positions to accept the error, which is then reported per contact.")
        return source, error

    # -- description -------------------------------------------------------------------------

    def describe(self) -> dict:
        """Files, kinds and precision, for provenance and ``demsplit check``."""
        def info(d):
            return None if d is None else {"path": str(d.path), "frames": len(d.steps)}
        return {"kind": "liggghts", "script": self.script_text or str(self.script.path), "atoms": info(self.atoms),
                "pairs": info(self.pairs), "walls": info(self.walls),
                "model": {"law": self.scene.model.law, "params": self.scene.model.params},
                "overlap_tolerance": self.overlap_tolerance, "force_positions": self.force_positions,
                "notes": self.notes}

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
                    problems.append(str(InputFormatError(
                        f"{len(missing)} timestep(s) of the atom dump have no frame here, e.g. "
                        f"{missing[:5].tolist()}.", file=dump.path, step=int(missing[0]),
                        fix="write the atom and contact dumps every N steps with the same N.")))
                if len(extra):
                    problems.append(str(InputFormatError(
                        f"{len(extra)} frame(s) have no atom frame and would be ignored, e.g. steps "
                        f"{extra[:5].tolist()}.", file=dump.path, step=int(extra[0]),
                        fix="write the atom and contact dumps every N steps with the same N.")))
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


def _refuse_overlaps_off_positions(pf: DumpFrame, token: str, delta: np.ndarray, gap: np.ndarray, h: np.ndarray,
                                   r: np.ndarray, id1: np.ndarray, id2: np.ndarray) -> None:
    """A dumped overlap must be the one the positions give, r1 + r2 - |x2 - x1| (LIGGGHTS computes it from
    the same positions, at the same step: they agree to 4e-18 m in the samples), within what the printing of
    both allows: twice sqrt(3) h for the centres, the dumped value's own rounding, and 1e-9 of r1 + r2 for
    the arithmetic. A pair dump of another run or step, or a damaged value, is refused by its line (an
    overlap > 0 only: a dumped overlap <= 0 is named by the checks of a contact that is not one)."""
    rounding = relative_rounding(pf.digits.get(token))

    def tolerance(lo: int, hi: int) -> np.ndarray:
        return 2.0 * np.sqrt(3.0) * h[lo:hi] + np.abs(delta[lo:hi]) * rounding + 1e-9 * r[lo:hi]

    def outside(lo: int, hi: int) -> np.ndarray:
        # an overlap <= 0, or positions that are not finite, are the other checks' findings
        d, g = delta[lo:hi], gap[lo:hi]
        return (d > 0) & np.isfinite(g) & ~(np.abs(d - g) <= tolerance(lo, hi))

    off = np.concatenate(threads.map_ranges(outside, len(delta)))  # numpy releases the GIL: pieces on every core
    if off.any():
        tol = tolerance(0, len(delta))
        row = int(np.flatnonzero(off)[0])
        raise ContactError(
            f"the contact of particles {int(id1[row])} and {int(id2[row])} has a dumped overlap of "
            f"{float(delta[row]):.6g} m, but its particles' positions give {float(gap[row]):.6g} m (the printing "
            f"allows {float(tol[row]):.2g} m); {int(off.sum())} such contact(s).", file=pf.file, step=pf.step,
            line=pf.line_of(row), fix="check that the pair and atom dumps belong to the same run and timestep.")


def _largest_printed_step(coordinates: list[np.ndarray], digits: list[int | None]) -> np.ndarray:
    """Per particle, the largest :func:`~demsplit.readers.precision.printed_step` of its coordinates
    (m; 0 at full precision), pieces of the particles on every core."""
    h = np.empty(len(coordinates[0]))

    def piece(lo: int, hi: int) -> None:
        h[lo:hi] = np.max([printed_step(x[lo:hi], d) for x, d in zip(coordinates, digits)], axis=0)
    threads.map_ranges(piece, len(h))
    return h


def _refuse_repeated_steps(dump: DumpFile) -> None:
    """A timestep written twice to one dump (a LIGGGHTS restart appending to it) is refused: which copy
    holds the run's state is the user's call, not a silent first-copy read."""
    values, counts = np.unique(dump.steps, return_counts=True)
    if np.any(counts > 1):
        raise InputFormatError(
            f"timestep(s) {values[counts > 1][:5].tolist()} appear more than once in this dump (a restart that "
            "appended to it writes its first step again).", file=dump.path, step=int(values[counts > 1][0]),
            fix="keep one copy of each timestep: cut the earlier or the later run out of the dump.")
