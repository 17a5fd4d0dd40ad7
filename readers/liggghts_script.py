"""Read a LIGGGHTS 3.8 input script: materials, contact models, walls, dumps,
and the meaning of every column of its contact dumps.

``read_script(path, variables)`` interprets the script the way LIGGGHTS'
``Input`` class reads it (``input.cpp``): a trailing ``&`` joins the next
physical line, ``#`` outside quotes starts a comment, ``$x``, ``${name}`` and
``$(expr)`` are substituted outside quotes before the line is split into words,
quoted text is one word, ``include FILE`` reads another file. Only the commands
that describe the run are interpreted; the result is a :class:`LiggghtsScript`.
Relative paths (``include``, mesh and dump files) are taken from the main
script's directory: LIGGGHTS opens them from its working directory, which is
where the main script is run from. ``jump``, ``if``, ``next`` and ``label`` are
not followed (a warning says so).

Contact dump columns
--------------------
``compute pair/gran/local`` and ``compute wall/gran/local`` write their blocks
in a fixed order set by the code (``compute_pair_gran_local.cpp``, ``add_pair``
and ``add_wall_1``/``add_wall_2``), whatever order the keywords are typed in.
With no keyword the blocks ``pos vel id force torque history contactArea`` are
written; with keywords, only those listed. Canonical names, block by block:

=================  ==========================================  ==============================================
keyword            pair row                                    wall row (mesh walls only)
=================  ==========================================  ==============================================
pos                x1 y1 z1 x2 y2 z2 (both remapped into box)  wall_cpx wall_cpy wall_cpz (contact point on the
                                                               wall), x1 y1 z1 (particle centre)
vel                vx1 vy1 vz1 vx2 vy2 vz2                     wall_vx wall_vy wall_vz, vx1 vy1 vz1
id                 id1 id2 periodic                            mesh_index tri_id id1 (0-based mesh in the wall
                                                               fix's ``meshes`` list, 0-based triangle, particle)
force              fx fy fz (total, on body 1)                 fx fy fz (on the particle)
force_normal       fnx fny fnz                                 fnx fny fnz
force_tangential   ftx fty ftz                                 ftx fty ftz
torque             tqx tqy tqz                                 tqx tqy tqz
torque_normal      tqnx tqny tqnz                              tqnx tqny tqnz
torque_tangential  tqtx tqty tqtz                              tqtx tqty tqtz
history            see :func:`history_columns`                 same
contactArea        area                                        area
delta              delta                                       delta
contactPoint       cpx cpy cpz                                 unwritten_cpx unwritten_cpy unwritten_cpz
                                                               (the code never fills them)
heatFlux           heat_flux (always the last column)          heat_flux
=================  ==========================================  ==============================================

Body 1 is the particle ``i`` of the pair (the particle, for a wall row), so the
names match the canonical ``contacts`` table of :mod:`demsplit.frame`.
``ms_id`` (multisphere) is refused: LIGGGHTS-PUBLIC has no multisphere and
the Debian 3.8.0 binary crashes on it.

History columns: the law's own history, in LIGGGHTS' order (normal model,
e.g. ``delta_max`` for ``hooke/hysteresis``; ``shearx sheary shearz`` with
``tangential history`` or ``tan_luding``; ``liquid_bridge`` (after the normal model's values) with ``cohesion
easo/capillary/viscous|washino/capillary/viscous``; ``rolling_torquex ..z`` with ``rolling_friction
epsd|epsd2|epsd3``, then ``torsion_torquex ..z`` with ``luding``:
:meth:`~demsplit.physics.laws._liggghts.LiggghtsNormalModel.history_columns`),
then 10 (pair) / 14 (wall) columns with ``computeElasticPotential on``
(``elastic_potential`` then ``elastic_history2`` ..., measured on Debian's
LIGGGHTS 3.8.0); nothing with ``tangential no_history`` and a normal model
without history (the defaults).

Precision
---------
A dump is ``full_precision`` when it is a ``dump custom`` to a ``.bin`` file,
or when every float conversion of its ``dump_modify format`` carries at least
15 significant digits (``%.15g`` and up, ``%.14e`` and up; ``%f`` is never
counted, its significant digits depend on the magnitude). ``dump local`` to a
``.bin`` file is *not*: Debian's 3.8.0 writes the text headers and replaces
every row by a stray byte (measured). A ``%d`` conversion in a ``dump local``
format prints garbage, because every ``c_`` value is a double (measured:
``596240344`` for an id of 1); the parser warns about it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..errors import DemsplitError, MaterialError, ScriptError, UnsupportedModelError
from ..physics.laws import ContactLaw, law_class, simulator_words
from ..physics.laws._liggghts import COHESION_MODELS, ROLLING_MODELS, TANGENTIAL_MODELS
from ..physics.laws._liggghts import SHEAR as SHEAR_COLUMNS
from ..physics.laws._liquid_bridge import BRIDGE_MODELS
from ..scene import ContactModel, Material, Scene, Wall
from .lammps_input import Unevaluable, Variables, Where, excerpt, logical_lines, split_words, strip_comment, substitute

__all__ = ["read_script", "LiggghtsScript", "DumpSpec", "LocalLayout", "local_layout", "history_columns"]

# --------------------------------------------------------------------------
# Column layouts of compute pair/gran/local and wall/gran/local
# --------------------------------------------------------------------------

CODE_ORDER = (
    "pos",
    "vel",
    "id",
    "force",
    "force_normal",
    "force_tangential",
    "torque",
    "torque_normal",
    "torque_tangential",
    "history",
    "contactArea",
    "delta",
    "contactPoint",
)
"""Blocks in the order ``add_pair``/``add_wall_2`` write them (``heatFlux`` goes last)."""

DEFAULT_KEYWORDS = ("pos", "vel", "id", "force", "torque", "history", "contactArea")
"""Blocks written when the compute is given no keyword."""

_KEYWORDS = set(CODE_ORDER) | {"heatFlux", "ms_id", "verbose"}


def _xyz(prefix: str) -> list[str]:
    return [f"{prefix}{c}" for c in "xyz"]


_PAIR_BLOCKS: dict[str, list[str]] = {
    "pos": ["x1", "y1", "z1", "x2", "y2", "z2"],
    "vel": ["vx1", "vy1", "vz1", "vx2", "vy2", "vz2"],
    "id": ["id1", "id2", "periodic"],
    "force": _xyz("f"),
    "force_normal": _xyz("fn"),
    "force_tangential": _xyz("ft"),
    "torque": _xyz("tq"),
    "torque_normal": _xyz("tqn"),
    "torque_tangential": _xyz("tqt"),
    "contactArea": ["area"],
    "delta": ["delta"],
    "contactPoint": _xyz("cp"),
}
_WALL_BLOCKS: dict[str, list[str]] = {
    **_PAIR_BLOCKS,
    "pos": _xyz("wall_cp") + ["x1", "y1", "z1"],
    "vel": _xyz("wall_v") + ["vx1", "vy1", "vz1"],
    "id": ["mesh_index", "tri_id", "id1"],
    "contactPoint": _xyz("unwritten_cp"),
}


_ELASTIC_POTENTIAL_HISTORY = {"pair": 10, "wall": 14}
"""History values ``computeElasticPotential on`` adds (pair measured; wall: 17 - 3)."""


def history_columns(law: ContactLaw, kind: str, *, elastic_potential: bool = False) -> list[str]:
    """Names of the ``history`` block of a ``compute pair/gran/local`` (``kind='pair'``) or
    ``wall/gran/local`` (``'wall'``) for the contact law ``law``: the law's own history, then the
    ``computeElasticPotential`` values."""
    names = list(law.history_columns())
    if elastic_potential:
        n = _ELASTIC_POTENTIAL_HISTORY[kind]
        names += ["elastic_potential"] + [f"elastic_history{k}" for k in range(2, n + 1)]
    return names


def local_layout(
    kind: str, keywords: Sequence[str], dnum: int = 3, *, history: Sequence[str] | None = None
) -> list[str]:
    """Canonical name of every column of a ``compute pair/gran/local``
    (``kind='pair'``) or ``wall/gran/local`` (``kind='wall'``) with these
    keywords, in the order the code writes them (see the module docstring).

    ``dnum`` is the width of the ``history`` block; ``history`` optionally names
    its columns (default: ``shearx sheary shearz`` when ``dnum == 3``, else
    ``history1`` ... ``history<dnum>``). Bad keywords raise :class:`ScriptError`
    without a location (the caller adds it with ``.located``).
    """
    if kind not in ("pair", "wall"):
        raise ValueError(f"kind must be 'pair' or 'wall', got {kind!r}")
    unknown = [k for k in keywords if k not in _KEYWORDS]
    if unknown:
        raise ScriptError(
            f"compute {kind}/gran/local: unknown keyword(s) {unknown}; LIGGGHTS 3.8 knows {sorted(_KEYWORDS)}.",
            fix="correct the compute line (LIGGGHTS refuses it too).",
        )
    if "ms_id" in keywords:
        raise UnsupportedModelError(
            f"compute {kind}/gran/local ms_id needs fix multisphere, which LIGGGHTS-PUBLIC does not have "
            "(Debian's 3.8.0 crashes on it).",
            fix="remove ms_id from the compute.",
        )
    if history is None:
        history = list(SHEAR_COLUMNS) if dnum == 3 else [f"history{k}" for k in range(1, dnum + 1)]
    elif len(history) != dnum:
        raise ValueError(f"history names {list(history)} do not match dnum = {dnum}")
    flags = set(keywords) if keywords else set(DEFAULT_KEYWORDS)
    if "history" in flags and dnum == 0:
        raise ScriptError(
            f"compute {kind}/gran/local asks for 'history' but the contact model stores none (tangential no_history).",
            fix="use 'tangential history', or drop 'history' from the compute.",
        )
    blocks = _PAIR_BLOCKS if kind == "pair" else _WALL_BLOCKS
    columns: list[str] = []
    for block in CODE_ORDER:
        if block in flags:
            columns += list(history) if block == "history" else blocks[block]
    if "heatFlux" in flags:  # add_heat / add_heat_wall write array[.][nvalues - 1]
        columns.append("heat_flux")
    return columns


@dataclass
class LocalLayout:
    """Meaning of every column of a ``dump local`` of a granular local compute.

    kind : ``'pair'`` or ``'wall'``.
    columns : canonical name of each dumped column, in file order.
    """

    kind: str
    columns: list[str]


@dataclass
class DumpSpec:
    """One ``dump`` command with its ``dump_modify`` settings.

    file : resolved against the script's directory; LAMMPS's ``*`` (timestep)
        and ``%`` (processor) patterns are kept as they are.
    keywords : the tokens after the file name.
    compute : for ``dump local``, the compute all its ``c_ID[k]`` columns read.
    layout : for ``dump local`` of a granular local compute, the name of every
        dumped column.
    full_precision : see the module docstring.
    """

    id: str
    style: str
    every: int
    file: str
    keywords: list[str]
    compute: str | None = None
    layout: LocalLayout | None = None
    format: str | None = None
    label: str | None = None
    sort: str | None = None
    full_precision: bool = False
    first_run: int = 0
    """The ``run`` commands before the dump line: it writes from the run of that index on."""


@dataclass
class WallFix:
    """A ``fix wall/gran``: its walls, model, whether it is the mesh kind, and the ``run`` commands it
    lasts for, ``first_run`` (the runs before the fix line) up to ``end_run`` (the runs before its ``unfix``
    line; None: to the end)."""

    id: str
    walls: list[Wall]
    spec: _ModelSpec
    is_mesh: bool
    first_run: int
    end_run: int | None = None
    store_force: bool = False
    """``store_force yes``: the fix keeps the force it applied to each particle in the step, the ``fix
    property/atom`` vector ``force_<ID>`` (``f_force_<ID>[1..3]`` in a ``dump custom``)."""
    moving: str | None = None
    """The keyword that moves the wall (``shear``, ``wiggle``), None for a wall at rest."""


@dataclass
class LiggghtsScript:
    """What :func:`read_script` found in a LIGGGHTS input script.

    scene : materials per atom type (1-based), the pair contact model, walls.
    periodic : periodicity per axis from ``boundary``.
    dumps : every ``dump`` command, in script order.
    gravity : m/s^2, magnitude x unit direction, or ``None``.
    coefficients : every ``fix property/global`` value: ``peratomtype`` as a 1-D
        array (index type-1), ``peratomtypepair`` as an (N, N) array
        ([i-1][j-1]), ``scalar`` as a float, ``vector`` as a 1-D array.
    local_computes : full layout of every granular local compute, by id.
    dumped_mesh_walls : index in ``scene.walls`` of each entry of the
        ``mesh_index`` column of a ``wall/gran/local`` dump (LIGGGHTS attaches
        the compute to the last mesh ``fix wall/gran``).
    warnings : what was ignored or is doubtful, and why.
    runs : the ``run`` commands, as the first and last timestep of each.
    wall_runs : for each wall of ``scene.walls``, the runs it exists in, ``(first, end)``: runs
        ``first <= k < end`` (end None: to the last run).
    """

    path: Path
    scene: Scene
    periodic: tuple[bool, bool, bool]
    dumps: list[DumpSpec]
    gravity: np.ndarray | None
    coefficients: dict
    ntypes: int | None
    timestep: float | None
    run_steps: list[int]
    runs: list[tuple[int, int]]
    wall_runs: list[tuple[int, int | None]]
    local_computes: dict[str, LocalLayout]
    dumped_mesh_walls: list[int]
    variables: dict[str, str]
    warnings: list[str]
    included: list[Path] = field(default_factory=list)
    """Every file an ``include`` line read, in order."""
    stored_force: dict[int, str] = field(default_factory=dict)
    """Index in ``scene.walls`` of each primitive wall whose ``fix wall/gran`` has ``store_force yes`` -> that
    fix's id (its force is the atom dump's ``f_force_<ID>[1..3]``)."""
    moving_walls: dict[int, str] = field(default_factory=dict)
    """Index in ``scene.walls`` of each wall moved by its fix (``shear``, ``wiggle``) -> the keyword."""
    pair_settings: dict[str, str] = field(default_factory=dict)
    """The on/off settings of the ``pair_style gran`` line (``tangential_damping off``, ``limitForce on``, ...)."""
    wall_settings: list[dict[str, str]] = field(default_factory=list)
    """The on/off settings of the ``fix wall/gran`` line of each wall of ``scene.walls``."""
    run_timesteps: list[float | None] = field(default_factory=list)
    """The timestep (s) in effect during each ``run`` of :attr:`runs`."""
    restart_run: int | None = None
    """The index of the first ``run`` after a ``read_restart``, whose timesteps the script does not tell
    (the restart file sets them); None without one."""
    unmodelled_forces: list[str] = field(default_factory=list)
    """The commands that change the particles' forces or their integration beyond what demsplit models
    (``fix gravity`` of the whole group, the contacts, ``fix nve/sphere``): ``fix ID STYLE`` of a drag, an added or
    set force, a freeze, a velocity limit; a gravity it cannot read; the lack of ``fix nve/sphere``."""
    local_histories: dict[str, list[str]] = field(default_factory=dict)
    """The ``history`` block a ``compute pair/gran/local`` (``'pair'``: the pair_style's model) or
    ``wall/gran/local`` (``'wall'``: the last mesh ``fix wall/gran``'s) would write, column names in
    order (:func:`history_columns`, ``computeElasticPotential`` included): what ``demsplit prepare``
    dumps whole."""

    def named_files(self) -> list[Path]:
        """Every file the script names: itself, its includes, its mesh files and the file (and compressed
        copies) of every dump it writes (:func:`dump_files`); what no output of demsplit may replace
        (:mod:`demsplit.outputs`)."""
        meshes = [Path(w.file) for w in self.scene.walls if w.kind == "mesh" and w.file]
        return [self.path, *self.included, *meshes, *dump_files(self.dumps)]


def dump_files(dumps: list[DumpSpec]) -> list[Path]:
    """The files of ``dumps`` and their compressed copies; for a per-step or per-processor pattern (``*``,
    ``%``), the files that exist."""
    files: list[Path] = []
    for dump in dumps:
        name = Path(dump.file)
        if "*" in name.name or "%" in name.name:
            pattern = name.name.replace("%", "*")
            files += [p for suffix in ("", *COMPRESSED_SUFFIXES) for p in name.parent.glob(pattern + suffix)]
        else:
            files += [name, *(name.with_name(name.name + suffix) for suffix in COMPRESSED_SUFFIXES)]
    return files


COMPRESSED_SUFFIXES = (".gz", ".bz2", ".xz")
"""The compressed copies of a dump file that are read in its place."""


# --------------------------------------------------------------------------
# Lines, quotes, substitution
# --------------------------------------------------------------------------


# --------------------------------------------------------------------------
# Contact models
# --------------------------------------------------------------------------

MAX_INCLUDE_DEPTH = 64
"""Files included inside each other, at most (LIGGGHTS has no bound; demsplit's reader recurses)."""

TANGENTIAL = TANGENTIAL_MODELS
"""LIGGGHTS ``tangential`` words, passed to the law as its ``tangential`` parameter."""
_MODEL_KEYS = ("model", "tangential", "cohesion", "rolling_friction", "surface")


@dataclass
class _ModelSpec:
    """A ``pair_style gran`` or ``fix wall/gran`` model, before the
    characteristic velocity is known."""

    law: str
    tangential: str
    rolling: str
    cohesion: str
    settings: dict[str, str]
    where: Where

    def on(self, name: str) -> bool:
        return self.settings.get(name, "off") in ("on", "yes")


def _parse_model(
    words: list[str], stop: tuple[str, ...], where: Where, warnings: list[str], what: str
) -> tuple[_ModelSpec, int]:
    """Parse ``model X tangential Y [cohesion C] [rolling_friction R] [surface S]
    [setting on|off ...]`` up to a word in ``stop``; return the spec and the
    index of that word."""
    kinds: dict[str, str] = {}
    settings: dict[str, str] = {}
    i = 0
    while i < len(words) and words[i] not in stop:
        if i + 1 >= len(words):
            raise ScriptError(
                f"{what}: '{words[i]}' needs a value.", file=where.file, line=where.line, fix="complete the command."
            )
        (kinds if words[i] in _MODEL_KEYS else settings)[words[i]] = words[i + 1]
        i += 2

    def unsupported(message: str, supported: str) -> UnsupportedModelError:
        return UnsupportedModelError(
            f"{what}: {message} Supported: {supported}.",
            file=where.file,
            line=where.line,
            fix="rerun with a supported model, or describe the contact energy yourself.",
        )

    normal = kinds.get("model")
    if normal is None:
        raise ScriptError(
            f"{what}: no 'model' keyword.", file=where.file, line=where.line, fix="give 'model hertz' or 'model hooke'."
        )
    normals = simulator_words("liggghts")  # every law registered as liggghts:WORD, when the line is read
    if normal not in normals:
        raise unsupported(f"normal model {normal!r} is not supported.", ", ".join(f"model {w}" for w in normals))
    tangential = kinds.get("tangential", "no_history")  # LIGGGHTS' default (measured)
    if tangential not in TANGENTIAL:
        raise unsupported(
            f"tangential model {tangential!r} is not supported.", ", ".join(f"tangential {w}" for w in TANGENTIAL)
        )
    cohesion = kinds.get("cohesion", "off")
    if cohesion not in COHESION_MODELS:
        raise unsupported(
            f"cohesion model {cohesion!r} is not supported.", ", ".join(f"cohesion {c}" for c in COHESION_MODELS)
        )
    rolling = kinds.get("rolling_friction", "off")
    if rolling not in ROLLING_MODELS:
        raise unsupported(
            f"rolling friction model {rolling!r} is not supported.",
            ", ".join(f"rolling_friction {r}" for r in ROLLING_MODELS),
        )
    surface = kinds.get("surface", "default")
    if surface != "default":
        raise unsupported(f"surface model {surface!r} is not supported.", "surface default")
    return _ModelSpec(normals[normal], tangential, rolling, cohesion, settings, where), i


# --------------------------------------------------------------------------
# The interpreter
# --------------------------------------------------------------------------

_INTERPRETED = {
    "units",
    "boundary",
    "create_box",
    "variable",
    "include",
    "fix",
    "pair_style",
    "compute",
    "dump",
    "dump_modify",
    "timestep",
    "run",
    "create_atoms",
    "unfix",
    "reset_timestep",
}
_CONTROL_FLOW = {"jump", "if", "next", "label", "clear"}
_COMMAND_NAME = re.compile(r"[a-z][a-z0-9_/]*")
"""What a LIGGGHTS command name looks like (input.cpp's commands and styles): a line of another kind of
text file (``root:x:0:0``, ``KEY=value``) is not one."""
_BENIGN_FIXES = {
    "nve/sphere",
    "nve",
    "nve/limit",
    "property/atom",
    "particledistribution/discrete",
    "insert/pack",
    "insert/stream",
    "insert/rate/region",
    "print",
    "ave/time",
    "ave/atom",
    "ave/histo",
    "ave/spatial",
    "ave/euler",
    "check/timestep/gran",
    "viscous",
    "freeze",
    "enforce2d",
    "momentum",
    "heat/gran",
    "heat/gran/conduction",
    "property/global",
}
_BALANCE_NEUTRAL_FIXES = {
    "nve/sphere",
    "property/atom",
    "property/global",
    "print",
    "check/timestep/gran",
    "heat/gran",
    "heat/gran/conduction",
    "mesh/surface",
    "mesh/surface/stress",
    "wall/gran",
    "gravity",
    "particledistribution/discrete",
    "insert/pack",
    "insert/stream",
    "insert/rate/region",
    "ave/time",
    "ave/atom",
    "ave/histo",
    "ave/spatial",
    "ave/euler",
}
"""Fix styles that leave each particle's force, torque and Verlet integration as the contacts, gravity (read apart)
and ``fix nve/sphere`` make them (a ``particletemplate/...`` too)."""
_MOVING_WALL_KEYWORDS = ("shear", "wiggle")
"""``fix wall/gran`` keywords that move a primitive wall."""
_PLANES = {"xplane": 0, "yplane": 1, "zplane": 2}
_CYLINDERS = {"xcylinder": 0, "ycylinder": 1, "zcylinder": 2}
_MATERIAL_PROPERTIES = ("youngsModulus", "poissonsRatio")
_DUMP_MODIFY_ARITY = {
    "format": 1,
    "label": 1,
    "sort": 1,
    "append": 1,
    "buffer": 1,
    "every": 1,
    "fileper": 1,
    "first": 1,
    "flush": 1,
    "header": 1,
    "image": 1,
    "nfile": 1,
    "pad": 1,
    "precision": 1,
    "region": 1,
    "scale": 1,
    "unwrap": 1,
    "thresh": 3,
}
_CONVERSION = re.compile(r"%[-+ #0]*\d*(?:\.(\d*))?[hlLqjzt]*([diouxXeEfFgGaAcsp%])")


def _format_conversions(fmt: str) -> list[tuple[str, int | None]]:
    """(conversion letter, precision or None) of each conversion of a printf format."""
    return [
        (m.group(2), None if m.group(1) is None else int(m.group(1) or 0))
        for m in _CONVERSION.finditer(fmt)
        if m.group(2) != "%"
    ]


def _format_full_precision(fmt: str, local: bool) -> bool:
    """True when every float conversion keeps >= 15 significant digits (and,
    for a ``dump local``, there is no integer conversion: its values are doubles)."""
    conversions = _format_conversions(fmt)
    floats = [(c, p) for c, p in conversions if c in "eEfFgGaA"]
    if not floats or (local and len(floats) < len(conversions)):
        return False
    for conv, prec in floats:
        prec = 6 if prec is None else prec
        digits = {"e": prec + 1, "g": max(prec, 1)}.get(conv.lower())
        if conv in "aA":
            digits = 17
        if digits is None or digits < 15:
            return False
    return True


class _Reader:
    def __init__(self, path: Path, variables: dict[str, str]) -> None:
        self.root = path
        self.vars = Variables(variables)
        self.warnings: list[str] = []
        self.units: str | None = None
        self.periodic = (False, False, False)
        self.ntypes: int | None = None
        self.properties: dict[str, tuple[str, object, Where]] = {}
        self.pair: _ModelSpec | None = None
        self.walls: list[WallFix] = []
        self.meshes: dict[str, Wall] = {}
        self.computes: dict[str, tuple[str, list[str], Where]] = {}
        self.dumps: dict[str, DumpSpec] = {}
        self.dump_where: dict[str, Where] = {}
        self.gravity: np.ndarray | None = None
        self.timestep: float | None = None
        self.run_steps: list[int] = []
        self.runs: list[tuple[int, int]] = []
        self.run_timesteps: list[float | None] = []
        self.restart_run: int | None = None
        self.unmodelled_forces: list[str] = []
        self.integrated = False
        self.gravity_fixes = 0
        self.step = 0
        self.type_uses: list[tuple[int, str, Where]] = []
        self.contact_distance_factor: float | None = None
        self.include_stack: list[Path] = []
        self.included: list[Path] = []

    # -- driver ------------------------------------------------------------

    def read(self, path: Path) -> None:
        if path in self.include_stack:
            raise ScriptError(
                f"{path} includes itself.", file=self.include_stack[-1], fix="remove the circular include."
            )
        self.include_stack.append(path)
        for number, text in logical_lines(path):
            self.command(text, Where(path, number))
        self.include_stack.pop()

    def command(self, text: str, where: Where) -> None:
        """Substitute and run one logical line; an error or a warning never quotes the text of a ``getenv``
        variable (it comes from the environment: :meth:`_hidden`)."""
        warned = len(self.warnings)
        try:
            self._command(text, where)
        except DemsplitError as exc:
            hidden = self._hidden(exc.message), self._hidden(exc.fix)
            if hidden == (exc.message, exc.fix):
                raise
            raise type(exc)(hidden[0], file=exc.file, step=exc.step, line=exc.line, fix=hidden[1]) from None
        finally:
            self.warnings[warned:] = [self._hidden(w) for w in self.warnings[warned:]]

    def _hidden(self, text: str | None) -> str | None:
        """``text`` with the value of every ``getenv`` variable replaced by its name (``${NAME}``)."""
        if text:
            for name, (style, value) in sorted(self.vars.values.items(), key=lambda item: -len(item[1][1])):
                if style == "getenv" and value:
                    text = text.replace(value, "${" + name + "}")
        return text

    def _command(self, text: str, where: Where) -> None:
        stripped = strip_comment(text)
        words0 = stripped.split()
        if not words0:
            return
        if not words0[0].startswith("$") and not _COMMAND_NAME.fullmatch(words0[0]):
            raise ScriptError(
                "this line does not start with a LIGGGHTS command name (lower-case letters, digits, _ and /; "
                "LIGGGHTS stops on it: 'Unknown command'; the line is not quoted: it may not be a script's)"
                + (f"; this file was included from {self.include_stack[-2]}" if len(self.include_stack) > 1 else "")
                + ": this is not an input script of a run.",
                file=where.file,
                line=where.line,
                fix="give the run's input script, and check its include lines.",
            )
        try:
            words = split_words(substitute(stripped, self.vars, where), where)
        except Unevaluable as exc:
            if words0[0] in _INTERPRETED:
                raise ScriptError(
                    f"{exc}: its value is only known while LIGGGHTS runs.",
                    file=where.file,
                    line=where.line,
                    fix="replace it by a number, or pass the value with --var NAME VALUE.",
                ) from None
            self.warnings.append(f"{where.file}:{where.line}: {excerpt(words0[0])} ignored ({exc}).")
            return
        if not words:
            return
        name, args = words[0], words[1:]
        handler = getattr(self, "cmd_" + name, None)
        if handler is not None:
            handler(args, where)
        elif name in _CONTROL_FLOW:
            self.warnings.append(
                f"{where.file}:{where.line}: '{name}' is not followed; demsplit reads the script once, top to bottom."
            )

    def error(self, cls: type[DemsplitError], message: str, where: Where, fix: str) -> DemsplitError:
        return cls(message, file=where.file, line=where.line, fix=fix)

    def number(self, text: str, where: Where, what: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise self.error(
                ScriptError,
                f"{what}: expected a number, found {excerpt(text)}.",
                where,
                "write a number (or a variable that holds one).",
            ) from None
        if not math.isfinite(value):  # nan, inf, or a literal beyond the doubles such as 1e400
            raise self.error(
                ScriptError, f"{what}: {excerpt(text)} is not a finite number.", where, "write a finite number."
            )
        return value

    def integer(self, text: str, where: Where, what: str) -> int:
        try:
            return int(text)
        except ValueError:
            raise self.error(
                ScriptError, f"{what}: expected an integer, found {excerpt(text)}.", where, "write an integer."
            ) from None

    def need(self, args: list[str], n: int, where: Where, what: str, syntax: str) -> None:
        if len(args) < n:
            raise self.error(
                ScriptError,
                f"{what}: expected '{syntax}', found {excerpt(' '.join(args))}.",
                where,
                f"write '{syntax}'.",
            )

    # -- commands ----------------------------------------------------------

    def cmd_variable(self, args: list[str], where: Where) -> None:
        self.vars.define(args, where)

    def cmd_include(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "include", "include FILE")
        target = Path(args[0])
        if not target.is_absolute():
            target = self.root.parent / target
        if not target.is_file():
            raise self.error(
                ScriptError,
                f"include: no file {target}.",
                where,
                "check the path (relative paths are taken from the main script's directory).",
            )
        if len(self.include_stack) >= MAX_INCLUDE_DEPTH:
            raise self.error(
                ScriptError,
                f"include: files include each other more than {MAX_INCLUDE_DEPTH} deep.",
                where,
                "include files from the main script, or fewer levels deep.",
            )
        self.included.append(target)
        self.read(target)

    def cmd_units(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "units", "units si")
        if args[0] != "si":
            raise self.error(
                UnsupportedModelError,
                f"units {excerpt(args[0])}: demsplit reads SI runs only.",
                where,
                "run the simulation with 'units si'.",
            )
        self.units = "si"

    def cmd_boundary(self, args: list[str], where: Where) -> None:
        self.need(args, 3, where, "boundary", "boundary X Y Z")
        self.periodic = tuple("p" in a for a in args[:3])

    def cmd_create_box(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "create_box", "create_box NTYPES REGION")
        self.ntypes = self.integer(args[0], where, "create_box")

    def cmd_timestep(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "timestep", "timestep DT")
        self.timestep = self.number(args[0], where, "timestep")
        if self.timestep <= 0:
            raise self.error(
                ScriptError,
                f"timestep {excerpt(args[0])}: the timestep must be > 0.",
                where,
                "write the run's timestep (s).",
            )

    def cmd_run(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "run", "run N")
        n = self.integer(args[0], where, "run")
        self.run_steps.append(n)
        end = n if "upto" in args[1:] else self.step + n  # 'run N upto' runs to timestep N
        self.runs.append((self.step, end))
        self.run_timesteps.append(self.timestep)
        self.step = end

    def cmd_read_restart(self, args: list[str], where: Where) -> None:
        if self.restart_run is None:
            self.restart_run = len(self.runs)

    def cmd_reset_timestep(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "reset_timestep", "reset_timestep N")
        self.step = self.integer(args[0], where, "reset_timestep")

    def cmd_create_atoms(self, args: list[str], where: Where) -> None:
        if args and args[0].isdigit():
            self.type_uses.append((int(args[0]), "create_atoms", where))

    def cmd_pair_style(self, args: list[str], where: Where) -> None:
        self.need(args, 1, where, "pair_style", "pair_style gran model hertz tangential history")
        if args[0] != "gran":
            raise self.error(
                UnsupportedModelError,
                f"pair_style {excerpt(args[0])} is not supported.",
                where,
                "use 'pair_style gran model hertz|hooke tangential history|no_history'.",
            )
        self.pair, _ = _parse_model(args[1:], (), where, self.warnings, "pair_style gran")

    def cmd_neigh_modify(self, args: list[str], where: Where) -> None:
        if "contact_distance_factor" in args[:-1]:
            value = args[args.index("contact_distance_factor") + 1]
            self.contact_distance_factor = self.number(value, where, "neigh_modify contact_distance_factor")

    def cmd_unfix(self, args: list[str], where: Where) -> None:
        for fix in self.walls:  # the wall fix of that id that exists now, if any
            if args and fix.id == args[0] and fix.end_run is None:
                fix.end_run = len(self.runs)

    def cmd_fix(self, args: list[str], where: Where) -> None:
        self.need(args, 3, where, "fix", "fix ID GROUP STYLE ...")
        fid, style, rest = args[0], args[2], args[3:]
        if style == "property/global":
            self.property_global(fid, rest, where)
        elif style == "wall/gran":
            self.wall_gran(fid, rest, where)
        elif style in ("mesh/surface", "mesh/surface/stress"):
            self.mesh_surface(fid, rest, where)
        elif "liquidtransfer" in style.split("/"):
            raise self.error(
                UnsupportedModelError,
                f"fix {fid} {style}: a mesh that holds liquid is not supported: "
                "washino/capillary/viscous bridges take its per-triangle liquid content, which LIGGGHTS "
                "does not dump.",
                where,
                "use a dry mesh (fix ID all mesh/surface ...).",
            )
        elif style == "gravity":
            self.gravity_fixes += 1
            if args[1] != "all" or self.gravity_fixes > 1:
                self.unmodelled_forces.append(
                    f"fix {fid} gravity of group {args[1]}"
                    + (" (a second gravity fix)" if self.gravity_fixes > 1 else "")
                )
            self.fix_gravity(rest, where)
        elif style.startswith("particletemplate/"):
            if style != "particletemplate/sphere":
                self.warnings.append(f"{where.file}:{where.line}: fix {style}: only spheres are handled.")
            if "atom_type" in rest[:-1]:
                t = rest[rest.index("atom_type") + 1]
                self.type_uses.append((self.integer(t, where, f"fix {style} atom_type"), f"fix {fid} {style}", where))
        elif style == "move/mesh":
            self.warnings.append(
                f"{where.file}:{where.line}: fix {fid} move/mesh moves a mesh: its "
                "geometry from the mesh file is only valid before it moves."
            )
        elif style not in _BENIGN_FIXES:
            self.warnings.append(
                f"{where.file}:{where.line}: fix style {style} ({fid}) is not "
                "interpreted by demsplit; check that it does not change the contacts."
            )
        if style == "nve/sphere":
            self.integrated = True
        elif style not in _BALANCE_NEUTRAL_FIXES and not style.startswith("particletemplate/"):
            self.unmodelled_forces.append(f"fix {fid} {style}")

    def property_global(self, fid: str, rest: list[str], where: Where) -> None:
        self.need(rest, 2, where, f"fix {fid} property/global", "NAME STYLE VALUES")
        name, style, values = rest[0], rest[1], rest[2:]
        what = f"fix {fid} property/global {name}"
        if style == "peratomtypepair":
            self.need(values, 1, where, what, f"{name} peratomtypepair N V11 V12 ... VNN")
            n = self.integer(values[0], where, what)
            nums = [self.number(v, where, what) for v in values[1:]]
            if self.ntypes is not None and n != self.ntypes:
                raise self.error(
                    MaterialError,
                    f"{what}: N = {n}, but create_box defines {self.ntypes} atom types.",
                    where,
                    f"give a {self.ntypes} x {self.ntypes} table.",
                )
            if len(nums) != n * n:
                raise self.error(
                    MaterialError,
                    f"{what}: expected {n}x{n} = {n * n} values, found {len(nums)}.",
                    where,
                    "give one value per pair of types, row by row.",
                )
            value: object = np.array(nums).reshape(n, n)
        elif style == "scalar":
            self.need(values, 1, where, what, f"{name} scalar VALUE")
            value = self.number(values[0], where, what)
        else:
            nums = [self.number(v, where, what) for v in values]
            if style == "peratomtype" and self.ntypes is not None and len(nums) != self.ntypes:
                raise self.error(
                    MaterialError,
                    f"{what}: expected {self.ntypes} values (one per atom "
                    f"type, create_box {self.ntypes}), found {len(nums)}.",
                    where,
                    "give one value per atom type, wall types included.",
                )
            value = np.array(nums)
        self.properties[name] = (style, value, where)

    def fix_gravity(self, rest: list[str], where: Where) -> None:
        self.need(rest, 2, where, "fix gravity", "fix ID GROUP gravity G vector X Y Z")
        if rest[1] != "vector" or len(rest) < 5:
            self.warnings.append(
                f"{where.file}:{where.line}: fix gravity style {excerpt(rest[1])} is not read; script.gravity is None."
            )
            self.unmodelled_forces.append(f"fix gravity of style {rest[1]} (not read)")
            return
        try:
            g = float(rest[0])
            d = np.array([float(v) for v in rest[2:5]])
            if not (math.isfinite(g) and np.all(np.isfinite(d))):
                raise ValueError
        except ValueError:
            self.warnings.append(
                f"{where.file}:{where.line}: fix gravity with a variable "
                f"({' '.join(rest)}) is not read; script.gravity is None."
            )
            self.unmodelled_forces.append(f"fix gravity {' '.join(rest)} (a variable, not read)")
            return
        norm = float(np.linalg.norm(d))
        if norm == 0.0:
            raise self.error(
                ScriptError, "fix gravity: the direction vector is zero.", where, "give a non-zero direction."
            )
        self.gravity = g * d / norm

    def mesh_surface(self, fid: str, rest: list[str], where: Where) -> None:
        syntax = "fix ID GROUP mesh/surface file FILE type T [scale S] [move DX DY DZ] [rotate axis AX AY AZ angle DEG]"
        self.need(rest, 4, where, f"fix {fid} mesh/surface", syntax)
        if rest[0] != "file" or rest[2] != "type":
            raise self.error(
                ScriptError,
                f"fix {fid} mesh/surface: expected 'file FILE type T', found {excerpt(' '.join(rest[:4]))}.",
                where,
                f"write '{syntax}'.",
            )
        file = Path(rest[1])
        if not file.is_absolute():
            file = self.root.parent / file
        wall_type = self.integer(rest[3], where, f"fix {fid} mesh/surface type")
        transforms: list[tuple[str, tuple[float, ...]]] = []
        i = 4
        while i < len(rest):
            word = rest[i]
            what = f"fix {fid} mesh/surface {word}"
            if word == "scale":
                self.need(rest[i + 1 :], 1, where, what, "scale S")
                transforms.append(("scale", (self.number(rest[i + 1], where, what),)))
                i += 2
            elif word == "move":
                self.need(rest[i + 1 :], 3, where, what, "move DX DY DZ")
                transforms.append(("move", tuple(self.number(v, where, what) for v in rest[i + 1 : i + 4])))
                i += 4
            elif word == "rotate":
                part = rest[i + 1 : i + 7]
                if len(part) < 6 or part[0] != "axis" or part[4] != "angle":
                    raise self.error(
                        ScriptError,
                        f"{what}: expected 'rotate axis AX AY AZ angle DEG'.",
                        where,
                        "write 'rotate axis AX AY AZ angle DEG'.",
                    )
                transforms.append(
                    ("rotate", tuple(self.number(v, where, what) for v in (part[1], part[2], part[3], part[5])))
                )
                i += 7
            else:
                i += 1
        wall = Wall(name=fid, kind="mesh", type=wall_type, file=str(file), transforms=tuple(transforms))
        self.meshes[fid] = wall
        self.type_uses.append((wall_type, f"fix {fid} mesh/surface", where))

    def wall_gran(self, fid: str, rest: list[str], where: Where) -> None:
        what = f"fix {fid} wall/gran"
        spec, i = _parse_model(rest, ("primitive", "mesh"), where, self.warnings, what)
        if i >= len(rest):
            raise self.error(
                ScriptError,
                f"{what}: expected 'primitive type T ...' or 'mesh n_meshes K meshes M1 ...'.",
                where,
                "complete the wall/gran command.",
            )
        walls: list[Wall] = []
        if rest[i] == "primitive":
            geo = rest[i + 1 :]
            syntax = "primitive type T xplane|yplane|zplane C  or  primitive type T zcylinder R C1 C2"
            self.need(geo, 4, where, what, syntax)
            if geo[0] != "type":
                raise self.error(
                    ScriptError,
                    f"{what}: expected 'primitive type T', found {excerpt(geo[0])}.",
                    where,
                    f"write '{syntax}'.",
                )
            wall_type = self.integer(geo[1], where, f"{what} type")
            shape = geo[2]
            if shape in _PLANES:
                wall = Wall(
                    name=fid,
                    kind="plane",
                    type=wall_type,
                    axis=_PLANES[shape],
                    position=self.number(geo[3], where, f"{what} {shape}"),
                )
            elif shape in _CYLINDERS:
                self.need(geo, 6, where, what, f"primitive type T {shape} RADIUS C1 C2")
                r, c1, c2 = (self.number(v, where, f"{what} {shape}") for v in geo[3:6])
                wall = Wall(
                    name=fid, kind="cylinder", type=wall_type, axis=_CYLINDERS[shape], radius=r, center=(c1, c2)
                )
            else:
                raise self.error(
                    UnsupportedModelError,
                    f"{what}: primitive {excerpt(shape)} is not supported.",
                    where,
                    "use xplane|yplane|zplane or xcylinder|ycylinder|zcylinder, or a mesh.",
                )
            self.type_uses.append((wall_type, what, where))
            walls.append(wall)
            tail = geo[6 if shape in _CYLINDERS else 4 :]
        else:
            geo = rest[i + 1 :]
            if len(geo) < 3 or geo[0] != "n_meshes" or geo[2] != "meshes":
                raise self.error(
                    ScriptError,
                    f"{what}: expected 'mesh n_meshes K meshes M1 ...'.",
                    where,
                    "write 'mesh n_meshes K meshes M1 ... MK'.",
                )
            k = self.integer(geo[1], where, f"{what} n_meshes")
            names = geo[3 : 3 + k]
            if len(names) != k:
                raise self.error(
                    ScriptError,
                    f"{what}: n_meshes {k} but {len(names)} mesh ids follow.",
                    where,
                    "list exactly n_meshes mesh fix ids after 'meshes'.",
                )
            for m in names:
                if m not in self.meshes:
                    raise self.error(
                        ScriptError,
                        f"{what}: mesh {excerpt(m)} is not a fix mesh/surface defined before.",
                        where,
                        "define 'fix M all mesh/surface file F type T' first.",
                    )
                walls.append(self.meshes[m])
            tail = geo[3 + k :]
        # fix wall/gran takes its on/off settings after the geometry (measured:
        # 'computeElasticPotential on' before 'mesh' is "wrong keyword order")
        spec.settings.update({a: b for a, b in zip(tail, tail[1:]) if b in ("on", "off")})
        store_force = any(a == "store_force" and b == "yes" for a, b in zip(tail, tail[1:]))
        moving = next((w for w in tail if w in _MOVING_WALL_KEYWORDS), None)
        for fix in self.walls:  # a fix defined again under its id replaces the one that exists
            if fix.id == fid and fix.end_run is None:
                fix.end_run = len(self.runs)
        self.walls.append(
            WallFix(fid, walls, spec, rest[i] == "mesh", len(self.runs), store_force=store_force, moving=moving)
        )

    def cmd_compute(self, args: list[str], where: Where) -> None:
        self.need(args, 3, where, "compute", "compute ID GROUP STYLE ...")
        style = args[2]
        if style in ("pair/gran/local", "wall/gran/local"):
            self.computes[args[0]] = (style.split("/")[0], args[3:], where)

    def cmd_dump(self, args: list[str], where: Where) -> None:
        self.need(args, 5, where, "dump", "dump ID GROUP STYLE N FILE ...")
        did, style = args[0], args[2]
        every = self.integer(args[3], where, f"dump {did} N")
        file = Path(args[4])
        if not file.is_absolute():
            file = self.root.parent / file
        self.dumps[did] = DumpSpec(
            id=did, style=style, every=every, file=str(file), keywords=args[5:], first_run=len(self.runs)
        )
        self.dump_where[did] = where

    def modified_dump(self, args: list[str], where: Where) -> DumpSpec:
        """The dump a ``dump_modify`` line names (defined before it, else a :class:`ScriptError`)."""
        self.need(args, 1, where, "dump_modify", "dump_modify ID KEYWORD VALUE ...")
        dump = self.dumps.get(args[0])
        if dump is None:
            raise self.error(
                ScriptError,
                f"dump_modify: no dump with id {excerpt(args[0])} is defined before.",
                where,
                "define the dump before modifying it.",
            )
        return dump

    def cmd_dump_modify(self, args: list[str], where: Where) -> None:
        dump = self.modified_dump(args, where)
        i, rest = 0, args[1:]
        while i < len(rest):
            key = rest[i]
            arity = _DUMP_MODIFY_ARITY.get(key)
            if arity is None:
                self.warnings.append(
                    f"{where.file}:{where.line}: dump_modify keyword {excerpt(key)} not "
                    "understood; the rest of the line is ignored."
                )
                return
            self.need(rest[i + 1 :], arity, where, f"dump_modify {key}", f"{key} VALUE")
            if key in ("format", "label", "sort"):
                setattr(dump, key, rest[i + 1])
            i += 1 + arity

    # -- assembly ----------------------------------------------------------

    def model(self, spec: _ModelSpec) -> ContactModel:
        """The contact model of a ``pair_style gran`` or ``fix wall/gran``: the law's key and the
        parameters it declares, from the model's words and the script's global properties."""
        law = law_class(spec.law)
        declared = law.parameters
        params: dict = {"tangential": spec.tangential, "rolling": spec.rolling, "cohesion": spec.cohesion}
        for prop, name in law.run_parameters().items():
            value = self.properties.get(prop)
            if value is None:
                if declared[name][0] is ContactLaw.REQUIRED:
                    raise self.error(
                        ScriptError,
                        f"{spec.law} needs 'fix ID all property/global {prop} ...' "
                        f"({declared[name][1]}), which the script does not define.",
                        spec.where,
                        f"add the {prop} the run used.",
                    )
                continue
            params[name] = float(value[1]) if np.ndim(value[1]) == 0 else value[1]
        for setting, (name, on, off) in law.simulator_settings.items():
            if name in declared:
                params[name] = on if spec.on(setting) else off
        if spec.cohesion in BRIDGE_MODELS:
            params["contact_distance_factor"] = self.contact_distance_factor
        if spec.cohesion == "washino/capillary/viscous":
            params["limit_liquid_content"] = "on" if spec.on("limitLiquidContent") else "off"
            if spec.on("modifyLbVolume"):
                lb = self.properties.get("lbVolumeFraction")
                if lb is None:
                    raise self.error(
                        ScriptError,
                        "washino/capillary/viscous with modifyLbVolume on needs 'fix ID all "
                        "property/global lbVolumeFraction scalar F', which the script does not define.",
                        spec.where,
                        "add the lbVolumeFraction the run used.",
                    )
                params["bridge_volume_fraction"] = float(lb[1])
        try:
            return ContactModel(spec.law, params)
        except DemsplitError as exc:  # a parameter the model's words need, missing from the script
            raise exc.located(file=spec.where.file, line=spec.where.line) from None

    def materials(self) -> dict[int, Material]:
        found = {name: self.properties.get(name) for name in _MATERIAL_PROPERTIES}
        missing = [name for name, p in found.items() if p is None]
        if missing:
            if self.pair is None and not self.walls:
                return {}
            raise ScriptError(
                f"the script defines no {' and no '.join(missing)}.",
                file=self.root,
                fix="add 'fix ID all property/global youngsModulus|poissonsRatio peratomtype V1 ... VN'.",
            )
        for name, (style, _values, where) in found.items():
            if style != "peratomtype":
                raise self.error(
                    MaterialError,
                    f"{name} must be given 'peratomtype', found {excerpt(style)}.",
                    where,
                    f"write 'property/global {name} peratomtype V1 ... VN'.",
                )
        (_, E, wE), (_, nu, wnu) = found["youngsModulus"], found["poissonsRatio"]
        if len(E) != len(nu):
            raise self.error(
                MaterialError,
                f"youngsModulus has {len(E)} values (line {wE.line}) but poissonsRatio has {len(nu)}.",
                wnu,
                "give both one value per atom type.",
            )
        for k in range(len(E)):
            if not E[k] > 0:
                raise self.error(
                    MaterialError,
                    f"youngsModulus of type {k + 1} is {float(E[k])!r}; it must be > 0.",
                    wE,
                    "correct the Young's modulus.",
                )
            if not 0.0 <= nu[k] <= 0.5:
                raise self.error(
                    MaterialError,
                    f"poissonsRatio of type {k + 1} is {float(nu[k])!r}; LIGGGHTS accepts 0 <= nu <= 0.5.",
                    wnu,
                    "correct the Poisson's ratio.",
                )
        return {k + 1: Material(float(E[k]), float(nu[k])) for k in range(len(E))}

    def local_layouts(self, pair_model: _ModelSpec | None, mesh_fix: tuple | None) -> dict[str, LocalLayout]:
        layouts = {}
        for cid, (kind, keywords, where) in self.computes.items():
            spec = pair_model if kind == "pair" else (mesh_fix[1] if mesh_fix else None)
            if spec is None:
                raise self.error(
                    ScriptError,
                    f"compute {cid} {kind}/gran/local needs "
                    + ("a 'pair_style gran'." if kind == "pair" else "a mesh 'fix wall/gran'."),
                    where,
                    "define it before the compute, as LIGGGHTS requires.",
                )
            history = history_columns(
                self.model(spec).contact_law, kind, elastic_potential=spec.on("computeElasticPotential")
            )
            try:
                columns = local_layout(kind, keywords, len(history), history=history)
            except DemsplitError as exc:
                raise exc.located(file=where.file, line=where.line) from None
            layouts[cid] = LocalLayout(kind, columns)
        return layouts

    def finish_dump(self, dump: DumpSpec, layouts: dict[str, LocalLayout]) -> None:
        where = self.dump_where[dump.id]
        binary = dump.file.endswith(".bin")
        if dump.style == "local" and binary:
            self.warnings.append(
                f"dump {dump.id}: dump local to a .bin file writes text headers and "
                "unreadable rows in LIGGGHTS 3.8.0; use a text file and dump_modify format."
            )
        dump.full_precision = (binary and dump.style != "local") or (
            dump.format is not None and _format_full_precision(dump.format, dump.style == "local")
        )
        if dump.format is not None:
            conversions = _format_conversions(dump.format)
            if len(conversions) != len(dump.keywords):
                self.warnings.append(
                    f"dump {dump.id}: the format has {len(conversions)} conversions for {len(dump.keywords)} columns."
                )
            if dump.style == "local":
                ints = [k + 1 for k, (c, _) in enumerate(conversions) if c in "diouxXc"]
                if ints:
                    self.warnings.append(
                        f"dump {dump.id}: format column(s) {ints} use an integer "
                        "conversion, but dump local passes doubles: those columns are garbage."
                    )
        if dump.style != "local":
            return
        refs = [re.fullmatch(r"c_([^\[\]]+)(?:\[(\d+)\])?", k) for k in dump.keywords]
        used = {m.group(1) for m in refs if m and m.group(1) in layouts}
        if len(used) > 1:
            raise self.error(
                ScriptError,
                f"dump {dump.id} mixes columns of computes {sorted(used)}.",
                where,
                "dump each granular local compute to its own file.",
            )
        if not used:
            return
        dump.compute = used.pop()
        full = layouts[dump.compute].columns
        names = []
        for keyword, m in zip(dump.keywords, refs):
            if m is None or m.group(1) != dump.compute:
                names.append(keyword)
                continue
            if m.group(2) is None:
                raise self.error(
                    ScriptError,
                    f"dump {dump.id}: {keyword} is an array; dump local needs one column per c_ID[k].",
                    where,
                    f"write {keyword}[1] {keyword}[2] ...",
                )
            k = int(m.group(2))
            if not 1 <= k <= len(full):
                raise self.error(
                    ScriptError,
                    f"dump {dump.id}: {keyword} is out of range; compute "
                    f"{dump.compute} has {len(full)} columns ({' '.join(full)}).",
                    where,
                    "correct the column index.",
                )
            names.append(full[k - 1])
        dump.layout = LocalLayout(layouts[dump.compute].kind, names)

    def result(self) -> LiggghtsScript:
        if self.units is None:
            self.warnings.append("no 'units' command; demsplit assumes units si.")
        materials = self.materials()
        pair_model = self.model(self.pair) if self.pair else ContactModel()
        walls: list[Wall] = []
        wall_runs: list[tuple[int, int | None]] = []
        mesh_fix, dumped_mesh_walls = None, []
        stored_force: dict[int, str] = {}
        moving_walls: dict[int, str] = {}
        wall_settings: list[dict[str, str]] = []
        for fix in self.walls:
            model = self.model(fix.spec)
            first = len(walls)
            walls += [replace(wall, model=None if model == pair_model else model) for wall in fix.walls]
            wall_runs += [(fix.first_run, fix.end_run)] * len(fix.walls)
            wall_settings += [dict(fix.spec.settings)] * len(fix.walls)
            for k in range(first, len(walls)):
                if fix.store_force and not fix.is_mesh:
                    stored_force[k] = fix.id
                if fix.moving is not None:
                    moving_walls[k] = fix.moving
            if fix.is_mesh:
                mesh_fix = (fix.id, fix.spec)
                dumped_mesh_walls = list(range(first, len(walls)))
        for t, what, where in self.type_uses:
            if materials and t not in materials:
                raise self.error(
                    MaterialError,
                    f"{what} uses type {t}, which has no material (materials "
                    f"are defined for types {sorted(materials)}).",
                    where,
                    "give youngsModulus and poissonsRatio one value per type, this one included.",
                )
        layouts = self.local_layouts(self.pair, mesh_fix)
        for dump in self.dumps.values():
            self.finish_dump(dump, layouts)
        scene = Scene(materials=materials, model=pair_model, walls=walls, units="si", source=str(self.root))
        coefficients = {name: value for name, (_, value, _) in self.properties.items()}
        variables = {}
        for name in self.vars.values:
            try:
                variables[name] = self.vars.retrieve(name, Where(self.root, 0))
            except (Unevaluable, DemsplitError):
                continue
        return LiggghtsScript(
            path=self.root,
            scene=scene,
            periodic=self.periodic,
            dumps=list(self.dumps.values()),
            gravity=self.gravity,
            coefficients=coefficients,
            ntypes=self.ntypes,
            timestep=self.timestep,
            run_steps=self.run_steps,
            runs=self.runs,
            wall_runs=wall_runs,
            local_computes=layouts,
            dumped_mesh_walls=dumped_mesh_walls,
            variables=variables,
            warnings=self.warnings,
            included=self.included,
            stored_force=stored_force,
            moving_walls=moving_walls,
            pair_settings=dict(self.pair.settings) if self.pair else {},
            wall_settings=wall_settings,
            run_timesteps=self.run_timesteps,
            restart_run=self.restart_run,
            unmodelled_forces=self.unmodelled_forces
            + ([] if self.integrated or not self.runs else ["no fix nve/sphere"]),
            local_histories={
                kind: history_columns(
                    self.model(spec).contact_law, kind, elastic_potential=spec.on("computeElasticPotential")
                )
                for kind, spec in (("pair", self.pair), ("wall", mesh_fix[1] if mesh_fix else None))
                if spec is not None
            },
        )


def read_script(path: str | Path, variables: dict[str, str] | None = None) -> LiggghtsScript:
    """Read a LIGGGHTS input script (see the module docstring).

    ``variables`` are the run's ``-var NAME VALUE`` command-line values; they
    win over the script's own definitions, as in LIGGGHTS.
    """
    path = Path(path).resolve()
    reader = _Reader(path, dict(variables or {}))
    reader.read(path)
    return reader.result()
