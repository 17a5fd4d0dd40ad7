"""The per-timestep join of a LIGGGHTS run: one atom frame, its pair contacts, its mesh-wall contacts and the
primitive-wall contacts rebuilt from positions, into one :class:`~demsplit.frame.Frame`.

:class:`StepJoin` holds what the join needs and what is fixed for the run (the scene, the contact dumps'
column names, the columns the laws read, the overlap tolerance); :mod:`demsplit.readers.liggghts` finds the
files and hands each timestep's dump frames to :meth:`StepJoin.frame`. Geometry comes from the atom dump
(minimum image across periodic boundaries); the overlap from the best source the run offers, chosen per run
and reported (``overlap_source``):

1. the dumped ``delta`` column (%g keeps it to 5e-6 relative);
2. positions at full precision (``%.17g`` format or a binary dump);
3. positions at printed precision, only when the error bound sqrt(3) h / delta (h = the printed step of the
   coordinates) stays below ``overlap_tolerance`` for every contact, or when ``force_positions`` is set (the
   bound is then reported per contact); else :class:`~demsplit.errors.PrecisionError`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ContactError, InputFormatError, MaterialError, PrecisionError
from ..frame import Box, Frame, ParticleIndex, Table
from ..physics.modes import HISTORY_LOST
from ..physics.shares import contact_point
from ..runtime import threads
from ..scene import Scene
from .lammps_dump import DumpFrame
from .liggghts_wallforce import REASONS, WallForce
from .liggghts_walls import primitive_wall_contacts
from .precision import position_error, printed_step, relative_rounding

ATOM_COLUMNS = ("id", "type", "x", "y", "z", "radius")
"""Atom dump columns every LIGGGHTS run needs (the laws may need more: :attr:`StepJoin.atom_columns`)."""

PRIMITIVE_HISTORY_UNKNOWN = (
    "the energies that depend on a contact's history (tangential and rolling springs, elasto-plastic normal "
    "state, an easo liquid bridge across a gap) of primitive-wall contacts are NOT COMPUTED: LIGGGHTS never writes "
    "the history of primitive-wall contacts (their rows carry not_computed bits). An equivalent mesh wall (fix "
    "mesh/surface of the same plane or cylinder, with compute wall/gran/local) would give them."
)
"""The note of a run whose law reads a history and which has primitive walls."""


@dataclass
class StepJoin:
    """The join of one timestep's dumps into a Frame (see the module docstring), with what is fixed for the run.

    scene : materials, contact model, walls.
    periodic : the script's periodic flags (a dump's box may lack them).
    timestep : seconds per step (None: unknown), for the frames' ``time``.
    atom_columns : the atom dump columns read (:data:`ATOM_COLUMNS`, then what the laws need of the particles).
    pair_names, wall_names : canonical column name -> dump header token of the pair and the mesh-wall dump.
    law_columns : contact columns the scene's laws read, in their order.
    mesh_walls : the scene's wall index of each mesh of the dumped mesh ``fix wall/gran`` (its ``mesh_index``).
    has_wall_dump : the run has a mesh-wall contact dump.
    overlap_tolerance, force_positions : the printed-positions policy (module docstring, point 3).
    wall_force : the rebuilding of the primitive-wall contacts' history from their fixes' stored forces
        (:mod:`.liggghts_wallforce`), None when the run does not allow it.
    primitive_note : what the run's notes say of the primitive-wall contacts' history (whether and how it is
        rebuilt), added to every frame with primitive-wall contacts of a law that reads a history.
    """

    scene: Scene
    periodic: tuple[bool, bool, bool]
    timestep: float | None
    atom_columns: list[str]
    pair_names: dict[str, str]
    wall_names: dict[str, str]
    law_columns: list[str]
    mesh_walls: list[int]
    has_wall_dump: bool
    overlap_tolerance: float
    force_positions: bool
    wall_force: WallForce | None = None
    primitive_note: str = PRIMITIVE_HISTORY_UNKNOWN

    def frame(
        self,
        af: DumpFrame,
        pf: DumpFrame,
        wf: DumpFrame | None,
        walls: tuple[int, ...] | None,
        kind: tuple[bool | None, float | None] = (None, None),
    ) -> Frame:
        """The Frame of one timestep's atom, pair and mesh-wall dump frames; ``walls``: the scene's walls
        that exist at this step (None: every one), the primitive ones rebuilt only where they exist; ``kind``:
        whether the frame was written at the setup of a run (None: unknown) and that run's timestep (s), for the
        rebuilding of the primitive walls' history (:attr:`wall_force`)."""
        step = af.step
        box = Box(af.box.lo, af.box.hi, tuple(p or q for p, q in zip(af.box.periodic, self.periodic)), af.box.tilt)
        particles: Table = {
            "id": af.int_column("id"),
            "type": af.int_column("type").astype(np.int32),
            "x": af.columns["x"],
            "y": af.columns["y"],
            "z": af.columns["z"],
            "radius": af.columns["radius"],
        }
        particles.update({c: af.columns[c] for c in self.atom_columns[len(ATOM_COLUMNS) :]})
        if np.any(~(particles["radius"] > 0)):
            row = int(np.flatnonzero(~(particles["radius"] > 0))[0])
            raise InputFormatError(
                f"particle radius must be > 0, found {float(particles['radius'][row])!r}.",
                file=af.file,
                step=step,
                line=af.line_of(row),
                fix="check the atom dump's radius column.",
            )
        unknown = ~np.isin(particles["type"], list(self.scene.materials))
        if unknown.any():
            row = int(np.flatnonzero(unknown)[0])
            raise MaterialError(
                f"particle type {int(particles['type'][row])} has no material (materials are "
                f"defined for types {sorted(self.scene.materials)}).",
                file=af.file,
                step=step,
                line=af.line_of(row),
                fix="define youngsModulus and poissonsRatio for every type in the input script, "
                "or pass --material TYPE:E:NU.",
            )
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
        reach = [
            (w.model or self.scene.model).contact_law.separation_limit(particles["radius"], np.inf)
            for w in self.scene.walls
        ]
        primitive = (
            primitive_wall_contacts(particles, self.scene.walls, margin=np.sqrt(3.0) * h, reach=reach, present=walls)
            if has_primitive
            else {}
        )
        notes = []
        # the law reads a contact history, which LIGGGHTS never writes for primitive walls: every frame's
        # contacts say which rows lack it (history_unknown), so that their modes are "not computed"
        history = [c for c in self.law_columns if c in parts[0]] if has_primitive else []
        if history:
            for part in parts:
                part["history_unknown"] = np.zeros(len(part["delta"]), dtype=np.int8)
        if primitive:
            rows = index.rows(primitive["id1"])
            # a contact apart beyond the positions' uncertainty (a liquid bridge's): the bound of its gap
            gap = -primitive["delta"]
            primitive["bound"] = np.where(
                gap >= np.sqrt(3.0) * h[rows], position_error(h[rows], gap), position_error(h[rows], primitive["delta"])
            )
            # LIGGGHTS' own point for a wall contact is on the wall: the particle takes the whole overlap
            primitive["cpx"], primitive["cpy"], primitive["cpz"] = contact_point(
                np.stack([primitive[c] for c in ("x1", "y1", "z1")], -1),
                np.stack([primitive[c] for c in ("nx", "ny", "nz")], -1),
                primitive["r1"],
                primitive["delta"],
                1.0,
            ).T
            for c in history:  # columns every part must have; the flag below says they are unknown here
                primitive[c] = np.zeros(len(primitive["delta"]))
            if history:
                primitive["history_unknown"] = np.full(len(primitive["delta"]), HISTORY_LOST, dtype=np.int8)
                if self.wall_force is not None:
                    notes += self._rebuild(primitive, history, particles, parts, af, pf, wf, box, kind)
            parts.append(primitive)
        if history:
            notes.insert(0, self.primitive_note)
        contacts = {c: np.concatenate([p[c] for p in parts]) if len(parts) > 1 else parts[0][c] for c in parts[0]}
        source, error = self._overlap_policy(contacts, contacts.pop("bound"), af, pf, step)
        time = None if self.timestep is None else step * self.timestep
        return Frame(
            step=step,
            particles=particles,
            contacts=contacts,
            box=box,
            time=time,
            source=(str(af.file), str(pf.file)) + ((str(wf.file),) if wf is not None else ()),
            overlap_source=source,
            overlap_error=error,
            notes=notes,
            walls=walls,
        )

    def _rebuild(
        self,
        primitive: Table,
        history: list[str],
        particles: Table,
        parts: list[Table],
        af: DumpFrame,
        pf: DumpFrame,
        wf: DumpFrame | None,
        box: Box,
        kind: tuple[bool | None, float | None],
    ) -> list[str]:
        """The primitive-wall rows' history rebuilt from the stored forces (:attr:`wall_force`), in place; the
        notes of the reasons of what stays unknown."""
        setup, dt = kind
        pairs = {**parts[0], "periodic": pf.columns[self.pair_names["periodic"]]}
        atom_digits = [af.digits.get(c) for c in ("x", "y", "z", "radius", *self.wall_force.particle_columns())]
        local_digits = [
            f.digits.get(names[c])
            for f, names in ((pf, self.pair_names), (wf, self.wall_names))
            if f is not None
            for c in (*history, "delta")
            if c in names
        ]
        print_rtol = max(relative_rounding(d) for d in atom_digits + local_digits)
        rebuilt = self.wall_force.rebuild(
            particles,
            pairs,
            parts[1] if wf is not None else None,
            primitive,
            box,
            setup,
            dt,
            print_rtol,
            "delta" in self.wall_names,
        )
        for c in history:
            if c in rebuilt.columns:
                primitive[c] = rebuilt.columns[c]
        primitive["history_unknown"] = rebuilt.unknown
        return [REASONS[r] for r in rebuilt.reasons]

    def _pairs(self, pf: DumpFrame, index: ParticleIndex, xyzr: np.ndarray, h: np.ndarray | None, box: Box) -> Table:
        from demsplit.kernels import pair_geometry  # compiled, lazily
        from demsplit.kernels import repeated_pair as repeated_rows

        names = self.pair_names
        col = {c: pf.columns[t] for c, t in names.items() if t in pf.columns}
        id1, id2 = pf.int_column(names["id1"]), pf.int_column(names["id2"])
        wall = np.full(len(id1), -1, np.int64)
        rows1, rows2 = self._pair_rows(index, pf, id1, id2, wall)
        first, repeat = repeated_rows(rows1, rows2, len(index.ids))
        if repeat >= 0:
            raise ContactError(
                f"particle {int(id1[first])} is paired with itself."
                if first == repeat
                else f"the contact of particles {int(id1[repeat])} and {int(id2[repeat])} is listed twice in this "
                f"frame "
                f"(rows {first + 1} and {repeat + 1}, lines {pf.line_of(first)} and {pf.line_of(repeat)}).",
                file=pf.file,
                step=pf.step,
                line=pf.line_of(repeat),
                fix="each contact must appear once per frame: check that the dump is not the concatenation of "
                "two runs or of two MPI ranks' output for the same step.",
            )
        dumped_cp = all(c in col for c in ("cpx", "cpy", "cpz"))
        nx, ny, nz, x1, y1, z1, r1, r2, gap, hmax, cp = pair_geometry(
            rows1, rows2, xyzr, np.zeros(0) if h is None else h, box.lengths, box.tilt, box.periodic, not dumped_cp
        )
        if "delta" in col and len(hmax):
            _refuse_overlaps_off_positions(pf, names["delta"], col["delta"], gap, hmax, r1 + r2, id1, id2)
        out: Table = {
            "id1": id1,
            "id2": id2,
            "wall": wall,
            "delta": col["delta"] if "delta" in col else gap,
            "nx": nx,
            "ny": ny,
            "nz": nz,
            "x1": x1,
            "y1": y1,
            "z1": z1,
            "r1": r1,
            "r2": r2,
        }
        out["bound"] = self._delta_error(pf, names, hmax, gap)
        out.update({c: col[c] for c in self.law_columns if c in col})
        # the dumped point, else LIGGGHTS' own radius-weighted point, (x1 r2 + x2 r1)/(r1 + r2), from the join
        cpx, cpy, cpz = (col["cpx"], col["cpy"], col["cpz"]) if dumped_cp else cp
        if box.any_periodic:
            cpx, cpy, cpz = box.wrap(np.stack([cpx, cpy, cpz], axis=-1)).T
        out.update(cpx=cpx, cpy=cpy, cpz=cpz)
        return out

    def _mesh_walls(
        self, wf: DumpFrame, particles: Table, index: ParticleIndex, xyz: np.ndarray, h: np.ndarray
    ) -> Table:
        names = self.wall_names
        col = {c: wf.columns[t] for c, t in names.items() if t in wf.columns}
        pid = wf.int_column(names["id1"])
        mesh = wf.int_column(names["mesh_index"])
        wall_of_mesh = np.asarray(self.mesh_walls, dtype=np.int64)
        if len(mesh) and (mesh.min() < 0 or mesh.max() >= len(wall_of_mesh)):
            row = int(np.flatnonzero((mesh < 0) | (mesh >= len(wall_of_mesh)))[0])
            raise InputFormatError(
                f"mesh index {int(mesh[row])} is not one of the {len(wall_of_mesh)} meshes of the script's "
                "last mesh 'fix wall/gran'.",
                file=wf.file,
                step=wf.step,
                line=wf.line_of(row),
                fix="pass the input script that wrote this dump.",
            )
        self._refuse_repeated_wall_contacts(wf, pid, mesh, col)
        (rows,) = self._rows(index, wf, pid)
        r = particles["radius"][rows]
        if all(c in col for c in ("wall_cpx", "wall_cpy", "wall_cpz")):
            on_wall = np.stack([col["wall_cpx"], col["wall_cpy"], col["wall_cpz"]], axis=-1)
        else:
            raise InputFormatError(
                "the wall contact dump lacks the 'pos' columns, so the wall normal is unknown.",
                file=wf.file,
                step=wf.step,
                fix="add 'pos' to the compute wall/gran/local keywords.",
            )
        d = on_wall - xyz[rows]
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        n = d / np.where(dist > 0, dist, 1.0)[:, None]
        out: Table = {
            "id1": pid,
            "id2": np.full(len(pid), -1, np.int64),
            "wall": wall_of_mesh[mesh],
            "delta": col["delta"] if "delta" in col else r - dist,
            "nx": n[:, 0],
            "ny": n[:, 1],
            "nz": n[:, 2],
            "x1": xyz[rows, 0],
            "y1": xyz[rows, 1],
            "z1": xyz[rows, 2],
            "r1": r,
            "r2": np.full(len(pid), np.inf),
        }
        wall_digits = min((wf.digits.get(names[c]) or 17) for c in ("wall_cpx", "wall_cpy", "wall_cpz"))
        h_wall = np.max(printed_step(on_wall, wall_digits), axis=1)
        out["bound"] = self._delta_error(wf, names, np.maximum(h[rows], h_wall), r - dist)
        out.update(
            {
                c: col[c] if c in col else np.zeros(len(pid))
                for c in self.law_columns
                if c in col or c in self.pair_names
            }
        )  # 0: a column only the pairs' law reads
        out.update(cpx=on_wall[:, 0], cpy=on_wall[:, 1], cpz=on_wall[:, 2])
        return out

    def _refuse_repeated_wall_contacts(self, wf: DumpFrame, pid: np.ndarray, mesh: np.ndarray, col: Table) -> None:
        """A mesh-wall contact (particle, mesh, triangle; without ``tri_id`` the whole row) listed twice in a
        frame would be counted twice: a ContactError naming both lines."""
        if len(pid) < 2:
            return
        keys = [pid, mesh] + (
            [wf.int_column(self.wall_names["tri_id"])]
            if "tri_id" in self.wall_names
            else [col[c] for c in ("delta", "wall_cpx", "wall_cpy", "wall_cpz") if c in col]
        )
        order = np.lexsort(keys[::-1])
        same = np.ones(len(pid) - 1, dtype=bool)
        for k in keys:
            same &= k[order][1:] == k[order][:-1]
        if same.any():
            at = int(np.flatnonzero(same)[0])
            first, repeat = sorted((int(order[at]), int(order[at + 1])))
            raise ContactError(
                f"the contact of particle {int(pid[repeat])} with mesh {int(mesh[repeat])} is listed twice in this "
                f"frame (lines {wf.line_of(first)} and {wf.line_of(repeat)}).",
                file=wf.file,
                step=wf.step,
                line=wf.line_of(repeat),
                fix="each contact must appear once per frame: check that the dump is "
                "not the concatenation of two runs or of two MPI ranks' output for the same step.",
            )

    @staticmethod
    def _pair_rows(
        index: ParticleIndex, f: DumpFrame, id1: np.ndarray, id2: np.ndarray, wall: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`ParticleIndex.contact_rows` of the particle pairs of contact dump frame
        ``f``; an unknown id is a ContactError naming the dump and the line of its first row."""
        try:
            return index.contact_rows(id1, id2, wall)
        except ContactError:
            StepJoin._rows(index, f, id1, id2)  # raises, with the line
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
    def _delta_error(
        f: DumpFrame, names: dict[str, str], h: np.ndarray, delta_from_positions: np.ndarray
    ) -> np.ndarray:
        """Relative error bound of each contact's overlap: the rounding of the
        dumped ``delta`` column, or the position bound when there is none."""
        token = names.get("delta")
        if token is not None:
            return np.full(len(delta_from_positions), relative_rounding(f.digits.get(token)))
        return position_error(h, delta_from_positions)

    def _overlap_policy(
        self, contacts: Table, error: np.ndarray, af: DumpFrame, pf: DumpFrame, step: int
    ) -> tuple[str, np.ndarray | None]:
        """Where the overlaps come from, their per-contact relative error bound,
        and refusal when overlaps recomputed from printed positions are too imprecise."""
        delta = self.pair_names.get("delta")
        digits = af.digits.get("x")
        positions = "full precision" if relative_rounding(digits) == 0 else f"printed precision ({digits} digits)"
        parts = [f"pairs: {'dumped delta' if delta else 'positions, ' + positions}"]
        if self.has_wall_dump:
            parts.append(f"mesh walls: {'dumped delta' if 'delta' in self.wall_names else 'positions'}")
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
                file=af.file,
                step=step,
                fix="dump the overlap ('delta' keyword of compute pair/gran/local and wall/gran/local), or write "
                "positions at full precision (dump_modify ID format with %.17g, or a binary .bin atom dump); "
                "primitive-wall overlaps always come from positions. Or raise --overlap-tolerance, or use "
                "--force-positions to accept the error, which is then reported per contact.",
            )
        return source, error


def _refuse_overlaps_off_positions(
    pf: DumpFrame,
    token: str,
    delta: np.ndarray,
    gap: np.ndarray,
    h: np.ndarray,
    r: np.ndarray,
    id1: np.ndarray,
    id2: np.ndarray,
) -> None:
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
            f"allows {float(tol[row]):.2g} m); {int(off.sum())} such contact(s).",
            file=pf.file,
            step=pf.step,
            line=pf.line_of(row),
            fix="check that the pair and atom dumps belong to the same run and timestep.",
        )


def _largest_printed_step(coordinates: list[np.ndarray], digits: list[int | None]) -> np.ndarray:
    """Per particle, the largest :func:`~demsplit.readers.precision.printed_step` of its coordinates
    (m; 0 at full precision), pieces of the particles on every core."""
    h = np.empty(len(coordinates[0]))

    def piece(lo: int, hi: int) -> None:
        h[lo:hi] = np.max([printed_step(x[lo:hi], d) for x, d in zip(coordinates, digits)], axis=0)

    threads.map_ranges(piece, len(h))
    return h
