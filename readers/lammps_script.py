"""Read a LAMMPS GRANULAR input script (Debian's LAMMPS 29 Sep 2021): the contact model of every pair of atom
types, the wall fixes, their regions, the runs, the computes and the dumps demsplit reads.

The lines are read by the interpreter LIGGGHTS' reader uses (:mod:`.lammps_input`, through
:class:`demsplit.readers.liggghts_script` 's reader: ``variable``, ``include``, ``boundary``, ``create_box``,
``timestep``, ``run``, ``reset_timestep``, ``unfix``, ``dump`` mean the same in both); this module gives the
commands their LAMMPS meaning:

* ``pair_style granular`` with ``pair_coeff I J <normal> ... [damping] tangential ... [rolling] [twisting]
  [limit_damping]`` (ranges ``*``, ``1*2``), or a legacy ``pair_style gran/hooke|gran/hooke/history|
  gran/hertz/history kn kt gamman gammat xmu dampflag [limit_damping]``: each type pair's model
  (:mod:`demsplit.physics.laws._lammps`); a cross pair without its own line is left to LAMMPS' mixing, which
  that version does not do for granular models (the mixed pair's models are unset, measured): such a pair is
  refused where it touches, naming the ``pair_coeff`` line to add;
* ``fix ID group wall/gran <model> xplane|yplane|zplane LO HI | zcylinder R [shear DIM V] [contacts]`` and
  ``fix ID group wall/gran/region <model> region RID [contacts]``, with ``region RID plane|cylinder ...
  [side in|out] [open F] [rotate v_theta Px Py Pz Ax Ay Az]``: each wall fix is one demsplit wall with its own
  model (``wall=True``: the wall formulas of that version);
* ``compute ID group pair/local KEYWORDS [cutoff type|radius]`` and ``property/local``, ``dump custom`` and
  ``dump local`` with ``dump_modify format float|line|int|N ...``: the meaning of every dumped column;
* ``units si|lj``: a run in ``lj`` is computed in LAMMPS' own units (reported as such).

``jump``, ``if``, ``next`` and ``label`` are not followed (a warning says so).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import DemsplitError, MaterialError, ScriptError, UnsupportedModelError
from ..physics.laws import law_class, simulator_words
from ..scene import ContactModel, Material
from .lammps_input import Where, excerpt
from .liggghts_script import DumpSpec, _format_full_precision, _Reader, dump_files

__all__ = ["read_lammps_script", "LammpsScript", "WallFix", "Region", "LocalCompute", "is_lammps_script"]

LEGACY_STYLES = ("gran/hooke", "gran/hooke/history", "gran/hertz/history")
"""The legacy granular pair styles (their models are registered as ``lammps:gran/...``)."""
_PLANES = {"xplane": 0, "yplane": 1, "zplane": 2}
_TANGENTIAL_ARGS = {"linear_nohistory": 2}  # the others take kt xgammat mu
_SETS_FORCES = {
    "addforce",
    "aveforce",
    "setforce",
    "viscous",
    "efield",
    "spring",
    "spring/self",
    "drag",
    "lineforce",
    "planeforce",
    "wall/lj93",
    "wall/lj126",
    "wall/harmonic",
    "wall/region",
    "move",
    "freeze",
    "smd",
}
"""Fix styles that add to the atoms' forces or torques (besides gravity and the granular walls): with one of
them, the per-atom balance that pins a spring single() capped cannot be closed."""
_DETECT = re.compile(
    rb"^[ \t]*(pair_style[ \t]+(granular|gran/hooke|gran/hooke/history|gran/hertz/history)\b|"
    rb"fix[ \t]+\S+[ \t]+\S+[ \t]+wall/gran(/region)?[ \t]+granular\b)",
    re.MULTILINE,
)


def is_lammps_script(text: bytes) -> bool:
    """Whether a script's text uses LAMMPS' own granular words (``pair_style granular``, a legacy
    ``gran/hooke*``/``gran/hertz/history`` style, or a ``granular`` wall fix): LIGGGHTS writes
    ``pair_style gran model ...``."""
    return _DETECT.search(text) is not None


@dataclass
class Region:
    """A ``region`` a wall/gran/region fix uses: ``style`` plane or cylinder, its numbers, ``side_in``,
    the faces left ``open`` (cylinder: 1 lo cap, 2 hi cap, 3 side), and a rotation ``rotate``:
    (variable name, point (3), axis (3)) or None."""

    id: str
    style: str
    args: list
    side_in: bool
    open: tuple[int, ...]
    rotate: tuple[str, tuple[float, float, float], tuple[float, float, float]] | None
    where: Where


@dataclass
class WallFix:
    """A ``fix wall/gran`` or ``wall/gran/region``: its model, geometry (``xplane``..``zplane`` with ``lo``,
    ``hi`` (None: NULL), ``zcylinder`` with ``radius``, or ``region``), ``shear`` (axis, velocity), whether it
    writes its ``contacts`` array, and the runs it exists in (``first_run`` <= k < ``end_run``)."""

    id: str
    model: ContactModel
    geometry: str
    lo: float | None = None
    hi: float | None = None
    radius: float = 0.0
    region: Region | None = None
    shear: tuple[int, float] | None = None
    contacts: bool = False
    first_run: int = 0
    end_run: int | None = None
    where: Where | None = None


@dataclass
class LocalCompute:
    """A ``compute pair/local`` or ``property/local``: its keywords (the columns, in order) and its cutoff."""

    id: str
    style: str
    keywords: list[str]
    cutoff: str
    where: Where


@dataclass
class LammpsScript:
    """What :func:`read_lammps_script` found (see the module docstring).

    pair_models : the model of every type pair set by a line, ``(i, j)`` with i <= j; pair_lines the line of each.
    line_materials : E and nu of type i from its ``i i`` line, where the model carries them.
    walls : the wall fixes in script order; regions by id.
    rotations : per region with ``rotate v_NAME``, the formula of NAME at each run (None: not an equal-style
        formula), for the wall's velocity.
    gravity : per run, the acceleration of the ``fix gravity`` in force (None: none or not read).
    other_forces : fix styles that add forces besides gravity and the walls (see :data:`_SETS_FORCES`).
    """

    path: Path
    units: str
    periodic: tuple[bool, bool, bool]
    ntypes: int | None
    timestep: float | None
    runs: list[tuple[int, int]]
    pair_style: str
    pair_models: dict[tuple[int, int], ContactModel]
    pair_lines: dict[tuple[int, int], Where]
    line_materials: dict[int, Material]
    walls: list[WallFix]
    regions: dict[str, Region]
    computes: dict[str, LocalCompute]
    dumps: list[DumpSpec]
    rotations: dict[str, list[str | None]]
    gravity: list[tuple[float, float, float] | None]
    other_forces: list[str]
    warnings: list[str]
    included: list[Path] = field(default_factory=list)

    def named_files(self) -> list[Path]:
        """Every file the script names: itself, its includes and the files of its dumps (:func:`dump_files`)."""
        return [self.path, *self.included, *dump_files(self.dumps)]


class _LammpsReader(_Reader):
    """The LIGGGHTS reader's interpreter with LAMMPS' granular commands (module docstring)."""

    def __init__(self, path: Path, variables: dict[str, str]) -> None:
        super().__init__(path, variables)
        self.pair_style: str | None = None
        self.pair_where: Where | None = None
        self.legacy_args: list[str] = []
        self.coeffs: list[tuple[str, str, list[str], Where]] = []
        self.lammps_walls: list[WallFix] = []
        self.regions: dict[str, Region] = {}
        self.local: dict[str, LocalCompute] = {}
        self.rotations: dict[str, list[str | None]] = {}
        self.gravities: list[tuple[float, float, float] | None] = []
        self.current_gravity: tuple[float, float, float] | None = None
        self.gravity_fix: str | None = None
        self.other_forces: list[str] = []

    # -- commands -----------------------------------------------------------------------------

    def cmd_units(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "units", "units si|lj")
        if args[0] not in ("si", "lj"):
            raise self.error(
                UnsupportedModelError,
                f"units {excerpt(args[0])}: demsplit reads LAMMPS runs in units si or lj.",
                where,
                "run the simulation with 'units si' (or lj).",
            )
        self.units = args[0]

    def cmd_change_box(self, args: list[str], where: Where) -> None:
        if "boundary" in args[:-3]:
            k = args.index("boundary")
            self.periodic = tuple("p" in a for a in args[k + 1 : k + 4])

    def cmd_run(self, args: list[str], where: Where) -> None:
        super().cmd_run(args, where)
        for rid, formulas in self.rotations.items():
            formulas.append(self.formula(self.regions[rid].rotate[0]))
        self.gravities.append(self.current_gravity)

    def formula(self, name: str) -> str | None:
        """The text of equal-style variable ``name`` now (None: not an equal-style variable)."""
        style, value = self.vars.values.get(name, ("", ""))
        return value if style == "equal" else None

    def cmd_pair_style(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "pair_style", "pair_style granular")
        style = args[0]
        if style != "granular" and style not in LEGACY_STYLES:
            raise self.error(
                UnsupportedModelError,
                f"pair_style {excerpt(style)} is not a granular style demsplit reads.",
                where,
                "use pair_style granular, gran/hooke, gran/hooke/history or gran/hertz/history.",
            )
        self.pair_style, self.pair_where, self.legacy_args = style, where, args[1:]
        self.coeffs = []

    def cmd_pair_coeff(self, args: list[str], where: Where) -> None:
        self.need(args, 2, where, "pair_coeff", "pair_coeff I J ...")
        self.coeffs.append((args[0], args[1], args[2:], where))

    def cmd_region(self, args: list[str], where: Where) -> None:
        self.need(args, 2, where, "region", "region ID STYLE ARGS")
        rid, style, rest = args[0], args[1], args[2:]
        nargs = {"plane": 6, "cylinder": 6}.get(style)
        numbers: list = []
        if nargs is not None:
            self.need(rest, nargs, where, f"region {rid} {style}", f"region {rid} {style} ...")
            numbers = (
                [rest[0]] + [self.region_number(v, where, f"region {rid}") for v in rest[1:nargs]]
                if style == "cylinder"
                else [self.number(v, where, f"region {rid}") for v in rest[:nargs]]
            )
        side_in, opened, rotate = True, [], None
        k = nargs or 0
        while k < len(rest):
            word = rest[k]
            if word == "side" and k + 1 < len(rest):
                side_in, k = rest[k + 1] == "in", k + 2
            elif word == "open" and k + 1 < len(rest):
                opened.append(int(rest[k + 1]))
                k += 2
            elif word == "rotate" and k + 7 < len(rest):
                var = rest[k + 1]
                if not var.startswith("v_"):
                    raise self.error(
                        ScriptError,
                        f"region {rid}: rotate takes v_NAME, found {excerpt(var)}.",
                        where,
                        "write rotate v_NAME Px Py Pz Ax Ay Az.",
                    )
                nums = [self.number(v, where, f"region {rid} rotate") for v in rest[k + 2 : k + 8]]
                rotate = (var[2:], tuple(nums[:3]), tuple(nums[3:]))
                k += 8
            elif word == "move":  # a moving region: refused where a wall fix uses it
                self.regions[rid] = Region(rid, "moving", [], side_in, (), None, where)
                return
            else:
                k += 2 if word == "units" else 1
        self.regions[rid] = Region(rid, style, numbers, side_in, tuple(opened), rotate, where)
        if rotate is not None:
            self.rotations[rid] = [None] * len(self.runs)

    def region_number(self, text: str, where: Where, what: str) -> float:
        """A region's number; INF and EDGE (a cylinder's open ends) as +-inf."""
        if text in ("INF", "EDGE"):
            return float("inf")
        if text in ("-INF", "-EDGE"):
            return float("-inf")
        return self.number(text, where, what)

    def cmd_fix(self, args: list[str], where: Where) -> None:
        self.need(args, 3, where, "fix", "fix ID GROUP STYLE ...")
        fid, style, rest = args[0], args[2], args[3:]
        if style in ("wall/gran", "wall/gran/region"):
            self.wall_fix(fid, style, rest, where)
        elif style == "gravity":
            self.fix_gravity_lammps(fid, rest, where)
        elif style in _SETS_FORCES or style.startswith("wall/"):
            self.other_forces.append(f"fix {fid} {style}")

    def cmd_unfix(self, args: list[str], where: Where) -> None:
        for fix in self.lammps_walls:
            if args and fix.id == args[0] and fix.end_run is None:
                fix.end_run = len(self.runs)
        if args and args[0] == self.gravity_fix:
            self.current_gravity, self.gravity_fix = None, None
        self.other_forces = [f for f in self.other_forces if not args or f.split()[1] != args[0]]

    def fix_gravity_lammps(self, fid: str, rest: list[str], where: Where) -> None:
        """``fix ID group gravity G vector X Y Z | spherical PHI THETA | chute ANGLE`` (fix_gravity.cpp:324-357)."""
        self.gravity_fix = fid
        try:
            g = float(rest[0])
            if rest[1] == "vector":
                d = np.array([float(v) for v in rest[2:5]])
                d = d / np.linalg.norm(d)
            else:
                phi, theta = (0.0, 180.0 - float(rest[2])) if rest[1] == "chute" else (float(rest[2]), float(rest[3]))
                phi, theta = math.radians(phi), math.radians(theta)
                d = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
            self.current_gravity = tuple(float(v) for v in g * d)
        except (ValueError, IndexError):
            self.current_gravity = None
            self.warnings.append(
                f"{where.file}:{where.line}: fix {fid} gravity is not read (a variable or a style "
                "demsplit does not evaluate); the atoms' force balance is not used."
            )

    def granular_words(self, words: list[str], where: Where, wall: bool, what: str) -> tuple[str, dict, int]:
        """The law key, the parameters and the number of words of the ``granular`` model words ``words``
        (pair_granular.cpp coeff() :781-980, fix_wall_gran.cpp :113-343)."""
        normals = {w: k for w, k in simulator_words("lammps").items() if not w.startswith("gran/")}
        if not words or words[0] not in normals:
            raise self.error(
                UnsupportedModelError,
                f"{what}: normal model {excerpt(words[0] if words else '')} is not supported.",
                where,
                f"use one of {', '.join(normals)}.",
            )
        name = words[0]
        law = law_class(normals[name])
        nums = law.line_coefficients
        self.need(words[1:], len(nums), where, what, f"{name} " + " ".join(nums))
        params: dict = {p: self.number(v, where, f"{what} {name}") for p, v in zip(nums, words[1:])}
        k = 1 + len(nums)
        while k < len(words):
            w = words[k]
            if w == "damping":
                self.need(words[k + 1 :], 1, where, what, "damping MODEL")
                params["damping"], k = words[k + 1], k + 2
            elif w == "tangential":
                self.need(words[k + 1 :], 1, where, what, "tangential MODEL ...")
                model = words[k + 1]
                n = _TANGENTIAL_ARGS.get(model, 3)
                self.need(words[k + 2 :], n, where, what, f"tangential {model} ...")
                values = words[k + 2 : k + 2 + n]
                params["tangential"] = model
                if n == 3:
                    params["kt"] = None if values[0] == "NULL" else self.number(values[0], where, what)
                params["xgammat"], params["mu"] = (self.number(v, where, what) for v in values[-2:])
                k += 2 + n
            elif w in ("rolling", "twisting"):
                self.need(words[k + 1 :], 1, where, what, f"{w} MODEL ...")
                model = words[k + 1]
                params[w] = model
                if model == "sds":
                    self.need(words[k + 2 :], 3, where, what, f"{w} sds K GAMMA MU")
                    names = ("kr", "gammar", "mur") if w == "rolling" else ("ktw", "gammatw", "mutw")
                    params.update({p: self.number(v, where, what) for p, v in zip(names, words[k + 2 : k + 5])})
                    k += 5
                else:
                    k += 2
            elif w == "limit_damping":
                params["limit_damping"], k = True, k + 1
            elif w == "cutoff" and not wall:
                k += 2
            else:
                break
        if "tangential" not in params:
            raise self.error(
                ScriptError,
                f"{what}: no tangential model (LAMMPS requires one).",
                where,
                "add 'tangential MODEL ...' as the run had it.",
            )
        params["wall"] = wall
        params.setdefault("history", False)  # a wall keeps its own flag; the pair style's is set with all lines
        try:
            law(params)
        except DemsplitError as exc:
            raise exc.located(file=where.file, line=where.line) from None
        return law.key, params, k

    def legacy_words(self, style: str, words: list[str], where: Where, wall: bool, what: str) -> tuple[str, dict, int]:
        """``kn kt gamman gammat xmu dampflag [limit_damping]`` of a legacy style (pair_gran_hooke_history.cpp:
        361-380, fix_wall_gran.cpp:96-122)."""
        self.need(words, 6, where, what, f"{style} KN KT GAMMAN GAMMAT XMU DAMPFLAG")
        kn, kt, gn, gt, mu = words[:5]
        params = {
            "kn": self.number(kn, where, what),
            "kt": None if kt == "NULL" else self.number(kt, where, what),
            "gamman": self.number(gn, where, what),
            "gammat": None if gt == "NULL" else self.number(gt, where, what),
            "mu": self.number(mu, where, what),
            "dampflag": self.integer(words[5], where, what),
            "wall": wall,
        }
        k = 6
        if len(words) > 6 and words[6] == "limit_damping":
            params["limit_damping"], k = True, 7
        return f"lammps:gran/{style.removeprefix('gran/')}", params, k

    def wall_fix(self, fid: str, style: str, rest: list[str], where: Where) -> None:
        what = f"fix {fid} {style}"
        self.need(rest, 1, where, what, f"{what} granular|hooke|hooke/history|hertz/history ...")
        if rest[0] == "granular":
            key, params, k = self.granular_words(rest[1:], where, True, what)
            k += 1
            if key == "lammps:jkr":
                raise self.error(
                    UnsupportedModelError,
                    f"{what}: a jkr wall is not supported: that version's wall "
                    "fix computes the pull-off distance with the radius where the pair uses R^2 "
                    "(fix_wall_gran.cpp:1699), so its contacts outlive pull-off and give NaN forces.",
                    where,
                    "use a hertz/material or dmt wall.",
                )
        elif f"gran/{rest[0]}" in LEGACY_STYLES:
            key, params, k = self.legacy_words(rest[0], rest[1:], where, True, what)
            k += 1
        else:
            raise self.error(
                UnsupportedModelError,
                f"{what}: model {excerpt(rest[0])} is not supported.",
                where,
                "use granular, hooke, hooke/history or hertz/history.",
            )
        try:
            model = ContactModel(key, params)
        except DemsplitError as exc:
            raise exc.located(file=where.file, line=where.line) from None
        geo = rest[k:]
        fix = WallFix(fid, model, "", first_run=len(self.runs), where=where)
        if style == "wall/gran/region":
            if len(geo) < 2 or geo[0] != "region":
                raise self.error(
                    ScriptError, f"{what}: expected 'region RID' after the model.", where, "write 'region RID'."
                )
            region = self.regions.get(geo[1])
            if region is None:
                raise self.error(
                    ScriptError,
                    f"{what}: region {excerpt(geo[1])} is not defined before.",
                    where,
                    "define the region first.",
                )
            if region.style not in ("plane", "cylinder"):
                raise self.error(
                    UnsupportedModelError,
                    f"{what}: region {region.id} is a {region.style} region; "
                    "demsplit rebuilds the contacts of plane and cylinder regions (static or rotating).",
                    where,
                    "use a plane or cylinder region.",
                )
            fix.geometry, fix.region, tail = "region", region, geo[2:]
        elif geo and geo[0] in _PLANES:
            self.need(geo, 3, where, what, f"{geo[0]} LO HI")
            fix.geometry = geo[0]
            fix.lo, fix.hi = (None if v == "NULL" else self.number(v, where, what) for v in geo[1:3])
            tail = geo[3:]
        elif geo and geo[0] == "zcylinder":
            self.need(geo, 2, where, what, "zcylinder R")
            fix.geometry, fix.radius, tail = "zcylinder", self.number(geo[1], where, what), geo[2:]
        else:
            raise self.error(
                UnsupportedModelError,
                f"{what}: wall {excerpt(geo[0] if geo else '')} is not supported.",
                where,
                "use xplane, yplane, zplane, zcylinder or a region.",
            )
        k = 0
        while k < len(tail):
            if tail[k] == "shear":
                self.need(tail[k + 1 :], 2, where, what, "shear DIM V")
                if fix.geometry == "zcylinder":
                    raise self.error(
                        UnsupportedModelError,
                        f"{what}: a shearing zcylinder is not supported (its "
                        "velocity at the contact is not a plain translation, fix_wall_gran.cpp:664).",
                        where,
                        "analyse a run whose cylinder wall does not shear.",
                    )
                fix.shear = ("xyz".index(tail[k + 1]), self.number(tail[k + 2], where, what))
                k += 3
            elif tail[k] == "wiggle":
                raise self.error(
                    UnsupportedModelError,
                    f"{what}: a wiggling wall is not supported.",
                    where,
                    "analyse a run without wiggle.",
                )
            elif tail[k] == "contacts":
                fix.contacts, k = True, k + 1
            else:
                k += 1
        for old in self.lammps_walls:  # a fix defined again under its id replaces the one that exists
            if old.id == fid and old.end_run is None:
                old.end_run = len(self.runs)
        self.lammps_walls.append(fix)

    def cmd_compute(self, args: list[str], where: Where) -> None:
        self.need(args, 3, where, "compute", "compute ID GROUP STYLE ...")
        if args[2] in ("pair/local", "property/local"):
            words, cutoff = args[3:], "type"
            if "cutoff" in words[:-1]:
                k = words.index("cutoff")
                cutoff, words = words[k + 1], words[:k] + words[k + 2 :]
            self.local[args[0]] = LocalCompute(args[0], args[2], words, cutoff, where)

    def cmd_dump_modify(self, args: list[str], where: Where) -> None:
        """LAMMPS' ``format line|float|int|N FMT|none`` and ``sort``; the other keywords are not needed."""
        dump = self.modified_dump(args, where)
        rest, k = args[1:], 0
        while k < len(rest):
            if rest[k] == "format" and k + 1 < len(rest):
                if rest[k + 1] == "none":
                    dump.format, k = None, k + 2
                    continue
                if rest[k + 1] in ("line", "float"):  # a whole line's format, or every float column's
                    dump.format = rest[k + 2] if k + 2 < len(rest) else None
                else:  # 'int FMT' or 'N FMT': one kind or one column; not every float at full precision
                    dump.format = None
                k += 3
            elif rest[k] == "sort" and k + 1 < len(rest):
                dump.sort, k = rest[k + 1], k + 2
            else:
                k += 1

    # -- assembly -----------------------------------------------------------------------------

    def pair_models(self) -> tuple[dict[tuple[int, int], ContactModel], dict[tuple[int, int], Where]]:
        """Every type pair's model set by a line (i <= j) and the line that set it."""
        if self.pair_style is None:
            raise ScriptError(
                "the script has no granular pair_style.",
                file=self.root,
                fix="give the run's input script (pair_style granular or gran/*).",
            )
        n = self.ntypes or 0
        lines: dict[tuple[int, int], tuple[list[str], Where]] = {}
        for ti, tj, words, where in self.coeffs:
            for i in self.type_range(ti, n, where):
                for j in self.type_range(tj, n, where):
                    if i <= j:
                        lines[(i, j)] = (words, where)
        if self.pair_style in LEGACY_STYLES:
            key, params, _ = self.legacy_words(
                self.pair_style, self.legacy_args, self.pair_where, False, f"pair_style {self.pair_style}"
            )
            model = ContactModel(key, params)
            return (
                {(i, j): model for i in range(1, n + 1) for j in range(i, n + 1)},
                {(i, j): self.pair_where for i in range(1, n + 1) for j in range(i, n + 1)},
            )
        parsed = {
            pair: self.granular_words(words, where, False, f"pair_coeff {pair[0]} {pair[1]}")
            for pair, (words, where) in lines.items()
        }
        history = any(law_class(key)(params).has_spring for key, params, _ in parsed.values())
        models = {pair: ContactModel(key, {**params, "history": history}) for pair, (key, params, _) in parsed.items()}
        return models, {pair: where for pair, (_, where) in lines.items()}

    def type_range(self, word: str, n: int, where: Where) -> range:
        """The types of a ``pair_coeff`` word: ``I``, ``*``, ``I*``, ``*J``, ``I*J``."""
        if "*" not in word:
            return range(self.integer(word, where, "pair_coeff type"), self.integer(word, where, "pair_coeff") + 1)
        lo, hi = word.split("*", 1)
        return range(
            self.integer(lo, where, "pair_coeff") if lo else 1, (self.integer(hi, where, "pair_coeff") if hi else n) + 1
        )

    def line_materials(self, models: dict[tuple[int, int], ContactModel]) -> dict[int, Material]:
        """E and nu of type i from its ``i i`` line where the model carries them."""
        out = {}
        for (i, j), model in models.items():
            material = model.contact_law.material() if i == j else None
            if material is not None:
                try:
                    out[i] = Material(*material)
                except MaterialError as exc:
                    raise exc.located(file=self.root) from None
        return out

    def finish_dumps(self) -> None:
        """A dump is at full precision when its float format keeps >= 15 significant digits (LAMMPS prints
        integer columns as integers, local dumps included)."""
        for dump in self.dumps.values():
            dump.full_precision = dump.format is not None and _format_full_precision(dump.format, False)

    def lammps_result(self) -> LammpsScript:
        models, lines = self.pair_models()
        self.finish_dumps()
        return LammpsScript(
            path=self.root,
            units=self.units or "lj",
            periodic=self.periodic,
            ntypes=self.ntypes,
            timestep=self.timestep,
            runs=self.runs,
            pair_style=self.pair_style,
            pair_models=models,
            pair_lines=lines,
            line_materials=self.line_materials(models),
            walls=self.lammps_walls,
            regions=self.regions,
            computes=self.local,
            dumps=list(self.dumps.values()),
            rotations=self.rotations,
            gravity=self.gravities,
            other_forces=self.other_forces,
            warnings=self.warnings,
            included=self.included,
        )


def read_lammps_script(path: str | Path, variables: dict[str, str] | None = None) -> LammpsScript:
    """Read a LAMMPS granular input script (see the module docstring); ``variables``: the run's
    ``-var NAME VALUE`` values, which win over the script's own definitions."""
    path = Path(path).resolve()
    reader = _LammpsReader(path, dict(variables or {}))
    reader.read(path)
    return reader.lammps_result()
