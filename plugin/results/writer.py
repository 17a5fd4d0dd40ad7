"""Writing the result store: once, as frames arrive, atomically and resumably.

The store is written to ``.OUT.h5.partial/store.h5`` next to the target, in HDF5's single-writer (SWMR)
mode, whose on-disk state stays a valid HDF5 file at every moment, so a run killed at any point (SIGKILL
included) leaves a readable file. After each frame the file is flushed and a commit record,
``.OUT.h5.partial/commit.npys``, is renamed into place: the steps and row offsets of the frames stored so
far and the rows that do not yet fill a chunk (less than one chunk per column). :meth:`ResultWriter.close`
writes those last rows, the frame index and the provenance, fsyncs the file and renames it to ``OUT.h5``.
Nothing exists at ``OUT.h5`` until it is complete. With ``resume=True`` an interrupted run is continued when
its provenance (input digests, options, scene, demsplit version) is the same: the committed frames' chunks
are copied, as stored, into a fresh file. The layout the store ends with: :mod:`demsplit.results.store`.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Mapping
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import DemsplitError, StoreError, system_error
from ..fingerprint import DIGEST, file_fingerprint
from ..outputs import check_output_path, publish, write_atomic
from ..runtime import threads
from ..runtime.writeback import WriteBack
from .chunks import CHUNK_ROWS, COMPRESSION, COMPRESSIONS, TableSink, choose_filters, chunk_rows
from .schema import TABLES, UNKNOWN, UNKNOWN_COLUMNS, Table, canonical_table
from .store import FORMAT, FORMAT_VERSION, STORE, demsplit_version, to_json, work_dir_of

LIBVER = ("v110", "v110")
"""HDF5 file-format bounds: the 1.10 format (which SWMR needs), readable by
every HDF5 library since 1.10.0 (2016)."""
WORK_VERSION = 4
"""Layout of an interrupted run's work directory (4: a store written in SWMR
mode plus a commit record, inputs identified by BLAKE3; 3 identified them by
sha256; 2 and 1 were per-frame parts). Other layouts are
not resumed."""

RESUME_KEYS = ("inputs", "options", "scene", "model", "demsplit_version")
"""Provenance entries that must be equal for a run to be resumed; ``inputs``
is compared by the digest (BLAKE3) of each input file."""

_STORE = "store.h5"
_COMMIT = "commit.npys"
_MANIFEST = "run.json"
_LOCK = "lock"
_SORTED = "sorted.h5.new"  # close(): the store in step order, when frames came out of order
_PUBLISHED = "published"  # close(): device and inode of the complete store it renames into place


def resume_identity(provenance: Mapping) -> dict:
    """What must not change between an interrupted run and its resumption."""
    ident = {key: provenance.get(key) for key in RESUME_KEYS}
    ident["inputs"] = sorted(str(f.get(DIGEST)) for f in provenance.get("inputs") or [])
    return json.loads(to_json(ident, "provenance"))


def check_output(path: str | Path, *, resume: bool = False, overwrite: bool = False, inputs=()) -> None:
    """Raise :class:`StoreError` when a store cannot be started at ``path``: it is not a
    writable output for a store (:func:`demsplit.outputs.check_output_path`: empty, a directory, a device, in a
    missing directory, one of ``inputs``, an existing file that is not a result store, unless ``overwrite``),
    another live process writes it, or an interrupted run's committed frames are there and ``resume`` is false
    (they are never silently discarded). A work directory that holds no committed frame (a run killed before its first
    commit, or after its store was complete, or whose first commit failed) is a leftover with nothing to
    resume: it is removed."""
    path = check_output_path(path, inputs, kind=STORE, overwrite=overwrite)
    work = work_dir_of(path)
    writer = _live_writer(work)
    if writer:
        raise StoreError(
            f"another demsplit process (pid {writer}) is writing this store.",
            file=path,
            fix="wait for it to finish, or write to another path.",
        )
    if work.exists() and not _resumable(work):
        shutil.rmtree(work, ignore_errors=True)
    if work.exists() and not resume:
        raise StoreError(
            f"an interrupted run left its finished frames in {work}.",
            file=path,
            fix=f"continue it: run the same command again with --resume; or delete {work} to start over.",
        )


def _resumable(work: Path) -> bool:
    """Whether the work directory ``work`` holds committed frames to resume: a commit record and the store it
    describes, unless its run already renamed its complete store (a copy in step order) into place (the
    ``published`` record names that file by device and inode, which the rename keeps)."""
    if not ((work / _COMMIT).is_file() and (work / _STORE).is_file()):
        return False
    try:
        published = (work / _PUBLISHED).read_text().split()
        st = os.stat(work.parent / work.name[1 : -len(".partial")])
    except (OSError, ValueError):
        return True
    return published != [str(st.st_dev), str(st.st_ino)]


def committed_steps(path: str | Path) -> list[int]:
    """Timesteps of the frames an unfinished (or interrupted) store ``path``
    holds so far, in the order they were appended ([] when none)."""
    commit = work_dir_of(path) / _COMMIT
    return list(_read_records(commit)[0]["steps"]) if commit.exists() else []


class ResultWriter:
    """Write the per-frame result tables of one run to an HDF5 store.

    >>> with ResultWriter("out.h5", provenance) as w:    # doctest: +SKIP
    ...     for tables in frames:
    ...         if step_of(tables) not in w.done_steps:
    ...             w.append(tables)

    ``append`` takes ``{"particles": {...}, "contacts": {...}, "walls": {...},
    "frames": {...}}`` for one frame (``frames`` with exactly one row; an absent
    table counts as empty, and a table absent from the first frame stays
    empty). Frames are stored in step order; frames appended out of step order
    cost one more copy of the store at ``close()``. Leaving the ``with`` block
    by an exception writes no store: an interruption (Ctrl-C, SIGTERM, an error of the system such as a
    full disk) keeps the frames committed so far for ``--resume``; a refusal of the run (any other
    :class:`~demsplit.errors.DemsplitError`: a bad frame, a bad input) leaves nothing, so that the next run
    is not taken for the continuation of an interrupted one.
    Entries added to ``writer.provenance`` before ``close()`` (skipped frames,
    notes) are stored. ``compression`` is one of :data:`COMPRESSIONS`
    (``None`` means ``"none"``).

    An input whose digest is None in the provenance (``build_provenance(..., wait=False)``: still
    being hashed in the background) is filled in as soon as its digest is known; a resumed run waits
    for it (the interrupted run's inputs are compared by it). Until then frames are stored but not
    committed: the run's manifest names its inputs by their digests, so a run killed before them has
    nothing to resume and starts over; the second frame's commit finishes the hashing itself.

    The store's pages are sent to disk while the run goes on (:class:`~demsplit.outputs.WriteBack`): a
    frame's after the frame, while the next one is computed, and the frame at ``final_step`` (the run's
    last timestep, when the caller knows it) column by column as it is written, since nothing follows it
    to hide its write-back behind: ``close()``'s fsync then finds little left to write.
    """

    def __init__(
        self,
        path: str | Path,
        provenance: Mapping,
        *,
        resume: bool = False,
        walls_meta: list[dict] | None = None,
        compression: str | None = COMPRESSION,
        final_step: int | None = None,
        overwrite: bool = False,
    ) -> None:
        self.path = Path(path)
        self.final_step = final_step
        self._final_frame = False  # the frame being appended is the one at final_step
        self.provenance = dict(provenance)
        self.walls_meta = list(walls_meta or [])
        self.compression = "none" if compression is None else compression
        if self.compression not in COMPRESSIONS:
            raise StoreError(
                f"unknown compression {compression!r}; expected one of {list(COMPRESSIONS)}.",
                file=self.path,
                fix="pick one of " + ", ".join(COMPRESSIONS) + ".",
            )
        check_output(self.path, resume=resume, overwrite=overwrite)
        self.work_dir = work_dir_of(self.path)
        self._store = self.work_dir / _STORE
        self._h5 = None  # the store being written, in SWMR mode, from the first frame on
        self._sinks: dict[str, TableSink] = {}
        self._steps: list[int] = []  # in append order
        self._rows: dict[str, list[int]] = {name: [0] for name in TABLES}  # row offsets, in append order
        self._closed = False
        self._manifest_written = False
        self._write_back = WriteBack()  # the store's pages on their way to disk before close()'s fsync
        resuming = self.work_dir.exists()
        try:
            with self._system_errors():
                if resuming:
                    self._lock()
                    self._fill_digests(wait=True)
                    self._resume(self._manifest())
                    self._write_manifest()
                else:
                    self.work_dir.mkdir()
                    self._lock()
                    if self._fill_digests(wait=False):
                        self._write_manifest()
        except BaseException:
            self._closed = True
            self._release(quiet=True)
            if resuming and _resumable(self.work_dir):
                (self.work_dir / _LOCK).unlink(missing_ok=True)
            else:  # nothing committed: nothing is left behind
                shutil.rmtree(self.work_dir, ignore_errors=True)
            raise

    # -- lifecycle -------------------------------------------------------
    def _fill_digests(self, wait: bool) -> bool:
        """Fill in the provenance's input digests that are None (being computed); ``wait``: finish them
        now (:func:`~demsplit.fingerprint.file_fingerprint`). Whether every digest is known."""
        known = True
        for entry in self.provenance.get("inputs") or []:
            if DIGEST in entry and entry[DIGEST] is None:
                entry.update(file_fingerprint(entry["path"], wait=wait))
                known &= entry[DIGEST] is not None
        return known

    def _manifest(self) -> dict:
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "work_version": WORK_VERSION,
            "identity": resume_identity(self.provenance),
            "provenance": self.provenance,
            "walls_meta": self.walls_meta,
            "compression": self.compression,
        }

    def _write_manifest(self) -> None:
        manifest = self._manifest()
        write_atomic(self.work_dir / _MANIFEST, lambda f: f.write(to_json(manifest, "provenance").encode()))
        self._manifest_written = True

    def _lock(self) -> None:
        lock = self.work_dir / _LOCK
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pid = _live_writer(self.work_dir)
            if pid:
                raise StoreError(
                    f"another demsplit process (pid {pid}) is writing this store.",
                    file=self.path,
                    fix="wait for it to finish, or write to another path.",
                ) from None
            lock.unlink(missing_ok=True)
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        with os.fdopen(fd, "w") as f:
            f.write(str(os.getpid()))

    def _resume(self, manifest: dict) -> None:
        """Continue the interrupted run in ``work_dir``: copy its committed
        chunks, as stored, into a fresh store and take over its carried rows."""
        try:
            old = json.loads((self.work_dir / _MANIFEST).read_text())
        except (OSError, ValueError):
            old = None
        if old is None or [old.get(k) for k in ("format", "format_version", "work_version")] != [
            FORMAT,
            FORMAT_VERSION,
            WORK_VERSION,
        ]:
            raise StoreError(
                f"{self.work_dir} holds no readable run manifest of this demsplit version.",
                file=self.path,
                fix=f"delete {self.work_dir} and run again without resume.",
            )
        if old["identity"] != manifest["identity"]:
            diff = [k for k in manifest["identity"] if manifest["identity"][k] != old["identity"].get(k)]
            raise StoreError(
                f"cannot resume: the interrupted run had different {', '.join(diff)} "
                f"(input files are compared by their BLAKE3 digest).",
                file=self.path,
                fix=f"rerun with the same inputs and options, or delete {self.work_dir} to start over.",
            )
        for p in self.work_dir.iterdir():  # a commit record or copy being written when the run died
            if p.name.endswith((".tmp", ".new")) or p.name == _PUBLISHED:
                p.unlink()
        commit = self.work_dir / _COMMIT
        if not commit.exists():  # killed before its first frame was committed: nothing to resume
            self._store.unlink(missing_ok=True)
            return
        header, carry = _read_records(commit)
        if header.get("compression") != self.compression:
            raise StoreError(
                f"cannot resume: the interrupted run used --compression {header.get('compression')}.",
                file=self.path,
                fix=f"resume with --compression {header.get('compression')}, or delete {self.work_dir} to start over.",
            )
        fresh = self._store.with_name(_STORE + ".new")
        self._open(fresh, _schema_of(carry), header["filters"], header["chunks"])  # the records keep the column order
        import h5py

        try:
            with h5py.File(self._store, "r", libver=LIBVER, swmr=True) as h5:
                for name, sink in self._sinks.items():
                    sink.adopt(
                        h5[name], header["written"][name], {col: np.array(v) for col, v in carry.get(name, {}).items()}
                    )
        except (OSError, KeyError, ValueError) as exc:
            self._release()
            fresh.unlink(missing_ok=True)
            raise StoreError(
                f"cannot read the interrupted run's store ({type(exc).__name__}: {exc}).",
                file=self._store,
                fix=f"delete {self.work_dir} and run again without resume.",
            ) from exc
        self._h5.flush()
        os.replace(fresh, self._store)  # the commit record describes the copy as it did the original
        self._steps = [int(s) for s in header["steps"]]
        self._rows = {name: [int(r) for r in header["rows"][name]] for name in TABLES}

    @property
    def done_steps(self) -> set[int]:
        """Timesteps already written (by this writer or the resumed run)."""
        return set(self._steps)

    def __enter__(self) -> ResultWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        elif isinstance(exc, DemsplitError) and not isinstance(exc.__cause__, OSError):
            self.discard()  # refused: nothing to resume
        else:
            self.abandon()

    def discard(self) -> None:
        """Stop without writing the store and remove the work directory, committed frames included: the
        run was refused, and a rerun (with other options, say) must not be taken for its continuation."""
        if not self._closed:
            self._closed = True
            self._write_back.stop()
            self._release(quiet=True)
            shutil.rmtree(self.work_dir, ignore_errors=True)

    def abandon(self) -> None:
        """Stop without writing the store; the committed frames stay for a
        resume (a work directory that holds no committed frame, e.g. after
        its first commit failed on a full disk, is removed: there is
        nothing to resume, and nothing is left behind)."""
        if not self._closed:
            self._closed = True
            self._write_back.stop()
            self._release(quiet=True)
            if _resumable(self.work_dir):
                (self.work_dir / _LOCK).unlink(missing_ok=True)
            else:
                shutil.rmtree(self.work_dir, ignore_errors=True)

    def _release(self, quiet: bool = False) -> None:
        """Close the store file (``quiet``: a file given up, whose close may fail too, e.g. on a full disk:
        the commit record says what it holds)."""
        if self._h5 is not None:
            h5, self._h5 = self._h5, None
            try:
                h5.close()
            except Exception:
                if not quiet:
                    raise

    @contextmanager
    def _system_errors(self):
        """An OSError of the system while writing (a full disk, a read-only file system) becomes the one
        StoreError naming the output and the cause, and what is kept for ``--resume``."""
        try:
            yield
        except OSError as exc:
            kept = self._steps_committed()
            note = (
                (
                    f"; the {kept} frame(s) committed before it are kept in {self.work_dir} for --resume "
                    f"(delete it to start over)"
                )
                if kept
                else ""
            )
            raise system_error(exc, self.path, doing="cannot write the store", note=note) from exc

    def _steps_committed(self) -> int:
        try:
            return len(committed_steps(self.path)) if _resumable(self.work_dir) else 0
        except StoreError:
            return 0

    # -- writing ---------------------------------------------------------
    def _open(
        self,
        path: Path,
        schema: Mapping[str, Mapping[str, str]],
        filters: Mapping[str, Mapping[str, str]],
        chunks: Mapping[str, int],
    ):
        """Create the store at ``path`` with every table's datasets (``chunks``:
        rows per chunk of each table), and start SWMR writing."""
        import h5py

        # no chunk cache: every chunk is written whole, once, and not read back (with lzf, whose chunks
        # HDF5 filters itself, the cache held ~100 MB more at the peak on the medium benchmark run)
        self._h5 = h5py.File(path, "w", libver=LIBVER, rdcc_nbytes=0)
        self._sinks = {
            name: TableSink(
                self._h5,
                name,
                dict(schema.get(name, {})),
                dict(filters.get(name, {})),
                chunks.get(name, CHUNK_ROWS),
                threads.pool(),
                on_written=self._column_written,
            )
            for name in TABLES
        }
        self._h5.swmr_mode = True

    def append(self, tables: Mapping[str, Mapping[str, np.ndarray]]) -> None:
        """Store the tables of one frame and commit it (see the module docstring). A table with a value
        that is not finite is refused: no stored number is NaN or inf."""
        with self._system_errors():
            self._append(tables)

    def _append(self, tables: Mapping[str, Mapping[str, np.ndarray]]) -> None:
        if self._closed:
            raise StoreError("append() after close().", file=self.path, fix="append every frame before closing.")
        step = _frame_step(tables)
        if step in self._steps:
            raise StoreError(
                "this frame was already stored (two frames with the same timestep?).",
                file=self.path,
                step=step,
                fix="skip timesteps in writer.done_steps.",
            )
        unknown = set(tables) - set(TABLES)
        if unknown:
            raise StoreError(
                f"unknown table(s) {sorted(unknown)}; expected some of {list(TABLES)}.",
                step=step,
                fix="name the tables particles, contacts, walls, frames.",
            )
        canon = {name: canonical_table(name, tables[name], step=step) for name in TABLES if name in tables}
        for name, table in canon.items():
            if "step" in table and np.any(table["step"] != step):
                raise StoreError(
                    f"table {name!r} has rows of other timesteps than its frame.",
                    step=step,
                    fix="append one frame at a time.",
                )
            _refuse_non_finite(name, table, step)
        schema = _schema_of(canon)
        if self._h5 is None:
            self._open(
                self._store,
                schema,
                choose_filters(canon, self.compression, threads.pool()),
                {name: chunk_rows(len(next(iter(table.values()), ()))) for name, table in canon.items()},
            )
        for name, cols in schema.items():
            if cols != self._sinks[name].schema:
                raise StoreError(
                    f"table {name!r} has columns {list(cols)}, earlier frames had {list(self._sinks[name].schema)}.",
                    step=step,
                    fix="give every frame the same columns (fill what is unknown with NaN; "
                    "a table absent from the first frame must stay absent, or be empty there).",
                )
        self._final_frame = step == self.final_step
        for name, sink in self._sinks.items():
            self._rows[name].append(self._rows[name][-1] + sink.append(canon.get(name)))
        self._steps.append(step)
        self._commit()
        self._write_back.request(self._store)

    def _column_written(self) -> None:
        """A column's chunks are in the file: the final frame's go to disk at once (class docstring). An
        earlier frame's wait for the request after the frame: asked for column by column they are written
        while the next columns are appended, and the appends were slower by more than ``close()`` gained."""
        if self._final_frame:
            self._write_back.request(self._store)

    def _commit(self) -> None:
        """Flush the store and record what it holds (renamed into place: a
        killed run leaves the previous record or this one, never a part); not
        before the run's manifest, which needs the inputs' digests: the first frame does not wait for the
        hashing on idle cores, the second takes it over (a busy machine leaves idle cores to none, and a run
        must be resumable from its first frames on)."""
        if not self._manifest_written:
            if not self._fill_digests(wait=len(self._steps) > 1):
                return
            self._write_manifest()
        self._h5.flush()
        header = {
            "steps": self._steps,
            "rows": self._rows,
            "compression": self.compression,
            "filters": {name: sink.filters for name, sink in self._sinks.items()},
            "chunks": {name: sink.chunk_rows for name, sink in self._sinks.items()},
            "written": {name: sink.written for name, sink in self._sinks.items()},
        }
        _write_records(self.work_dir / _COMMIT, header, {name: sink.carry for name, sink in self._sinks.items()})

    def close(self) -> None:
        """Write the last rows, the frame index and the provenance; rename the store into place.

        At every instant of it (SIGKILL included) the run stays resumable or the store is complete at
        its path: the store the commit record describes gets only its last rows, in SWMR mode, and
        then, still in SWMR mode, the frame index and the attributes (frames appended out of step order
        are copied in order into a new file, finished there); the file is fsynced and renamed to the
        output. The work directory, whose store is then gone (or, for a copy in step order, which names
        the file it renamed), is removed last (a run killed before that leaves one with nothing to
        resume, which the next run removes)."""
        if self._closed:
            return
        self._write_back.stop()  # what it started goes on; the rest is fsynced below
        try:
            with self._system_errors():
                if self._h5 is None:  # no frame: a store with empty tables
                    self._open(self._store, {}, {}, {})
                for sink in self._sinks.values():
                    sink.finish()
                self._fill_digests(wait=True)  # for the provenance the store's attributes hold
                final = self._store
                order = np.argsort(np.array(self._steps, dtype=np.int64), kind="stable")
                if np.any(order != np.arange(len(order))):
                    final = self._rewrite_in_step_order(order)
                self._write_index()
                self._release()
                if final != self._store:  # the commit record stays valid: say which file completes the run
                    st = os.stat(final)
                    write_atomic(
                        self.work_dir / _PUBLISHED,
                        lambda f: f.write(f"{st.st_dev} {st.st_ino}".encode()),
                        durable=False,
                    )
                publish(final, self.path)
        except BaseException:
            self.abandon()  # the committed frames stay for --resume
            raise
        self._closed = True
        shutil.rmtree(self.work_dir, ignore_errors=True)

    def _write_index(self) -> None:
        """The frame index and the attributes, into the open store."""
        h5 = self._h5
        h5.attrs.update(
            format=FORMAT,
            format_version=FORMAT_VERSION,
            demsplit_version=demsplit_version(),
            provenance=to_json(self.provenance, "provenance"),
            walls_meta=to_json(self.walls_meta, "walls_meta"),
            compression=self.compression,
        )
        index = h5.create_group("index")
        index.create_dataset("step", data=np.array(self._steps, dtype=np.int64))
        for name in TABLES:
            index.create_dataset(name, data=np.array(self._rows[name], dtype=np.int64))
        h5.flush()

    def _rewrite_in_step_order(self, order: np.ndarray) -> Path:
        """Copy the store frame by frame in step order into a new file (frames were appended out of
        order; one frame's rows in memory at a time) and return it, open as the writer's file; the store
        the commit record describes is left as it is."""
        import h5py

        schema = {name: sink.schema for name, sink in self._sinks.items()}
        filters = {name: sink.filters for name, sink in self._sinks.items()}
        chunks = {name: sink.chunk_rows for name, sink in self._sinks.items()}
        self._release()
        sorted_path = self.work_dir / _SORTED
        with h5py.File(self._store, "r", libver=LIBVER) as src:
            self._open(sorted_path, schema, filters, chunks)
            for k in order:
                for name, sink in self._sinks.items():
                    lo, hi = self._rows[name][k], self._rows[name][k + 1]
                    sink.append({col: src[name][col][lo:hi] for col in sink.schema} if sink.schema else None)
            for sink in self._sinks.values():
                sink.finish()
        for name in TABLES:
            sizes = np.diff(self._rows[name])[order]
            self._rows[name] = [0, *np.cumsum(sizes).tolist()]
        self._steps = [self._steps[k] for k in order]
        return sorted_path


def _refuse_non_finite(name: str, table: Table, step: int) -> None:
    """Raise StoreError for the first value of ``table`` that is not finite (NaN or inf)."""
    for col, values in table.items():
        if values.dtype.kind != "f" or not len(values):
            continue
        with np.errstate(all="ignore"):
            if np.isfinite(np.add.reduce(values)):  # fast: a NaN or inf anywhere makes the sum one
                continue
        bad = ~np.isfinite(values)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise StoreError(
                f"table {name}, column {col}, row {row} is {float(values[row])} ({int(bad.sum())} "
                "value(s) of the column are not finite): no stored number is NaN or inf.",
                step=step,
                fix=f"give a finite number, or {UNKNOWN} in a frames column of "
                f"{', '.join(UNKNOWN_COLUMNS)} whose value is not known.",
            )


def _write_records(path: Path, header: Mapping, tables: Mapping[str, Table]) -> None:
    """``header`` (JSON) and ``tables`` as one file of consecutive ``.npy``
    records (``np.save``: a header, then the array's raw bytes): first the
    header with the tables' column names under ``"columns"`` (``[[table,
    [column, ...]], ...]``), then every column in that order; written under ``path.tmp`` and renamed when complete. Not
    fsynced: the record exists for a resume after the process was killed,
    which the page cache survives; after a power cut a short record is named
    by :func:`_read_records`, and the final store is fsynced before it is
    renamed into place."""
    head = to_json({**header, "columns": [[name, list(table)] for name, table in tables.items()]}, "commit record")

    def write(f) -> None:
        np.save(f, np.frombuffer(head.encode(), np.uint8))
        for table in tables.values():
            for values in table.values():
                np.save(f, values, allow_pickle=False)

    write_atomic(path, write, durable=False)


def _live_writer(work: Path) -> int | None:
    """The pid of the live process that holds the lock of the work directory ``work``, or None."""
    try:
        pid = int((work / _LOCK).read_text() or "0")
    except (OSError, ValueError):
        return None
    return pid if pid > 0 and pid != os.getpid() and _alive(pid) else None


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
        raise StoreError(
            "each appended frame needs a 'frames' table with exactly one row and a 'step' column.",
            fix="pass tables['frames'] = {'step': np.array([step]), ...}.",
        )
    return int(np.atleast_1d(frames["step"])[0])


def _schema_of(tables: Mapping[str, Table]) -> dict[str, dict[str, str]]:
    return {name: {col: np.asarray(v).dtype.str for col, v in table.items()} for name, table in tables.items()}


def _read_records(path: Path) -> tuple[dict, dict[str, Table]]:
    """A record file's header and tables (see :func:`_write_records`), each column memory-mapped read-only."""
    try:
        with open(path, "rb") as f:  # every column is mapped from this open file: a record renamed over
            size = os.fstat(f.fileno()).st_size  # `path` meanwhile (a running writer's next commit) is not mixed in
            header = json.loads(np.load(f, allow_pickle=False).tobytes())
            tables = {name: {col: _map_record(f, size) for col in cols} for name, cols in header.pop("columns")}
            return header, tables
    except (OSError, ValueError, EOFError, KeyError) as exc:
        raise StoreError(
            f"cannot read the commit record: {exc}.",
            file=path,
            fix=f"delete {path.parent} and run again without resume.",
        ) from exc


def _map_record(f, size: int) -> np.ndarray:
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
    column = np.memmap(f, dtype, "r", offset, shape) if end > offset else np.empty(shape, dtype)
    f.seek(end)  # (np.memmap moves the file's position)
    return column
