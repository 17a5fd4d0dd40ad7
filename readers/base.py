"""The one interface every run reader implements, and the registry the readers fill themselves.

A *run* is what a simulation left on disk. Opening it gives a :class:`Run`:
its :class:`~demsplit.scene.Scene`, the timesteps of its frames, random
access to frame ``k`` and iteration that yields one
:class:`~demsplit.frame.Frame` at a time (a frame is the unit of memory).
``describe()`` says what the reader found: files, kinds, precision, where the
overlaps come from.

Readers register themselves (OVITO's file readers, MDAnalysis'
``coordinates``): every subclass that sets ``format_name`` is added to
:data:`REGISTRY` when its module is imported, and says with
:meth:`Run.detect` whether it reads a file. :func:`demsplit.readers.open_run`
asks them; nothing else knows the formats.
"""

from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ..errors import InputFormatError
from ..frame import Frame
from ..scene import Material, Scene

REGISTRY: dict[str, type[Run]] = {}
"""``format_name`` -> reader class, in registration order."""


@dataclass(frozen=True)
class Option:
    """A reader option as the command line gives it: ``flags`` and ``help``, the other keywords of argparse's
    ``add_argument`` in ``argparse``, and where the parsed value goes: the reader's constructor keyword ``name``,
    through ``convert`` (default: as parsed), or, with ``into``, the entry ``name`` of the dict keyword
    ``into``. ``group``: the help section (default: the reader's ``cli_group``). Readers that take the same
    flag share one definition, declared once below (:data:`MATERIALS`, :data:`ATOMS`, ...)."""

    name: str
    flags: tuple[str, ...]
    help: str
    argparse: Mapping[str, Any] = field(default_factory=dict)
    convert: Callable[[Any], Any] | None = None
    into: str | None = None
    group: str | None = None

    def value(self, parsed: Any) -> Any:
        """The constructor's value of what argparse parsed."""
        return self.convert(parsed) if self.convert is not None else parsed


def material_spec(text: str) -> tuple[int, Material]:
    """``TYPE:E:NU`` (e.g. ``1:5e7:0.3``: Pa, -) as ``(type, Material)``; ValueError when malformed."""
    try:
        t, E, nu = text.split(":")
        return int(t), Material(float(E), float(nu))
    except ValueError:
        raise ValueError(f"expected TYPE:E:NU (e.g. 1:5e7:0.3), got {text!r}") from None


MATERIALS = Option(
    "materials",
    ("--material",),
    "the elastic constants of a material type, TYPE:E:NU (Pa, -), "
    "completing or overriding what the run's files say (repeatable)",
    {"action": "append", "type": material_spec, "metavar": "TYPE:E:NU"},
    convert=dict,
)
"""The option every reader with materials takes."""
OVERLAP_TOLERANCE = Option(
    "overlap_tolerance",
    ("--overlap-tolerance",),
    "largest relative overlap error accepted when overlaps must be recomputed from printed positions (default 1e-3)",
    {"type": float, "metavar": "REL"},
)
"""The option of readers that may recompute overlaps from printed positions."""


SCRIPT_FILES = "Input scripts, LIGGGHTS and LAMMPS (default: the files the script's dump lines write)"
"""The help section of the options every input-script reader takes."""
ATOMS = Option(
    "atoms", ("--atoms",), "atom dump (dump custom: text; LIGGGHTS also binary .bin or compressed)", group=SCRIPT_FILES
)
CONTACTS = Option(
    "contacts",
    ("--contacts",),
    "pair contact dump (LIGGGHTS: dump local of compute pair/gran/local; "
    "LAMMPS: dump local of compute property/local and pair/local)",
    group=SCRIPT_FILES,
)
VARIABLES = Option(
    "variables",
    ("--var",),
    "script variable, as liggghts -var or lmp -var NAME VALUE",
    {"nargs": 2, "action": "append", "metavar": ("NAME", "VALUE")},
    convert=dict,
    group=SCRIPT_FILES,
)
"""The options of the readers of input scripts."""


class Run(ABC):
    """A run opened for reading (see the module docstring).

    Class attributes a reader sets: ``format_name`` (its registry key),
    ``formats`` (the inputs it accepts, in words, for messages and ``info``),
    ``priority`` (readers with a higher priority are asked first; a
    reader whose ``detect`` is a weak guess, like "any text file is a script",
    asks last; one above 0 recognises its files by a signature and is asked
    before ``info`` takes a compressed file for a dump) and ``several_files``
    (several paths are one run: :func:`~demsplit.readers.open_run` hands it the
    list, as YADE's saved states, one file per instant).

    Instance attributes every reader sets: ``scene``, ``steps`` (timestep of
    every readable frame, int64; frames ``len(steps)`` to ``len(self) - 1``, if
    any, are damaged ones whose step cannot be read and whose ``frame(k)``
    raises their error), ``sources`` (the input files, for provenance),
    ``notes`` (what the reader could not provide, and why); ``spec`` (the path
    and options it was opened with) is set by ``open_run``.
    """

    format_name: ClassVar[str]
    formats: ClassVar[tuple[str, ...]]
    simulator: ClassVar[str | None] = None
    """The simulator whose runs the reader reads (``liggghts``, ``lammps``), for ``--simulator``."""
    priority: ClassVar[int] = 0
    several_files: ClassVar[bool] = False
    cli_group: ClassVar[str] = ""
    cli_options: ClassVar[tuple[Option, ...]] = ()

    scene: Scene
    steps: np.ndarray
    sources: list[Any]
    notes: list[str]
    spec: dict

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "format_name" in cls.__dict__:
            REGISTRY[cls.format_name] = cls

    @classmethod
    @abstractmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        """Whether this reader reads the run at ``path`` whose first bytes are ``head``
        (``path`` None: the run is given by options alone)."""

    @classmethod
    def open(cls, path: Path | None, **options: Any) -> Run:
        """Open the run at ``path`` with reader ``options``; an option this reader does not take is an
        error that names it (options are the keyword parameters of the reader's constructor)."""
        taken = list(inspect.signature(cls.__init__).parameters)[2:]  # after self and the path
        unknown = sorted(set(options) - set(taken))
        if unknown:
            raise InputFormatError(
                f"option(s) {unknown} do not apply to {cls.formats[0]}.",
                file=path,
                fix=f"leave them out; this reader takes {sorted(taken) or 'none'}.",
            )
        return cls(path, **options)

    @classmethod
    def output_options(cls, output: Path) -> dict[str, Any]:
        """Reader options for a run analysed into ``output`` (``demsplit run -o``), below the user's own: a
        reader that converts its inputs keeps them next to the output. Default: none."""
        return {}

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """What ``demsplit info`` prints about a file this reader reads."""
        with cls.open(path) as run:
            scene = run.scene
            lines = [
                f"{path}: {cls.formats[0]}",
                f"  frames:   {len(run)}",
                f"  model:    {scene.model.describe()}",
                "  materials: "
                + ", ".join(f"{t}: E={m.E:g} Pa nu={m.nu:g}" for t, m in sorted(scene.materials.items())),
                f"  walls:    {len(scene.walls)}",
            ]
        return "\n".join(lines)

    @classmethod
    def first_frame_rows(cls, path: Path | None, **options: Any) -> tuple[int, int] | None:
        """The rows of the run's first frame, ``(particles, contacts)`` (walls' contacts included), read from
        the first lines of its files without opening the run, or None where that is not cheap (the
        default). A hint: the command prepares that frame's memory while the run opens
        (:mod:`demsplit.runtime.prefault`); the opening reports any problem of the files."""
        return None

    @abstractmethod
    def __len__(self) -> int:
        """The number of frames."""

    @abstractmethod
    def frame(self, k: int) -> Frame:
        """Frame ``k`` (0 <= k < len(self))."""

    def __iter__(self) -> Iterator[Frame]:
        """The frames in order, one in memory at a time (readers may stream them faster)."""
        for k in range(len(self)):
            yield self.frame(k)

    def describe(self) -> dict:
        """Files, kinds and precision, for provenance and ``demsplit check``."""
        return {"kind": self.format_name, "sources": [str(s) for s in self.sources]}

    def named_files(self) -> list[Path]:
        """Every file the run names, read or not: what an output must never replace
        (:func:`demsplit.outputs.check_output_path`). Default: ``sources``."""
        return [Path(s) for s in self.sources]

    def check_files(self, out: list[str]) -> list[str]:
        """Problems of the run's files that reading frame by frame does not show (timesteps missing
        from one of several dumps, ...), for ``demsplit check``; lines describing the files go to
        ``out``. Default: none."""
        return []

    def locate(self, frame: Frame, row: int) -> tuple[str | None, int | None]:
        """File and line of contact ``row`` of ``frame``, for messages (line None: unknown)."""
        return (frame.source[0] if frame.source else None), None

    def close(self) -> None:
        """Release the files (idempotent)."""

    def __enter__(self) -> Run:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
