"""The ingest cache: ``convert_run`` then ``open_run(CACHE.h5)`` gives the
frames of the original reader exactly, and the pipeline the same results."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from demsplit.cli import main
from demsplit.errors import DemsplitError, InputFormatError, StoreError
from demsplit.pipeline import analyze
from demsplit.readers import open_run, reader_for
from demsplit.readers.cache import FORMAT, CacheRun, convert_run
from reader_contract import ReaderContract, assert_frames_equal
from test_parallel import assert_same_results

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


def assert_same_frames(a, b) -> None:
    assert len(a) == len(b) > 0
    for k in range(len(a)):
        assert_frames_equal(a.frame(k), b.frame(k))


@pytest.mark.slow
class TestCacheOfTheYadeSample(ReaderContract):
    """The cache as a reader of its own (the contract's round trip covers every other reader's cache)."""

    reader = CacheRun

    @pytest.fixture
    def run_path(self, tmp_path):
        return convert_run(SAMPLES / "yade" / "mindlin_box.h5", tmp_path / "mindlin.h5")


def _repack(src, dst, **dataset_options) -> None:
    """Copy the cache ``src`` to ``dst``, every non-empty dataset rewritten with
    ``dataset_options`` (``byteorder``: stored with that byte order)."""
    order = dataset_options.pop("byteorder", "=")
    with h5py.File(src, "r") as a, h5py.File(dst, "w") as b:
        b.attrs.update(a.attrs)

        def copy(name, obj):
            if isinstance(obj, h5py.Group):
                b.require_group(name).attrs.update(obj.attrs)
            elif obj.size:
                b.create_dataset(name, data=obj[()].astype(obj.dtype.newbyteorder(order)), **dataset_options)
            else:
                b.create_dataset(name, data=obj[()])

        a.visititems(copy)


@pytest.mark.slow
@pytest.mark.parametrize("layout", [{"chunks": True, "compression": "gzip"}, {"byteorder": ">"}])
def test_a_repacked_cache_is_read_through_hdf5(layout, samples, tmp_path):
    """Columns that are not contiguous, native-endian datasets (chunked and
    compressed, or big-endian, as h5repack may leave them) are read by h5py."""
    cache = convert_run(samples / "liggghts" / "packing" / "in.packing", tmp_path / "cache.h5")
    repacked = tmp_path / "repacked.h5"
    _repack(cache, repacked, **layout)
    with h5py.File(cache, "r") as original, h5py.File(repacked, "r") as h5:
        assert original["frames/000001/contacts/delta"].id.get_offset() is not None  # read by preadv
        d = h5["frames/000001/contacts/delta"]
        assert d.chunks is not None or not d.dtype.isnative
    assert_same_frames(open_run(cache), open_run(repacked))


@pytest.mark.slow
def test_a_column_past_the_end_of_the_cache_is_refused_with_its_name(samples, tmp_path):
    """A dataset whose bytes the file does not hold (a cache cut short) is an
    error naming the file, not an array of garbage."""
    cache = convert_run(samples / "liggghts" / "packing" / "in.packing", tmp_path / "cache.h5")
    run = open_run(cache)
    with pytest.raises(InputFormatError, match="ends inside a dataset") as err:
        run._pread(cache.stat().st_size - 4, np.empty(1))
    assert err.value.file == str(cache)
    run.close()


@pytest.mark.slow
def test_cache_results_equal_text_results_and_work_in_workers(samples, tmp_path, monkeypatch):
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "THREADS", 4)  # as on 4 cores: --jobs 2 starts two worker processes
    script = samples / "liggghts" / "packing" / "in.packing"
    cache = tmp_path / "cache.h5"
    assert main(["convert", str(script), "-o", str(cache), "-q"]) == 0
    text = analyze(script)
    assert_same_results(analyze(cache), text)
    assert_same_results(analyze(cache, jobs=2), text)


def test_cache_is_written_atomically(samples, tmp_path, monkeypatch):
    """A conversion that fails leaves neither the cache nor its temporary file, and its error names the cache."""
    import demsplit.readers.cache as cache_module

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(cache_module, "_write_frame", fail)
    with pytest.raises(StoreError, match="cache.h5: cannot write the output: disk full"):
        convert_run(samples / "liggghts" / "packing" / "in.packing", tmp_path / "cache.h5")
    assert list(tmp_path.iterdir()) == []


def test_refused_frames_are_kept_as_their_error(run_dir, tmp_path):
    """A damaged contact frame is stored as its error and raised again from the cache."""
    pairs = run_dir / "pairs.txt"
    lines = pairs.read_bytes().split(b"\n")
    second = [i for i, line in enumerate(lines) if line == b"ITEM: TIMESTEP"][1]
    lines[second + 10] = b" ".join(lines[second + 10].split(b" ")[:5])  # a short row in frame 2
    pairs.write_bytes(b"\n".join(lines))
    script = run_dir / "in.packing"
    with pytest.raises(DemsplitError) as direct:
        open_run(script).frame(1)
    cached = open_run(convert_run(script, tmp_path / "cache.h5"))
    cached.frame(0)
    with pytest.raises(type(direct.value)) as again:
        cached.frame(1)
    assert str(again.value) == str(direct.value)


@pytest.mark.slow
def test_reader_options_are_refused_and_foreign_hdf5_is_not_a_cache(samples, tmp_path):
    cache = convert_run(samples / "yade" / "mindlin_box.h5", tmp_path / "cache.h5")
    with pytest.raises(InputFormatError, match="fixed when it was written"):
        open_run(cache, overlap_tolerance=1e-2)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as h5:
        h5.attrs["format"] = "something else"
    assert reader_for(other) is not CacheRun
    shutil.copy(cache, tmp_path / "copy.h5")
    with h5py.File(tmp_path / "copy.h5", "r") as h5:
        assert h5.attrs["format"] == FORMAT


def _rewrite(group, col: str, values) -> None:
    del group[col]
    group.create_dataset(col, data=values)


@pytest.mark.parametrize(
    "how",
    [
        "a contact twice",
        "a short column",
        "a NaN position",
        "an unknown particle",
        "a wall the scene lacks",
        "a particle twice",
        "a string column",
        "a stored error of another class",
        "a frame group missing",
    ],
)
def test_a_damaged_cache_is_one_refusal_naming_the_cache(samples, tmp_path, capsys, how):
    """A cache is an input: a pair contact listed twice (its energy was counted twice, exit 0), a column
    shorter than its table (exit 3), a NaN (blamed on the intact dump the frame came from), ... : exit 2,
    one line naming the cache and the frame, nothing written."""
    cache = convert_run(samples / "liggghts" / "packing" / "in.packing", tmp_path / "cache.h5")
    with h5py.File(cache, "a") as h5:
        frame = h5["frames/000001"]
        c, p = frame["contacts"], frame["particles"]
        pairs = np.flatnonzero(c["wall"][()] < 0)
        if how == "a contact twice":
            rows = np.concatenate([np.arange(c["delta"].shape[0]), pairs[:1]])
            for col in json.loads(c.attrs["order"]):
                _rewrite(c, col, c[col][()][rows])
            if "overlap_error" in frame:
                _rewrite(frame, "overlap_error", frame["overlap_error"][()][rows])
        elif how == "a short column":
            _rewrite(c, "delta", c["delta"][()][:-1])
        elif how == "a NaN position":
            x = p["x"][()]
            x[4] = np.nan
            p["x"][...] = x
        elif how == "an unknown particle":
            id1 = c["id1"][()]
            id1[pairs[0]] = 10**9
            c["id1"][...] = id1
        elif how == "a wall the scene lacks":
            wall = c["wall"][()]
            wall[0] = 999
            c["wall"][...] = wall
        elif how == "a particle twice":
            ids = p["id"][()]
            ids[1] = ids[0]
            p["id"][...] = ids
        elif how == "a string column":
            _rewrite(p, "radius", np.array([b"0.002"] * p["radius"].shape[0]))
        elif how == "a stored error of another class":
            frame.attrs["error"] = json.dumps({"class": "os", "message": "x"})
        else:
            del h5["frames/000002"]
    out = tmp_path / "out.h5"
    assert main(["run", str(cache), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"demsplit: error: {cache}") and "the ingest cache is damaged" in err, err
    assert err.count("\n") == 1 and "atoms_full" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache.h5"]
