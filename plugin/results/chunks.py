"""How the store's columns are cut into chunks and compressed.

Compression (``compression="auto"``, the default): each dataset is gzip (level :data:`GZIP_LEVEL`, with
shuffle) when its first chunk compresses to at most :data:`AUTO_MAX_RATIO` of its size, else stored without
filter; the choice is the dataset's HDF5 filter pipeline, which every HDF5 reader decodes. The deflate
streams are made by ISA-L (``isal``), for its speed; they are standard zlib streams, which any inflate
decodes. :class:`TableSink` writes a table's whole chunks with ``write_direct_chunk``, compressed on the
process's thread pool (docs/performance.md, "Standing decisions").
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import Executor

import numpy as np
from isal import isal_zlib

from .schema import UNITS, Table

COMPRESSIONS = ("auto", "gzip", "lzf", "none")
"""``auto``: gzip for the columns that compress, none for the others (below);
``gzip``: every column gzip + shuffle; ``lzf``: every column lzf + shuffle
(h5py's filter, not in every HDF5 reader); ``none``: no filter."""
COMPRESSION = "auto"
GZIP_LEVEL = 1
"""Deflate level of the gzip filter: a higher level shrinks the columns gzip is
kept for only a little more, at a fraction of the speed (docs/performance.md, "Standing decisions")."""
AUTO_MAX_RATIO = 0.5
"""``auto`` gzips a column when its first chunk, shuffled and deflated, is at
most this fraction of its raw size: below it deflating costs less than writing
the bytes it saves; integer columns and shares fall far below it, energies and
overlaps (full-mantissa floats) far above (docs/performance.md, "Standing
decisions"). A table without rows in its first
frame is decided by dtype: integers gzip, reals none."""
CHUNK_ROWS = 65536
"""Rows per HDF5 chunk (512 KiB of float64 before compression), at most: a
table whose first frame is smaller gets smaller chunks (:func:`chunk_rows`)."""
MIN_CHUNK_ROWS = 1024
"""Rows per chunk, at least (8 KiB of float64)."""


class TableSink:
    """Streams one table's rows into resizable chunked datasets, whole chunks at a time.

    Each column's chunks are written with ``write_direct_chunk``: as they are
    (no filter), or shuffled and deflated here rather than by HDF5 (gzip;
    lzf, h5py's own filter, is left to HDF5): the shuffle filter is a byte
    transpose and deflate is ``isal_zlib.compress``, which releases the GIL,
    so the thread pool compresses a column's chunks on every core. The
    datasets carry the same filters as an ordinary h5py dataset, so every
    HDF5 reader decodes them as usual. Rows that do not fill a chunk are
    carried (a copy, less than one chunk per column) to the next frame and
    kept in the commit record; :meth:`finish` writes the last, partial chunk
    (zero-padded, outside the dataset's shape). ``written``: rows in the file. ``on_written()`` is
    called after each column's chunks are written (the writer's write-back, :class:`ResultWriter`).
    """

    def __init__(
        self,
        h5,
        name: str,
        schema: dict[str, str],
        filters: dict[str, str],
        chunk_rows: int,
        pool: Executor,
        on_written: Callable[[], None],
    ) -> None:
        self.name, self.schema, self.filters, self.pool = name, schema, filters, pool
        self.on_written = on_written
        self.chunk_rows = chunk_rows
        self.group = h5.create_group(name)
        self.group.attrs["columns"] = json.dumps(list(schema))
        self.group.attrs["units"] = json.dumps({c: UNITS.get(c, "") for c in schema})
        self.datasets = {col: self._create(col) for col in schema}
        self.carry = {col: np.empty(0, np.dtype(dtype)) for col, dtype in schema.items()}
        self.written = 0

    def _create(self, col: str):
        """The empty, resizable dataset of ``col`` with its chosen filter."""
        kind = self.filters[col]
        ds = self.group.create_dataset(
            col,
            shape=(0,),
            maxshape=(None,),
            dtype=np.dtype(self.schema[col]),
            chunks=(self.chunk_rows,),
            compression=None if kind == "none" else kind,
            compression_opts=GZIP_LEVEL if kind == "gzip" else None,
            shuffle=kind != "none",
        )
        ds.attrs["unit"] = UNITS.get(col, "")
        return ds

    def append(self, table: Mapping[str, np.ndarray] | None) -> int:
        """Write the whole chunks that ``table`` (one frame) completes and return its row count. The
        chunks of every gzip column go to the pool first, so that the columns stored as they are get
        written while the pool compresses; each column's blobs are then written in order as they come."""
        if not table or not self.schema:
            return 0
        n = len(next(iter(table.values())))
        chunks = {}
        for col in self.schema:
            chunks[col], self.carry[col] = _whole_chunks(self.carry[col], table[col], self.chunk_rows)
        blobs = {col: self._compressed(chunks[col]) for col in self.schema if self.filters[col] == "gzip"}
        for col in self.schema:
            if col not in blobs:
                self._write(col, chunks[col])
        for col, compressed in blobs.items():
            self._write(col, chunks[col], compressed)
        self.written = self.datasets[next(iter(self.schema))].shape[0]
        return n

    def adopt(self, group, written: int, carry: dict[str, np.ndarray]) -> None:
        """Take over an interrupted run's table: its first ``written`` rows
        (whole chunks of ``group``, copied as stored) and its carried rows."""
        for col, ds in self.datasets.items():
            src = group[col]
            if src.shape[0] < written or written % self.chunk_rows:
                raise ValueError(f"{self.name}/{col} holds {src.shape[0]} rows, the commit record {written}")
            ds.resize((written,))
            for start in range(0, written, self.chunk_rows):
                mask, blob = src.id.read_direct_chunk((start,))
                ds.id.write_direct_chunk((start,), blob, mask)
        self.carry.update(carry)
        self.written = written

    def finish(self) -> None:
        """Write the carried rows (each column's last, partial chunk)."""
        for col, rows in self.carry.items():
            self._write(col, [rows] if len(rows) else [])
            self.carry[col] = rows[:0]

    def _compressed(self, chunks: list[np.ndarray]) -> Iterator[bytes]:
        """The chunks (padded) shuffled and deflated on the pool, every one submitted now; in order."""
        return self.pool.map(_shuffle_deflate, [_padded(c, self.chunk_rows) for c in chunks])

    def _write(self, col: str, chunks: list[np.ndarray], blobs: Iterable[bytes] | None = None) -> None:
        """Append the chunks of one column (all whole but possibly the table's last one); ``blobs``:
        their compressed bytes when already asked of the pool (:meth:`_compressed`)."""
        if not chunks:
            return
        ds = self.datasets[col]
        start = ds.shape[0]
        ds.resize((start + sum(len(c) for c in chunks),))  # the rows, not the padding: it never shrinks
        if self.filters[col] == "lzf":  # h5py's own filter: HDF5 applies it to the chunk-aligned slices
            for k, c in enumerate(chunks):
                ds[start + k * self.chunk_rows : start + k * self.chunk_rows + len(c)] = c
        else:
            if blobs is None:
                blobs = (
                    self._compressed(chunks)
                    if self.filters[col] == "gzip"
                    else (_padded(c, self.chunk_rows) for c in chunks)
                )
            for k, blob in enumerate(blobs):
                ds.id.write_direct_chunk((start + k * self.chunk_rows,), blob)
        self.on_written()


def choose_filters(tables: Mapping[str, Table], compression: str, pool: Executor) -> dict[str, dict[str, str]]:
    """Each column's filter: ``compression`` itself, or for ``auto`` the choice
    of :func:`_choose_filter` on the column's first chunk of rows (measured in
    the thread pool), by dtype when the table has no rows."""
    if compression != "auto":
        return {name: dict.fromkeys(table, compression) for name, table in tables.items()}
    chosen = {}
    for name, table in tables.items():
        firsts = [np.asarray(v)[:CHUNK_ROWS] for v in table.values()]
        chosen[name] = dict(zip(table, pool.map(_choose_filter, firsts)))
    return chosen


def chunk_rows(first_rows: int) -> int:
    """Rows per chunk of a table whose first frame has ``first_rows`` rows: the
    power of two that holds them, within [MIN_CHUNK_ROWS, CHUNK_ROWS], so that
    a small run is not stored as mostly padding (its last chunk is padded to
    a whole chunk) and a large one in chunks of CHUNK_ROWS."""
    return min(CHUNK_ROWS, max(MIN_CHUNK_ROWS, 1 << max(first_rows - 1, 0).bit_length()))


def _whole_chunks(carry: np.ndarray, values: np.ndarray, size: int) -> tuple[list[np.ndarray], np.ndarray]:
    """Split ``carry`` + ``values`` into whole chunks of ``size`` rows (the first
    one joins the carried rows, the others are views of ``values``) and the
    rows left over (a copy, so that ``values`` can be released)."""
    chunks = []
    if len(carry):
        fill = size - len(carry)
        carry = np.concatenate([carry, values[:fill]])
        if len(carry) < size:
            return [], carry
        chunks.append(carry)
        values = values[fill:]
    whole = len(values) // size * size
    chunks.extend(values[k : k + size] for k in range(0, whole, size))
    return chunks, np.array(values[whole:])


def _choose_filter(first: np.ndarray) -> str:
    """``auto``'s choice for a column from its first chunk: ``"gzip"`` when
    shuffle + deflate (level GZIP_LEVEL) shrinks it to at most AUTO_MAX_RATIO
    of its size, else ``"none"``; for a column without rows, ``"gzip"`` for
    integers and ``"none"`` for reals."""
    if not len(first):
        return "gzip" if first.dtype.kind in "iub" else "none"
    deflated = len(isal_zlib.compress(_shuffled(first), GZIP_LEVEL))
    return "gzip" if deflated <= AUTO_MAX_RATIO * first.nbytes else "none"


def _padded(values: np.ndarray, size: int) -> np.ndarray:
    """A chunk's values, zero-padded to ``size`` rows (the bytes HDF5 stores for a chunk)."""
    if len(values) == size:
        return np.ascontiguousarray(values)
    return np.concatenate([values, np.zeros(size - len(values), values.dtype)])


def _shuffled(values: np.ndarray) -> bytes:
    """HDF5's shuffle filter: the values' bytes grouped by byte position."""
    return np.ascontiguousarray(values).view(np.uint8).reshape(len(values), values.itemsize).T.tobytes()


def _shuffle_deflate(chunk: np.ndarray) -> bytes:
    """One (padded) chunk as HDF5's shuffle + deflate filters store it."""
    return isal_zlib.compress(_shuffled(chunk), GZIP_LEVEL)
