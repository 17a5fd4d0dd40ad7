"""The per-timestep join of a LAMMPS granular run: an atom frame and its local-dump frame into the contacts,
their springs rebuilt, checked against what LAMMPS dumped, into one :class:`~demsplit.frame.Frame`.

:class:`LammpsJoin` holds what is fixed for the run (the script, the scene, which dump column is which);
:meth:`LammpsJoin.assemble` builds one step's contacts with every column the rebuild reads
(:data:`demsplit.physics.laws._lammps.VELOCITIES`, ``DUMPED``, ...), runs each law's
:meth:`~demsplit.physics.laws._lammps.LammpsModel.rebuild` on its contacts, checks the rebuilt normal force
against the dumped one (a wrong model or coefficient is an error naming the line), and checks the springs single()
found at their limit against the atoms' force and torque balance (:mod:`.lammps_balance`);
:meth:`LammpsJoin.frame` keeps the canonical columns and the springs.

Velocities (verlet.cpp:254-352, fix_nve_sphere.cpp:117-135): the step's forces were computed with the half-step
velocities v - dt/2 f/m, omega - dt/2 tau/(0.4 m r^2) of every atom; ``compute pair/local`` (single()) ran after
the step with the full-step velocities of the owned atom i and of j, but the half-step ones of a ghost j, which on
one process is a periodic image (its separation p10..p12 differs from x_i - x_j). A frame written at a run's setup
holds forces of the full-step velocities everywhere.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import ContactError, InputFormatError
from ..frame import Box, ParticleIndex, Table
from ..physics.bodies import FrameContacts, LawRows
from ..physics.laws._lammps import CURVATURE, DUMP_ROW, UNKNOWN_MODES, UNKNOWN_WHY, Rebuilt, norm
from ..physics.modes import NOT_COMPUTED_BITS
from ..scene import ContactModel, Scene
from .lammps_dump import DumpFrame
from .lammps_input import Variables, Where
from .lammps_script import LammpsScript, WallFix
from .lammps_walls import fix_contacts

ATOM_COLUMNS = (
    "id",
    "type",
    "x",
    "y",
    "z",
    "vx",
    "vy",
    "vz",
    "omegax",
    "omegay",
    "omegaz",
    "fx",
    "fy",
    "fz",
    "tqx",
    "tqy",
    "tqz",
    "radius",
    "mass",
)
"""Atom dump columns a LAMMPS run needs: the half-step velocities are rebuilt from the forces and torques."""
WALL_POINT_TOLERANCE = 1e-9
"""Largest distance between the wall point a fix wrote and demsplit's, over the particle's radius."""
FORCE_TOLERANCE = 1e-9
"""Largest relative difference between a dumped normal force and the rebuilt one (scale |F_ne| + |damping|)."""
NEIGHBOUR_BLOCK = 256
"""Atoms per block of the search for pairs apart within their model's reach."""


@dataclass
class Assembled:
    """One step's atoms and contacts with every column the rebuild read, and the rebuild.

    atoms : per atom (rows of the atom dump): ``f``, ``tq`` (dumped), ``m``, ``r``; ``rows1``, ``rows2``: the
    atom rows of every contact's bodies (-1: a wall); ``rebuilt``: the contacts' springs and step forces,
    concatenated in contact order; ``lines``: per contact, (file, line) for messages."""

    step: int
    particles: Table
    contacts: Table
    box: Box
    atoms: dict[str, np.ndarray]
    rows1: np.ndarray
    rows2: np.ndarray
    rebuilt: Rebuilt
    lines: list[tuple[str, np.ndarray]]
    run: int
    notes: list[str] = field(default_factory=list)
    source: tuple[str, ...] = ()


def run_of_step(script: LammpsScript, first_run: int, step: int) -> int:
    """The index of the run that wrote a dump's frame of ``step``: the first run from ``first_run`` on
    (the dump's) whose steps hold it (a step that ends one run and starts the next is written at the end)."""
    runs = [k for k, (start, end) in enumerate(script.runs) if k >= first_run and start <= step <= end]
    return runs[0] if runs else len(script.runs) - 1


def step_value(formula: str, step: int, run_start: int, dt: float, where: Where) -> float:
    """An equal-style formula at timestep ``step``: ``step``, ``elapsed`` (steps since the run started),
    ``time`` (step dt) and ``dt`` substituted, the rest evaluated as :class:`~.lammps_input.Variables` does."""
    values = {"step": step, "elapsed": step - run_start, "elaplong": step - run_start, "time": step * dt, "dt": dt}
    text = re.sub(r"\b(step|elapsed|elaplong|time|dt)\b", lambda m: repr(float(values[m.group(1)])), formula)
    return Variables({}).evaluate(text, where)


@dataclass
class LammpsJoin:
    """The join of one step's dumps (module docstring), with what is fixed for the run.

    pair_names : canonical pair quantity (``patom1 patom2 dist force p1`` ..) -> the local dump's header token.
    wall_index : per wall fix of the script, its index in ``scene.walls`` (None: not a wall of the scene).
    dump_first_run : the run from which the atom dump writes (its line's place in the script).
    """

    script: LammpsScript
    scene: Scene
    pair_names: dict[str, str]
    wall_index: list[int | None]
    dump_first_run: int
    legacy: bool

    # -- atoms ------------------------------------------------------------------------------------------------

    def atoms(self, af: DumpFrame, setup: bool) -> dict[str, np.ndarray]:
        """The atoms' columns, with their half-step velocities ``v_h``, ``w_h`` (the full-step ones at a setup
        frame)."""
        c = af.columns

        def vec(*names: str) -> np.ndarray:
            return np.stack([np.asarray(c[k], dtype=np.float64) for k in names], axis=-1)

        x, v, w = vec("x", "y", "z"), vec("vx", "vy", "vz"), vec("omegax", "omegay", "omegaz")
        f, tq = vec("fx", "fy", "fz"), vec("tqx", "tqy", "tqz")
        r, m = np.asarray(c["radius"], dtype=np.float64), np.asarray(c["mass"], dtype=np.float64)
        dt = self.script.timestep or 0.0
        if setup:
            v_h, w_h = v, w
        else:
            v_h = v - 0.5 * dt * f / m[:, None]
            w_h = w - 0.5 * dt * tq / (0.4 * m * r * r)[:, None]
        return {
            "id": integers(af, "id"),
            "type": integers(af, "type"),
            "x": x,
            "v": v,
            "w": w,
            "f": f,
            "tq": tq,
            "r": r,
            "m": m,
            "v_h": v_h,
            "w_h": w_h,
        }

    def setup_frame(self, step: int) -> bool:
        """Whether the dump wrote ``step`` at a run's setup: the start of the first run it writes in."""
        runs = self.script.runs
        return self.dump_first_run < len(runs) and step == runs[self.dump_first_run][0]

    # -- pairs ------------------------------------------------------------------------------------------------

    def pairs(self, lf: DumpFrame, atoms: dict, index: ParticleIndex, box: Box) -> tuple[Table, np.ndarray, np.ndarray]:
        """The pair contacts of the local-dump frame ``lf`` with the rebuild's columns, and the atom rows of their
        bodies."""
        names = self.pair_names
        col = {
            k: np.asarray(lf.columns[t], dtype=np.float64) for k, t in names.items() if k not in ("patom1", "patom2")
        }
        id1, id2 = integers(lf, names["patom1"]), integers(lf, names["patom2"])
        try:
            i, j = index.rows(id1), index.rows(id2)
        except ContactError as exc:
            known = np.isin(id1, index.ids) & np.isin(id2, index.ids)
            raise ContactError(
                exc.message, file=lf.file, step=lf.step, line=lf.line_of(int(np.flatnonzero(~known)[0])), fix=exc.fix
            ) from None
        raw = atoms["x"][i] - atoms["x"][j]
        image = box.minimum_image(raw)
        if self.legacy:
            d = image  # the legacy styles write no separation vector
        else:
            d = np.stack([col["p10"], col["p11"], col["p12"]], axis=-1)
            d = np.where(np.all(d == 0, axis=1)[:, None], image, d)  # a row single() wrote as zeros (jkr)
        dumped = {
            "fn_dumped": col["force"],
            "ft_dumped": np.stack([col["p1"], col["p2"], col["p3"]], axis=-1),
            "fr_dumped": np.zeros((len(i), 3)) if self.legacy else np.stack([col["p5"], col["p6"], col["p7"]], axis=-1),
        }
        return pair_table(atoms, i, j, d, col["dist"], dumped), i, j

    def necks(self, atoms: dict, box: Box) -> tuple[Table, np.ndarray, np.ndarray]:
        """The pairs apart by less than their model's reach (a jkr neck that may still hold, which no ``cutoff
        radius`` row lists), as contacts whose every value is unknown, and their atom rows."""
        reach = {
            pair: m.contact_law
            for pair, m in self.script.pair_models.items()
            if np.any(m.contact_law.reach(np.ones(1)) > 0)
        }
        x, r, t = atoms["x"], atoms["r"], atoms["type"]
        found_i, found_j = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
        if reach and len(r):
            far = 2.0 * r.max() + max(float(law.reach(np.array([r.max()]))[0]) for law in reach.values())
            for lo in range(0, len(r), NEIGHBOUR_BLOCK):
                i = np.arange(lo, min(lo + NEIGHBOUR_BLOCK, len(r)))
                d = box.minimum_image((x[i, None, :] - x[None, :, :]).reshape(-1, 3)).reshape(len(i), len(r), 3)
                dist = np.sqrt(np.einsum("abk,abk->ab", d, d))
                radsum = r[i, None] + r[None, :]
                ii, jj = np.nonzero((dist >= radsum) & (dist < radsum + far))
                ii = i[ii]
                keep = ii < jj
                ii, jj = ii[keep], jj[keep]
                gap = dist[ii - lo, jj] - (r[ii] + r[jj])
                R = r[ii] * r[jj] / (r[ii] + r[jj])
                lo_t, hi_t = np.minimum(t[ii], t[jj]), np.maximum(t[ii], t[jj])
                hit = np.zeros(len(ii), dtype=bool)
                for (a, b), law in reach.items():
                    hit |= (lo_t == a) & (hi_t == b) & (gap < law.reach(R))
                found_i.append(ii[hit])
                found_j.append(jj[hit])
        i, j = np.concatenate(found_i), np.concatenate(found_j)
        d = box.minimum_image(x[i] - x[j])
        unknown = {
            "fn_dumped": np.full(len(i), np.nan),
            "ft_dumped": np.full((len(i), 3), np.nan),
            "fr_dumped": np.full((len(i), 3), np.nan),
        }
        return pair_table(atoms, i, j, d, np.sqrt(np.einsum("ak,ak->a", d, d)), unknown), i, j

    def as_ghosts(self, contacts: Table, atoms: dict, i: np.ndarray, j: np.ndarray, rows: np.ndarray) -> Table:
        """The pair contacts ``rows`` (atom rows ``i``, ``j``) as if single() had read atom 2's half-step velocities
        (a ghost of another process)."""
        sub = {c: v[rows].copy() for c, v in contacts.items()}
        vj, wj = atoms["v_h"][j], atoms["w_h"][j]
        _put_vectors(
            sub,
            {
                "dv_s": atoms["v"][i] - vj,
                "wr_s": atoms["w"][i] - wj,
                "ws_s": atoms["r"][i, None] * atoms["w"][i] + atoms["r"][j, None] * wj,
            },
        )
        return sub

    # -- walls ------------------------------------------------------------------------------------------------

    def walls(self, af: DumpFrame, atoms: dict, run: int) -> tuple[list[Table], list[np.ndarray], list[str]]:
        """The contacts of every wall fix that exists in run ``run``, from its contacts columns f_ID[1..8]; a
        particle touching a second surface of a region gets a row whose tangential spring is unknown."""
        parts, rows, notes = [], [], []
        for k, fix in enumerate(self.script.walls):
            index = self.wall_index[k]
            if index is None or not (fix.first_run <= run and (fix.end_run is None or run < fix.end_run)):
                continue
            part, i, note = self.wall(fix, index, af, atoms, run)
            parts.append(part)
            rows.append(i)
            notes += note
        return parts, rows, notes

    def wall(self, fix: WallFix, index: int, af: DumpFrame, atoms: dict, run: int) -> tuple[Table, np.ndarray, list]:
        c = af.columns
        touching = np.asarray(c[f"f_{fix.id}[1]"]) == 1
        x, r = atoms["x"], atoms["r"]
        theta, omega = self.region_turn(fix, af.step, run)
        surfaces = fix_contacts(fix, x, r, theta)
        dumped = np.stack([np.asarray(c[f"f_{fix.id}[{q}]"], dtype=np.float64) for q in (5, 6, 7)], axis=-1)
        force = np.stack([np.asarray(c[f"f_{fix.id}[{q}]"], dtype=np.float64) for q in (2, 3, 4)], axis=-1)
        which = np.full(len(r), -1)
        for s, (_, _, _, touch) in enumerate(surfaces):
            which = np.where(touch, s, which)  # the fix keeps the last contact
        rows_list, extra_list = [np.flatnonzero(touching)], []
        chosen = which[rows_list[0]]
        if np.any(chosen < 0):
            a = int(rows_list[0][np.flatnonzero(chosen < 0)[0]])
            raise ContactError(
                f"fix {fix.id} wrote a contact of atom {int(atoms['id'][a])} that demsplit's geometry "
                "of the wall does not find.",
                file=af.file,
                step=af.step,
                line=af.line_of(a),
                fix="check that the script is the one that wrote this dump (the wall's geometry).",
            )
        for s, (_, _, _, touch) in enumerate(surfaces):
            extra = np.flatnonzero(touch & (which != s))
            if len(extra):
                extra_list.append((s, extra))
        rows_all, surface_of, is_extra = [rows_list[0]], [chosen], [np.zeros(len(chosen), bool)]
        for s, extra in extra_list:
            rows_all.append(extra)
            surface_of.append(np.full(len(extra), s))
            is_extra.append(np.ones(len(extra), bool))
        i, surface, extra = np.concatenate(rows_all), np.concatenate(surface_of), np.concatenate(is_extra)
        d = np.zeros((len(i), 3))
        dist, curvature = np.zeros(len(i)), np.zeros(len(i))
        for s, (ds, rs, ks, _) in enumerate(surfaces):
            sel = surface == s
            d[sel], dist[sel], curvature[sel] = ds[i[sel]], rs[i[sel]], ks[i[sel]]
        self.check_wall_points(fix, af, atoms, i[~extra], d[~extra], dumped[i[~extra]])
        n_L = d / np.where(dist > 0, dist, 1.0)[:, None]
        vwall = np.zeros((len(i), 3))
        if fix.shear is not None:
            vwall[:, fix.shear[0]] = fix.shear[1]
        if omega is not None:
            vwall = np.cross(omega, (x[i] - d) - np.asarray(fix.region.rotate[1]))
        F = np.where(extra[:, None], np.nan, force[i])
        fn = np.einsum("ij,ij->i", F, n_L)
        v_h, w_h = atoms["v_h"][i], atoms["w_h"][i]
        out: Table = {
            "id1": atoms["id"][i],
            "id2": np.full(len(i), -1, np.int64),
            "wall": np.full(len(i), index),
            "delta": r[i] - dist,
            "nx": -n_L[:, 0],
            "ny": -n_L[:, 1],
            "nz": -n_L[:, 2],
            "x1": x[i, 0],
            "y1": x[i, 1],
            "z1": x[i, 2],
            "r1": r[i],
            "r2": np.full(len(i), np.inf),
            "m1": atoms["m"][i],
            "m2": np.full(len(i), np.inf),
            CURVATURE: curvature,
            DUMP_ROW: np.full(len(i), -1.0),
            "fn_dumped": fn,
        }
        ws = r[i, None] * w_h
        _put_vectors(
            out,
            {
                "dv_s": v_h - vwall,
                "dv_h": v_h - vwall,
                "ws_s": ws,
                "ws_h": ws,
                "wr_s": w_h,
                "wr_h": w_h,
                "ft_dumped": F - fn[:, None] * n_L,
                "fr_dumped": np.zeros((len(i), 3)),
            },
        )
        out["extra_contact"] = extra
        notes = []
        if extra.any():
            notes.append(
                f"fix {fix.id}: particles touching a second surface of region {fix.region.id} have that "
                "contact's tangential spring not computed (the fix's contacts array holds the last contact "
                "only)"
            )
        return out, i, notes

    def region_turn(self, fix: WallFix, step: int, run: int) -> tuple[float, np.ndarray | None]:
        """A rotating region's angle theta(step) (rad) and angular velocity (theta(step) - theta(step - 1))/dt
        (region.cpp:457-517), from its variable's formula in run ``run``; (0, None) for other walls."""
        region = fix.region
        if region is None or region.rotate is None:
            return 0.0, None
        formulas = self.script.rotations[region.id]
        formula = formulas[run] if run < len(formulas) else None
        where = Where(self.script.path, region.where.line)
        if formula is None:
            raise InputFormatError(
                f"region {region.id} rotates by v_{region.rotate[0]}, which is not an equal-style "
                "formula demsplit can evaluate in this run.",
                file=self.script.path,
                line=region.where.line,
                fix="define the angle as an equal-style variable.",
            )
        start, dt = self.script.runs[run][0], self.script.timestep
        theta = step_value(formula, step, start, dt, where)
        before = step_value(formula, step - 1, start, dt, where)
        axis = np.asarray(region.rotate[2], dtype=np.float64)
        return theta, (theta - before) / dt * axis / np.linalg.norm(axis)

    def check_wall_points(
        self, fix: WallFix, af: DumpFrame, atoms: dict, i: np.ndarray, d: np.ndarray, dumped: np.ndarray
    ) -> None:
        """The wall point x - d the fix wrote must be demsplit's, to WALL_POINT_TOLERANCE of the radius."""
        off = norm(atoms["x"][i] - d - dumped) > WALL_POINT_TOLERANCE * atoms["r"][i]
        if off.any():
            a = int(i[np.flatnonzero(off)[0]])
            raise ContactError(
                f"fix {fix.id} wrote the wall point of atom {int(atoms['id'][a])} at {dumped[np.flatnonzero(off)[0]]}, "
                f"not where demsplit's geometry of its {fix.geometry} puts it ({int(off.sum())} such contact(s)).",
                file=af.file,
                step=af.step,
                line=af.line_of(a),
                fix="check that the script is the one that wrote this dump (the wall's geometry and motion).",
            )

    # -- rebuild ----------------------------------------------------------------------------------------------

    def rebuild(self, contacts: Table, particles: Table, run: int, walls_first_run: dict[int, int]) -> Rebuilt:
        """Every contact's :class:`Rebuilt`, law by law (a wall's own model, the model of each pair of types),
        in contact order; a cross pair whose model LAMMPS left to its mixing is refused."""
        frame = FrameContacts(contacts, self.scene, particles)
        n = len(contacts["delta"])
        wall = contacts["wall"]
        groups: list[tuple[ContactModel, np.ndarray, int]] = []
        for w in np.unique(wall[wall >= 0]):
            groups.append(
                (self.scene.walls[int(w)].model, np.flatnonzero(wall == w), run - walls_first_run[int(w)] + 1)
            )
        pair = np.flatnonzero(wall < 0)
        if len(pair):
            t1, t2 = (np.asarray(t)[pair] for t in frame.types())
            lo, hi = np.minimum(t1, t2), np.maximum(t1, t2)
            for a, b in sorted(set(zip(lo.tolist(), hi.tolist()))):
                groups.append(
                    (self.pair_model(a, b, contacts, pair[(lo == a) & (hi == b)]), pair[(lo == a) & (hi == b)], 1)
                )
        parts = []
        for model, rows, inits in groups:
            parts.append((rows, model.contact_law.rebuild(LawRows(frame, rows, model.law), inits=inits)))
        return _gather(parts, n)

    def pair_model(self, a: int, b: int, contacts: Table, rows: np.ndarray) -> ContactModel:
        """The model of type pair (a, b); a pair no line set is refused (LAMMPS 29 Sep 2021 does not mix granular
        models: the pair's models are unset)."""
        model = self.script.pair_models.get((a, b))
        if model is None:
            raise ContactError(
                f"{len(rows)} contact(s) join atom types {a} and {b}, whose model no pair_coeff line sets: LAMMPS "
                "29 Sep 2021 leaves the models of a mixed granular pair unset, so their forces are not a model's.",
                file=self.script.path,
                fix=f"add 'pair_coeff {a} {b} ...' to the script and rerun (for material "
                "models: E = 2E*, nu = 0, k_t = 8G* of the two materials give the mixed values).",
            )
        return model


def integers(f: DumpFrame, name: str) -> np.ndarray:
    """An integer column of a LAMMPS dump as int64: LAMMPS prints ids and types with ``%d`` whatever the float
    format, so every value is exact (a frame whose integer-looking columns the parser read as reals, because one
    of them held a real, keeps their values); a value that is not an integer is an error naming its line."""
    values = f.columns[name]
    if values.dtype.kind in "iu":
        return values.astype(np.int64, copy=False)
    bad = ~(values == np.rint(values)) | ~(np.abs(values) < 2.0**53)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise InputFormatError(
            f"column '{name}' must hold integers, but row {row + 1} of the frame holds {values[row].item()!r}.",
            file=f.file,
            step=f.step,
            line=f.line_of(row),
            fix="pass the dump the script's line writes (LAMMPS prints ids with %d).",
        )
    return values.astype(np.int64)


def pair_table(
    atoms: dict, i: np.ndarray, j: np.ndarray, d: np.ndarray, dist: np.ndarray, dumped: dict[str, np.ndarray]
) -> Table:
    """Pair contacts of atom rows ``i``, ``j`` separated by ``d`` = x_i - x_j as LAMMPS used it (a periodic image:
    j a ghost, whose velocities single() read at the half step) at distance ``dist``, with the rebuild's columns
    and the ``dumped`` force (``fn_dumped`` (n,), ``ft_dumped``, ``fr_dumped`` (n, 3))."""
    x = atoms["x"]
    ghost = np.any(d != x[i] - x[j], axis=1)
    n_L = d / np.where(dist > 0, dist, 1.0)[:, None]
    ri, rj = atoms["r"][i], atoms["r"][j]
    vj_s = np.where(ghost[:, None], atoms["v_h"][j], atoms["v"][j])
    wj_s = np.where(ghost[:, None], atoms["w_h"][j], atoms["w"][j])
    v_h, w_h = atoms["v_h"], atoms["w_h"]
    out: Table = {
        "id1": atoms["id"][i],
        "id2": atoms["id"][j],
        "wall": np.full(len(i), -1, np.int64),
        "delta": ri + rj - dist,
        "nx": -n_L[:, 0],
        "ny": -n_L[:, 1],
        "nz": -n_L[:, 2],
        "x1": x[i, 0],
        "y1": x[i, 1],
        "z1": x[i, 2],
        "r1": ri,
        "r2": rj,
        "m1": atoms["m"][i],
        "m2": atoms["m"][j],
        CURVATURE: np.zeros(len(i)),
        DUMP_ROW: np.arange(len(i), dtype=np.float64),
        "fn_dumped": dumped["fn_dumped"],
    }
    _put_vectors(
        out,
        {
            "dv_s": atoms["v"][i] - vj_s,
            "dv_h": v_h[i] - v_h[j],
            "ws_s": ri[:, None] * atoms["w"][i] + rj[:, None] * wj_s,
            "ws_h": ri[:, None] * w_h[i] + rj[:, None] * w_h[j],
            "wr_s": atoms["w"][i] - wj_s,
            "wr_h": w_h[i] - w_h[j],
            "ft_dumped": dumped["ft_dumped"],
            "fr_dumped": dumped["fr_dumped"],
        },
    )
    return out


def _put_vectors(out: Table, vectors: dict[str, np.ndarray]) -> None:
    """Vectors ``NAME_SUFFIX`` (n, 3) as the contact columns ``NAMEx_SUFFIX`` ... (``ft_dumped`` -> ``ftx_dumped``)."""
    for name, v in vectors.items():
        head, _, tail = name.partition("_")
        for k, c in enumerate("xyz"):
            out[f"{head}{c}_{tail}"] = v[:, k]


def _gather(parts: list[tuple[np.ndarray, Rebuilt]], n: int) -> Rebuilt:
    """The rebuilds of groups of rows as one, in contact order."""
    fields = Rebuilt.__dataclass_fields__
    out = {}
    for name in fields:
        sample = next((getattr(r, name) for _, r in parts), None)
        shape = (n,) + (np.shape(sample)[1:] if sample is not None else ())
        dtype = sample.dtype if sample is not None else np.float64
        values = np.zeros(shape, dtype=dtype)
        for rows, r in parts:
            values[rows] = getattr(r, name)
        out[name] = values
    return Rebuilt(**out)


def unknown_columns(
    rebuilt: Rebuilt, extra: np.ndarray, neck: np.ndarray, rolling: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The ``unknown_modes`` bits and ``unknown_why`` codes of every contact: the rebuild's, a region's second
    contact (its tangential and rolling springs) and a possible jkr neck (every mode)."""
    springs = NOT_COMPUTED_BITS["u_t"] | (NOT_COMPUTED_BITS["u_r"] if rolling else 0)
    bits = np.where(extra, rebuilt.unknown | springs, rebuilt.unknown)
    why = np.where(extra, 4, rebuilt.why)
    bits = np.where(neck, sum(NOT_COMPUTED_BITS.values()), bits)
    why = np.where(neck, 5, why)
    return bits.astype(np.int8), why.astype(np.int8)


__all__ = ["ATOM_COLUMNS", "Assembled", "LammpsJoin", "UNKNOWN_MODES", "UNKNOWN_WHY", "run_of_step", "unknown_columns"]
