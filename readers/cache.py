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
from pathlib import Path

import h5py
import numpy as np

from .. import errors
from ..outputs import atomic_path
from ..errors import DemsplitError, InputFormatError, plain
from ..frame import Box, Frame
from ..outputs import check_output_path
from ..scene import scene_from_dict, scene_to_dict
from ..runtime.threads import pool
from .base import Run
from .hdf5_inputs import refuse_foreign_storage

FORMAT = "demsplit-ingest-cache"
VERSION = 2
"""2: the scene's contact model is (law, params) of the law registry; 1 (normal, tangential) is not read."""
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


# --------------------------------------------------------------------------- scene <-> JSON

# --------------------------------------------------------------------------- writing

def convert_run(input: str | Path, output: str | Path, **reader_options) -> Path:
    """Write every frame of the run ``input`` to the cache ``output`` (atomically).

    ``reader_options`` go to :func:`demsplit.readers.open_run`. Frames are
    streamed: one in memory at a time. Returns the path written.
    """
    from . import open_run

    run = open_run(input, **reader_options)
    try:
        output = check_output_path(output, run.named_files())
        # no chunk cache: each dataset is written once, whole (a cache only holds memory)
        with atomic_path(output) as tmp, h5py.File(tmp, "w", rdcc_nbytes=0) as h5:
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
                    g.attrs["error"] = json.dumps({"class": type(exc).__name__, "message": exc.message,
                                                   "file": exc.file, "step": exc.step, "line": exc.line,
                                                   "fix": exc.fix})
                    steps.append(exc.step if exc.step is not None else int(run.steps[k]) if k < len(run.steps)
                                 else None)  # a damaged frame past the readable ones: its step is not known
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
    """True when ``path`` is an HDF5 file written by :func:`convert_run`."""
    try:
        with h5py.File(path, "r") as h5:
            return h5.attrs.get("format") == FORMAT
    except OSError:
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
            raise InputFormatError(f"reader options {sorted(options)} do not apply to an ingest cache: they "
                                   "were fixed when it was written.", file=path,
                                   fix="convert the run again with these options, or pass the original run.")
        return cls(path)

    def __init__(self, path: str | Path) -> None:
        self.path = str(path)
        self._h5 = h5py.File(path, "r")
        attrs = self._h5.attrs
        if attrs.get("format") != FORMAT:
            found = plain(attrs.get("format"))
            self._h5.close()
            raise InputFormatError(f"not a demsplit ingest cache (format attribute {found!r}).",
                                   file=path, fix="write one with 'demsplit convert RUN -o CACHE.h5'.")
        if int(attrs["version"]) != VERSION:
            version = int(attrs["version"])
            self._h5.close()
            raise InputFormatError(f"cache format version {version} is "
                                   f"{'newer' if version > VERSION else 'older'} than this demsplit reads "
                                   f"({VERSION}).", file=path,
                                   fix="convert the run again with this version of demsplit.")
        try:
            refuse_foreign_storage(self._h5, path)
        except InputFormatError:
            self._h5.close()
            raise
        self.scene = scene_from_dict(json.loads(attrs["scene"]))
        steps = np.asarray(attrs["steps"], dtype=np.int64)
        self._n_frames = len(steps)
        self.steps = steps[:len(steps) - int(np.argmax(steps[::-1] >= 0)) if (steps >= 0).any() else 0]
        self.sources = [self.path] + json.loads(attrs["sources"])
        self.notes = []
        self._describe = json.loads(attrs["describe"])
        self._frames = self._h5["frames"]
        self._fd = os.open(path, os.O_RDONLY)

    def __len__(self) -> int:
        return self._n_frames  # the damaged frames past ``steps`` (stored with step -1) included

    def frame(self, k: int) -> Frame:
        """Frame ``k`` exactly as the original reader built it."""
        if not -len(self) <= k < len(self):
            raise IndexError(f"{self.path}: frame {k} out of range ({len(self)} frames)")
        g = self._frames[f"{k % len(self):06d}"]
        a = g.attrs
        if "error" in a:
            e = json.loads(a["error"])
            cls = getattr(errors, e["class"], DemsplitError)
            raise cls(e["message"], file=e["file"], step=e["step"], line=e["line"], fix=e["fix"])
        box = None
        if "box_lo" in a:
            box = Box(np.array(a["box_lo"]), np.array(a["box_hi"]),
                      tuple(bool(p) for p in a["box_periodic"]), np.array(a["box_tilt"]))
        time = float(a["time"])
        datasets = {(name, col): g[name][col] for name in ("particles", "contacts")
                    for col in json.loads(g[name].attrs["order"])}  # in the order the reader built them
        if "overlap_error" in g:
            datasets["overlap_error", None] = g["overlap_error"]
        arrays = self._read(datasets)
        particles, contacts = ({col: v for (name, col), v in arrays.items() if name == table}
                               for table in ("particles", "contacts"))
        return Frame(step=int(a["step"]), particles=particles, contacts=contacts,
                     box=box, time=None if np.isnan(time) else time, source=tuple(json.loads(a["source"])),
                     overlap_source=str(a["overlap_source"]),
                     overlap_error=arrays.get(("overlap_error", None)), notes=json.loads(a["notes"]),
                     walls=_walls(a))

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
                raise InputFormatError(f"the cache ends inside a dataset (byte {offset + done}).", file=self.path,
                                       fix="the file was cut short: convert the run again.")
            done += got


def _walls(attrs) -> tuple[int, ...] | None:
    """A frame's walls as :func:`_write_frame` stored them (a cache without them: every wall)."""
    walls = json.loads(attrs["walls"]) if "walls" in attrs else None
    return None if walls is None else tuple(int(w) for w in walls)
