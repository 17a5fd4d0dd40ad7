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
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ..errors import StoreError
from ..fingerprint import file_fingerprint
from ..scene import scene_to_dict
from .schema import TABLES, UNKNOWN, UNKNOWN_COLUMNS, to_dataframe
from .tables import Results

FORMAT = "demsplit-results"
FORMAT_VERSION = 1


def demsplit_version() -> str:
    """The installed demsplit version ("unknown" when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("demsplit")
    except PackageNotFoundError:
        return "unknown"


def build_provenance(inputs: Iterable[str | Path], *, scene=None, options: dict | None = None, wait: bool = True,
                     **extra) -> dict:
    """A provenance dict: ``inputs`` (fingerprints), ``scene`` (materials per type,
    walls) and ``model`` (contact model) from a :class:`demsplit.scene.Scene`,
    ``options``, ``demsplit_version``, plus any ``extra`` entries (e.g.
    ``overlap_source``, ``skipped``, ``bad_frames``). Must be JSON-serialisable.
    ``wait=False``: an input whose digest is still being computed has digest None
    (:func:`~demsplit.fingerprint.file_fingerprint`), which the
    :class:`~demsplit.results.writer.ResultWriter` fills in."""
    prov: dict = {"inputs": [file_fingerprint(p, wait=wait) for p in inputs], "options": dict(options or {}),
                  "demsplit_version": demsplit_version()}
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


def to_json(obj, what: str) -> str:
    try:
        return json.dumps(obj, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise StoreError(f"the {what} is not JSON-serialisable: {exc}.",
                         fix=f"put only str, numbers, lists and dicts in the {what}.") from exc


def read_store(path: str | Path, *, steps: Iterable[int] | None = None, every_frame_row: bool = False) -> Results:
    """Read a store into :class:`~demsplit.results.Results` (every frame, or only
    timesteps ``steps``, each read through the frame index without the rest;
    ``every_frame_row``: the ``frames`` table of every frame all the same, e.g.
    for the energy balance of a whole run beside one frame's tables)."""
    import h5py

    path = Path(path)
    if not path.is_file():
        work = work_dir_of(path)
        hint = f" An interrupted run left its finished frames in {work}." if work.exists() else ""
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
                if steps is None or (every_frame_row and name == "frames"):
                    table = {col: group[col][()] for col in columns}
                else:
                    table = {col: np.concatenate([group[col][off[k]:off[k + 1]] for k in frames_k]
                                                 or [np.empty(0, group[col].dtype)]) for col in columns}
                if name == "frames":  # stores written before UNKNOWN held NaN for it
                    for col in set(UNKNOWN_COLUMNS) & set(table):
                        table[col] = np.where(np.isnan(table[col]), UNKNOWN, table[col])
                frames[name] = to_dataframe(table)
            return Results(**frames, provenance=json.loads(h5.attrs["provenance"]),
                           walls_meta=json.loads(h5.attrs["walls_meta"]))
    except (KeyError, ValueError, OSError) as exc:  # a group, dataset or attribute missing or unreadable
        raise StoreError(f"the store is damaged or incomplete ({type(exc).__name__}: {exc}).", file=path,
                         fix="rerun demsplit run to rewrite it.") from exc


def read_last_frame(path: str | Path) -> Results:
    """The last frame's tables and every frame's row of the ``frames`` table:
    what ``demsplit run`` summarises, in memory independent of the number of
    frames."""
    import h5py

    try:
        with h5py.File(path, "r") as h5:
            stored = h5["index/step"][()]
    except (OSError, KeyError):
        return read_store(path)  # read_store names what is wrong with the file
    return read_store(path, steps=stored[-1:], every_frame_row=True)


def load_results(path: str | Path, *, steps: Iterable[int] | None = None) -> Results:
    """Read a result store written by :class:`~demsplit.results.writer.ResultWriter` (all frames, or only
    timesteps ``steps``)."""
    return read_store(path, steps=steps)
