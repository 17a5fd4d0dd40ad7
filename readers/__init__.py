"""Readers: one per source format, all behind :func:`open_run`.

``open_run(path, **options)`` looks at ``path`` and returns a
:class:`~demsplit.readers.base.Run`:

* a LIGGGHTS input script (the run's dumps are found from its ``dump``
  lines, or given as ``atoms=``, ``contacts=``, ``walls=``):
  :class:`demsplit.readers.liggghts.LiggghtsRun`;
* ``None``: LIGGGHTS dumps given as ``atoms=``, ``contacts=`` (``walls=``)
  with the scene as options (``materials=``, ``scene_options=``; see
  :func:`demsplit.readers.liggghts.scene_script`);
* a snapshot file written by :func:`demsplit.yade.snapshot`:
  :class:`demsplit.readers.yade_snapshot.YadeSnapshotRun`;
* an ingest cache written by ``demsplit convert`` (an HDF5 file whose
  ``format`` attribute says so): :class:`demsplit.readers.cache.CacheRun`.

Format sniffing, column mapping and precision facts live in this package and
nowhere else.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputFormatError
from .base import Run


def read_head(path: Path, size: int = 4096) -> bytes:
    """The first ``size`` bytes of ``path``, for sniffing its kind; a missing file is an error."""
    if not path.is_file():
        raise InputFormatError("no such file.", file=path, fix="check the path.")
    with open(path, "rb") as f:
        return f.read(size)


def sniff(path: str | Path) -> str:
    """Kind of run file: ``'cache'``, ``'yade-snapshot'`` or ``'liggghts-script'``."""
    from ..yade import HDF5_SIGNATURE, NPY_STREAM_MAGIC

    path = Path(path)
    head = read_head(path)
    if head.startswith(HDF5_SIGNATURE):
        from .cache import is_cache

        return "cache" if is_cache(path) else "yade-snapshot"
    if head.startswith(NPY_STREAM_MAGIC):
        return "yade-snapshot"
    if b"ITEM: TIMESTEP" in head:
        raise InputFormatError(
            "this is a dump file, not a run: demsplit needs the run's input script for the materials, "
            "the contact model and the column layout of the contact dumps.", file=path,
            fix="pass the LIGGGHTS input script (demsplit run in.script --atoms DUMP --contacts DUMP), "
            "or describe the scene with --material TYPE:E:NU and --columns.")
    if b"\0" in head:
        raise InputFormatError("unrecognised binary file.", file=path,
                               fix="pass a LIGGGHTS input script or a demsplit.yade snapshot file.")
    return "liggghts-script"


def open_run(path: str | Path | None, **options) -> Run:
    """Open a run (see the module docstring). ``options`` go to the reader.

    The returned run remembers ``(path, options)`` as ``run.spec`` so that
    worker processes can open the same run again.
    """
    kind = "liggghts-dumps" if path is None else sniff(path)
    if kind == "cache":
        from .cache import open_cache

        run = open_cache(path, **options)
    elif kind == "yade-snapshot":
        from .yade_snapshot import open_yade_snapshot

        run = open_yade_snapshot(path, **options)
    else:
        from .liggghts import open_liggghts_run

        run = open_liggghts_run(path, **options)
    run.spec = {"path": None if path is None else str(path), **options}
    return run


__all__ = ["Run", "open_run", "sniff"]
