"""The result store: one HDF5 file per run, written atomically and resumably.

Layout (see docs/store.md)::

    /                 attrs: format, format_version, demsplit_version,
                             provenance (JSON), walls_meta (JSON)
    /particles/<col>  one 1-D dataset per column, chunked, compressed, resizable
    /contacts/<col>   (group attrs: columns (JSON list, stored order), units (JSON))
    /walls/<col>
    /frames/<col>     one row per frame
    /index/step       (n_frames,) timestep of frame k
    /index/<table>    (n_frames + 1,) row offset of frame k in <table>:
                      frame k is rows offsets[k]:offsets[k+1]

Writing (:class:`ResultWriter`): each appended frame goes to its own part,
``.OUT.h5.parts/frame_<seq>_<step>.npys`` next to the target: the columns as
consecutive raw ``.npy`` records, written under a temporary name and renamed,
so a run killed at any moment leaves only complete parts. :meth:`ResultWriter.close`
memory-maps the parts' columns, in step order, copies them into ``OUT.h5.tmp``
a whole chunk at a time and renames it to ``OUT.h5``; only then are the parts
removed. Nothing exists at ``OUT.h5`` until it is complete. With
``resume=True`` the parts of an interrupted run are kept when its provenance
(input checksums, options, scene, demsplit version) is the same.

Compression (``compression="auto"``, the default): each dataset is gzip
(level :data:`GZIP_LEVEL`, with shuffle) when its first chunk compresses to at
most :data:`AUTO_MAX_RATIO` of its size, else stored without filter; the
choice is the dataset's HDF5 filter pipeline, which every HDF5 reader decodes.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import zlib
from collections.abc import Iterable, Mapping
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .fingerprint import file_fingerprint  # noqa: F401  (part of this module's API)
from .errors import StoreError
from .scene import scene_to_dict
from .results import TABLES, UNITS, Results, Table, canonical_table, to_dataframe

FORMAT = "demsplit-results"
FORMAT_VERSION = 1
COMPRESSIONS = ("auto", "gzip", "lzf", "none")
"""``auto``: gzip for the columns that compress, none for the others (below);
``gzip``: every column gzip + shuffle; ``lzf``: every column lzf + shuffle
(h5py's filter, not in every HDF5 reader); ``none``: no filter."""
COMPRESSION = "auto"
GZIP_LEVEL = 1
"""zlib level of the gzip filter: on real results level 4 shrinks the columns
gzip is kept for only a little more, at half the speed (docs/store.md)."""
AUTO_MAX_RATIO = 0.5
"""``auto`` gzips a column when its first chunk, shuffled and deflated, is at
most this fraction of its raw size (measured, docs/store.md: integer columns
and shares 0.004-0.2, contact points 0.3-0.6, energies and overlaps 0.83-0.89)."""
CHUNK_ROWS = 65536
"""Rows per HDF5 chunk (512 KiB of float64 before compression)."""
PARTS_VERSION = 2
"""Layout of the parts (2: one file of .npy records per frame; 1 was one
.npz per frame). Parts of another layout are not resumed."""

RESUME_KEYS = ("inputs", "options", "scene", "model", "demsplit_version")
"""Provenance entries that must be equal for parts to be resumed; ``inputs``
is compared by the sha256 of each input file."""

_PART = re.compile(r"^frame_(\d+)_(-?\d+)\.npys$")
_MANIFEST = "run.json"
_LOCK = "lock"


def demsplit_version() -> str:
    """The installed demsplit version ("unknown" when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("demsplit")
    except PackageNotFoundError:
        return "unknown"


def build_provenance(inputs: Iterable[str | Path], *, scene=None, options: dict | None = None, **extra) -> dict:
    """A provenance dict: ``inputs`` (fingerprints), ``scene`` (materials per type,
    walls) and ``model`` (contact model) from a :class:`demsplit.scene.Scene`,
    ``options``, ``demsplit_version``, plus any ``extra`` entries (e.g.
    ``overlap_source``, ``skipped``, ``bad_frames``). Must be JSON-serialisable."""
    prov: dict = {"inputs": [file_fingerprint(p) for p in inputs], "options": dict(options or {}),
                  "demsplit_version": demsplit_version()}
    if scene is not None:
        prov["scene"] = scene_to_dict(scene)
        prov["model"] = prov["scene"].pop("model")
    prov.update(extra)
    _to_json(prov, "provenance")
    return prov


def resume_identity(provenance: Mapping) -> dict:
    """What must not change between an interrupted run and its resumption."""
    ident = {key: provenance.get(key) for key in RESUME_KEYS}
    ident["inputs"] = sorted(str(f.get("sha256")) for f in provenance.get("inputs") or [])
    return json.loads(_to_json(ident, "provenance"))


def _to_json(obj, what: str) -> str:
    try:
        return json.dumps(obj, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise StoreError(f"the {what} is not JSON-serialisable: {exc}.",
                         fix=f"put only str, numbers, lists and dicts in the {what}.") from exc


def _write_atomic(path: Path, write, *, durable: bool = True) -> None:
    """Call ``write(file)`` on a temporary file renamed to ``path`` when complete
    (fsynced first unless ``durable=False``, see :func:`~demsplit.atomic.atomic_path`)."""
    with atomic_path(path, durable=durable) as tmp, open(tmp, "wb") as f:
        write(f)


class ResultWriter:
    """Write the per-frame result tables of one run to an HDF5 store.

    >>> with ResultWriter("out.h5", provenance) as w:    # doctest: +SKIP
    ...     for tables in frames:
    ...         if step_of(tables) not in w.done_steps:
    ...             w.append(tables)

    ``append`` takes ``{"particles": {...}, "contacts": {...}, "walls": {...},
    "frames": {...}}`` for one frame (``frames`` with exactly one row; an absent
    table counts as empty). Leaving the ``with`` block by an exception keeps the
    parts and writes no store. Entries added to ``writer.provenance`` before
    ``close()`` (skipped frames, notes) are stored. ``compression`` is one of
    :data:`COMPRESSIONS` (``None`` means ``"none"``).
    """

    def __init__(self, path: str | Path, provenance: Mapping, *, resume: bool = False,
                 walls_meta: list[dict] | None = None, compression: str | None = COMPRESSION) -> None:
        self.path = Path(path)
        self.provenance = dict(provenance)
        self.walls_meta = list(walls_meta or [])
        self.compression = "none" if compression is None else compression
        if self.compression not in COMPRESSIONS:
            raise StoreError(f"unknown compression {compression!r}; expected one of {list(COMPRESSIONS)}.",
                             file=self.path, fix="pick one of " + ", ".join(COMPRESSIONS) + ".")
        self.parts_dir = self.path.parent / f".{self.path.name}.parts"
        self._schema: dict[str, dict[str, str]] | None = None
        self._parts: dict[int, tuple[int, Path]] = {}  # step -> (seq, part file)
        self._closed = False
        if not self.path.parent.is_dir():
            raise StoreError("the output directory does not exist.", file=self.path.parent,
                             fix="create it, or choose another output path.")
        manifest = {"format": FORMAT, "format_version": FORMAT_VERSION, "parts_version": PARTS_VERSION,
                    "identity": resume_identity(self.provenance), "provenance": self.provenance,
                    "walls_meta": self.walls_meta}
        if self.parts_dir.exists():
            if not resume:
                raise StoreError(
                    f"an interrupted run left its finished frames in {self.parts_dir}.", file=self.path,
                    fix=f"resume it (resume=True, demsplit run --resume), or delete {self.parts_dir} to start over.",
                )
            self._lock()
            try:
                self._adopt_parts(manifest)
            except StoreError:
                (self.parts_dir / _LOCK).unlink(missing_ok=True)
                raise
        else:
            self.parts_dir.mkdir()
            self._lock()
        _write_atomic(self.parts_dir / _MANIFEST, lambda f: f.write(_to_json(manifest, "provenance").encode()))

    # -- lifecycle -------------------------------------------------------
    def _lock(self) -> None:
        lock = self.parts_dir / _LOCK
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            try:
                pid = int(lock.read_text() or "0")
            except (OSError, ValueError):
                pid = 0
            if pid > 0 and _alive(pid):
                raise StoreError(f"another demsplit process (pid {pid}) is writing this store.", file=self.path,
                                 fix="wait for it to finish, or write to another path.") from None
            lock.unlink(missing_ok=True)
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        with os.fdopen(fd, "w") as f:
            f.write(str(os.getpid()))

    def _adopt_parts(self, manifest: dict) -> None:
        try:
            old = json.loads((self.parts_dir / _MANIFEST).read_text())
        except (OSError, ValueError):
            old = None
        if old is None or [old.get(k) for k in ("format", "format_version", "parts_version")] != \
                [FORMAT, FORMAT_VERSION, PARTS_VERSION]:
            raise StoreError(f"{self.parts_dir} holds no readable run manifest of this demsplit version.",
                             file=self.path, fix=f"delete {self.parts_dir} and run again without resume.")
        if old["identity"] != manifest["identity"]:
            diff = [k for k in manifest["identity"] if manifest["identity"][k] != old["identity"].get(k)]
            raise StoreError(
                f"cannot resume: the interrupted run had different {', '.join(diff)} "
                f"(input files are compared by sha256).",
                file=self.path,
                fix=f"rerun with the same inputs and options, or delete {self.parts_dir} to start over.",
            )
        for p in self.parts_dir.iterdir():
            m = _PART.match(p.name)
            if m:
                self._parts[int(m.group(2))] = (int(m.group(1)), p)
            elif p.name.endswith(".tmp"):  # a part or manifest being written when the run died
                p.unlink()
        if self._parts:
            self._schema = _schema_of(_load_part(min(self._parts.values())[1]))

    @property
    def done_steps(self) -> set[int]:
        """Timesteps already written (by this writer or the resumed run)."""
        return set(self._parts)

    def __enter__(self) -> "ResultWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abandon()

    def abandon(self) -> None:
        """Stop without writing the store; the parts stay for a resume (a parts
        directory that holds no frame is removed: there is nothing to resume)."""
        if not self._closed:
            self._closed = True
            if self._parts:
                (self.parts_dir / _LOCK).unlink(missing_ok=True)
            else:
                shutil.rmtree(self.parts_dir, ignore_errors=True)

    # -- writing ---------------------------------------------------------
    def append(self, tables: Mapping[str, Mapping[str, np.ndarray]]) -> None:
        """Store the tables of one frame (a part file, renamed into place when complete)."""
        if self._closed:
            raise StoreError("append() after close().", file=self.path, fix="append every frame before closing.")
        step = _frame_step(tables)
        if step in self._parts:
            raise StoreError("this frame was already stored (two frames with the same timestep?).",
                             file=self.path, step=step, fix="skip timesteps in writer.done_steps.")
        unknown = set(tables) - set(TABLES)
        if unknown:
            raise StoreError(f"unknown table(s) {sorted(unknown)}; expected some of {list(TABLES)}.",
                             step=step, fix="name the tables particles, contacts, walls, frames.")
        canon = {name: canonical_table(name, tables[name], step=step) for name in TABLES if name in tables}
        for name, table in canon.items():
            if "step" in table and np.any(table["step"] != step):
                raise StoreError(f"table {name!r} has rows of other timesteps than its frame.", step=step,
                                 fix="append one frame at a time.")
        schema = _schema_of(canon)
        if self._schema is None:
            self._schema = schema
        else:
            for name, cols in schema.items():
                if name in self._schema and cols != self._schema[name]:
                    raise StoreError(
                        f"table {name!r} has columns {cols}, earlier frames had {self._schema[name]}.",
                        step=step, fix="give every frame the same columns (fill what is unknown with NaN).",
                    )
                self._schema.setdefault(name, cols)
        seq = 1 + max((s for s, _ in self._parts.values()), default=-1)
        part = self.parts_dir / f"frame_{seq:08d}_{step}.npys"
        _write_part(part, canon)
        self._parts[step] = (seq, part)

    def close(self) -> None:
        """Assemble the parts into the store, rename it into place, remove the parts."""
        if self._closed:
            return
        import h5py

        order = sorted(self._parts.items(), key=lambda kv: (kv[0], kv[1][0]))
        schema = self._schema or {}
        with atomic_path(self.path) as tmp, h5py.File(tmp, "w") as h5, \
                ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
            h5.attrs.update(format=FORMAT, format_version=FORMAT_VERSION, demsplit_version=demsplit_version(),
                            provenance=_to_json(self.provenance, "provenance"),
                            walls_meta=_to_json(self.walls_meta, "walls_meta"), compression=self.compression)
            sinks = {name: _TableSink(h5, name, schema.get(name, {}), self.compression, pool) for name in TABLES}
            offsets = {name: np.zeros(len(order) + 1, np.int64) for name in TABLES}
            for k, (_, (_, part)) in enumerate(order):
                frame = _load_part(part)  # memory-mapped; each sink releases a column once written
                for name, sink in sinks.items():
                    offsets[name][k + 1] = offsets[name][k] + sink.append(frame.pop(name, None), part)
            index = h5.create_group("index")
            index.create_dataset("step", data=np.array([s for s, _ in order], dtype=np.int64))
            for name, sink in sinks.items():
                sink.finish()
                index.create_dataset(name, data=offsets[name])
        self._closed = True
        shutil.rmtree(self.parts_dir)


class _TableSink:
    """Streams one table's rows into resizable chunked datasets, whole chunks at a time.

    Each column's chunks are written with ``write_direct_chunk``: as they are
    (no filter), or shuffled and deflated here rather than by HDF5 (gzip;
    lzf, h5py's own filter, is left to HDF5): the shuffle filter is a byte
    transpose and deflate is ``zlib.compress``, which releases the GIL, so the
    thread pool compresses a column's chunks on every core. The datasets carry
    the same filters as an ordinary h5py dataset, so every HDF5 reader decodes
    them as usual. The filters are chosen when the table's first chunk is
    complete, when ``auto`` can measure it (:func:`_choose_filter`, the
    columns in the thread pool). Rows that do not fill a chunk are carried (a copy, less
    than one chunk per column) to the next frame; :meth:`finish` writes the
    last, partial chunk (zero-padded, outside the dataset's shape).
    """

    def __init__(self, h5, name: str, schema: dict[str, str], compression: str, pool: ThreadPoolExecutor) -> None:
        self.name, self.schema = name, schema
        self.compression, self.pool = compression, pool
        self.group = h5.create_group(name)
        self.group.attrs["columns"] = json.dumps(list(schema))
        self.group.attrs["units"] = json.dumps({c: UNITS.get(c, "") for c in schema})
        self.carry = {col: np.empty(0, np.dtype(dtype)) for col, dtype in schema.items()}
        self.filters: dict[str, str] = {}  # column -> "gzip" | "lzf" | "none", once chosen

    def append(self, table: dict[str, np.ndarray] | None, part: Path) -> int:
        """Write the whole chunks that ``table`` (one frame) completes, one
        column at a time, and return its row count. Consumes ``table``: each
        column is dropped once written, so that only one column of a
        memory-mapped part is resident at a time."""
        if not table:
            return 0
        if _schema_of({self.name: table})[self.name] != self.schema:
            raise StoreError(f"table {self.name!r} in this part has columns {list(table)}, expected {list(self.schema)}.",
                             file=part, fix=f"delete {part} (the frame is recomputed on resume).")
        n = len(next(iter(table.values())))
        carried = len(next(iter(self.carry.values())))  # the same for every column
        if not self.filters and carried + n >= CHUNK_ROWS:  # the table's first chunk is complete
            self._decide({col: np.concatenate([self.carry[col], table[col][:CHUNK_ROWS - carried]]) if carried
                          else table[col][:CHUNK_ROWS] for col in self.schema})  # (views: keep none after this)
        for col in self.schema:
            chunks, self.carry[col] = _whole_chunks(self.carry[col], table.pop(col))
            self._write(col, chunks)
        return n

    def finish(self) -> None:
        """Write the carried rows (each column's last, partial chunk); a
        column without rows gets an empty dataset."""
        if not self.filters:  # the table has less than a chunk of rows
            self._decide(self.carry)
        for col, rows in self.carry.items():
            self._write(col, [rows] if len(rows) else [])
            if col not in self.group:
                self._create(col)

    def _decide(self, first: dict[str, np.ndarray]) -> None:
        """Choose each column's filter from ``first``, its first chunk (or all its rows, if fewer)."""
        if self.compression == "auto":
            self.filters = dict(zip(first, self.pool.map(_choose_filter, first.values())))
        else:
            self.filters = dict.fromkeys(first, self.compression)

    def _create(self, col: str):
        """The empty, resizable dataset of ``col`` with its chosen filter."""
        kind = self.filters[col]
        ds = self.group.create_dataset(
            col, shape=(0,), maxshape=(None,), dtype=np.dtype(self.schema[col]), chunks=(CHUNK_ROWS,),
            compression=None if kind == "none" else kind,
            compression_opts=GZIP_LEVEL if kind == "gzip" else None, shuffle=kind != "none",
        )
        ds.attrs["unit"] = UNITS.get(col, "")
        return ds

    def _write(self, col: str, chunks: list[np.ndarray]) -> None:
        """Append the chunks of one column (all whole but possibly the table's last one)."""
        if not chunks:
            return
        ds = self.group[col] if col in self.group else self._create(col)
        start = ds.shape[0]
        ds.resize((start + sum(len(c) for c in chunks),))  # the rows, not the padding: it never shrinks
        if self.filters[col] == "lzf":  # h5py's own filter: HDF5 applies it to the chunk-aligned slices
            for k, c in enumerate(chunks):
                ds[start + k * CHUNK_ROWS: start + k * CHUNK_ROWS + len(c)] = c
            return
        blobs = self.pool.map(_shuffle_deflate, chunks) if self.filters[col] == "gzip" else map(_padded, chunks)
        for k, blob in enumerate(blobs):
            ds.id.write_direct_chunk((start + k * CHUNK_ROWS,), blob)


def _whole_chunks(carry: np.ndarray, values: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Split ``carry`` + ``values`` into whole CHUNK_ROWS chunks (the first one
    joins the carried rows, the others are views of ``values``) and the rows
    left over (a copy, so that ``values`` can be released)."""
    chunks = []
    if len(carry):
        fill = CHUNK_ROWS - len(carry)
        carry = np.concatenate([carry, values[:fill]])
        if len(carry) < CHUNK_ROWS:
            return [], carry
        chunks.append(carry)
        values = values[fill:]
    whole = len(values) // CHUNK_ROWS * CHUNK_ROWS
    chunks.extend(values[k: k + CHUNK_ROWS] for k in range(0, whole, CHUNK_ROWS))
    return chunks, np.array(values[whole:])


def _choose_filter(first: np.ndarray) -> str:
    """``auto``'s choice for a column from its first chunk: ``"gzip"`` when
    shuffle + deflate (level GZIP_LEVEL) shrinks it to at most AUTO_MAX_RATIO
    of its size, else ``"none"`` (also for a column without rows)."""
    if not len(first):
        return "none"
    return "gzip" if len(zlib.compress(_shuffled(first), GZIP_LEVEL)) <= AUTO_MAX_RATIO * first.nbytes else "none"


def _padded(values: np.ndarray) -> np.ndarray:
    """A chunk's values, zero-padded to CHUNK_ROWS (the bytes HDF5 stores for a chunk)."""
    if len(values) == CHUNK_ROWS:
        return np.ascontiguousarray(values)
    return np.concatenate([values, np.zeros(CHUNK_ROWS - len(values), values.dtype)])


def _shuffled(values: np.ndarray) -> bytes:
    """HDF5's shuffle filter: the values' bytes grouped by byte position."""
    return np.ascontiguousarray(values).view(np.uint8).reshape(len(values), values.itemsize).T.tobytes()


def _shuffle_deflate(values: np.ndarray) -> bytes:
    """One chunk as HDF5's shuffle + deflate filters store it (zero-padded to CHUNK_ROWS)."""
    return zlib.compress(_shuffled(_padded(values)), GZIP_LEVEL)


def _write_part(path: Path, tables: Mapping[str, Table]) -> None:
    """One frame's tables as a part: a file of consecutive ``.npy`` records
    (``np.save``: a header, then the array's raw bytes), first the column
    names (``{table: [column, ...]}`` as JSON bytes), then every column in that
    order; written under ``path.tmp`` and renamed when complete. Not fsynced: a
    part exists for a resume after the process was killed, which the page
    cache survives; after a power cut a short part is named by
    :func:`_load_part` (delete it and resume), and the final store is fsynced
    before it is renamed into place."""
    names = json.dumps({name: list(table) for name, table in tables.items()}).encode()

    def write(f) -> None:
        np.save(f, np.frombuffer(names, np.uint8))
        for table in tables.values():
            for values in table.values():
                np.save(f, values, allow_pickle=False)

    _write_atomic(path, write, durable=False)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _frame_step(tables: Mapping[str, Mapping[str, np.ndarray]]) -> int:
    frames = tables.get("frames")
    if frames is None or "step" not in frames or len(np.atleast_1d(frames["step"])) != 1:
        raise StoreError("each appended frame needs a 'frames' table with exactly one row and a 'step' column.",
                         fix="pass tables['frames'] = {'step': np.array([step]), ...}.")
    return int(np.atleast_1d(frames["step"])[0])


def _schema_of(tables: Mapping[str, Table]) -> dict[str, dict[str, str]]:
    return {name: {col: np.asarray(v).dtype.str for col, v in table.items()} for name, table in tables.items()}


def _load_part(path: Path) -> dict[str, Table]:
    """A part's tables (see :func:`_write_part`), each column memory-mapped read-only."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            names = json.loads(np.load(f, allow_pickle=False).tobytes())
            return {name: {col: _map_record(f, path, size) for col in cols} for name, cols in names.items()}
    except (OSError, ValueError, EOFError) as exc:
        raise StoreError(f"cannot read a stored frame: {exc}.", file=path,
                         fix=f"delete {path} (the frame is recomputed on resume).") from exc


def _map_record(f, path: Path, size: int) -> np.ndarray:
    """Memory-map the 1-D ``.npy`` record at ``f``'s position and move ``f`` past it."""
    version = np.lib.format.read_magic(f)
    read_header = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
    if version not in read_header:
        raise ValueError(f"unexpected .npy version {version}")
    shape, _, dtype = read_header[version](f)
    offset = f.tell()
    end = offset + int(np.prod(shape)) * dtype.itemsize
    if end > size:
        raise ValueError(f"the file ends at byte {size}, inside a column that ends at byte {end}")
    f.seek(end)
    return np.memmap(path, dtype, "r", offset, shape) if end > offset else np.empty(shape, dtype)


def read_store(path: str | Path, *, steps: Iterable[int] | None = None) -> Results:
    """Read a store into :class:`~demsplit.results.Results` (every frame, or only
    timesteps ``steps``, each read through the frame index without the rest)."""
    import h5py

    path = Path(path)
    if not path.is_file():
        parts = path.parent / f".{path.name}.parts"
        hint = f" An interrupted run left parts in {parts}." if parts.exists() else ""
        raise StoreError(f"no result store here.{hint}", file=path,
                         fix="run demsplit first (or resume the interrupted run with --resume).")
    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        raise StoreError(f"not a readable HDF5 file ({exc}).", file=path,
                         fix="point to a store written by demsplit run.") from exc
    try:
        with h5:
            if h5.attrs.get("format") != FORMAT:
                raise StoreError(f"not a demsplit result store (format attribute {h5.attrs.get('format')!r}).",
                                 file=path, fix="point to a store written by demsplit run.")
            if int(h5.attrs["format_version"]) > FORMAT_VERSION:
                raise StoreError(f"store format version {int(h5.attrs['format_version'])} is newer than this "
                                 f"demsplit reads ({FORMAT_VERSION}).", file=path, fix="upgrade demsplit.")
            stored_steps = h5["index/step"][()]
            frames_k = np.arange(len(stored_steps))
            if steps is not None:
                wanted = np.asarray(list(steps), dtype=np.int64)
                missing = np.setdiff1d(wanted, stored_steps)
                if len(missing):
                    raise StoreError(f"timestep(s) {missing.tolist()[:10]} are not in the store "
                                     f"({len(stored_steps)} frames).", file=path, fix="pick stored timesteps.")
                frames_k = frames_k[np.isin(stored_steps, wanted)]
            frames = {}
            for name in TABLES:
                group = h5[name]
                columns = json.loads(group.attrs["columns"])
                off = h5[f"index/{name}"][()]
                if steps is None:
                    table = {col: group[col][()] for col in columns}
                else:
                    table = {col: np.concatenate([group[col][off[k]:off[k + 1]] for k in frames_k]
                                                 or [np.empty(0, group[col].dtype)]) for col in columns}
                frames[name] = to_dataframe(table)
            return Results(**frames, provenance=json.loads(h5.attrs["provenance"]),
                           walls_meta=json.loads(h5.attrs["walls_meta"]))
    except (KeyError, ValueError, OSError) as exc:  # a group, dataset or attribute missing or unreadable
        raise StoreError(f"the store is damaged or incomplete ({type(exc).__name__}: {exc}).", file=path,
                         fix="rerun demsplit run to rewrite it.") from exc


def export_tables(results: Results, directory: str | Path, fmt: str = "parquet") -> list[Path]:
    """Write each table to ``directory/<table>.parquet`` (or ``.csv``) and the
    provenance to ``provenance.json``, each file atomically. Parquet files carry
    the units (field metadata ``unit``) and the provenance (schema metadata).
    CSV numbers are written with 17 significant digits (round-trip exact)."""
    if fmt not in ("parquet", "csv"):
        raise StoreError(f"unknown export format {fmt!r}.", fix="use 'parquet' or 'csv'.")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    prov = _to_json({"provenance": results.provenance, "walls_meta": results.walls_meta}, "provenance")
    written = []
    for name in TABLES:
        df = getattr(results, name)
        out = directory / f"{name}.{fmt}"
        if fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            units = df.attrs.get("units", {})
            table = pa.Table.from_pandas(df, preserve_index=False)
            fields = [f.with_metadata({"unit": units.get(f.name, "")}) for f in table.schema]
            schema = pa.schema(fields, metadata={b"demsplit": prov.encode()})
            table = table.cast(schema)
            _write_atomic(out, lambda f, t=table: pq.write_table(t, f))
        else:
            _write_atomic(out, lambda f, d=df: d.to_csv(f, index=False, float_format="%.17g"))
        written.append(out)
    meta = directory / "provenance.json"
    _write_atomic(meta, lambda f: f.write(prov.encode()))
    return [*written, meta]
