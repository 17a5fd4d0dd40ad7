"""Readers: one class per source format, each registered by itself, all behind :func:`open_run`.

``open_run(path, **options)`` reads the first bytes of ``path`` and asks
every registered reader (:data:`demsplit.readers.base.REGISTRY`, highest
``priority`` first) whether it reads it (``detect``); the first that says
yes opens it. ``path=None`` means a run given by options alone (LIGGGHTS
dumps with ``atoms=``, ``contacts=`` and the scene as options). The readers
of this package are imported on first use (:data:`READER_MODULES`), so
``import demsplit`` stays light.

Format sniffing, column mapping and precision facts live in this package and
nowhere else.
"""

from __future__ import annotations

from importlib import import_module
from pathlib import Path

from ..errors import InputFormatError
from .base import REGISTRY, Run

READER_MODULES = ("cache", "yade_snapshot", "yade_state", "yade_export", "lammps", "liggghts")
"""Modules of this package that define readers (each registers its classes when imported)."""

HEAD_BYTES = 4096
"""Bytes of a file a reader's ``detect`` sees."""


def readers() -> list[type[Run]]:
    """Every registered reader, highest priority first (registration order among equals)."""
    for name in READER_MODULES:
        import_module(f"{__name__}.{name}")
    return sorted(REGISTRY.values(), key=lambda cls: -cls.priority)


def read_head(path: Path, size: int = HEAD_BYTES) -> bytes:
    """The first ``size`` bytes of ``path``, for sniffing its kind; a missing file is an error, and a
    directory is answered with the files in it that a reader takes."""
    if path.is_dir() or (not path.exists() and any(c in str(path) for c in "*?[")):
        return b""  # a directory or a glob: only a reader of several files (YADE saved states) takes it
    if not path.is_file():
        raise InputFormatError("no such file.", file=path, fix="check the path.")
    with open(path, "rb") as f:
        return f.read(size)


def _looks_like_a_run(path: Path) -> bool:
    """Whether a reader other than the text-script fallback, or a LIGGGHTS script name (``in.*``), takes it."""
    with open(path, "rb") as f:
        head = f.read(HEAD_BYTES)
    return path.name.startswith("in.") or any(cls.detect(path, head) for cls in readers() if cls.priority >= 0)


def reader_for(path: str | Path | None, simulator: str | None = None) -> type[Run]:
    """The reader class that reads ``path`` (None: a run given by options); ``simulator`` (``--simulator``): the
    reader of that simulator's runs, where the file's words cannot tell (a LAMMPS and a LIGGGHTS script are
    both text in the same language)."""
    path = None if path is None else Path(path)
    head = b"" if path is None else read_head(path)
    if simulator is not None:
        own = [cls for cls in readers() if cls.simulator == simulator]
        if not own:
            known = sorted({cls.simulator for cls in readers() if cls.simulator})
            raise InputFormatError(
                f"no reader reads {simulator!r} runs.",
                file=path,
                fix=f"use --simulator with one of {', '.join(known)}.",
            )
        return next((cls for cls in own if cls.detect(path, head)), own[-1])
    for cls in readers():
        if cls.detect(path, head):
            return cls
    if path is not None and path.is_dir():
        found = sorted(p.name for p in path.iterdir() if p.is_file() and _looks_like_a_run(p))
        raise InputFormatError(
            "this is a directory, not a run.",
            file=path,
            fix=(
                "give one of the runs it holds: "
                + ", ".join(found[:30])
                + (f" (and {len(found) - 30} more)" if len(found) > 30 else "")
            )
            if found
            else "give the run's input script or snapshot file.",
        )
    if path is not None and not path.exists():
        raise InputFormatError("no such file (and no file matches it as a pattern).", file=path, fix="check the path.")
    if b"ITEM: TIMESTEP" in head:
        raise InputFormatError(
            "this is a dump file, not a run: demsplit needs the run's input script for the materials, "
            "the contact model and the column layout of the contact dumps.",
            file=path,
            fix="pass the LIGGGHTS input script (demsplit run in.script --atoms DUMP --contacts DUMP), "
            "or describe the scene with --material TYPE:E:NU and --columns.",
        )
    accepted = "; ".join(f for cls in readers() for f in cls.formats)
    raise InputFormatError("unrecognised file: no reader reads it.", file=path, fix=f"pass one of: {accepted}.")


def open_run(path: str | Path | list | None, simulator: str | None = None, **options) -> Run:
    """Open a run (see the module docstring). ``options`` go to the reader; ``simulator`` picks the reader of
    that simulator (:func:`reader_for`). A list of paths is a run of several files (YADE saved states).

    The returned run remembers ``(path, options)`` as ``run.spec`` so that
    worker processes can open the same run again.
    """
    if isinstance(path, (list, tuple)) and len(path) == 1:
        path = path[0]
    if isinstance(path, (list, tuple)):
        paths = [Path(p) for p in path]
        cls = reader_for(paths[0], simulator)
        if not cls.several_files:
            raise InputFormatError(
                f"several inputs were given, but {paths[0].name} is {cls.formats[0]}, which is a run by itself.",
                file=paths[0],
                fix="give one run (several files are one run only for YADE saved states).",
            )
        for other in paths[1:]:
            if reader_for(other, simulator) is not cls:
                raise InputFormatError(
                    f"this input is not {cls.formats[0]}, as {paths[0].name} is.",
                    file=other,
                    fix="give the files of one run.",
                )
        run = cls.open(paths, **options)
        run.spec = {"path": [str(p) for p in path], **options}
        return run
    run = reader_for(path, simulator).open(None if path is None else Path(path), **options)
    run.spec = {"path": None if path is None else str(path), **options}
    if simulator is not None:
        run.spec["simulator"] = simulator
    return run


__all__ = ["REGISTRY", "Run", "open_run", "reader_for", "readers"]
