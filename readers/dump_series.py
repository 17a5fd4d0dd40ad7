"""A dump written one file per timestep (``dump ... post/dump*.liggghts``) read as one dump.

LAMMPS and LIGGGHTS replace the ``*`` of a dump's file name by the timestep and
start a new file at every output; the LIGGGHTS tutorials write their dumps this
way. :class:`DumpSeries` is a :class:`~demsplit.readers.lammps_dump.DumpFile`
over every file the pattern matches (compressed copies included), its frames
ordered by timestep; each frame is read by the dump of its own file, so errors
name that file. A ``%`` in the name (one file per processor) splits a frame
over several files and is not read.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

from ..errors import InputFormatError
from .lammps_dump import DumpFile, DumpFrame, open_dump

COMPRESSED = (".gz", ".bz2", ".xz")


class SeriesEntry(NamedTuple):
    """One frame of a series: the dump of its file and its entry in that dump's index."""

    dump: DumpFile
    entry: object

    @property
    def step(self) -> int:
        return self.entry.step

    @property
    def n_rows(self) -> int:
        return self.entry.n_rows


def series_files(pattern: str | Path) -> list[Path]:
    """The files a dump file name with ``*`` matches (each also as .gz/.bz2/.xz), by name."""
    pattern = Path(pattern)
    found = {p for suffix in ("", *COMPRESSED) for p in pattern.parent.glob(pattern.name + suffix) if p.is_file()}
    return sorted(found)


class DumpSeries(DumpFile):
    """The dumps of ``files`` (one or more frames each) as one dump, frames ordered by timestep
    (module docstring). ``pattern`` names the series in messages."""

    def __init__(self, pattern: str | Path, files: Sequence[Path], columns: Sequence[str] | None = None) -> None:
        super().__init__(Path(pattern))
        if not files:
            raise InputFormatError(
                "no file matches this dump's name.",
                file=pattern,
                fix="check the dump's file name and that the run wrote it.",
            )
        self._dumps = [open_dump(f, columns) for f in files]
        first = self._dumps[0]
        self.kind, self.label, self.columns, self.head_rows = first.kind, first.label, first.columns, first.head_rows
        self._compression = first.compression

    @property
    def files(self) -> list[str]:
        return [d.path for d in self._dumps]

    @property
    def compression(self) -> str | None:
        return self._compression

    def _build_index(self) -> tuple[list, list]:
        entries, damaged = [], []
        for dump in self._dumps:
            entries += [SeriesEntry(dump, e) for e in dump._index()]
            damaged += dump.damaged
        return sorted(entries, key=lambda e: e.step), damaged

    def _stream(self):
        return contextlib.nullcontext()  # each frame is read from its own file

    def _read(self, entry: SeriesEntry, columns: Sequence[str] | None, stream) -> DumpFrame:
        return entry.dump._read(entry.entry, columns, None)
