"""Low-level readers of LAMMPS/LIGGGHTS dump files: per-frame column arrays.

``open_dump(path)`` sniffs the file and returns a :class:`DumpFile`: a text ``dump custom`` (kind
``'atoms'``) or ``dump local`` (kind ``'local'``, any ``dump_modify label``), plain or compressed with gzip,
bzip2 or xz (recognised by their magic bytes), or a LAMMPS binary ``dump custom`` (``*.bin``, native byte
order, no column names: pass ``columns=``). It does not interpret columns (which ``c_ID[k]`` is a force is
the input script's business); it indexes the frames, streams one frame at a time and names bad input by
its line.

Index: the first access to ``steps``/``frame(k)`` scans the file once, on every core, with a compiled pass
(:func:`~demsplit.readers.fastparse.scan_chunk`) that counts newlines and finds ``ITEM: TIMESTEP``: each
frame's step, header, box, column names and byte range, plus the newline count before every 1 MiB (the
checkpoints where a frame is cut for the threads). Binary files are indexed by hopping from header to header.

Reading a frame: rows are parsed straight into preallocated arrays by the compiled kernel
(:func:`~demsplit.readers.fastparse.parse_rows`), each thread reading (``os.preadv``) and parsing its own
slice; a compressed file is read in blocks of whole rows. The kernel checks every row's shape and converts
only the requested columns, integers exactly and reals correctly rounded; what it cannot finish (``nan``,
a non-number, too many long literals) goes to ``polars.read_csv``, which also gives the located error.
Every value read is finite, every row has the header's number of fields, and a frame holds the rows its
header announces (else :class:`~demsplit.errors.TruncatedFileError` at the end of a file).

Printed precision (``DumpFrame.digits``): the significant digits of each real column, counted on the frame's
first 128 KiB of rows (``None``: exact, as for integer and binary columns); a column of at most 16 distinct
values, which prints with fewer digits than its format allows, takes the frame's largest count. Why it is
built this way: docs/performance.md, "Standing decisions".
"""

from __future__ import annotations

import bz2
import gzip
import io
import lzma
import os
import struct
import threading
import zlib
from abc import ABC, abstractmethod
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

import numpy as np
from demsplit.errors import DemsplitError, InputFormatError, PrecisionError, TruncatedFileError
from demsplit.frame import Box, describe_steps
from demsplit.runtime import threads

if TYPE_CHECKING:  # polars is imported where the fallback parse needs it
    import polars as pl

__all__ = ["open_dump", "describe_dump", "looks_like_dump", "DumpFile", "DumpFrame"]

MARKER = b"ITEM: TIMESTEP"
HEADER_LINES = 9  # TIMESTEP, step, NUMBER OF, n, BOX BOUNDS, 3 bounds, ITEM: <label> names
HEADER_MAX = 1 << 16  # bytes a header may occupy (hundreds of column names fit)
CHUNK = 1 << 24  # index scan chunk (16 MiB)
CHECKPOINT = 1 << 20  # the index records the newlines before every CHECKPOINT bytes (1 MiB)
ROW_MAX = 1 << 16  # bytes a slice reads past its end to finish its last row
DIGITS_SAMPLE = 1 << 17  # bytes of rows sampled per frame for DumpFrame.digits
BLOCK = 1 << 24  # bytes of rows parsed at a time (16 MiB)
LOW_VARIETY = 16  # distinct values at or below which a column gets the frame's precision

_MAGIC = {b"\x1f\x8b": gzip.open, b"BZh": bz2.open, b"\xfd7zXZ\x00": lzma.open}
_BOUNDARY = {0: "p", 1: "f", 2: "s", 3: "m"}  # LAMMPS binary boundary codes

FIX_COUNT = (
    "rewrite the dump, or cut the damaged frame with a text editor; the header count and the rows of a frame must agree"
)
FIX_TRUNCATED = (
    "the run was interrupted while writing: rerun, or drop the incomplete last frame "
    "(truncate the file before its last 'ITEM: TIMESTEP')"
)


# --------------------------------------------------------------------------- frames


@dataclass
class DumpFrame:
    """One frame of a dump: its step, box and the requested columns.

    ``columns`` maps header names to arrays of length ``n_rows`` (float64, or
    int64 for columns whose text is all integer literals). ``first_line`` is
    the 1-based line number of the frame's first data row in the
    (decompressed) file (``None`` for binary dumps), so row ``i`` is line
    ``first_line + i``. ``digits`` gives the significant digits printed per
    column (``None`` = exact / full precision; see the module docstring).
    """

    step: int
    n_rows: int
    box: Box
    columns: dict[str, np.ndarray]
    file: str
    first_line: int | None
    digits: dict[str, int | None]

    def line_of(self, row: int) -> int | None:
        """1-based file line of data row ``row`` (``None`` for binary dumps)."""
        return None if self.first_line is None else self.first_line + int(row)

    def int_column(self, name: str) -> np.ndarray:
        """Column ``name`` as int64, refusing values that are not exact integers.

        Ids written as doubles with ``%g`` (LIGGGHTS ``dump local``) keep only
        ``digits`` significant digits: 1234567 prints as ``1.23457e+06``. A value
        is accepted when it is integral and, for a column printed with ``P``
        digits, below 10**P in magnitude (so no digit was rounded away).

        Raises
        ------
        PrecisionError
            naming the file, step and line of the first value that is not an
            exact integer.
        """
        col = self.columns[name]
        if col.dtype.kind in "iu":
            return col.astype(np.int64, copy=False)
        p = self.digits.get(name)
        limit = np.inf if p is None else 10.0**p
        bad = (col != np.rint(col)) | ~(np.abs(col) < min(limit, 2.0**53))
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise PrecisionError(
                f"column '{name}' must hold integer ids but row {row + 1} of the frame holds "
                f"{col[row].item()!r}, which is not an exact integer"
                + (f" at the {p} significant digits printed" if p is not None else "")
                + "; ids printed with %g above 999999 are destroyed",
                file=self.file,
                step=self.step,
                line=self.line_of(row),
                fix="write ids with dump_modify format using %d (dump custom) or %.17g (dump local), "
                "or use a binary dump",
            )
        return col.astype(np.int64)


# --------------------------------------------------------------------------- index entries


@dataclass(frozen=True)
class _TextEntry:
    """Where one text frame lives in the (decompressed) file."""

    step: int
    n_rows: int  # header count
    box: Box
    label: str
    names: tuple[str, ...]
    header_line: int  # 1-based line of 'ITEM: TIMESTEP'
    data_start: int  # byte offset of the first row
    data_end: int  # byte offset after the last row
    n_lines: int  # lines found between data_start and data_end
    last: bool  # last frame of the file
    ends_with_newline: bool

    @property
    def first_line(self) -> int:
        return self.header_line + HEADER_LINES


@dataclass(frozen=True)
class _BinaryEntry:
    step: int
    n_rows: int
    box: Box
    n_cols: int
    chunks: tuple[tuple[int, int], ...]  # (byte offset of the doubles, number of doubles)


# --------------------------------------------------------------------------- opening


def open_dump(path: str | Path, columns: Sequence[str] | None = None) -> DumpFile:
    """Open a LAMMPS/LIGGGHTS dump, sniffing its format from its first bytes.

    ``columns`` names the columns of a binary dump (which carries none); for a
    text dump it must equal the header's names if given.

    Raises
    ------
    InputFormatError
        empty file, unknown format, or a binary header that is not LAMMPS's.
    """
    path = Path(path)
    with open(path, "rb") as f:
        head = f.read(HEADER_MAX)
    if not head:
        raise InputFormatError(
            "the file is empty; expected a LAMMPS dump starting with 'ITEM: TIMESTEP'",
            file=path,
            line=1,
            fix="check that the run wrote this dump (dump every N, run length)",
        )
    opener = next((op for magic, op in _MAGIC.items() if head.startswith(magic)), None)
    if opener is not None:
        with opener(path, "rb") as f:
            buf = bytearray(HEADER_MAX)
            head = bytes(buf[: _read_into(f, memoryview(buf))])  # a stream damaged at once reads as empty
        if not head:
            raise TruncatedFileError(
                "the compressed file holds no data: it is cut or damaged at its start",
                file=path,
                line=1,
                fix=FIX_TRUNCATED,
            )
        if not head.startswith(MARKER):
            raise InputFormatError(
                "the decompressed file does not start with 'ITEM: TIMESTEP'; compressed binary dumps are not supported",
                file=path,
                line=1,
                fix="decompress it, or write a text dump",
            )
        return TextDump(path, opener, head, columns)
    if head.startswith(MARKER):
        return TextDump(path, None, head, columns)
    if path.suffix == ".bin" or not _looks_like_text(head):
        return BinaryDump(path, columns)
    first = head.split(b"\n", 1)[0]
    excerpt = repr(first[:40])[2:-1] + ("..." if len(first) > 40 else "")  # bounded and printable
    raise InputFormatError(
        f"expected a LAMMPS dump starting with 'ITEM: TIMESTEP', found '{excerpt}'",
        file=path,
        line=1,
        fix="pass a file written by the dump command",
    )


def _looks_like_text(head: bytes) -> bool:
    sample = head[:4096]
    return b"\0" not in sample


def looks_like_dump(path: Path, head: bytes) -> bool:
    """Whether a file whose first bytes are ``head`` is a dump by its look alone: a text dump's
    marker, a compressed stream, or a ``.bin`` file; for ``demsplit info``, which asks the run readers
    about everything else."""
    return head.startswith(MARKER) or any(head.startswith(m) for m in _MAGIC) or path.suffix == ".bin"


def describe_dump(path: str | Path) -> str:
    """What ``demsplit info`` prints about a dump: format, kind, frames, steps, rows per frame,
    damaged headers, and the first frame's box and columns with their printed significant digits."""
    dump = open_dump(path)
    form = (
        "binary (LAMMPS dump custom, native byte order; no column names in the file)"
        if isinstance(dump, BinaryDump)
        else f"text{', ' + dump.compression + '-compressed' if dump.compression else ''}"
    )
    rows = dump.rows
    lo, hi = (int(rows.min()), int(rows.max())) if len(rows) else (0, 0)
    lines = [
        f"{path}: LAMMPS/LIGGGHTS dump",
        f"  format:   {form}",
        f"  kind:     {dump.kind} (label {dump.label})",
        f"  frames:   {dump.n_frames}, steps {describe_steps(dump.steps)}",
        f"  rows:     {lo if lo == hi else f'{lo}..{hi}'} per frame",
    ]
    lines += [f"  DAMAGED frame header: {err}" for err in dump.damaged]
    if dump.n_frames:
        first = dump.frame(0)
        lines.append(
            f"  box (first frame): lo {first.box.lo.tolist()}, hi {first.box.hi.tolist()}, "
            f"periodic {list(first.box.periodic)}"
        )
        lines.append(
            f"  columns ({len(first.columns)}), printed significant digits in the first frame "
            "('exact': integers or full precision):"
        )
        for name, values in first.columns.items():
            d = first.digits.get(name)
            lines.append(
                f"    {name:<16} {'exact' if d is None else d:>5}   "
                + (f"{np.min(values):.6g} .. {np.max(values):.6g}" if len(values) else "(no rows)")
            )
    return "\n".join(lines)


class DumpFile(ABC):
    """A dump file: an index of its frames and readers for them.

    Attributes: ``path`` (str), ``kind`` (``'atoms'`` or ``'local'``),
    ``label`` (``'ATOMS'``, ``'ENTRIES'``, ...), ``columns`` (header names of
    the first frame; for binary the names given to :func:`open_dump`),
    ``head_rows`` (the rows the first frame's header announces: read when the
    file is opened, before it is indexed).
    """

    path: str
    kind: str
    label: str
    columns: list[str] | None
    head_rows: int

    def __init__(self, path: Path) -> None:
        self.path = str(path)
        self._entries: list | None = None
        self._damaged: list[DemsplitError] = []

    # -- index
    def _index(self) -> list:
        if self._entries is None:
            self._entries, self._damaged = self._build_index()
        return self._entries

    @abstractmethod
    def _build_index(self) -> tuple[list, list[DemsplitError]]:
        """Index entries of the readable frames, and the errors of the damaged ones."""

    @property
    def n_frames(self) -> int:
        """Number of frames whose header is complete (frames with a damaged
        header are in :attr:`damaged`, and raised by iteration after the last good frame)."""
        return len(self._index())

    @property
    def damaged(self) -> list[DemsplitError]:
        """The error of each frame whose header cannot be read (not in ``steps``).
        A text dump lists every damaged header and indexes the frames after it;
        a binary dump stops at the first (the next header's offset is unknown)."""
        self._index()
        return list(self._damaged)

    @property
    def steps(self) -> np.ndarray:
        """Timestep of each frame (int64)."""
        return np.array([e.step for e in self._index()], dtype=np.int64)

    @property
    def rows(self) -> np.ndarray:
        """Row count of each frame as its header announces it (int64)."""
        return np.array([e.n_rows for e in self._index()], dtype=np.int64)

    @property
    def compression(self) -> str | None:
        """``'gzip'``, ``'bz2'``, ``'xz'`` or None (plain text or binary)."""
        return None

    def __len__(self) -> int:
        return self.n_frames

    # -- reading
    def frame(self, k: int, columns: Sequence[str] | None = None) -> DumpFrame:
        """Frame ``k`` (0-based, negative counts from the end), parsing only that frame."""
        entries = self._index()
        if not -len(entries) <= k < len(entries):
            raise IndexError(f"{self.path}: frame {k} out of range ({len(entries)} frames)")
        return self._read(entries[k], columns, None)

    def frame_at_step(self, step: int, columns: Sequence[str] | None = None) -> DumpFrame:
        """The first frame written at timestep ``step``."""
        hits = np.flatnonzero(self.steps == step)
        if hits.size == 0:
            raise InputFormatError(
                f"no frame at timestep {step}; the dump has {len(self.steps)} frame(s), "
                f"steps {describe_steps(self.steps)}",
                file=self.path,
                step=step,
                fix="pick one of the dumped timesteps",
            )
        return self.frame(int(hits[0]), columns)

    def frames(self, columns: Sequence[str] | None = None) -> Iterator[DumpFrame]:
        """Stream the frames in file order, one in memory at a time; then raise
        the error of the first damaged header, if any."""
        entries = self._index()
        with self._stream() as stream:
            for e in entries:
                yield self._read(e, columns, stream)
        if self._damaged:
            raise self._damaged[0]

    def __iter__(self) -> Iterator[DumpFrame]:
        return self.frames()

    def _stream(self):
        """Context manager: a handle reused across frames by ``frames()``."""
        return open(self.path, "rb")

    @abstractmethod
    def _read(self, entry, columns: Sequence[str] | None, stream: BinaryIO | None) -> DumpFrame:
        """Parse the frame of index ``entry`` (from ``stream`` when streaming)."""

    def _pick(self, names: Sequence[str], columns: Sequence[str] | None, step: int) -> list[int]:
        """Indices of the requested columns in ``names`` (all when None)."""
        if columns is None:
            return list(range(len(names)))
        missing = [c for c in columns if c not in names]
        if missing:
            raise InputFormatError(
                f"no column {missing} in this frame; its columns are {list(names)}",
                file=self.path,
                step=step,
                fix="request columns the dump line writes",
            )
        return [names.index(c) for c in columns]

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.path!r}, kind={self.kind!r}, label={self.label!r})"


# --------------------------------------------------------------------------- text dumps


class TextDump(DumpFile):
    """A text dump (plain or compressed)."""

    def __init__(self, path: Path, opener, head: bytes, columns: Sequence[str] | None) -> None:
        super().__init__(path)
        self._opener = opener
        # blocks of rows parsed so far by the compiled fast path / by its polars fallback (observability)
        self.fast_blocks = 0
        self.fallback_blocks = 0
        first = _parse_header(head[:HEADER_MAX].split(b"\n")[:HEADER_LINES], self.path, 1, last=True)
        self.label = first["label"]
        self.kind = "atoms" if self.label == "ATOMS" else "local"
        self.columns = list(first["names"])
        self.head_rows = first["n"]
        if columns is not None and list(columns) != self.columns:
            raise InputFormatError(
                f"columns {list(columns)} given, but the header names {self.columns}",
                file=self.path,
                line=HEADER_LINES,
                fix="omit columns= for text dumps (the header names them)",
            )

    def _stream(self):
        return (self._opener or open)(self.path, "rb")

    @property
    def compression(self) -> str | None:
        return {gzip.open: "gzip", bz2.open: "bz2", lzma.open: "xz"}.get(self._opener)

    # -- index
    def _build_index(self) -> tuple[list[_TextEntry], list[DemsplitError]]:
        with self._stream() as f:
            markers, headers, lines_before, total, total_newlines, last_byte, checkpoints = _scan(f)
        self._checkpoints = checkpoints
        entries: list[_TextEntry] = []
        damaged: list[DemsplitError] = []
        for i, (pos, head, nl_before) in enumerate(zip(markers, headers, lines_before)):
            last = i == len(markers) - 1
            header_line = nl_before + 1
            hl = head.split(b"\n")
            try:
                if len(hl) <= HEADER_LINES:  # fewer than 9 complete lines before the next frame / EOF
                    raise _header_short(self.path, header_line, len(hl) - 1, last)
                h = _parse_header(hl[:HEADER_LINES], self.path, header_line, last)
            except DemsplitError as err:  # this frame is unreadable; the next marker starts a new one
                damaged.append(err)
                continue
            data_start = pos + sum(len(x) + 1 for x in hl[:HEADER_LINES])
            data_end = markers[i + 1] if not last else total
            end_newlines = lines_before[i + 1] if not last else total_newlines
            n_lines = end_newlines - (nl_before + HEADER_LINES)
            ends_nl = last_byte == b"\n" if last else True
            if data_end > data_start and not ends_nl:
                n_lines += 1
            entries.append(
                _TextEntry(
                    h["step"],
                    h["n"],
                    h["box"],
                    h["label"],
                    h["names"],
                    header_line,
                    data_start,
                    data_end,
                    n_lines,
                    last,
                    ends_nl,
                )
            )
        return entries, damaged

    # -- frames
    def _read(self, e: _TextEntry, columns: Sequence[str] | None, stream: BinaryIO | None) -> DumpFrame:
        idx = self._pick(e.names, columns, e.step)
        self._check_count(e)
        if stream is None:
            with self._stream() as s:
                return self._read(e, columns, s)
        try:  # a forward seek in a compressed stream decompresses only the header
            stream.seek(e.data_start)
        except (*_DECOMPRESSION_ERRORS, OSError):
            raise TruncatedFileError(
                f"the compressed data is damaged before the frame at timestep {e.step} (line {e.header_line})",
                file=self.path,
                step=e.step,
                fix=FIX_TRUNCATED,
            ) from None
        return self._parse(e, stream, idx)

    def _check_count(self, e: _TextEntry) -> None:
        """Header count against the lines the index found."""
        what = f"NUMBER OF {e.label}"
        if e.last and not e.ends_with_newline:
            raise TruncatedFileError(
                f"the file ends in the middle of a row (line {e.first_line + e.n_lines - 1}, row {e.n_lines} "
                f"of the {e.n_rows} the header announces; no newline at the end)",
                file=self.path,
                step=e.step,
                line=e.first_line + e.n_lines - 1,
                fix=FIX_TRUNCATED,
            )
        if e.n_lines == e.n_rows:
            return
        if e.last and e.n_lines < e.n_rows:
            raise TruncatedFileError(
                f"the file ends after {e.n_lines} of the {e.n_rows} rows announced by '{what}' "
                f"(line {e.header_line + 3})",
                file=self.path,
                step=e.step,
                line=e.first_line + e.n_lines,
                fix=FIX_TRUNCATED,
            )
        if e.n_lines > e.n_rows:
            raise InputFormatError(
                f"'{what}' (line {e.header_line + 3}) says {e.n_rows} rows but {e.n_lines} lines follow "
                f"before the next frame; the first extra row is this line",
                file=self.path,
                step=e.step,
                line=e.first_line + e.n_rows,
                fix=FIX_COUNT,
            )
        raise InputFormatError(
            f"'{what}' (line {e.header_line + 3}) says {e.n_rows} rows but only {e.n_lines} lines follow "
            f"before the next 'ITEM: TIMESTEP', which is this line",
            file=self.path,
            step=e.step,
            line=e.first_line + e.n_lines,
            fix=FIX_COUNT,
        )

    def _parse(self, e: _TextEntry, stream: BinaryIO, idx: list[int]) -> DumpFrame:
        """Parse the rows of frame ``e`` (``stream`` is positioned at its first row) into
        preallocated arrays of the requested columns: a plain file in slices read and parsed on
        every core (:meth:`_parse_slices`), a compressed stream block by block (:meth:`_parse_blocks`)."""
        names = [e.names[i] for i in idx]
        if e.n_rows == 0:
            return DumpFrame(
                e.step, 0, e.box, {n: np.empty(0) for n in names}, self.path, e.first_line, {n: None for n in names}
            )
        ncols = len(e.names)
        row = None
        if self._opener is None:
            head = _pread(stream.fileno(), e.data_start, min(DIGITS_SAMPLE, e.data_end - e.data_start))
            cols, trailing, sample, int_like = self._layout(e, idx, head)
            row = self._parse_slices(e, stream.fileno(), cols, trailing)
        if row is None:  # compressed, or a row longer than ROW_MAX
            stream.seek(e.data_start)
            cols, row, sample, int_like = self._parse_blocks(e, stream, idx)
        if row != e.n_rows:  # the file shrank since it was indexed
            raise TruncatedFileError(
                f"the frame ends after {row} of its {e.n_rows} rows: the file changed after it was indexed",
                file=self.path,
                step=e.step,
                line=e.first_line + row,
                fix="read the run once the simulation has finished writing it",
            )
        out = {n: cols.column(i) for n, i in zip(names, idx)}
        for n, i in zip(names, idx):
            bad = ~np.isfinite(out[n]) if out[n].dtype.kind == "f" else None
            if bad is not None and bad.any():
                row = int(np.flatnonzero(bad)[0])
                raise InputFormatError(
                    f"column {i + 1} ('{n}') of row {row + 1} is {out[n][row].item()!r}; expected a finite number",
                    file=self.path,
                    step=e.step,
                    line=e.first_line + row,
                    fix="the simulation produced NaN/inf (unstable run: smaller timestep, check materials); "
                    "dump a frame before it diverged",
                )
        digits = _digits(sample, ncols, idx, out, int_like)
        return DumpFrame(
            e.step, e.n_rows, e.box, out, self.path, e.first_line, {n: digits[i] for n, i in zip(names, idx)}
        )

    def _layout(self, e: _TextEntry, idx: list[int], head: bytes) -> tuple[_Columns, bool, tuple, np.ndarray]:
        """From the first bytes of the frame's rows: the arrays to fill, whether rows end with
        a space, the digits sample and which columns hold integer literals."""
        ncols = len(e.names)
        trailing = head.split(b"\n", 1)[0].endswith(b" ")
        sample = _tokens(head[: head.rfind(b"\n") + 1] or head, ncols)
        int_like = _integer_columns(sample, ncols)
        cols = _Columns(ncols, e.n_rows, [i for i in idx if not int_like[i]], [i for i in idx if int_like[i]])
        return cols, trailing, sample, int_like

    def _parse_blocks(self, e: _TextEntry, stream: BinaryIO, idx: list[int]) -> tuple[_Columns, int, tuple, np.ndarray]:
        """The rows of frame ``e`` from a (compressed) ``stream`` in blocks of about ``BLOCK``
        bytes through one reused buffer, each block parsed on every core (:func:`_parse_fast`):
        (arrays, rows parsed, digits sample, integer-like columns)."""
        ncols = len(e.names)
        cols, sample, int_like = None, None, None
        row = 0
        for block in _blocks(stream, e.data_end - e.data_start):
            if cols is None:
                cols, trailing, sample, int_like = self._layout(e, idx, block[:DIGITS_SAMPLE].tobytes())
            n, converted = _parse_fast(block, ncols, trailing, cols, row, e.n_rows - row)
            if n is None:
                raise self._diagnose(e, block.tobytes(), row, trailing)
            if converted:
                self.fast_blocks += 1
            else:
                self.fallback_blocks += 1
                self._parse_block(e, block.tobytes(), row, n, trailing, cols)
            row += n
        return cols, row, sample, int_like

    def _parse_slices(self, e: _TextEntry, fd: int, cols: _Columns, trailing: bool) -> int | None:
        """The rows of frame ``e`` of the plain file ``fd`` into ``cols``, in slices cut at the
        index's checkpoints, each read (``os.preadv``) and parsed
        (:func:`~demsplit.readers.fastparse.parse_rows`) by one thread of the pool: the copy out of
        the page cache runs on every core with the parse. A slice's first row number is the
        newlines before its checkpoint (from the index), so no slice waits for another. A slice
        with a malformed row is diagnosed, one with a token the compiled parse leaves (``nan``,
        long ``%.17g`` text) is parsed again by polars (:meth:`_parse_block`), after the others.
        Returns the rows parsed, or None when a row is longer than a slice's margin (``ROW_MAX``
        bytes past its end): the caller then parses the whole frame block by block."""
        cuts = _slice_cuts(self._checkpoints, e.data_start, e.data_end, e.first_line - 1, threads.count())
        jobs = [
            (fd, lo, hi, e.data_start, e.data_end, nl - (e.first_line - 1), e.n_rows, trailing, cols)
            for (lo, nl), hi in zip(cuts, [c for c, _ in cuts[1:]] + [e.data_end])
        ]
        results = list(threads.pool().map(lambda job: _parse_slice(*job), jobs))
        if any(status is None for status, *_ in results):
            return None
        row = 0
        for status, row0, n, lo, hi in results:
            if status == SLICE_SHAPE:
                raise self._diagnose(e, _pread(fd, lo, hi - lo), row0, trailing)
            if row0 != row:  # the file changed after it was indexed
                break
            if status == SLICE_OK:
                self.fast_blocks += 1
            else:
                self.fallback_blocks += 1
                self._parse_block(e, _pread(fd, lo, hi - lo), row0, n, trailing, cols)
            row += n
        return row

    def _parse_block(self, e: _TextEntry, block: bytes, row: int, n: int, trailing: bool, cols: _Columns) -> None:
        """polars parse of one block of ``n`` whole, well-formed rows (the fallback of
        the compiled parse) into ``cols`` from ``row`` on; an integer-looking column
        that holds a real here turns every integer column of the frame into float64."""
        import polars as pl  # only here: most blocks take the compiled parse

        for _ in range(2):
            try:
                table = _csv(block, len(e.names) + trailing, cols.dtypes)
                break
            except (pl.exceptions.ComputeError, pl.exceptions.ShapeError, pl.exceptions.SchemaError) as err:
                if not cols.ints.shape[0] or "i64" not in str(err):
                    raise self._diagnose(e, block, row, trailing) from err
                cols.ints_to_float()
        else:
            raise self._diagnose(e, block, row, trailing)
        if table.height != n:
            raise self._diagnose(e, block, row, trailing)
        for i in cols.dtypes:
            cols.column(i)[row : row + n] = table.get_column(f"c{i}").to_numpy()

    def _diagnose(self, e: _TextEntry, text: bytes, row0: int, trailing: bool) -> DemsplitError:
        """Slow pass over one block (starting at row ``row0``) that failed the fast parse: first bad line."""
        ncols = len(e.names)
        for k, raw in enumerate(text.split(b"\n")[: e.n_rows - row0]):
            line = e.first_line + row0 + k
            tokens = raw.split(b" ")
            if trailing and tokens and tokens[-1] == b"":
                tokens = tokens[:-1]
            if raw.endswith(b"\r"):
                return InputFormatError(
                    f"row {row0 + k + 1} ends with a carriage return (CR LF, Windows line ends); LAMMPS writes LF",
                    file=self.path,
                    step=e.step,
                    line=line,
                    fix="convert the file's line ends to LF (dos2unix FILE), or read the run's original dump",
                )
            if b"" in tokens:
                gap = (
                    "starts with a space"
                    if raw.startswith(b" ")
                    else f"has two spaces in a row before value {tokens.index(b'') + 1}"
                )
                return InputFormatError(
                    f"row {row0 + k + 1} {gap}; LAMMPS separates values by one space",
                    file=self.path,
                    step=e.step,
                    line=line,
                    fix="the row was edited or damaged: rewrite the dump, or repair that line",
                )
            if len(tokens) != ncols:
                return InputFormatError(
                    f"row {row0 + k + 1} has {len([t for t in tokens if t])} values, expected {ncols} (one per "
                    f"header name{', then a trailing space' if trailing else ''}, single spaces between)",
                    file=self.path,
                    step=e.step,
                    line=line,
                    fix=FIX_COUNT,
                )
            for c, tok in enumerate(tokens):
                try:
                    float(tok)
                except ValueError:
                    return InputFormatError(
                        f"column {c + 1} ('{e.names[c]}') of row {row0 + k + 1} is "
                        f"'{tok.decode('utf-8', 'replace')}'; expected a number",
                        file=self.path,
                        step=e.step,
                        line=line,
                        fix=FIX_COUNT,
                    )
        return InputFormatError(
            "the rows of this frame could not be parsed",
            file=self.path,
            step=e.step,
            line=e.first_line + row0,
            fix=FIX_COUNT,
        )


def _csv(block: bytes, n_fields: int, dtypes: dict[int, np.dtype]) -> pl.DataFrame:
    """polars (multi-threaded, compiled) parse of whole rows of ``n_fields`` fields: only
    the columns ``dtypes`` names (0-based) are converted, to Int64 or Float64."""
    import polars as pl

    schema = {f"c{k}": pl.String for k in range(n_fields)}
    schema.update({f"c{i}": pl.Int64 if d.kind == "i" else pl.Float64 for i, d in dtypes.items()})
    return pl.read_csv(block, separator=" ", has_header=False, quote_char=None, schema=schema, columns=sorted(dtypes))


def _blocks(stream: BinaryIO, size: int) -> Iterator[np.ndarray]:
    """The next ``size`` bytes of ``stream`` in pieces of about ``BLOCK`` bytes,
    each ending with a whole row, so that a frame never sits in memory as text.

    Each piece is a uint8 array over one reused buffer (the bytes after its
    last newline move to the buffer's front), valid until the next is asked for.
    """
    buf = bytearray(min(BLOCK, size))
    kept = 0
    while size > 0:
        if kept == len(buf):  # a row longer than the buffer
            buf = buf + bytearray(len(buf))
        got = _read_into(stream, memoryview(buf)[kept : kept + min(len(buf) - kept, size)])
        size -= got
        n = kept + got
        end = n if size == 0 or not got else buf.rfind(b"\n", 0, n) + 1
        if end:
            yield np.frombuffer(buf, dtype=np.uint8, count=end)
            buf[: n - end] = buf[end:n]
        kept = n - end
        if not got:
            return


class _Columns:
    """The requested columns of a frame as the compiled parse writes them: the
    float64 ones are the rows of ``reals``, the int64 ones the rows of ``ints``
    (C order, so each column is a contiguous view); per column of the dump,
    ``kind`` is 0 (not read), 1 (real) or 2 (integer) and ``slot`` its row."""

    def __init__(self, ncols: int, n_rows: int, reals: list[int], ints: list[int]) -> None:
        self.kind = np.zeros(ncols, dtype=np.int64)
        self.slot = np.zeros(ncols, dtype=np.int64)
        self.kind[reals], self.kind[ints] = 1, 2
        self.slot[reals], self.slot[ints] = np.arange(len(reals)), np.arange(len(ints))
        self.reals = np.empty((len(reals), n_rows), dtype=np.float64)
        self.ints = np.empty((len(ints), n_rows), dtype=np.int64)

    @property
    def dtypes(self) -> dict[int, np.dtype]:
        """Dtype of each requested column (by its 0-based index in the row)."""
        return {int(i): self.column(int(i)).dtype for i in np.flatnonzero(self.kind)}

    def column(self, i: int) -> np.ndarray:
        return (self.reals if self.kind[i] == 1 else self.ints)[self.slot[i]]

    def ints_to_float(self) -> None:
        """Make every integer column real (the values written so far kept)."""
        ints = np.flatnonzero(self.kind == 2)
        self.slot[ints] += self.reals.shape[0]
        self.kind[ints] = 1
        self.reals = np.concatenate([self.reals, self.ints.astype(np.float64)])
        self.ints = self.ints[:0]


SLICE_OK, SLICE_FALLBACK, SLICE_SHAPE = "ok", "fallback", "shape"  # what _parse_slice found
_thread_buffers = threading.local()


def _slice_cuts(
    checkpoints: np.ndarray, start: int, end: int, newlines_before: int, n_threads: int
) -> list[tuple[int, int]]:
    """Where :meth:`TextDump._parse_slices` cuts the rows in ``[start, end)`` (``newlines_before``
    ``start``): checkpoints (offset, newlines before it) about a quarter of a thread's share apart
    (so that slices of uneven cost still end together), at least ``CHECKPOINT`` and at most
    ``BLOCK`` bytes, the first cut ``start`` itself."""
    target = min(BLOCK, max(CHECKPOINT, (end - start) // (4 * n_threads)))
    inside = checkpoints[(checkpoints[:, 0] > start) & (checkpoints[:, 0] < end)]
    cuts = [(start, newlines_before)]
    for offset, newlines in inside.tolist():
        if offset - cuts[-1][0] >= target:
            cuts.append((offset, newlines))
    return cuts


def _parse_slice(
    fd: int,
    lo: int,
    hi: int,
    data_start: int,
    data_end: int,
    row_base: int,
    n_rows: int,
    trailing: bool,
    cols: _Columns,
) -> tuple[str | None, int, int, int, int]:
    """Read and parse the rows of a frame (bytes ``[data_start, data_end)`` of the file ``fd``) that
    start in ``[lo, hi)``, ``row_base`` being the rows before ``lo``, into ``cols``; run by one thread.

    The slice owns the first row starting at or after ``lo`` up to the first starting at or after
    ``hi`` (the next slice's first), so it reads from ``lo - 1`` (is ``lo`` itself a row start?) to
    ``ROW_MAX`` bytes past ``hi``, into this thread's reused buffer. Returns (status, first row,
    rows, byte range of those rows): ``SLICE_OK`` (every requested token written; the few reals
    outside the compiled fast path converted by ``float``), ``SLICE_FALLBACK`` (well formed, but some
    token left for the general parse), ``SLICE_SHAPE`` (a malformed row), or None when the last row
    runs past the margin.
    """
    from .fastparse import FALLBACK, SHAPE, next_newline, parse_rows

    begin = lo if lo == data_start else lo - 1
    stop = min(hi + ROW_MAX, data_end)
    a = _thread_buffer(stop - begin)
    a = a[: _read_at(fd, a, begin)]  # shorter only when the file shrank since the index
    p = 0 if lo == data_start else next_newline(a, 0)
    row0 = row_base + (0 if lo == data_start or p == 1 else 1)
    q = a.size if hi == data_end else next_newline(a, hi - 1 - begin)
    if q == a.size and stop < data_end and (a.size == 0 or a[-1] != 10):
        return None, row0, 0, begin + p, begin + q
    if p >= q or row0 >= n_rows:
        return SLICE_OK, row0, 0, begin + q, begin + q
    slow = np.empty((_SLOW_MAX, 4), dtype=np.int64)
    status, _, n, n_slow = parse_rows(
        a, p, q, len(cols.kind), trailing, cols.kind, cols.slot, cols.reals, cols.ints, row0, n_rows - row0, slow
    )
    if status == SHAPE:
        return SLICE_SHAPE, row0, n, begin + p, begin + q
    if status == FALLBACK:
        return SLICE_FALLBACK, row0, n, begin + p, begin + q
    for slot, row, t0, t1 in slow[:n_slow].tolist():
        cols.reals[slot, row] = float(a[t0:t1].tobytes())
    return SLICE_OK, row0, n, begin + p, begin + q


def _thread_buffer(n: int) -> np.ndarray:
    """``n`` bytes of this thread's reused read buffer (grown when too small)."""
    buf = getattr(_thread_buffers, "buffer", None)
    if buf is None or buf.size < n:
        buf = _thread_buffers.buffer = np.empty(n, dtype=np.uint8)
    return buf[:n]


def _read_at(fd: int, out: np.ndarray, offset: int) -> int:
    """Fill ``out`` with the bytes of ``fd`` from ``offset`` (``os.preadv``, which releases the GIL);
    bytes read (fewer at the end of the file)."""
    view, total = memoryview(out), 0
    while total < out.size:
        n = os.preadv(fd, [view[total:]], offset + total)
        if not n:
            break
        total += n
    return total


def _pread(fd: int, offset: int, n: int) -> bytes:
    """``n`` bytes of ``fd`` from ``offset`` (fewer at the end of the file)."""
    out = np.empty(n, dtype=np.uint8)
    return out[: _read_at(fd, out, offset)].tobytes()


_SLICE_MIN = 1 << 20  # bytes below which a block is parsed by one thread
_SLOW_MAX = 4096  # reals outside the compiled fast path converted by float() per slice, at most


def _parse_fast(
    a: np.ndarray, ncols: int, trailing: bool, cols: _Columns, row0: int, rows_left: int
) -> tuple[int | None, bool]:
    """Compiled parse (:func:`~demsplit.readers.fastparse.parse_rows`) of the whole
    rows in ``a`` into ``cols`` from row ``row0`` on, in line-aligned slices on
    every core (the same result as one slice). The few reals outside the
    compiled fast path (module docstring of :mod:`~demsplit.readers.fastparse`)
    are converted by Python's ``float``, which is correctly rounded too.

    Returns (rows, converted): ``rows`` is None when a row is malformed;
    ``converted`` is False when some requested token could not be converted
    here (the rows are then well formed, but not every value was written).
    """
    from .fastparse import FALLBACK, SHAPE, count_newlines, next_newline, parse_rows

    n_slices = max(1, min(threads.count(), a.size // _SLICE_MIN))
    cuts = [0] + [next_newline(a, a.size * k // n_slices) for k in range(1, n_slices)] + [a.size]
    rows = [count_newlines(a, lo, hi) for lo, hi in zip(cuts[:-2], cuts[1:-1])]
    rows.append(rows_left - sum(rows))
    first = np.cumsum([0] + rows[:-1]).tolist()
    jobs = [
        (
            a,
            lo,
            hi,
            ncols,
            trailing,
            cols.kind,
            cols.slot,
            cols.reals,
            cols.ints,
            row0 + r,
            m,
            np.empty((_SLOW_MAX, 4), dtype=np.int64),
        )
        for lo, hi, r, m in zip(cuts[:-1], cuts[1:], first, rows)
    ]
    if n_slices == 1:
        results = [parse_rows(*jobs[0])]
    else:
        results = list(threads.pool().map(lambda job: parse_rows(*job), jobs))
    statuses = [status for status, _, _, _ in results]
    if SHAPE in statuses:
        return None, False
    rows_parsed = sum(n for _, _, n, _ in results)
    if FALLBACK in statuses:
        return rows_parsed, False
    for job, (_, _, _, n_slow) in zip(jobs, results):
        for s, r, lo, hi in job[-1][:n_slow].tolist():
            cols.reals[s, r] = float(a[lo:hi].tobytes())
    return rows_parsed, True


def _scan(f: BinaryIO) -> tuple[list[int], list[bytes], list[int], int, int, bytes, np.ndarray]:
    """One pass over a (decompressed) stream, window by window.

    Returns the byte offsets of the ``ITEM: TIMESTEP`` lines, up to
    ``HEADER_MAX`` bytes of text from each (cut at the next marker), the number
    of newlines before each, the total size, the total number of newlines, the
    last byte, and the checkpoints: an (n, 2) int64 array of offsets, one per
    ``CHECKPOINT`` bytes, with the newlines before each (where a frame's rows
    can be cut into slices whose first row number is known: :meth:`TextDump._parse_slices`).
    Newlines are counted and markers found by one compiled pass per
    ``CHECKPOINT`` bytes (:func:`~demsplit.readers.fastparse.scan_chunk`). A
    plain file is read window by window (``CHUNK`` bytes) into each thread's
    buffer, the windows on every core (:func:`_scan_read`); a compressed
    stream through one reused buffer (:func:`_windows`). (The provenance's
    digest of the file is not taken here: :mod:`demsplit.fingerprint` hashes
    the inputs in the background, on idle cores, while the frames are computed.)
    """
    if isinstance(f, (io.BufferedReader, io.FileIO)) and (size := os.fstat(f.fileno()).st_size):
        fd = f.fileno()
        pieces = threads.pool().map(lambda start: _scan_read(fd, start, size), range(0, size, CHUNK))
    else:  # a compressed stream, or an empty file (the buffered path, which reads nothing)
        pieces = (_scan_window(start, window, limit) for start, window, limit in _windows(f))
    markers: list[int] = []
    headers: list[bytes] = []
    lines_before: list[int] = []
    checkpoints: list[np.ndarray] = []
    newlines, total, last_byte = 0, 0, b""
    for found, nl, marks, end, last in pieces:
        for pos, before, head in found:
            markers.append(pos)
            headers.append(head)
            lines_before.append(newlines + before)
        marks[:, 1] += newlines
        checkpoints.append(marks)
        newlines += nl
        total, last_byte = end, last or last_byte
    return (
        markers,
        headers,
        lines_before,
        total,
        newlines,
        last_byte,
        np.concatenate(checkpoints) if checkpoints else np.zeros((0, 2), np.int64),
    )


def _scan_window(start: int, window: np.ndarray, limit: int) -> tuple[list, int, np.ndarray, int, bytes]:
    """The markers of ``window[:limit]`` (``window`` holds the stream from offset ``start``):
    ([(offset, newlines before it in the window, its header text)], newlines in ``window[:limit]``,
    the checkpoints of the window (offset, newlines before it in the window), the offset after
    ``window``, its last byte)."""
    from .fastparse import scan_chunk

    step = max(1, min(CHECKPOINT, limit))
    pos_out = np.empty(step // len(MARKER) + 1, dtype=np.int64)
    nl_out = np.empty_like(pos_out)
    found: list[tuple[int, int, bytes]] = []
    marks = np.zeros((len(range(0, limit, step)), 2), dtype=np.int64)
    newlines = 0
    for k, lo in enumerate(range(0, limit, step)):
        n, nl = scan_chunk(window[lo:], min(step, limit - lo), pos_out, nl_out)
        for pos, before in zip(pos_out[:n].tolist(), nl_out[:n].tolist()):
            head = window[lo + pos : lo + pos + HEADER_MAX].tobytes()
            nxt = head.find(MARKER, 1)
            found.append((start + lo + pos, newlines + before, head if nxt == -1 else head[:nxt]))
        marks[k] = start + lo, newlines
        newlines += nl
    return found, newlines, marks, start + window.size, window[-1:].tobytes()


def _scan_read(fd: int, start: int, size: int) -> tuple[list, int, np.ndarray, int, bytes]:
    """:func:`_scan_window` of the window of a plain file of ``size`` bytes that starts at ``start``
    (``CHUNK`` bytes and ``HEADER_MAX`` more, so that a header starting in it is whole), read with
    ``os.preadv`` into this thread's reused buffer (the one its parses use, :func:`_thread_buffer`).
    Copying the window out of the page cache into memory that stays mapped costs less than mapping
    the window's pages each time (docs/performance.md, "Standing decisions")."""
    window = _thread_buffer(min(start + CHUNK + HEADER_MAX, size) - start)
    window = window[: _read_at(fd, window, start)]  # shorter only when the file shrank since its size was taken
    return _scan_window(start, window, min(CHUNK, size - start, window.size))


def _windows(f: BinaryIO) -> Iterator[tuple[int, np.ndarray, int]]:
    """A compressed stream as ``(offset, window, limit)``, for the index scan:
    ``window`` holds the bytes from ``offset`` on (uint8, valid until the next
    window is asked for); the scan searches ``window[:limit]``, and the window
    reaches ``HEADER_MAX`` bytes past ``limit`` (or to the end) so that a header
    that starts before ``limit`` is whole. Consecutive limits tile the stream.
    One reused buffer of ``HEADER_MAX + CHUNK`` bytes, the last ``HEADER_MAX``
    bytes of each window moving to the front for the next.
    """
    buf = bytearray(HEADER_MAX + CHUNK)
    kept, limit, start = 0, 0, 0
    while True:
        buf[:kept] = buf[limit : limit + kept]
        got = _read_into(f, memoryview(buf)[kept:])
        size = kept + got
        limit = size if got == 0 else max(size - HEADER_MAX, 0)
        yield start, np.frombuffer(buf, dtype=np.uint8, count=size), limit
        if got == 0:
            return
        kept, start = size - limit, start + limit


def _read_into(f: BinaryIO, view: memoryview) -> int:
    """Fill ``view`` from ``f`` as far as the stream goes; bytes read (0 at the end).

    A compressed stream ends where its data is damaged or cut (what a killed
    simulation leaves): the dump then reads like a cut text file, whose last
    frame is short, and the frames before it stay readable.
    """
    total = 0
    # a decompressor loses what it decoded in the call that fails: small calls lose at most one step
    step = DECOMPRESSED_STEP if isinstance(f, (gzip.GzipFile, bz2.BZ2File, lzma.LZMAFile)) else len(view)
    while total < len(view):
        try:
            n = f.readinto(view[total : total + step])
        except _DECOMPRESSION_ERRORS:
            break
        except OSError:  # bz2 says "Invalid data stream" with a plain OSError
            if not isinstance(f, bz2.BZ2File):
                raise
            break
        if not n:
            break
        total += n
    return total


_DECOMPRESSION_ERRORS = (EOFError, zlib.error, lzma.LZMAError, gzip.BadGzipFile)
"""What gzip, zlib and xz raise on a damaged or cut stream."""
DECOMPRESSED_STEP = 1 << 16
"""Bytes asked of a decompressor per call (64 KiB): what a damaged stream can lose before its damage."""


def _header_short(path: str, header_line: int, n_complete: int, last: bool) -> DemsplitError:
    msg = (
        f"the frame header starting at line {header_line} has {n_complete} complete lines, expected "
        f"{HEADER_LINES} (TIMESTEP, step, NUMBER OF, count, BOX BOUNDS, 3 bounds, the column names)"
    )
    if last:
        return TruncatedFileError(
            msg + " before the end of the file", file=path, line=header_line + n_complete, fix=FIX_TRUNCATED
        )
    return InputFormatError(msg, file=path, line=header_line + n_complete, fix=FIX_COUNT)


def _parse_header(lines: list[bytes], path: str, line0: int, last: bool) -> dict:
    """Parse the 9 header lines of a frame (``line0`` = line of 'ITEM: TIMESTEP')."""
    if len(lines) < HEADER_LINES:
        raise _header_short(path, line0, len(lines), last)
    text = [x.decode("utf-8", "replace").rstrip("\r") for x in lines]

    def bad(k: int, expected: str, step: int | None = None) -> InputFormatError:
        return InputFormatError(
            f"expected {expected}, found '{text[k][:120]}'",
            file=path,
            step=step,
            line=line0 + k,
            fix="the frame header is damaged; rewrite the dump",
        )

    if text[0].strip() != "ITEM: TIMESTEP":
        raise bad(0, "'ITEM: TIMESTEP'")
    try:
        step = int(text[1])
    except ValueError:
        raise bad(1, "an integer timestep") from None
    if not 0 <= step < 2**63:  # LAMMPS' bigint; beyond it the store's int64 steps overflow
        raise bad(1, "a timestep in [0, 2^63)")
    if not text[2].startswith("ITEM: NUMBER OF "):
        raise bad(2, "'ITEM: NUMBER OF <label>'", step)
    try:
        n = int(text[3])
    except ValueError:
        raise bad(3, "an integer row count", step) from None
    if n < 0:
        raise bad(3, "a row count >= 0", step)
    if not text[4].startswith("ITEM: BOX BOUNDS"):
        raise bad(4, "'ITEM: BOX BOUNDS [xy xz yz] <flags>'", step)
    flags = text[4][len("ITEM: BOX BOUNDS") :].split()
    triclinic = flags[:3] == ["xy", "xz", "yz"]
    flags = flags[3:] if triclinic else flags
    if flags and (len(flags) != 3 or any(len(f) != 2 or set(f) - set("pfsm") for f in flags)):
        raise bad(4, "three boundary flags such as 'pp pp ff'", step)
    try:
        b = np.array([[float(v) for v in text[5 + a].split()] for a in range(3)], dtype=np.float64)
        if b.shape != (3, 3 if triclinic else 2):
            raise ValueError
    except ValueError:
        raise bad(5, f"three lines of {3 if triclinic else 2} box numbers", step) from None
    if not text[8].startswith("ITEM: "):
        raise bad(8, "'ITEM: <label> <column names>'", step)
    words = text[8][len("ITEM: ") :].split()
    label, names = words[0], tuple(words[1:])
    if text[2][len("ITEM: NUMBER OF ") :].strip() != label:
        raise bad(8, f"'ITEM: {text[2][len('ITEM: NUMBER OF ') :].strip()} ...' to match line {line0 + 2}", step)
    if not names:
        raise bad(8, "column names after the label", step)
    periodic = tuple(f == "pp" for f in flags) if flags else (False, False, False)
    return {
        "step": step,
        "n": n,
        "label": label,
        "names": names,
        "box": _box(b[:, 0], b[:, 1], periodic, b[:, 2] if triclinic else None),
    }


def _box(lo_bound: np.ndarray, hi_bound: np.ndarray, periodic, tilt: np.ndarray | None) -> Box:
    """Box from dumped bounds. A triclinic dump writes the bounding box
    (``xlo_bound`` ...) and ``xy xz yz``; LAMMPS (``dump`` docs, "triclinic")
    recovers the box as xlo = xlo_bound - min(0, xy, xz, xy+xz),
    xhi = xhi_bound - max(0, xy, xz, xy+xz), ylo = ylo_bound - min(0, yz),
    yhi = yhi_bound - max(0, yz), z unchanged."""
    if tilt is None:
        return Box(lo_bound, hi_bound, periodic)
    xy, xz, yz = tilt
    lo = lo_bound - np.array([min(0.0, xy, xz, xy + xz), min(0.0, yz), 0.0])
    hi = hi_bound - np.array([max(0.0, xy, xz, xy + xz), max(0.0, yz), 0.0])
    return Box(lo, hi, periodic, tilt)


def _tokens(sample: bytes, ncols: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Byte-level view of whole rows: the bytes, per byte its token number (-1
    on separators), and per token its column (``ncols`` for stray extra
    tokens). Vectorised; ``sample`` holds whole lines."""
    a = np.frombuffer(sample, dtype=np.uint8)
    sep = (a == 32) | (a == 10) | (a == 13) | (a == 9)
    start = ~sep & np.concatenate(([True], sep[:-1]))
    tok = np.cumsum(start, dtype=np.int64) - 1
    tok[sep] = -1
    line_of_tok = np.cumsum(a == 10)[start] if start.any() else np.empty(0, np.int64)
    first_tok_of_line = np.searchsorted(line_of_tok, line_of_tok, side="left")
    col = np.arange(line_of_tok.size) - first_tok_of_line
    return a, tok, np.minimum(col, ncols)


def _integer_columns(sample: tuple[np.ndarray, np.ndarray, np.ndarray], ncols: int) -> np.ndarray:
    """Per column: True when every sampled token (``_tokens`` of whole rows) is
    an integer literal (digits with an optional sign): it can be read as int64."""
    a, tok, col = sample
    inside = tok >= 0
    is_digit = (a >= 48) & (a <= 57)
    non_int = inside & ~is_digit & (a != 45) & (a != 43)
    tok_non_int = np.bincount(tok[non_int], minlength=col.size) > 0
    col_non_int = np.bincount(col, weights=tok_non_int.astype(np.float64), minlength=ncols + 1)[:ncols] > 0
    present = np.bincount(col, minlength=ncols + 1)[:ncols] > 0
    return present & ~col_non_int


def _digits(
    sample: tuple[np.ndarray, np.ndarray, np.ndarray],
    ncols: int,
    idx: list[int],
    cols: dict[str, np.ndarray],
    int_like: np.ndarray,
) -> dict[int, int | None]:
    """Printed significant digits of the requested columns (module docstring)."""
    a, tok, col = sample
    inside = tok >= 0
    is_digit = (a >= 48) & (a <= 57)
    is_exp = inside & ((a == 101) | (a == 69))
    ntok = col.size
    # per byte: has this token seen an exponent marker / a nonzero digit up to here?
    first_byte = np.concatenate(([0], np.flatnonzero(np.diff(tok) != 0) + 1))

    def seen(mask: np.ndarray) -> np.ndarray:
        c = np.cumsum(mask)
        base = np.repeat(c[first_byte] - mask[first_byte], np.diff(np.append(first_byte, a.size)))
        return c - base > 0

    significant = inside & is_digit & ~seen(is_exp) & seen(inside & (a >= 49) & (a <= 57))
    per_tok = np.bincount(tok[significant], minlength=ntok)
    observed = np.zeros(ncols + 1, dtype=np.int64)
    np.maximum.at(observed, col, per_tok)
    real = ~int_like
    precision = int(observed[:ncols][real].max()) if real.any() else 0
    out: dict[int, int | None] = {}
    for (_name, values), i in zip(cols.items(), idx):
        if values.dtype.kind in "iu":
            out[i] = None
        elif np.unique(values[: max(1, int(np.count_nonzero(col == i)))]).size <= LOW_VARIETY:
            out[i] = max(int(observed[i]), precision)
        else:
            out[i] = int(observed[i])
    return out


# --------------------------------------------------------------------------- binary dumps

_BIN_HEAD = struct.Struct("=qqi6i")  # step, n, triclinic, boundary[6]


class BinaryDump(DumpFile):
    """A LAMMPS binary ``dump custom`` file (native byte order, no names)."""

    def __init__(self, path: Path, columns: Sequence[str] | None) -> None:
        super().__init__(path)
        self.kind, self.label = "atoms", "ATOMS"
        self._given = list(columns) if columns is not None else None
        with open(path, "rb") as f:
            entry, _ = self._header(f, 0, _file_size(path))
        if self._given is not None and len(self._given) != entry.n_cols:
            raise InputFormatError(
                f"{len(self._given)} column names given but the binary frame has {entry.n_cols} columns",
                file=path,
                step=entry.step,
                fix="pass one name per keyword of the dump custom line, in order",
            )
        self.columns = self._given or [f"col{k + 1}" for k in range(entry.n_cols)]
        self.head_rows = entry.n_rows

    def _header(self, f: BinaryIO, offset: int, size: int) -> tuple[_BinaryEntry, int]:
        """Parse the frame header at ``offset``; return it and the next frame's offset."""
        f.seek(offset)
        raw = f.read(_BIN_HEAD.size)

        def fail(what: str, step: int | None = None, truncated: bool = False) -> DemsplitError:
            cls = TruncatedFileError if truncated else InputFormatError
            return cls(
                f"binary frame at byte {offset}: {what}",
                file=self.path,
                step=step,
                fix=FIX_TRUNCATED
                if truncated
                else "this is not a LAMMPS binary dump custom file (or not in this machine's byte order)",
            )

        if len(raw) < _BIN_HEAD.size:
            raise fail(f"file ends inside the header ({len(raw)} of {_BIN_HEAD.size} bytes)", truncated=True)
        step, n, tri, *bnd = _BIN_HEAD.unpack(raw)
        if step < 0:
            raise fail(
                f"timestep {step} < 0 (newer LAMMPS binary dumps start with a magic string; "
                "only the LIGGGHTS/old LAMMPS layout is supported)"
            )
        if tri not in (0, 1) or any(b not in _BOUNDARY for b in bnd) or n < 0:
            raise fail(
                f"expected triclinic flag 0/1, boundary codes 0-3 and rows >= 0, found "
                f"triclinic={tri}, boundary={bnd}, rows={n}",
                step,
            )
        nb = 9 if tri else 6
        raw = f.read(8 * nb + 8)
        if len(raw) < 8 * nb + 8:
            raise fail("file ends inside the header", step, truncated=True)
        bounds = np.frombuffer(raw, dtype="=f8", count=nb)
        ncols, nchunk = struct.unpack_from("=ii", raw, 8 * nb)
        if ncols <= 0 or nchunk < 0:
            raise fail(f"expected columns > 0 and chunks >= 0, found {ncols} and {nchunk}", step)
        pos = offset + _BIN_HEAD.size + 8 * nb + 8
        chunks, total = [], 0
        for _ in range(nchunk):  # one chunk per MPI rank that wrote
            f.seek(pos)
            raw = f.read(4)
            if len(raw) < 4:
                raise fail("file ends before a chunk size", step, truncated=True)
            (m,) = struct.unpack("=i", raw)
            if m < 0:
                raise fail(f"chunk of {m} values", step)
            chunks.append((pos + 4, m))
            pos += 4 + 8 * m
            total += m
        if pos > size:
            raise fail(f"file ends inside the rows ({size} bytes, frame needs {pos})", step, truncated=True)
        if total != n * ncols:
            raise fail(f"chunks hold {total} values, expected rows x columns = {n} x {ncols}", step)
        periodic = (bnd[0] == 0, bnd[2] == 0, bnd[4] == 0)
        lo, hi = bounds[0:6:2], bounds[1:6:2]
        box = _box(lo, hi, periodic, bounds[6:9] if tri else None)
        return _BinaryEntry(step, n, box, ncols, tuple(chunks)), pos

    def _build_index(self) -> tuple[list[_BinaryEntry], list[DemsplitError]]:
        size = _file_size(self.path)
        entries, pos = [], 0
        with open(self.path, "rb") as f:
            while pos < size:
                try:
                    e, pos = self._header(f, pos, size)
                except DemsplitError as err:
                    return entries, [err]
                entries.append(e)
        return entries, []

    def _read(self, e: _BinaryEntry, columns: Sequence[str] | None, stream: BinaryIO | None) -> DumpFrame:
        names = self.columns if e.n_cols == len(self.columns) else [f"col{k + 1}" for k in range(e.n_cols)]
        idx = self._pick(names, columns, e.step)
        if stream is None:
            with open(self.path, "rb") as f:
                return self._read(e, columns, f)
        parts = []
        for off, m in e.chunks:
            stream.seek(off)
            parts.append(np.frombuffer(stream.read(8 * m), dtype="=f8"))
        rows = (np.concatenate(parts) if parts else np.empty(0)).reshape(e.n_rows, e.n_cols)
        cols = {names[i]: np.ascontiguousarray(rows[:, i]) for i in idx}
        return DumpFrame(e.step, e.n_rows, e.box, cols, self.path, None, {names[i]: None for i in idx})


def _file_size(path: str | Path) -> int:
    return Path(path).stat().st_size
