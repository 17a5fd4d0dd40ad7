"""A LAMMPS GRANULAR run: the input script plus the dumps its own lines name, assembled into Frames.

:class:`LammpsRun` reads the script (:mod:`.lammps_script`) for each type pair's model, the wall fixes and the
meaning of every dumped column, then joins per timestep (:mod:`.lammps_join`)

* the atom dump (``dump custom`` with ``id type x y z vx vy vz omegax omegay omegaz fx fy fz tqx tqy tqz radius
  mass`` and ``f_ID[1]`` .. ``f_ID[8]`` of every wall fix with ``contacts``),
* the pair dump (``dump local`` of ``compute property/local patom1 patom2 ... cutoff radius`` and
  ``compute pair/local dist force ... p1 .. p12 cutoff radius``, legacy styles p1 .. p10),

both at full precision (``dump_modify ID format float %.17g``), into one Frame whose contacts carry the springs
rebuilt from them. Dump files are the ones the script's dump lines write (a ``.gz``, ``.bz2`` or ``.xz`` copy is
found too) unless given as ``atoms=``, ``contacts=``. What no dump holds is refused, or marked "not computed" with
``--allow-missing`` (``docs/lammps-output.md``).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..errors import InputFormatError, MaterialError, ScriptError
from ..frame import Box, Frame, ParticleIndex, describe_steps
from ..physics.laws._lammps import DUMP_ROW, SPRING_R, SPRING_T, UNKNOWN_MODES, UNKNOWN_WHY, Rebuilt
from ..scene import Material, Scene, Wall
from .base import ATOMS, CONTACTS, MATERIALS, VARIABLES, Option, Run
from .lammps_balance import close_balances
from .lammps_dump import HEADER_LINES, DumpFile, DumpFrame, open_dump
from .lammps_join import ATOM_COLUMNS, FORCE_TOLERANCE, Assembled, LammpsJoin, run_of_step, unknown_columns
from .lammps_script import is_lammps_script, read_lammps_script
from .liggghts import existing_file
from .liggghts_script import DumpSpec

_TOKEN = re.compile(r"^c_([^\[\]]+)\[(\d+)\]$")
_PAIR_QUANTITIES = ("patom1", "patom2", "dist", "force", *(f"p{k}" for k in range(1, 13)))
_WALL_KINDS = {"xplane": "plane", "yplane": "plane", "zplane": "plane", "zcylinder": "cylinder"}
FORMAT_FIX = "add 'dump_modify {id} format float %.17g' to the script and rerun"
"""How to write a dump at full precision."""


def wall_material_spec(text: str) -> tuple[str, Material]:
    """``FIXID:E:NU`` (Pa, -) as ``(fix id, Material)``; ValueError when malformed."""
    try:
        fid, E, nu = text.rsplit(":", 2)
        return fid, Material(float(E), float(nu))
    except ValueError:
        raise ValueError(f"expected FIXID:E:NU (e.g. floor:5e7:0.3), got {text!r}") from None


def _off_of(r: Rebuilt, dumped: np.ndarray) -> np.ndarray:
    """Rows whose dumped normal force the rebuilt one misses by more than FORCE_TOLERANCE of its scale (rows
    without a dumped value are not compared)."""
    known = np.isfinite(r.fn_rebuilt) & np.isfinite(dumped)
    return known & ~(np.abs(r.fn_rebuilt - dumped) <= FORCE_TOLERANCE * r.fn_scale + 1e-300)


def _off(a: Assembled) -> np.ndarray:
    return _off_of(a.rebuilt, a.contacts["fn_dumped"])


def _dump_name(dump: DumpSpec) -> str:
    return f"dump {dump.id} ({Path(dump.file).name})"


class LammpsRun(Run):
    """A LAMMPS granular run opened for reading (see the module docstring)."""

    format_name = "lammps"
    simulator = "lammps"
    formats = ("a LAMMPS GRANULAR input script (pair_style granular or gran/*; its dumps found from its dump lines)",)
    priority = -5  # a text file: after the file formats, before the LIGGGHTS script that takes any text
    cli_group = "LAMMPS inputs (default: the files the script's dump lines write)"
    cli_options = (
        ATOMS,
        CONTACTS,
        VARIABLES,
        MATERIALS,
        Option(
            "wall_materials",
            ("--wall-material",),
            "the elastic constants of a LAMMPS wall fix whose model has "
            "none (hooke, hertz, gran/*), FIXID:E:NU (Pa, -) (repeatable)",
            {"action": "append", "type": wall_material_spec, "metavar": "FIXID:E:NU"},
            convert=dict,
        ),
    )

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        if path is None or not path.is_file() or b"\0" in head or b"ITEM: TIMESTEP" in head:
            return False
        with open(path, "rb") as f:
            return is_lammps_script(f.read(1 << 20))

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """The script's models, walls and dumps, without reading the dumps."""
        script = read_lammps_script(path)
        lines = [
            f"{path}: LAMMPS input script (units {script.units})",
            f"  timestep: {script.timestep}; periodic {list(script.periodic)}",
        ]
        lines += [f"  pair {i} {j}: {m.describe()}" for (i, j), m in sorted(script.pair_models.items())]
        lines += [
            f"  wall {w.id} ({w.geometry}{', contacts' if w.contacts else ''}): {w.model.describe()}"
            for w in script.walls
        ]
        lines += [
            f"  dump {d.id:<10} {d.style:<7} every {d.every:<7} {d.file}"
            f"  ({'full precision' if d.full_precision else 'printed precision'})"
            for d in script.dumps
        ]
        lines += [f"  warning: {w}" for w in script.warnings]
        return "\n".join(lines)

    def __init__(
        self,
        script: str | Path | None,
        *,
        atoms: str | Path | None = None,
        contacts: str | Path | None = None,
        variables: dict[str, str] | None = None,
        materials: dict[int, Material] | None = None,
        wall_materials: dict[str, Material] | None = None,
    ) -> None:
        if script is None:
            raise InputFormatError(
                "a LAMMPS run is read from its input script.", fix="pass the script (demsplit run in.script)."
            )
        self.script = read_lammps_script(script, variables)
        self.notes: list[str] = list(self.script.warnings)
        self.atom_spec = self._atom_dump_spec(atoms)
        self.atoms = self._open(atoms, self.atom_spec, "atom")
        self.pair_spec, pair_names = self._pair_dump_spec(contacts)
        self.pairs = (
            None if self.pair_spec is None and contacts is None else self._open(contacts, self.pair_spec, "pair")
        )
        self.scene, wall_index = self._scene(materials or {}, wall_materials or {})
        self._check_atom_columns()
        first_run = self.atom_spec.first_run if self.atom_spec is not None else 0
        self.join = LammpsJoin(
            self.script, self.scene, pair_names, wall_index, first_run, self.script.pair_style != "granular"
        )
        self.steps = np.asarray(self.atoms.steps, dtype=np.int64)
        self.damaged = self.atoms.damaged
        self.sources = [self.script.path] + [d.path for d in (self.atoms, self.pairs) if d is not None]
        self.walls_first_run = {k: self.script.walls[f].first_run for f, k in enumerate(wall_index) if k is not None}
        if self.script.units == "lj":
            self.notes.append(
                "units lj: every energy is in LAMMPS' lj units (epsilon = m sigma^2/tau^2 of the "
                "run's mass, length and time units), not J"
            )

    # -- the script's dumps -------------------------------------------------------------------------------------

    def _atom_dump_spec(self, given) -> DumpSpec | None:
        """The script's atom dump: a ``dump custom`` with every column of :data:`ATOM_COLUMNS`; refused when it
        is not at full precision."""
        candidates = [d for d in self.script.dumps if d.style == "custom" and "id" in d.keywords]
        if given is not None:
            path = existing_file(given)
            return next((d for d in candidates if path is not None and existing_file(d.file) == path), None)
        if not candidates:
            raise InputFormatError(
                "the script writes no atom dump ('dump ID all custom N FILE id type x y z ...').",
                file=self.script.path,
                fix="'demsplit prepare SCRIPT' writes a copy of the script "
                "with the dumps demsplit reads; or add them (docs/lammps-output.md).",
            )
        spec = max(candidates, key=lambda d: sum(c in d.keywords for c in ATOM_COLUMNS))
        return spec

    def _pair_dump_spec(self, given) -> tuple[DumpSpec | None, dict[str, str]]:
        """The script's pair dump (a ``dump local`` of a property/local and a pair/local compute) and the header
        token of every pair quantity (:data:`_PAIR_QUANTITIES`)."""
        computes = self.script.computes
        for dump in self.script.dumps:
            if dump.style != "local":
                continue
            names: dict[str, str] = {}
            used = set()
            for token in dump.keywords:
                m = _TOKEN.match(token)
                if m is None or m.group(1) not in computes:
                    continue
                compute = computes[m.group(1)]
                k = int(m.group(2))
                if k > len(compute.keywords):
                    raise ScriptError(
                        f"dump {dump.id}: {token} is beyond the {len(compute.keywords)} columns of "
                        f"compute {compute.id}.",
                        file=self.script.path,
                        fix="correct the column.",
                    )
                names.setdefault(compute.keywords[k - 1], token)
                used.add(compute.id)
            if "patom1" not in names and "dist" not in names:
                continue
            self._refuse_local_dump(dump, names, [computes[c] for c in sorted(used)])
            return dump, names
        if given is not None:
            raise InputFormatError(
                "the pair dump given is no dump local of the script's pair/local and property/local computes.",
                file=given,
                fix="pass the script that wrote it.",
            )
        return None, {}

    def _refuse_local_dump(self, dump: DumpSpec, names: dict[str, str], computes: list) -> None:
        """A pair dump demsplit cannot read exactly: a quantity missing, a compute with ``cutoff type``, or
        printed precision."""
        needed = ["patom1", "patom2", "dist", "force", "p1", "p2", "p3"]
        if self.script.pair_style == "granular":
            needed += ["p5", "p6", "p7", "p10", "p11", "p12"]
        missing = [q for q in needed if q not in names]
        if missing:
            raise InputFormatError(
                f"{_dump_name(dump)} lacks the pair quantities {missing}.",
                file=self.script.path,
                fix="dump 'compute property/local patom1 patom2 cutoff radius' and 'compute pair/local dist force p1 "
                f"... p{12 if self.script.pair_style == 'granular' else 10} cutoff radius' (every column).",
            )
        for compute in computes:
            if compute.cutoff != "radius":
                raise InputFormatError(
                    f"compute {compute.id} {compute.style} lists pairs within the neighbour cutoff ('cutoff "
                    f"{compute.cutoff}'), not touching pairs only: its rows of pairs apart are zeros, and the two "
                    "computes' rows need not line up.",
                    file=self.script.path,
                    line=compute.where.line,
                    fix=f"add 'cutoff radius' to compute {compute.id} and rerun.",
                )
        if not dump.full_precision:
            raise InputFormatError(
                f"{_dump_name(dump)} prints its reals with {dump.format or '%g'}: the overlap r_i + r_j - dist of a "
                "contact needs dist at full precision (with %g its error reaches 10 % of the overlap).",
                file=self.script.path,
                fix=FORMAT_FIX.format(id=dump.id) + ".",
            )

    def _open(self, given, spec: DumpSpec | None, kind: str) -> DumpFile:
        if given is not None:
            path = existing_file(given)
            if path is None:
                raise InputFormatError(f"{kind} dump not found.", file=given, fix="check the path.")
            return open_dump(path)
        if spec is None:
            raise InputFormatError(f"no {kind} dump.", file=self.script.path, fix="add it (docs/lammps-output.md).")
        if "*" in Path(spec.file).name or "%" in Path(spec.file).name:
            raise InputFormatError(
                f"{_dump_name(spec)} writes several files ('*' or '%'); demsplit reads a LAMMPS "
                "run's frames from one file per dump.",
                file=self.script.path,
                fix="write each dump to one file.",
            )
        path = existing_file(spec.file)
        if path is None:
            raise InputFormatError(
                f"{_dump_name(spec)}: its file {spec.file} does not exist (nor a compressed copy).",
                file=self.script.path,
                fix="run the script, or pass the dump with --atoms/--contacts.",
            )
        if kind == "atom" and not spec.full_precision:
            raise InputFormatError(
                f"{_dump_name(spec)} prints its reals with {spec.format or '%g'}: the springs are rebuilt from the "
                "velocities, forces and positions, which %g rounds to 6 digits.",
                file=self.script.path,
                fix=FORMAT_FIX.format(id=spec.id) + ".",
            )
        return open_dump(path)

    def _check_atom_columns(self) -> None:
        columns = list(self.atoms.columns or [])
        missing = [c for c in ATOM_COLUMNS if c not in columns]
        for k, fix in enumerate(self.script.walls):
            if self.scene.walls[k].missing:
                continue
            missing += [f"f_{fix.id}[{q}]" for q in range(1, 9) if f"f_{fix.id}[{q}]" not in columns]
        if missing:
            raise InputFormatError(
                f"the atom dump lacks the columns {missing}.",
                file=self.atoms.path,
                step=int(self.atoms.steps[0]) if len(self.atoms.steps) else None,
                line=HEADER_LINES,
                fix="add them to the 'dump ... custom' line ('demsplit prepare SCRIPT' writes them).",
            )

    # -- the scene ----------------------------------------------------------------------------------------------

    def _scene(
        self, materials: dict[int, Material], wall_materials: dict[str, Material]
    ) -> tuple[Scene, list[int | None]]:
        """Materials (the ``i i`` lines' E, nu, then ``--material``), every type pair's model, and one wall per wall
        fix, of material type ntypes + 1 + k (its model's E, nu, then ``--wall-material``)."""
        script = self.script
        found = {**script.line_materials, **materials}
        ntypes = script.ntypes or max(found, default=0)
        absent = [t for t in range(1, ntypes + 1) if t not in found]
        if absent:
            laws = sorted({script.pair_models[(t, t)].law for t in absent if (t, t) in script.pair_models})
            raise MaterialError(
                f"atom type(s) {absent} have no E and nu: the model of their pair ({', '.join(laws)}) carries none.",
                file=script.path,
                fix="give them with --material TYPE:E:NU (Pa, -), e.g. "
                + " ".join(f"--material {t}:1e7:0.3" for t in absent[:2])
                + ".",
            )
        unknown = sorted(set(wall_materials) - {w.id for w in script.walls})
        if unknown:
            raise MaterialError(
                f"--wall-material names {unknown}, which are not wall fixes of the script "
                f"({', '.join(w.id for w in script.walls) or 'none'}).",
                file=script.path,
                fix="name a fix wall/gran or wall/gran/region by its ID.",
            )
        walls, wall_index = [], []
        for k, fix in enumerate(script.walls):
            wall_type = ntypes + 1 + k
            material = wall_materials.get(fix.id)
            if material is None and fix.model.contact_law.material() is not None:
                material = Material(*fix.model.contact_law.material())
            if material is None:
                raise MaterialError(
                    f"fix {fix.id}'s model ({fix.model.law}) carries no E and nu.",
                    file=script.path,
                    line=fix.where.line,
                    fix=f"give them with --wall-material {fix.id}:E:NU (Pa, -).",
                )
            found[wall_type] = material
            kind = _WALL_KINDS.get(fix.geometry, fix.region.style if fix.region else "plane")
            missing = (
                ""
                if fix.contacts
                else (
                    f"its fix has no 'contacts' keyword, so no dump holds its contacts: add 'contacts' to the fix line "
                    f"and f_{fix.id}[1] .. f_{fix.id}[8] to the atom dump ('demsplit prepare SCRIPT' does)"
                )
            )
            walls.append(
                Wall(
                    fix.id,
                    kind,
                    wall_type,
                    axis="xyz".index(fix.geometry[0]) if kind == "plane" and fix.geometry != "region" else 2,
                    position=fix.lo or 0.0,
                    radius=fix.radius,
                    model=fix.model,
                    missing=missing,
                )
            )
            wall_index.append(k)
        models = script.pair_models
        first = models.get((1, 1)) or next(iter(models.values()))
        scene = Scene(
            found, first, walls, script.units, str(script.path), {k: m for k, m in models.items() if m != first}
        )
        return scene, wall_index

    # -- frames -------------------------------------------------------------------------------------------------

    def __len__(self) -> int:
        return len(self.steps) + len(self.damaged)

    def frame(self, k: int) -> Frame:
        if k >= len(self.steps):
            raise self.damaged[k - len(self.steps)]
        step = int(self.steps[k])
        af = self.atoms.frame(k, columns=self._atom_columns())
        lf = self._local_at(step)
        return self.to_frame(self.assemble(af, lf))

    def __iter__(self) -> Iterator[Frame]:
        for k in range(len(self)):
            yield self.frame(k)

    def _atom_columns(self) -> list[str]:
        cols = list(ATOM_COLUMNS)
        for k, fix in enumerate(self.script.walls):
            if not self.scene.walls[k].missing:
                cols += [f"f_{fix.id}[{q}]" for q in range(1, 9)]
        return cols

    def _local_at(self, step: int) -> DumpFrame | None:
        if self.pairs is None:
            return None
        matches = np.flatnonzero(np.asarray(self.pairs.steps) == step)
        if not len(matches):
            raise InputFormatError(
                f"the pair dump has no frame at timestep {step}, which the atom dump has.",
                file=self.pairs.path,
                step=step,
                fix="write the atom and pair dumps every N steps with the same N.",
            )
        return self.pairs.frame(int(matches[0]), columns=list(self.join.pair_names.values()))

    def assemble(self, af: DumpFrame, lf: DumpFrame | None) -> Assembled:
        """One step's contacts with the rebuild's columns, their springs rebuilt and checked
        (:mod:`.lammps_join`, :mod:`.lammps_balance`)."""
        join, step = self.join, af.step
        run = run_of_step(self.script, join.dump_first_run, step)
        box = Box(
            af.box.lo, af.box.hi, tuple(p or q for p, q in zip(af.box.periodic, self.script.periodic)), af.box.tilt
        )
        atoms = join.atoms(af, join.setup_frame(step))
        index = ParticleIndex(atoms["id"], file=af.file, step=step)
        particles = {
            "id": atoms["id"],
            "type": atoms["type"].astype(np.int32),
            "x": atoms["x"][:, 0],
            "y": atoms["x"][:, 1],
            "z": atoms["x"][:, 2],
            "radius": atoms["r"],
            "mass": atoms["m"],
        }
        parts, rows1, rows2, lines, notes = [], [], [], [], []
        if lf is not None:
            part, i, j = join.pairs(lf, atoms, index, box)
            parts.append(part)
            rows1.append(i)
            rows2.append(j)
            lines.append((str(lf.file), lf.first_line + np.arange(len(i)) if lf.first_line is not None else None))
        part, i, j = join.necks(atoms, box)
        if len(i):
            part[DUMP_ROW] = np.full(len(i), -1.0)
            part["neck"] = np.ones(len(i), bool)
            parts.append(part)
            rows1.append(i)
            rows2.append(j)
            lines.append((str(af.file), af.first_line + i if af.first_line is not None else None))
            notes.append(
                "jkr pairs apart by less than their pull-off distance may hold a neck, which no dump says: "
                "their energies are not computed (the contacts' not_computed column marks them)"
            )
        wall_parts, wall_rows, wall_notes = join.walls(af, atoms, run)
        notes += wall_notes
        for part, i in zip(wall_parts, wall_rows):
            parts.append(part)
            rows1.append(i)
            rows2.append(np.full(len(i), -1))
            lines.append((str(af.file), af.first_line + i if af.first_line is not None else None))
        for part in parts:
            n = len(part["delta"])
            part.setdefault("extra_contact", np.zeros(n, bool))
            part.setdefault("neck", np.zeros(n, bool))
        contacts = {c: np.concatenate([p[c] for p in parts]) for c in parts[0]} if parts else {}
        r1 = np.concatenate(rows1) if rows1 else np.zeros(0, int)
        r2 = np.concatenate(rows2) if rows2 else np.zeros(0, int)
        rebuilt = join.rebuild(contacts, particles, run, self.walls_first_run) if len(r1) else None
        assembled = Assembled(
            step,
            particles,
            contacts,
            box,
            atoms,
            r1,
            r2,
            rebuilt,
            lines,
            run,
            notes,
            (str(af.file),) + ((str(lf.file),) if lf is not None else ()),
        )
        if rebuilt is not None:
            self._ghosts_of_other_processes(assembled, particles)
            self._check_normal_forces(assembled)
            gravity = self.script.gravity[run] if run < len(self.script.gravity) else None
            close_balances(assembled, None if self.script.other_forces else gravity)
        return assembled

    def _ghosts_of_other_processes(self, a: Assembled, particles: dict) -> None:
        """In a run on several processes, atom 2 of a pair across two sub-domains was a ghost too, whose half-step
        velocities single() read, and no dump says which pairs those are: a pair row whose dumped normal force the
        full-step velocities of atom 2 do not give, and its half-step ones do, is taken with them (the two differ
        by far more than the check's tolerance wherever the damping acts: sample_dumps/lammps/README.md)."""
        off = np.flatnonzero(_off(a) & (a.contacts["wall"] < 0) & ~a.contacts["neck"])
        if not len(off):
            return
        sub = self.join.as_ghosts(a.contacts, a.atoms, a.rows1[off], a.rows2[off], off)
        again = self.join.rebuild(sub, particles, a.run, self.walls_first_run)
        fixed = ~_off_of(again, sub["fn_dumped"])
        rows = off[fixed]
        for name, values in sub.items():
            a.contacts[name][rows] = values[fixed]
        for name in type(again).__dataclass_fields__:
            getattr(a.rebuilt, name)[rows] = getattr(again, name)[fixed]
        if len(rows):
            a.notes.append(
                "pairs whose atom 2 single() read at the half step though it is no periodic image (a "
                "ghost of another process: an MPI run) were found by their dumped normal force"
            )

    def _check_normal_forces(self, a: Assembled) -> None:
        """Each dumped normal force must be the one the script's model gives, to FORCE_TOLERANCE of its scale."""
        r = a.rebuilt
        dumped = a.contacts["fn_dumped"]
        off = _off(a)
        if off.any():
            c = int(np.flatnonzero(off)[0])
            file, line = self._line(a, c)
            wall = int(a.contacts["wall"][c])
            law = (
                self.scene.walls[wall].model
                if wall >= 0
                else self.scene.pair_model(int(a.atoms["type"][a.rows1[c]]), int(a.atoms["type"][a.rows2[c]]))
            ).law
            raise InputFormatError(
                f"the normal force LAMMPS wrote for the contact of atom {int(a.contacts['id1'][c])} with "
                + (f"wall {self.scene.walls[wall].name}" if wall >= 0 else f"atom {int(a.contacts['id2'][c])}")
                + f" is {float(dumped[c]):.17g}, but the script's model ({law}) gives {float(r.fn_rebuilt[c]):.17g} "
                f"({int(off.sum())} such contact(s)): the model, a coefficient or the velocities are not the run's.",
                file=file,
                step=a.step,
                line=line,
                fix="pass the script that wrote these dumps (its models and coefficients as they were when it ran).",
            )

    def _line(self, a: Assembled, c: int) -> tuple[str, int | None]:
        offset = 0
        for file, lines in a.lines:
            n = 0 if lines is None else len(lines)
            if c < offset + n:
                return file, int(lines[c - offset])
            offset += n
        return a.source[0], None

    def to_frame(self, a: Assembled) -> Frame:
        """The Frame of an assembled step: the canonical contact columns, the rebuilt springs and what is unknown."""
        keep = ("id1", "id2", "wall", "delta", "nx", "ny", "nz", "x1", "y1", "z1", "r1", "r2", "wall_curvature")
        laws = [m.contact_law for m in self.scene.models()]
        rolling = any("u_r" in law.modes for law in laws)
        springs = [*(SPRING_T if any("u_t" in law.modes for law in laws) else ()), *(SPRING_R if rolling else ())]
        if a.rebuilt is None:  # no contact: the columns of every other frame, empty
            contacts = {
                c: np.zeros(0, dtype=np.int64 if c in ("id1", "id2", "wall") else np.float64) for c in (*keep, *springs)
            }
            contacts[UNKNOWN_MODES] = contacts[UNKNOWN_WHY] = np.zeros(0, dtype=np.int8)
        else:
            contacts = {c: a.contacts[c] for c in keep}
            bits, why = unknown_columns(a.rebuilt, a.contacts["extra_contact"], a.contacts["neck"], rolling)
            lost = bits != 0
            vectors = {**dict(zip(SPRING_T, a.rebuilt.spring_t.T)), **dict(zip(SPRING_R, a.rebuilt.spring_r.T))}
            for c in springs:
                contacts[c] = np.where(lost, 0.0, vectors[c])
            contacts[UNKNOWN_MODES], contacts[UNKNOWN_WHY] = bits, why
        present = tuple(
            k
            for k, w in enumerate(self.script.walls)
            if w.first_run <= a.run and (w.end_run is None or a.run < w.end_run)
        )
        time = None if self.script.timestep is None else a.step * self.script.timestep
        return Frame(
            step=a.step,
            particles=a.particles,
            contacts=contacts,
            box=a.box,
            time=time,
            source=a.source,
            overlap_source="pairs: dist of compute pair/local; walls: positions (full precision)",
            notes=list(a.notes),
            walls=None if len(present) == len(self.script.walls) else present,
        )

    # -- description ----------------------------------------------------------------------------------------------

    def describe(self) -> dict:
        return {
            "kind": "lammps",
            "script": str(self.script.path),
            "units": self.script.units,
            "atoms": {"path": str(self.atoms.path), "frames": len(self.atoms.steps)},
            "pairs": None if self.pairs is None else {"path": str(self.pairs.path), "frames": len(self.pairs.steps)},
            "pair_models": {f"{i} {j}": m.law for (i, j), m in sorted(self.script.pair_models.items())},
            "notes": self.notes,
        }

    def named_files(self) -> list[Path]:
        """The files read, and every other file the script names (:meth:`LammpsScript.named_files`)."""
        return [Path(s) for s in self.sources] + self.script.named_files()

    def check_files(self, out: list[str]) -> list[str]:
        problems = []
        for name, dump in (("atoms", self.atoms), ("pairs", self.pairs)):
            if dump is None:
                out.append(f"  {name + ':':<10} none")
                continue
            out.append(f"  {name + ':':<10} {dump.path} ({len(dump.steps)} frames, steps {describe_steps(dump.steps)})")
            if dump is self.pairs:
                missing = np.setdiff1d(self.steps, dump.steps)
                if len(missing):
                    problems.append(
                        str(
                            InputFormatError(
                                f"{len(missing)} timestep(s) of the atom dump have no frame here, "
                                f"e.g. {missing[:5].tolist()}.",
                                file=dump.path,
                                step=int(missing[0]),
                                fix="write both dumps every N steps with the same N.",
                            )
                        )
                    )
        return problems

    def locate(self, frame: Frame, row: int) -> tuple[str | None, int | None]:
        """Pair rows are the local dump's rows in order; wall rows have the atom dump's line of their particle."""
        n_pairs = int(np.count_nonzero(frame.contacts["wall"] < 0)) if frame.n_contacts else 0
        if row < n_pairs and self.pairs is not None:
            k = int(np.flatnonzero(self.pairs.steps == frame.step)[0])
            return str(self.pairs.path), self.pairs.frame(k, columns=self.pairs.columns[:1]).line_of(row)
        return str(self.atoms.path), None


__all__ = ["LammpsRun", "wall_material_spec"]
