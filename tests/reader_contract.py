"""The contract every run reader keeps (MDAnalysis' BaseReaderTest, for demsplit's readers).

A reader's test module inherits :class:`ReaderContract` once per sample it
reads::

    class TestPackingSample(ReaderContract):
        reader = LiggghtsRun
        path = SAMPLES / "liggghts" / "packing" / "in.packing"
        options = {}

(or overrides the ``run_path`` fixture when the input must be made first), and
every test below runs on that run: the reader is registered and detects
its own input, columns and dtypes are the canonical ones (docs/design.md, "Data
flow and tables"), ``len(run)`` equals the frames iterated, ``frame(k)``
equals the k-th iterated frame bit for bit, ``steps`` are the frames' steps,
``close()`` may be called twice, and the ingest cache gives back the same
frames bit for bit.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest
from demsplit.frame import CONTACT_REQUIRED, PARTICLE_REQUIRED, Frame
from demsplit.readers import REGISTRY, open_run, reader_for
from demsplit.readers.cache import convert_run

INT64 = {"id", "clump", "id1", "id2", "wall"}
"""Integer columns (int64); ``type`` is int32 and ``type1 type2`` are material types of any integer width."""


def assert_frames_equal(a: Frame, b: Frame) -> None:
    """Two frames hold the same step, time, box, tables (same columns, dtypes, bits), sources and notes."""
    assert (a.step, a.time, a.source, a.overlap_source, a.notes, a.walls) == (
        b.step,
        b.time,
        b.source,
        b.overlap_source,
        b.notes,
        b.walls,
    )
    for name in ("particles", "contacts"):
        ta, tb = getattr(a, name), getattr(b, name)
        assert list(ta) == list(tb), name
        for col in ta:
            assert ta[col].dtype == tb[col].dtype, (name, col)
            np.testing.assert_array_equal(ta[col], tb[col], err_msg=f"{name}.{col}")
            assert ta[col].tobytes() == tb[col].tobytes(), f"{name}.{col}: equal values, other bits (-0.0, NaN)"
    assert (a.box is None) == (b.box is None)
    if a.box is not None:
        for attr in ("lo", "hi", "tilt"):
            np.testing.assert_array_equal(getattr(a.box, attr), getattr(b.box, attr))
        assert a.box.periodic == b.box.periodic
    if a.overlap_error is None or b.overlap_error is None:
        assert a.overlap_error is None and b.overlap_error is None
    else:
        np.testing.assert_array_equal(a.overlap_error, b.overlap_error)
        assert a.overlap_error.tobytes() == b.overlap_error.tobytes()


class ReaderContract:
    """Inherit it with ``reader`` (the class under test), ``path`` (the run) and ``options`` (the
    reader options) set."""

    reader: ClassVar[type]
    path: ClassVar[Path]
    options: ClassVar[dict[str, Any]] = {}

    @pytest.fixture
    def run_path(self) -> Path:
        return self.path

    def open(self, path: Path):
        return open_run(path, **self.options)

    def test_registered_and_detected(self, run_path):
        run = self.open(run_path)
        try:
            assert type(run) is self.reader
            assert REGISTRY[type(run).format_name] is type(run)
            assert reader_for(run_path) is type(run)
            assert type(run).formats and all(isinstance(f, str) and f for f in type(run).formats)
        finally:
            run.close()

    def test_columns_dtypes_and_units(self, run_path):
        with self.open(run_path) as run:
            for frame in run:
                p, c = frame.particles, frame.contacts
                assert set(PARTICLE_REQUIRED) <= set(p)
                if frame.n_contacts:
                    assert set(CONTACT_REQUIRED) <= set(c)
                assert p["type"].dtype == np.int32
                for name, table in (("particles", p), ("contacts", c)):
                    for col, values in table.items():
                        assert values.ndim == 1 and len(values) == len(next(iter(table.values()))), (name, col)
                        if col in INT64:
                            assert values.dtype == np.int64, (name, col, values.dtype)
                        elif col in ("type1", "type2", "history_unknown", "unknown_modes", "unknown_why"):
                            assert values.dtype.kind == "i", (name, col, values.dtype)
                        elif col != "type":
                            assert values.dtype == np.float64, (name, col, values.dtype)  # SI reals
                assert np.all(p["radius"] > 0) and np.all(np.isfinite(p["radius"]))
                if frame.n_contacts:
                    normal = np.sqrt(c["nx"] ** 2 + c["ny"] ** 2 + c["nz"] ** 2)
                    np.testing.assert_allclose(normal, 1.0, rtol=1e-5)  # %g normals: 6 digits
                    assert np.all(c["wall"] >= -1) and np.all(c["r1"] > 0) and np.all(c["r2"] > 0)

    def test_length_steps_and_random_access(self, run_path):
        with self.open(run_path) as run:
            frames = list(run)
            assert len(frames) == len(run) == len(run.steps) > 0
            assert [f.step for f in frames] == [int(s) for s in run.steps]
            for k, frame in enumerate(frames):
                assert_frames_equal(run.frame(k), frame)

    def test_description_sources_and_notes(self, run_path):
        with self.open(run_path) as run:
            assert isinstance(run.describe(), dict)
            assert run.sources and all(Path(s).is_file() for s in run.sources)
            assert isinstance(run.notes, list)
            assert run.scene.model.describe()
            assert run.spec["path"] == str(run_path)

    def test_close_is_idempotent(self, run_path):
        run = self.open(run_path)
        run.close()
        run.close()

    def test_ingest_cache_round_trip(self, run_path, tmp_path):
        cache = convert_run(run_path, tmp_path / "cache.h5", **self.options)
        with self.open(run_path) as run, open_run(cache) as cached:
            assert len(cached) == len(run)
            np.testing.assert_array_equal(cached.steps, run.steps)
            assert cached.scene.model == run.scene.model
            for a, b in zip(run, cached):
                assert_frames_equal(a, b)
