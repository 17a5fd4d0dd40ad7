"""The result store: one HDF5 file per run, written once, atomically and resumably.

Layout (see docs/store.md)::

    /                 attrs: format, format_version, demsplit_version,
                             provenance (JSON), walls_meta (JSON), compression
    /particles/<col>  one 1-D dataset per column, chunked, compressed, resizable
    /contacts/<col>   (group attrs: columns (JSON list, stored order), units (JSON))
    /walls/<col>
    /frames/<col>     one row per frame
    /index/step       (n_frames,) timestep of frame k
    /index/<table>    (n_frames + 1,) row offset of frame k in <table>:
                      frame k is rows offsets[k]:offsets[k+1]

The store is written by :class:`demsplit.results.writer.ResultWriter` (once, as frames arrive, resumably),
its chunks compressed by :mod:`demsplit.results.chunks`; this module holds the format, the provenance and
the reading.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ..errors import StoreError
from ..fingerprint import file_fingerprint
from ..outputs import hdf5_kind, text_attribute
from ..scene import scene_to_dict
from .schema import TABLES, UNKNOWN, UNKNOWN_COLUMNS, Table, canonical_dtype, to_dataframe
from .tables import Results

FORMAT = "demsplit-results"
FORMAT_VERSION = 1
STORE = hdf5_kind("demsplit result store", FORMAT)
"""The output kind of a store: an existing store is replaced by a new one, any other file is not
(:func:`demsplit.outputs.check_output_path`)."""


def demsplit_version() -> str:
    """The installed demsplit version ("unknown" when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("demsplit")
    except PackageNotFoundError:
        return "unknown"


def build_provenance(
    inputs: Iterable[str | Path], *, scene=None, options: dict | None = None, wait: bool = True, **extra
) -> dict:
    """A provenance dict: ``inputs`` (fingerprints), ``scene`` (materials per type,
    walls) and ``model`` (contact model) from a :class:`demsplit.scene.Scene`,
    ``options``, ``demsplit_version``, plus any ``extra`` entries (e.g.
    ``overlap_source``, ``skipped``, ``bad_frames``). Must be JSON-serialisable.
    ``wait=False``: an input whose digest is still being computed has digest None
    (:func:`~demsplit.fingerprint.file_fingerprint`), which the
    :class:`~demsplit.results.writer.ResultWriter` fills in."""
    prov: dict = {
        "inputs": [file_fingerprint(p, wait=wait) for p in inputs],
        "options": dict(options or {}),
        "demsplit_version": demsplit_version(),
    }
    if scene is not None:
        prov["scene"] = scene_to_dict(scene)
        prov["model"] = prov["scene"].pop("model")
    prov.update(extra)
    to_json(prov, "provenance")
    return prov


def work_dir_of(path: str | Path) -> Path:
    """Where an unfinished store ``path`` is being written: ``.NAME.partial`` beside it."""
    path = Path(path)
    return path.parent / f".{path.name}.partial"


def protected_files(path: str | Path, provenance: dict) -> list[str]:
    """The files no output of ``report`` or ``export`` may replace: the store at ``path`` and the files its
    provenance lists (the run's inputs and every file its script names)."""
    inputs = [f.get("path") for f in provenance.get("inputs") or [] if isinstance(f, dict)]
    named = provenance.get("named_files") or []
    return [str(path), *(p for p in [*inputs, *named] if isinstance(p, str) and p)]


def to_json(obj, what: str) -> str:
    try:
        return json.dumps(obj, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise StoreError(
            f"the {what} is not JSON-serialisable: {exc}.", fix=f"put only str, numbers, lists and dicts in the {what}."
        ) from exc


MAX_CHUNK_ROWS = 1 << 20
"""The most rows a chunk of a stored column may declare: the writer's chunks are at most
:data:`~demsplit.results.chunks.CHUNK_ROWS`; a larger one is not a store's (memory per chunk read is bounded)."""

_PROVENANCE_TYPES = {
    "inputs": list,
    "options": dict,
    "scene": dict,
    "model": dict,
    "notes": list,
    "bad_frames": list,
    "type_names": dict,
    "named_files": list,
    "not_computed": dict,
    "skipped": dict,
    "run": dict,
}
"""The type of each provenance entry that readers of a store use (a missing entry is fine)."""


class _Layout:
    """What a store holds, read from its index and attributes and checked (:func:`open_store`): the
    timesteps, each table's row offsets per frame and columns, the provenance and the walls' metadata."""

    def __init__(
        self,
        steps: np.ndarray,
        offsets: dict[str, np.ndarray],
        columns: dict[str, list[str]],
        provenance: dict,
        walls_meta: list,
    ) -> None:
        self.steps, self.offsets, self.columns = steps, offsets, columns
        self.provenance, self.walls_meta = provenance, walls_meta


def _damaged(path: Path, what: str, fix: str = "rerun demsplit run to rewrite it.") -> StoreError:
    return StoreError(f"the store is damaged: {what}", file=path, fix=fix)


def open_store(path: str | Path):
    """Open the result store ``path`` read-only and check its layout before any column is read: the format
    attributes, no data outside the file (external storage, links, virtual datasets), the index (one
    increasing int64 step per frame, row offsets from 0, non-decreasing), every table's columns (named in
    its ``columns`` attribute, 1-D, of the column's kind, as long as the index says, every chunk stored and
    none larger than :data:`MAX_CHUNK_ROWS`), and the provenance and walls' metadata (JSON of the types
    their readers use). Returns ``(h5py.File, layout)``; raises one :class:`StoreError` naming the file
    (and the table and column)."""
    import h5py

    from ..readers.hdf5_inputs import refuse_foreign_storage

    path = Path(path)
    if not path.is_file():
        work = work_dir_of(path)
        hint = f" An interrupted run left its finished frames in {work}." if work.exists() else ""
        raise StoreError(
            f"no result store here.{hint}",
            file=path,
            fix="run demsplit first (or continue the interrupted run: demsplit run ... --resume).",
        )
    try:
        h5 = h5py.File(path, "r")
    except Exception as exc:  # h5py raises OSError, and others on damaged metadata
        raise StoreError(
            f"not a readable HDF5 file ({type(exc).__name__}).",
            file=path,
            fix="point to a store written by demsplit run.",
        ) from None
    try:
        layout = _check_layout(h5, path, refuse_foreign_storage)
    except StoreError:
        h5.close()
        raise
    except Exception as exc:  # any other fault of the file's metadata, as h5py reports it
        h5.close()
        raise _damaged(path, f"its metadata cannot be read ({type(exc).__name__}: {_short(exc)}).") from None
    return h5, layout


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 200 else text[:200] + "..."


def _check_layout(h5, path: Path, refuse_foreign_storage) -> _Layout:
    import h5py

    from ..errors import InputFormatError

    if text_attribute(h5, "format") != FORMAT:
        raise StoreError(
            f"not a demsplit result store (its format attribute is not {FORMAT!r}).",
            file=path,
            fix="point to a store written by demsplit run.",
        )
    version = h5.attrs.get("format_version")
    if not isinstance(version, (int, np.integer)) or version < 1:
        raise _damaged(path, "its format_version attribute is not a positive integer.")
    if int(version) > FORMAT_VERSION:
        raise StoreError(
            f"store format version {int(version)} is newer than this demsplit reads ({FORMAT_VERSION}).",
            file=path,
            fix="upgrade demsplit.",
        )
    try:
        refuse_foreign_storage(h5, path)
    except InputFormatError as exc:
        raise StoreError(exc.message, file=path, fix="point to a store as demsplit run wrote it.") from None
    provenance = _json_attr(h5, "provenance", dict, path)
    for key, kind in _PROVENANCE_TYPES.items():
        if key in provenance and provenance[key] is not None and not isinstance(provenance[key], kind):
            raise _damaged(path, f"its provenance entry {key!r} is not a JSON {kind.__name__}.")
    for key, kind in (("inputs", dict), ("bad_frames", dict), ("notes", str), ("named_files", str)):
        if any(not isinstance(v, kind) for v in provenance.get(key) or []):
            raise _damaged(path, f"an item of its provenance entry {key!r} is not a JSON {kind.__name__}.")
    _check_names(provenance, path)
    walls_meta = _json_attr(h5, "walls_meta", list, path)
    for w in walls_meta:
        if not (
            isinstance(w, dict)
            and _small_int(w.get("wall"))
            and w["wall"] >= 0
            and isinstance(w.get("name"), str)
            and isinstance(w.get("kind"), str)
            and (w.get("type") is None or _small_int(w["type"]))
        ):
            raise _damaged(path, "an entry of its walls_meta attribute is not {wall: index, name, kind, type}.")
    if len({w["wall"] for w in walls_meta}) != len(walls_meta):
        raise _damaged(path, "its walls_meta attribute lists a wall twice.")
    index = h5.get("index")
    if not isinstance(index, h5py.Group):
        raise _damaged(path, "it has no index group.")
    steps = _index_column(index, "step", path)
    if len(steps) and np.any(np.diff(steps) <= 0):
        k = int(np.flatnonzero(np.diff(steps) <= 0)[0]) + 1
        raise _damaged(
            path,
            f"frame {k} has timestep {int(steps[k])}, not after the frame before it "
            f"({int(steps[k - 1])}): each frame is stored once, in step order.",
        )
    offsets, columns = {}, {}
    for name in TABLES:
        off = _index_column(index, name, path)
        if len(off) != len(steps) + 1 or (len(off) and off[0] != 0) or np.any(np.diff(off) < 0):
            raise _damaged(path, f"index/{name} is not {len(steps) + 1} non-decreasing row offsets from 0.")
        offsets[name] = off
        group = h5.get(name)
        if not isinstance(group, h5py.Group):
            raise _damaged(path, f"it has no {name} table.")
        try:
            cols = json.loads(group.attrs["columns"])
        except (KeyError, TypeError, ValueError):
            cols = None
        if not (isinstance(cols, list) and all(isinstance(c, str) for c in cols) and len(set(cols)) == len(cols)):
            raise _damaged(path, f"the {name} table's columns attribute is not a JSON list of distinct names.")
        for col in cols:
            _check_column(group.get(col), name, col, int(off[-1]), path)
        columns[name] = cols
    if "step" in columns["frames"] and int(offsets["frames"][-1]) != len(steps):
        raise _damaged(path, f"the frames table has {int(offsets['frames'][-1])} rows for {len(steps)} frames.")
    return _Layout(steps, offsets, columns, provenance, walls_meta)


def _small_int(value) -> bool:
    """Whether a JSON value is an integer of 32 bits (an index, a material type; not a bool)."""
    return isinstance(value, int) and not isinstance(value, bool) and -(2**31) <= value < 2**31


def _check_names(provenance: dict, path: Path) -> None:
    """The material names the readers of a store look up by type: ``type_names`` and the scene's materials,
    keyed by the decimal text of a type; the simulator's own energies the report prints (``run.yade_energies``)."""
    scene = provenance.get("scene") or {}
    if not isinstance(scene.get("walls") or [], list) or not isinstance(scene.get("source") or "", str):
        raise _damaged(path, "its provenance's scene has walls that are not a list, or a source that is not text.")
    materials = scene.get("materials")
    for what, names in (("type_names", provenance.get("type_names") or {}), ("scene materials", materials or {})):
        if not isinstance(names, dict) or not all(
            isinstance(t, str) and t.lstrip("-").isdecimal() and _small_int(int(t)) for t in names
        ):
            raise _damaged(path, f"its provenance's {what} are not keyed by material type.")
    if any(not isinstance(n, str) for n in (provenance.get("type_names") or {}).values()) or any(
        not isinstance(m, dict) for m in (materials or {}).values()
    ):
        raise _damaged(path, "its provenance's material names are not text, or its materials not JSON objects.")
    run = provenance.get("run") or {}
    energies = run.get("yade_energies", []) if isinstance(run, dict) else None
    if not isinstance(energies, list) or not all(
        isinstance(e, dict)
        and isinstance(e.get("step"), int)
        and not isinstance(e.get("step"), bool)
        and isinstance(e.get("name"), str)
        and isinstance(e.get("value"), (int, float))
        and not isinstance(e.get("value"), bool)
        and math.isfinite(e["value"])
        and isinstance(e.get("modes"), list)
        and all(isinstance(m, str) for m in e["modes"])
        for e in energies
    ):
        raise _damaged(path, "its provenance's run, or the simulator's own energies it lists, are not as written.")


def _json_attr(h5, name: str, kind: type, path: Path):
    text = h5.attrs.get(name)
    try:
        value = json.loads(text, parse_constant=_no_constant) if isinstance(text, (str, bytes)) else None
    except ValueError:
        value = None
    if not isinstance(value, kind):
        raise _damaged(path, f"its {name} attribute is not a JSON {kind.__name__}.")
    return value


def _no_constant(name: str):
    """JSON's NaN and Infinity: no stored number is one."""
    raise ValueError(f"{name} in JSON")


def _index_column(index, name: str, path: Path) -> np.ndarray:
    import h5py

    d = index.get(name)
    if not isinstance(d, h5py.Dataset) or d.ndim != 1 or d.dtype.kind not in "iu" or d.dtype.itemsize > 8:
        raise _damaged(path, f"index/{name} is not a 1-D integer dataset.")
    if d.size > MAX_CHUNK_ROWS * 64:
        raise _damaged(path, f"index/{name} declares {d.size} frames.")
    _check_storage(d, f"index/{name}", path)
    return d[()].astype(np.int64)


def _check_column(d, table: str, col: str, rows: int, path: Path) -> None:
    """A column of a stored table: a 1-D dataset of its kind, ``rows`` long, its data all in the file."""
    import h5py

    where = f"table {table}, column {col}"
    if not isinstance(d, h5py.Dataset):
        raise _damaged(path, f"{where} is missing.")
    kind = canonical_dtype(col).kind
    if d.ndim != 1 or d.dtype.kind not in ("iu" if kind in "iu" else "f") or d.dtype.itemsize > 8:
        raise _damaged(
            path,
            f"{where} is {d.dtype} of shape {d.shape}, not a column of "
            f"{'integers' if kind in 'iu' else 'real numbers'}.",
        )
    if d.shape[0] != rows:
        raise _damaged(path, f"{where} has {d.shape[0]} rows; the index says {rows}.")
    if d.chunks is not None and d.chunks[0] > MAX_CHUNK_ROWS:
        raise _damaged(path, f"{where} is stored in chunks of {d.chunks[0]} rows (at most {MAX_CHUNK_ROWS}).")
    _check_storage(d, where, path)


def _check_storage(d, where: str, path: Path) -> None:
    """Every chunk (or the contiguous block) of the dataset ``d`` is in the file: a dataset that declares rows it
    does not hold is damage (and would be read as its fill value, at any size it declares)."""
    if d.size == 0:
        return
    if d.chunks is None:
        stored = d.id.get_storage_size() >= d.nbytes
    else:
        stored = d.id.get_num_chunks() == -(-d.shape[0] // d.chunks[0])
    if not stored:
        raise _damaged(path, f"{where} declares {d.shape[0]} rows that the file does not hold.")


def read_store(path: str | Path, *, steps: Iterable[int] | None = None, every_frame_row: bool = False) -> Results:
    """Read a store into :class:`~demsplit.results.Results` (every frame, or only
    timesteps ``steps``, each read through the frame index without the rest;
    ``every_frame_row``: the ``frames`` table of every frame all the same, e.g.
    for the energy balance of a whole run beside one frame's tables). The store is checked as an input
    (:func:`open_store`), and every value read: finite, each frame's particles, walls and particle pairs
    listed once."""
    path = Path(path)
    h5, layout = open_store(path)
    try:
        with h5:
            return _read_tables(h5, layout, path, steps, every_frame_row)
    except StoreError:
        raise
    except MemoryError:
        raise StoreError(
            "the store does not fit in memory.",
            file=path,
            fix="read fewer frames at a time (load_results(path, steps=[...])).",
        ) from None
    except Exception as exc:  # a chunk h5py cannot decode (a damaged byte, a filter it does not have)
        raise _damaged(path, f"its data cannot be read ({type(exc).__name__}: {_short(exc)}).") from None


def _read_tables(h5, layout: _Layout, path: Path, steps: Iterable[int] | None, every_frame_row: bool) -> Results:
    stored_steps = layout.steps
    frames_k = np.arange(len(stored_steps))
    if steps is not None:
        wanted = np.asarray(list(steps), dtype=np.int64)
        missing = np.setdiff1d(wanted, stored_steps)
        if len(missing):
            raise StoreError(
                f"timestep(s) {missing.tolist()[:10]} are not in the store ({len(stored_steps)} frames).",
                file=path,
                fix="pick stored timesteps.",
            )
        frames_k = frames_k[np.isin(stored_steps, wanted)]
    frames = {}
    for name in TABLES:
        group, off = h5[name], layout.offsets[name]
        whole = steps is None or (every_frame_row and name == "frames")
        table = {}
        for col in layout.columns[name]:
            values = (
                group[col][()]
                if whole
                else np.concatenate(
                    [group[col][off[k] : off[k + 1]] for k in frames_k] or [np.empty(0, group[col].dtype)]
                )
            )
            table[col] = _checked_column(values, name, col, path)
        _check_rows(
            table,
            name,
            path,
            stored_steps if whole else stored_steps[frames_k],
            off if whole else np.concatenate([[0], np.cumsum(np.diff(off)[frames_k])]),
        )
        frames[name] = to_dataframe(table)
    return Results(**frames, provenance=layout.provenance, walls_meta=layout.walls_meta)


def _checked_column(values: np.ndarray, table: str, col: str, path: Path) -> np.ndarray:
    """A column as read, in its canonical dtype; a value that is not finite is damage (a frames column of
    :data:`UNKNOWN_COLUMNS` written before :data:`UNKNOWN` held NaN for an unknown value: it is read as it)."""
    values = values.astype(canonical_dtype(col), copy=False)
    if values.dtype.kind == "f":
        bad = ~np.isfinite(values)
        if table == "frames" and col in UNKNOWN_COLUMNS:
            values = np.where(np.isnan(values), UNKNOWN, values)
            bad = ~np.isfinite(values)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise _damaged(
                path,
                f"table {table}, column {col}, row {row} is {float(values[row])} "
                f"({int(bad.sum())} value(s) are not finite; demsplit stores none).",
            )
    return values


_KEYS = {"particles": ("id",), "walls": ("wall",)}
"""The columns that name a row of each table within its frame."""


def _check_rows(table: Table, name: str, path: Path, steps: np.ndarray, offsets: np.ndarray) -> None:
    """Each row of ``table`` in the frame the index puts it in, and named once there (:data:`_KEYS`)."""
    if "step" in table and len(table["step"]):
        expected = np.repeat(steps, np.diff(offsets))
        bad = table["step"] != expected
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise _damaged(
                path,
                f"table {name}, row {row} has timestep {int(table['step'][row])}; the index puts it "
                f"in the frame of timestep {int(expected[row])}.",
            )
    if name == "frames" and "step" in table and not np.array_equal(table["step"], steps):
        raise _damaged(path, "the frames table's timesteps are not the index's.")
    keys = _KEYS.get(name)
    if not keys or not set(keys) <= set(table) or "step" not in table:
        return
    cols = [table[c] for c in ("step", *keys)]
    if len(cols[0]) < 2:
        return
    order = np.lexsort(cols[::-1])
    same = np.ones(len(order) - 1, dtype=bool)
    for c in cols:
        same &= c[order][1:] == c[order][:-1]
    if same.any():
        row = int(order[int(np.flatnonzero(same)[0]) + 1])
        who = " ".join(f"{c} {int(table[c][row])}" for c in keys)
        raise _damaged(path, f"table {name}, timestep {int(table['step'][row])}: {who} is listed twice (row {row}).")


def read_last_frame(path: str | Path) -> Results:
    """The last frame's tables and every frame's row of the ``frames`` table:
    what ``demsplit run`` summarises, in memory independent of the number of
    frames."""
    h5, layout = open_store(path)
    h5.close()
    return read_store(path, steps=layout.steps[-1:], every_frame_row=True)


def load_results(path: str | Path, *, steps: Iterable[int] | None = None) -> Results:
    """Read a result store written by :class:`~demsplit.results.writer.ResultWriter` (all frames, or only
    timesteps ``steps``)."""
    return read_store(path, steps=steps)
