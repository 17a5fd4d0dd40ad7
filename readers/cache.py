"""Ingest cache: a run's frames converted once to HDF5, read back much faster.

``demsplit convert IN -o CACHE.h5`` (:func:`convert_run`) opens any run
:func:`demsplit.readers.open_run` reads (a LIGGGHTS script with its dumps, a
YADE snapshot), and writes every frame exactly as the reader built it: the
canonical ``particles`` and ``contacts`` tables, box, step, time, overlap
source and per-contact error bound, notes and source files, plus the
:class:`~demsplit.scene.Scene`. ``open_run(CACHE.h5)`` then returns a
:class:`CacheRun` whose frames equal the text reader's, bit for bit, without
parsing, index scan or geometry rebuild (``benchmarks/bench.py`` measures the
speed-up).

Layout (root attribute ``format`` = ``"demsplit-ingest-cache"``, ``version``)::

    /                attrs: format, version, scene (JSON), describe (JSON), sources (JSON),
                            n_frames, steps (int64 array)
    /frames/000000   attrs: step, time (NaN if unknown), source (JSON), overlap_source, notes (JSON),
                            box_lo, box_hi, box_periodic, box_tilt (absent without a box),
                            error (JSON: class, message, file, step, line, fix) for a frame
                            the reader refused
        particles/<column>   one contiguous, uncompressed dataset per column
        contacts/<column>
        overlap_error        (absent when the frame has none)

Reading: h5py serialises every HDF5 call on one lock, so reading a frame's
columns through it copies them one at a time. A contiguous dataset's bytes
lie at one offset in the file (``DatasetID.get_offset``), so :class:`CacheRun`
reads each column with ``os.preadv`` straight into its array, the columns
spread over :func:`demsplit.runtime.threads.pool` (``preadv`` releases the GIL). A
dataset that is not contiguous, native-endian and unfiltered (a cache someone
repacked with ``h5repack``, say) is read through h5py, into native byte
order (what it saves: ``docs/performance.md``).

The file is written to a temporary name in the same directory and renamed
when complete, so a cache is either whole or absent. A frame the reader
refused (damaged dump frame) is stored as its error and raised again, with
the same class and message, by :meth:`CacheRun.frame`.
"""

from __future__ import annotations

import json
import os
from dataclasses import replace
from pathlib import Path

import h5py
import numpy as np

from .. import errors
from ..errors import ContactError, DemsplitError, InputFormatError
from ..frame import CONTACT_REQUIRED, PARTICLE_REQUIRED, Box, Frame, ParticleIndex, require_columns
from ..outputs import HDF5_SIGNATURE, atomic_path, check_output_path, hdf5_kind, output_errors, text_attribute
from ..runtime.threads import pool
from ..scene import scene_from_dict, scene_to_dict
from ..validate import validated_frame
from .base import Run
from .hdf5_inputs import refuse_foreign_storage

FORMAT = "demsplit-ingest-cache"
VERSION = 2
"""2: the scene's contact model is (law, params) of the law registry; 1 (normal, tangential) is not read."""
H5_FAULTS = (OSError, RuntimeError, KeyError, ValueError, TypeError)
"""What h5py raises on a file whose metadata or chunks are damaged (and json on a damaged attribute)."""
CACHE = hdf5_kind("demsplit ingest cache", FORMAT)
"""The output kind of ``convert``: an existing cache is replaced by a new one, any other file is not."""


# --------------------------------------------------------------------------- scene <-> JSON

# --------------------------------------------------------------------------- writing


def convert_run(input: str | Path, output: str | Path, *, overwrite: bool = False, **reader_options) -> Path:
    """Write every frame of the run ``input`` to the cache ``output`` (atomically).

    ``reader_options`` go to :func:`demsplit.readers.open_run`. Frames are
    streamed: one in memory at a time. Returns the path written. ``output`` is never a file of the run,
    nor an existing file that is not an ingest cache unless ``overwrite`` (:mod:`demsplit.outputs`).
    """
    from . import open_run

    run = open_run(input, **reader_options)
    try:
        output = check_output_path(output, run.named_files(), kind=CACHE, overwrite=overwrite)
        # no chunk cache: each dataset is written once, whole (a cache only holds memory)
        with output_errors(output), atomic_path(output) as tmp, h5py.File(tmp, "w", rdcc_nbytes=0) as h5:
            h5.attrs["format"] = FORMAT
            h5.attrs["version"] = VERSION
            h5.attrs["scene"] = json.dumps(scene_to_dict(run.scene))
            h5.attrs["describe"] = json.dumps(run.describe(), default=str)
            h5.attrs["sources"] = json.dumps([str(s) for s in run.sources])
            frames = h5.create_group("frames")
            steps = []
            for k in range(len(run)):
                g = frames.create_group(f"{k:06d}")
                try:
                    frame = run.frame(k)
                except DemsplitError as exc:  # kept, and raised again when the frame is read
                    g.attrs["error"] = json.dumps(
                        {
                            "class": type(exc).__name__,
                            "message": exc.message,
                            "file": exc.file,
                            "step": exc.step,
                            "line": exc.line,
                            "fix": exc.fix,
                        }
                    )
                    steps.append(
                        exc.step if exc.step is not None else int(run.steps[k]) if k < len(run.steps) else None
                    )  # a damaged frame past the readable ones: its step is not known
                    continue
                _write_frame(g, frame)
                steps.append(frame.step)
                del frame  # not alive while the next frame is read (peak memory: one frame)
            h5.attrs["n_frames"] = len(steps)
            h5.attrs["steps"] = np.array([-1 if s is None else s for s in steps], dtype=np.int64)
    finally:
        run.close()
    return output


def _write_frame(g: h5py.Group, frame: Frame) -> None:
    g.attrs["step"] = int(frame.step)
    g.attrs["time"] = np.nan if frame.time is None else float(frame.time)
    g.attrs["source"] = json.dumps(list(frame.source))
    g.attrs["overlap_source"] = frame.overlap_source
    g.attrs["notes"] = json.dumps(list(frame.notes))
    g.attrs["walls"] = json.dumps(None if frame.walls is None else list(frame.walls))
    if frame.box is not None:
        g.attrs["box_lo"], g.attrs["box_hi"] = frame.box.lo, frame.box.hi
        g.attrs["box_periodic"] = np.array(frame.box.periodic, dtype=bool)
        g.attrs["box_tilt"] = frame.box.tilt
    for name, table in (("particles", frame.particles), ("contacts", frame.contacts)):
        t = g.create_group(name)
        t.attrs["order"] = json.dumps(list(table))  # column order, as the reader built it
        for col, values in table.items():
            t.create_dataset(col, data=np.ascontiguousarray(values))
    if frame.overlap_error is not None:
        g.create_dataset("overlap_error", data=frame.overlap_error)


# --------------------------------------------------------------------------- reading


def is_cache(path: str | Path) -> bool:
    """True when ``path`` is an HDF5 file written by :func:`convert_run` (False for one whose metadata cannot
    even be read: the reader of its format, if any, names the damage)."""
    try:
        with h5py.File(path, "r") as h5:
            return text_attribute(h5, "format") == FORMAT
    except H5_FAULTS:
        return False


class CacheRun(Run):
    """A run read from an ingest cache (see the module docstring)."""

    format_name = "demsplit-cache"
    formats = ("an ingest cache written by demsplit convert",)
    priority = 10  # an HDF5 file: asked before the YADE snapshot reader, which takes any other HDF5 file

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is not None and head.startswith(HDF5_SIGNATURE) and is_cache(path)

    @classmethod
    def open(cls, path: Path | None, **options) -> CacheRun:
        """Open an ingest cache; reader options are not accepted (they were applied by ``convert``)."""
        if options:
            raise InputFormatError(
                f"reader options {sorted(options)} do not apply to an ingest cache: they "
                "were fixed when it was written.",
                file=path,
                fix="convert the run again with these options, or pass the original run.",
            )
        return cls(path)

    def __init__(self, path: str | Path) -> None:
        self.path = str(path)
        try:
            self._h5 = h5py.File(path, "r")
        except Exception:  # h5py's errors on a damaged file are OSError and others
            raise self._damaged("it is not a readable HDF5 file.") from None
        try:
            self._open()
        except H5_FAULTS as exc:
            self._h5.close()
            raise self._damaged(
                f"it cannot be read ({type(exc).__name__}: {' '.join(str(exc).split())[:200]})."
            ) from None
        except BaseException:
            self._h5.close()
            raise
        self._fd = os.open(path, os.O_RDONLY)

    def _damaged(self, what: str, k: int | None = None, step: int | None = None) -> InputFormatError:
        """The error of a cache whose content is not what convert wrote: it names the cache (and the frame)."""
        return InputFormatError(
            f"the ingest cache is damaged: {'' if k is None else f'frame {k}: '}{what}",
            file=self.path,
            step=step,
            fix="convert the run again (demsplit convert RUN -o CACHE.h5), or give the run itself.",
        )

    def _open(self) -> None:
        """Check the cache's attributes and frame groups (what :func:`convert_run` writes) and read the scene."""
        attrs = self._h5.attrs
        if text_attribute(self._h5, "format") != FORMAT:
            raise InputFormatError(
                f"not a demsplit ingest cache (its format attribute is not {FORMAT!r}).",
                file=self.path,
                fix="write one with 'demsplit convert RUN -o CACHE.h5'.",
            )
        version = attrs.get("version")
        if not isinstance(version, (int, np.integer)):
            raise self._damaged("its version attribute is not an integer.")
        if int(version) != VERSION:
            raise InputFormatError(
                f"cache format version {int(version)} is "
                f"{'newer' if version > VERSION else 'older'} than this demsplit reads "
                f"({VERSION}).",
                file=self.path,
                fix="convert the run again with this version of demsplit.",
            )
        refuse_foreign_storage(self._h5, self.path)
        steps = attrs.get("steps")
        if not (isinstance(steps, np.ndarray) and steps.ndim == 1 and steps.dtype.kind in "iu"):
            raise self._damaged("its steps attribute is not a list of integers.")
        steps = steps.astype(np.int64)
        self._n_frames = len(steps)  # a damaged frame past the readable ones is stored with step -1
        self.steps = steps[: len(steps) - int(np.argmax(steps[::-1] >= 0)) if (steps >= 0).any() else 0]
        self.sources = [self.path] + self._json(attrs, "sources", list, str)
        self._describe = self._json(attrs, "describe", dict)
        try:
            self.scene = scene_from_dict(self._json(attrs, "scene", dict))
        except DemsplitError:
            raise
        except Exception as exc:  # whatever the scene's parts make of a damaged dict
            raise self._damaged(f"its scene attribute cannot be read ({type(exc).__name__}).") from None
        self.notes = []
        frames = self._h5.get("frames")
        names = [f"{k:06d}" for k in range(self._n_frames)]
        if (
            not isinstance(frames, h5py.Group)
            or sorted(frames) != names
            or not all(isinstance(frames[n], h5py.Group) for n in names)
        ):
            raise self._damaged(f"its frames group does not hold one group per frame ({self._n_frames}).")
        if attrs.get("n_frames", self._n_frames) != self._n_frames:
            raise self._damaged("its n_frames attribute is not the number of its frames.")
        self._frames = frames
        self._boxed = next(("box_lo" in frames[n].attrs for n in names if "error" not in frames[n].attrs), False)

    def _json(self, attrs, name: str, kind: type, item: type | None = None, k: int | None = None):
        """The attribute ``name`` (JSON) as a ``kind`` (of ``item``s)."""
        try:
            value = json.loads(attrs[name], parse_constant=_no_constant)
        except (KeyError, TypeError, ValueError):
            value = None
        if not isinstance(value, kind) or (item is not None and not all(isinstance(v, item) for v in value)):
            raise self._damaged(
                f"its {name} attribute is not a JSON {kind.__name__}"
                + (f" of {item.__name__}" if item is not None else "")
                + ".",
                k,
            )
        return value

    def __len__(self) -> int:
        return self._n_frames  # the damaged frames past ``steps`` (stored with step -1) included

    def frame(self, k: int) -> Frame:
        """Frame ``k`` exactly as the original reader built it, after the checks the pipeline makes of every
        frame (:func:`~demsplit.validate.validated_frame`, particle ids once, contacts of known particles and
        walls, each pair once): damage of the cache is named as the cache's, never as the dump it came from."""
        if not -len(self) <= k < len(self):
            raise IndexError(f"{self.path}: frame {k} out of range ({len(self)} frames)")
        k %= len(self)
        try:
            frame = self._frame(k)
        except H5_FAULTS as exc:  # what h5py raises on damaged metadata or chunks
            raise self._damaged(
                f"it cannot be read ({type(exc).__name__}: {' '.join(str(exc).split())[:200]}).", k, self._step(k)
            ) from None
        self._check(frame, k)
        return frame

    def _step(self, k: int) -> int | None:
        """Frame ``k``'s step; None for a damaged frame past the readable ones."""
        return int(self.steps[k]) if k < len(self.steps) else None

    def _frame(self, k: int) -> Frame:
        g = self._frames[f"{k:06d}"]
        a = g.attrs
        step = self._step(k)
        if "error" in a:
            raise self._error(self._json(a, "error", dict, k=k), k)
        try:
            if int(a["step"]) != step:
                raise self._damaged(f"its step attribute {int(a['step'])} is not the cache's step for it.", k, step)
            box = None
            if ("box_lo" in a) != self._boxed:  # a reader gives every frame a box, or none
                raise self._damaged("its box attributes are not those of its other frames.", k, step)
            if "box_lo" in a:
                box = Box(
                    *(np.array(a[n], dtype=np.float64).reshape(3) for n in ("box_lo", "box_hi")),
                    tuple(bool(p) for p in np.array(a["box_periodic"]).reshape(3)),
                    np.array(a["box_tilt"], dtype=np.float64).reshape(3),
                )
            time = float(a["time"])
            overlap_source = a["overlap_source"]
            if not isinstance(overlap_source, str):
                raise TypeError("overlap_source")
            walls = _walls(a)
        except (KeyError, TypeError, ValueError) as exc:
            raise self._damaged(
                f"an attribute is missing or of another kind ({type(exc).__name__}: {exc}).", k, step
            ) from None
        datasets = {}
        for name in ("particles", "contacts"):
            order = self._json(g[name].attrs if isinstance(g.get(name), h5py.Group) else {}, "order", list, str, k)
            if sorted(order) != sorted(g[name]):
                raise self._damaged(f"the {name} table's columns are not those its order attribute lists.", k, step)
            datasets.update({(name, col): self._dataset(g, name, col, k, step) for col in order})  # the reader's order
        if "overlap_error" in g:
            datasets["overlap_error", None] = self._dataset(g, "overlap_error", None, k, step)
        arrays = self._read(datasets)
        particles, contacts = (
            {col: v for (name, col), v in arrays.items() if name == table} for table in ("particles", "contacts")
        )
        frame = Frame(
            step=step,
            particles=particles,
            contacts=contacts,
            box=box,
            time=None if np.isnan(time) else time,
            source=tuple(self._json(a, "source", list, str, k=k)),
            overlap_source=overlap_source,
            overlap_error=arrays.get(("overlap_error", None)),
            notes=self._json(a, "notes", list, str, k=k),
            walls=walls,
        )
        return frame

    def _dataset(self, g, name: str, col: str | None, k: int, step: int):
        """The dataset of a frame's column: 1-D, of numbers, every chunk in the file."""
        d = g.get(name) if col is None else g[name].get(col)
        what = name if col is None else f"{name} column {col}"
        if not isinstance(d, h5py.Dataset) or d.ndim != 1 or d.dtype.kind not in "biuf" or d.dtype.itemsize > 8:
            raise self._damaged(f"{what} is not a 1-D column of numbers.", k, step)
        if d.chunks is not None and d.size and d.id.get_num_chunks() != -(-d.shape[0] // d.chunks[0]):
            raise self._damaged(f"{what} declares {d.shape[0]} rows that the file does not hold.", k, step)
        return d

    def _check(self, frame: Frame, k: int) -> None:
        """The pipeline's checks of a frame, and the cache's own: every table's columns of one length, the
        overlap bounds one per contact, walls the scene has, each contact pair once."""
        for name, table in (("particles", frame.particles), ("contacts", frame.contacts)):
            lengths = {len(v) for v in table.values()}
            if len(lengths) > 1:
                raise self._damaged(f"the {name} columns are not of one length ({sorted(lengths)}).", k, frame.step)
        if frame.overlap_error is not None and len(frame.overlap_error) != frame.n_contacts:
            raise self._damaged("the overlap bounds are not one per contact.", k, frame.step)
        try:
            require_columns(frame.particles, PARTICLE_REQUIRED, "particles")
            require_columns(frame.contacts, CONTACT_REQUIRED, "contacts")
            checked = validated_frame(replace(frame, source=()), self.scene)
            c = checked.contacts
            wall = c["wall"]
            if len(wall) and (wall.min() < -1 or wall.max() >= len(self.scene.walls)):
                raise ContactError(
                    f"a contact names wall {int(wall[(wall < -1) | (wall >= len(self.scene.walls))][0])}"
                    f"; the scene has {len(self.scene.walls)}."
                )
            from ..kernels import repeated_pair  # compiled, lazily

            index = ParticleIndex(checked.particles["id"])
            rows1, rows2 = index.contact_rows(c["id1"], c["id2"], wall)
            pair = wall < 0
            first, repeat = repeated_pair(rows1[pair], rows2[pair], len(index.ids))
            if repeat >= 0:
                ids = c["id1"][pair][repeat], c["id2"][pair][repeat]
                raise ContactError(
                    f"particle {int(ids[0])} is paired with itself."
                    if first == repeat
                    else f"the contact of particles {int(ids[0])} and {int(ids[1])} is listed twice."
                )
        except DemsplitError as exc:
            raise self._damaged(exc.message, k, frame.step) from None

    def _error(self, e: dict, k: int) -> DemsplitError:
        """The error a refused frame was stored as, raised again with its class and message."""
        cls = getattr(errors, str(e.get("class")), None)
        fields = {"file": str, "step": int, "line": int, "fix": str}
        if not (
            isinstance(cls, type)
            and issubclass(cls, DemsplitError)
            and isinstance(e.get("message"), str)
            and all(e.get(f) is None or isinstance(e.get(f), t) for f, t in fields.items())
        ):
            raise self._damaged("its stored error is not one demsplit wrote.", k, self._step(k))
        return cls(e["message"], **{f: e.get(f) for f in fields})

    def describe(self) -> dict:
        """The original reader's description, with the cache named."""
        return {**self._describe, "cache": self.path}

    def close(self) -> None:
        if self._fd >= 0:
            self._h5.close()
            os.close(self._fd)
            self._fd = -1

    def _read(self, datasets: dict) -> dict:
        """The arrays of ``datasets`` (same keys), read in parallel where the
        layout allows (module docstring: Reading)."""
        out, direct = {}, []
        for key, d in datasets.items():
            offset = d.id.get_offset()
            out[key] = np.empty(d.shape, d.dtype.newbyteorder("="))
            if offset is None or d.chunks is not None or d.external or not d.dtype.isnative:
                if d.size:
                    d.read_direct(out[key])  # HDF5 decodes (and converts to native byte order)
            else:
                direct.append((offset, out[key]))
        for _ in pool().map(lambda job: self._pread(*job), direct):
            pass
        return out

    def _pread(self, offset: int, into: np.ndarray) -> None:
        """Fill ``into`` with the file's bytes from ``offset`` on."""
        view = memoryview(into).cast("B")
        done = 0
        while done < len(view):
            got = os.preadv(self._fd, [view[done:]], offset + done)
            if not got:
                raise InputFormatError(
                    f"the cache ends inside a dataset (byte {offset + done}).",
                    file=self.path,
                    fix="the file was cut short: convert the run again.",
                )
            done += got


def _no_constant(name: str):
    """JSON's NaN and Infinity: no attribute convert writes holds them."""
    raise ValueError(f"{name} in JSON")


def _walls(attrs) -> tuple[int, ...] | None:
    """A frame's walls as :func:`_write_frame` stored them (a cache without them: every wall)."""
    walls = json.loads(attrs["walls"]) if "walls" in attrs else None
    return None if walls is None else tuple(int(w) for w in walls)
