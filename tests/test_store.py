"""The HDF5 result store: round trip, frame index, atomicity, resume, export."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import demsplit.results.chunks as chunks
import demsplit.results.writer as writer
import h5py
import numpy as np
import pandas as pd
import pandas.testing as pdt
import pytest
from demsplit.errors import StoreError
from demsplit.fingerprint import file_fingerprint
from demsplit.results import TABLES, Results, load_results
from demsplit.results.exports.tables import export_tables
from demsplit.results.store import read_store
from demsplit.results.writer import ResultWriter
from result_frames import PROVENANCE, WALLS_META, synthetic_frame

STEPS = (2000, 0, 1000)  # appended out of order: the store is in step order


def frames():
    return [synthetic_frame(s) for s in STEPS]


def assert_same(a: Results, b: Results) -> None:
    for name in TABLES:
        pdt.assert_frame_equal(getattr(a, name), getattr(b, name), check_dtype=True, check_exact=True)
        assert getattr(a, name).attrs["units"] == getattr(b, name).attrs["units"]
    assert a.provenance == b.provenance
    assert a.walls_meta == b.walls_meta


def test_round_trip_identical_dataframes(tmp_path):
    out = tmp_path / "out.h5"
    with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META) as w:
        for f in frames():
            w.append(f)
    stored = load_results(out)
    assert_same(stored, Results.from_frames(frames(), PROVENANCE, WALLS_META))
    assert stored.frames["step"].tolist() == sorted(STEPS)
    assert stored.particles["id"].dtype == np.int64 and stored.particles["type"].dtype == np.int32
    assert stored.particles.attrs["units"]["u"] == "J" and stored.contacts.attrs["units"]["delta"] == "m"
    assert sorted(os.listdir(tmp_path)) == ["out.h5"]  # work directory and temporaries removed


def test_layout_and_frame_index(tmp_path):
    out = tmp_path / "out.h5"
    with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META) as w:
        for f in frames():
            w.append(f)
    with h5py.File(out) as h5:
        assert h5.attrs["format"] == "demsplit-results"
        assert json.loads(h5.attrs["provenance"]) == PROVENANCE
        ds = h5["particles/u"]
        assert ds.maxshape == (None,) and ds.chunks is not None
        assert h5.attrs["compression"] == chunks.COMPRESSION == "auto" and ds.compression in (None, "gzip")
        assert ds.attrs["unit"] == "J"
        np.testing.assert_array_equal(h5["index/step"][()], sorted(STEPS))
        off = h5["index/contacts"][()]
        k = list(sorted(STEPS)).index(1000)
        np.testing.assert_array_equal(h5["contacts/step"][off[k] : off[k + 1]], 1000)
        assert off[-1] == h5["contacts/step"].shape[0]
    one = read_store(out, steps=[1000])
    assert_same(one, Results.from_frames([synthetic_frame(1000)], PROVENANCE, WALLS_META))
    with pytest.raises(StoreError, match=r"timestep\(s\) \[5\] are not in the store"):
        read_store(out, steps=[5])


def test_exception_mid_run_leaves_no_store_and_parts_resume(tmp_path):
    out = tmp_path / "out.h5"
    fs = frames()
    with pytest.raises(RuntimeError):
        with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META) as w:
            w.append(fs[0])
            w.append(fs[1])
            raise RuntimeError("reader failed on the third frame")
    assert not out.exists()
    with pytest.raises(StoreError, match="interrupted run"):
        read_store(out)
    with pytest.raises(StoreError, match="resume"):
        ResultWriter(out, PROVENANCE)  # not silently overwritten
    with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META, resume=True) as w:
        assert w.done_steps == {STEPS[0], STEPS[1]}
        for f in fs:
            if int(f["frames"]["step"][0]) not in w.done_steps:
                w.append(f)
    assert_same(load_results(out), Results.from_frames(fs, PROVENANCE, WALLS_META))


@pytest.mark.slow
def test_sigkill_mid_run_then_resume(tmp_path):
    """A writer killed with SIGKILL after two frames: no store, two frames to resume."""
    out = tmp_path / "out.h5"
    script = textwrap.dedent(f"""
        import os, signal, sys
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from result_frames import synthetic_frame, PROVENANCE, WALLS_META
        from demsplit.results.writer import ResultWriter
        w = ResultWriter({str(out)!r}, PROVENANCE, walls_meta=WALLS_META)
        for s in {STEPS[:2]!r}:
            w.append(synthetic_frame(s))
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True)
    assert proc.returncode == -9, proc.stderr.decode()
    assert not out.exists()
    with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META, resume=True) as w:  # stale lock taken over
        assert w.done_steps == set(STEPS[:2])
        w.append(synthetic_frame(STEPS[2]))
    assert_same(load_results(out), Results.from_frames(frames(), PROVENANCE, WALLS_META))


def test_resume_refuses_other_inputs_or_options(tmp_path):
    out = tmp_path / "out.h5"
    w = ResultWriter(out, PROVENANCE)
    w.append(synthetic_frame(0))
    w.abandon()
    other_input = {**PROVENANCE, "inputs": [{"path": "/data/run.dump", "size": 123, "blake3": "cd" * 32}]}
    with pytest.raises(StoreError, match="different inputs") as err:
        ResultWriter(out, other_input, resume=True)
    assert "Fix:" in str(err.value) and str(out) in str(err.value)
    with pytest.raises(StoreError, match="different options"):
        ResultWriter(out, {**PROVENANCE, "options": {"split": "equal"}}, resume=True)
    moved = {**PROVENANCE, "inputs": [{"path": "/elsewhere/run.dump", "size": 123, "blake3": "ab" * 32}]}
    with ResultWriter(out, moved, resume=True) as w:  # same content, another path: resumable
        assert w.done_steps == {0}


def test_inconsistent_frames_are_errors(tmp_path):
    w = ResultWriter(tmp_path / "out.h5", PROVENANCE)
    w.append(synthetic_frame(0))
    with pytest.raises(StoreError, match="already stored") as err:
        w.append(synthetic_frame(0))
    assert "timestep 0" in str(err.value)
    bad = synthetic_frame(1, simulator_point=False)
    with pytest.raises(StoreError, match="columns"):
        w.append(bad)
    bad = synthetic_frame(2)
    bad["particles"]["id"] = bad["particles"]["id"].astype(float)
    bad["particles"]["id"][3] = np.nan
    with pytest.raises(StoreError, match="must hold integers") as err:
        w.append(bad)
    assert "timestep 2" in str(err.value)
    w.abandon()


def test_store_without_walls_or_contacts(tmp_path):
    f = synthetic_frame(5)
    del f["walls"]
    f["contacts"] = {k: v[:0] for k, v in f["contacts"].items()}
    with ResultWriter(tmp_path / "out.h5", PROVENANCE) as w:
        w.append(f)
    r = load_results(tmp_path / "out.h5")
    assert len(r.contacts) == 0 and list(r.contacts.columns) == list(f["contacts"])
    assert len(r.walls) == 0
    assert_same(r, Results.from_frames([f], PROVENANCE))


def test_export_parquet_and_csv(tmp_path):
    res = Results.from_frames(frames(), PROVENANCE, WALLS_META)
    written = export_tables(res, tmp_path / "pq", "parquet")
    assert sorted(p.name for p in written) == sorted([f"{t}.parquet" for t in TABLES] + ["provenance.json"])
    import pyarrow.parquet as pq

    tab = pq.read_table(tmp_path / "pq" / "particles.parquet")
    assert tab.schema.field("u").metadata[b"unit"] == b"J"
    assert json.loads(tab.schema.metadata[b"demsplit"])["provenance"] == PROVENANCE
    pdt.assert_frame_equal(tab.to_pandas(), res.particles, check_dtype=True)
    export_tables(res, tmp_path / "csv", "csv")
    back = pd.read_csv(tmp_path / "csv" / "contacts.csv")
    pdt.assert_frame_equal(back, res.contacts, check_dtype=False, check_exact=True)  # 17 digits: exact
    assert not list((tmp_path / "csv").glob("*.tmp"))


def test_frames_are_committed_once_the_inputs_digests_are_known(tmp_path):
    """A provenance built while its inputs are still being hashed (digest None): the writer stores frames
    but commits none (a run killed then has nothing to resume, and starts over) until the digest is
    known; then the manifest names the input by it, and so does the finished store."""
    from demsplit.results.store import build_provenance, work_dir_of
    from demsplit.runtime import hashing

    dump = tmp_path / "pairs.txt"
    dump.write_bytes(b"ITEM: TIMESTEP\n0\n" * 1000)
    job = hashing._Digest(dump)  # hashing in the background, held up
    hashing._PENDING[hashing._key(dump)] = (os.getpid(), job)
    prov = build_provenance([dump], wait=False)
    assert prov["inputs"][0]["blake3"] is None
    out = tmp_path / "out.h5"
    work = work_dir_of(out)
    with ResultWriter(out, prov, walls_meta=WALLS_META) as w:
        w.append(synthetic_frame(0))
        assert not (work / "commit.npys").exists() and not (work / "run.json").exists()
        assert not writer._resumable(work)
        job.hash_in_background()  # the thread gets a core
        w.append(synthetic_frame(1000))
        assert writer._resumable(work) and w.done_steps == {0, 1000}
        manifest = json.loads((work / "run.json").read_text())
        assert manifest["identity"]["inputs"] == [hashing.file_digest(dump)]
    with h5py.File(out) as h5:
        stored = json.loads(h5.attrs["provenance"])["inputs"]
    assert stored == [{"path": str(dump.resolve()), "size": dump.stat().st_size, "blake3": hashing.file_digest(dump)}]


def test_a_store_closed_before_the_digests_are_known_waits_for_them(tmp_path):
    from demsplit.results.store import build_provenance
    from demsplit.runtime import hashing

    dump = tmp_path / "atoms.txt"
    dump.write_bytes(b"1 2 3\n" * 5000)
    hashing._PENDING[hashing._key(dump)] = (os.getpid(), hashing._Digest(dump))  # never run
    out = tmp_path / "out.h5"
    with ResultWriter(out, build_provenance([dump], wait=False), walls_meta=WALLS_META) as w:
        w.append(synthetic_frame(0))
    with h5py.File(out) as h5:
        assert json.loads(h5.attrs["provenance"])["inputs"][0]["blake3"] == hashing.file_digest(dump)


def test_file_fingerprint(tmp_path):
    p = tmp_path / "in.txt"
    p.write_bytes(b"abc")
    fp = file_fingerprint(p)
    assert fp["size"] == 3
    # BLAKE3 of "abc" (b3sum 1.2.0 prints it; so does the reference implementation's test of "abc")
    assert fp["blake3"] == "6437b3ac38465133ffb63b75273a8db548c558465d79db03fd359c6cd5bd9d85"
    with pytest.raises(StoreError, match="cannot read input"):
        file_fingerprint(tmp_path / "missing")


def test_writing_memory_does_not_grow_with_frames(tmp_path, monkeypatch):
    """Frames are written as they come: the writer's peak allocation while
    appending and closing is the same for 3 and 12 frames (the smaller of two tries each: tracemalloc counts
    every thread of the process, and another test's thread may allocate meanwhile)."""
    import tracemalloc

    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)

    def peak(n: int, k: int) -> int:
        frames_n = [synthetic_frame(s, n_particles=300, n_pairs=1000) for s in range(n)]
        tracemalloc.start()
        base = tracemalloc.get_traced_memory()[0]
        w = ResultWriter(tmp_path / f"out{n}_{k}.h5", PROVENANCE)
        for f in frames_n:
            w.append(f)
        w.close()
        used = tracemalloc.get_traced_memory()[1] - base
        tracemalloc.stop()
        assert len(read_store(tmp_path / f"out{n}_{k}.h5").frames) == n
        return used

    peaks = [min(peak(n, k) for k in range(2)) for n in (3, 12)]
    assert peaks[1] < 1.5 * peaks[0], peaks


def test_gzip_chunks_compressed_in_threads_decode_as_ordinary_hdf5(tmp_path, monkeypatch):
    """The gzip store writes pre-filtered chunks (shuffle + zlib, in a thread pool):
    HDF5 itself must decode them to the same values, across whole and partial chunks."""
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)
    frames = [synthetic_frame(s, n_particles=700, n_pairs=1300) for s in range(3)]
    w = ResultWriter(tmp_path / "o.h5", PROVENANCE, compression="gzip")
    for f in frames:
        w.append(f)
    w.close()
    with h5py.File(tmp_path / "o.h5") as h5:
        for table in ("particles", "contacts"):
            for col in frames[0][table]:
                ds = h5[f"{table}/{col}"]
                assert ds.compression == "gzip" and ds.shuffle and ds.chunks == (512,)
                expected = np.concatenate([np.asarray(f[table][col]) for f in frames]).astype(ds.dtype)
                np.testing.assert_array_equal(ds[()], expected, err_msg=f"{table}/{col}")


def low_variety_frame(step: int, **sizes) -> dict:
    """A synthetic frame whose share_n1 takes three values (as with three material pairs)."""
    f = synthetic_frame(step, **sizes)
    rng = np.random.default_rng(step)
    f["contacts"]["share_n1"] = rng.choice([0.5, 0.25, 0.75], len(f["contacts"]["share_n1"]))
    return f


def stored_columns(path) -> dict[str, h5py.Dataset]:
    """Every column dataset of a store, read by h5py: {"table/column": (values, filter)}."""
    with h5py.File(path) as h5:
        return {f"{t}/{c}": (h5[t][c][()], h5[t][c].compression) for t in TABLES for c in h5[t]}


def test_auto_compression_gzips_only_what_compresses(tmp_path, monkeypatch):
    """auto: gzip (+ shuffle) for constant, integer and low-variety columns, no
    filter for random floats; decided from the first chunk, values exact."""
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)
    frames = [low_variety_frame(s, n_particles=700, n_pairs=1300) for s in (0, 1000, 2000)]
    with ResultWriter(tmp_path / "o.h5", PROVENANCE, walls_meta=WALLS_META) as w:  # the default: auto
        for f in frames:
            w.append(f)
    columns = stored_columns(tmp_path / "o.h5")
    filters = {name: comp for name, (_, comp) in columns.items()}
    for name in (
        "particles/step",
        "particles/id",
        "particles/type",
        "particles/n_contacts",
        "contacts/step",
        "contacts/wall",
        "contacts/share_n1",
    ):
        assert filters[name] == "gzip", name
    for name in ("particles/u", "contacts/delta", "contacts/u_n", "contacts/u_t", "contacts/u1"):
        assert filters[name] is None, name
    with h5py.File(tmp_path / "o.h5") as h5:
        assert h5["contacts/step"].shuffle and h5["contacts/step"].compression_opts == chunks.GZIP_LEVEL
        assert not h5["contacts/u_n"].shuffle
    for name, (values, _) in columns.items():
        table, col = name.split("/")
        expected = np.concatenate([np.asarray(f[table][col]) for f in frames]).astype(values.dtype)
        np.testing.assert_array_equal(values, expected, err_msg=name)


def test_auto_store_equals_uncompressed_store(tmp_path, monkeypatch):
    """auto and none hold the same values; only the filters differ."""
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)
    frames = [low_variety_frame(s, n_particles=900, n_pairs=2000) for s in (0, 1000, 2000, 3000)]
    for comp in ("auto", "none"):
        with ResultWriter(tmp_path / f"{comp}.h5", PROVENANCE, walls_meta=WALLS_META, compression=comp) as w:
            for f in frames:
                w.append(f)
    assert_same(read_store(tmp_path / "auto.h5"), read_store(tmp_path / "none.h5"))
    auto, none = stored_columns(tmp_path / "auto.h5"), stored_columns(tmp_path / "none.h5")
    assert auto.keys() == none.keys()
    for name in auto:
        assert auto[name][0].dtype == none[name][0].dtype
        np.testing.assert_array_equal(auto[name][0], none[name][0], err_msg=name)
    assert {c for _, c in none.values()} == {None} and {c for _, c in auto.values()} == {None, "gzip"}
    assert os.path.getsize(tmp_path / "auto.h5") < os.path.getsize(tmp_path / "none.h5")


@pytest.mark.parametrize("compression", ["auto", "gzip", "lzf", "none"])
def test_every_compression_round_trips_across_chunk_boundaries(tmp_path, monkeypatch, compression):
    """Frames of 1 to 3 chunks' worth of rows, not aligned to chunks, and an empty
    walls table: every column reads back exactly, by read_store and by h5py."""
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)
    frames = [synthetic_frame(s, n_particles=n, n_pairs=n + 9) for s, n in ((0, 300), (1, 1100), (2, 77), (3, 1500))]
    for f in frames:
        f["walls"] = {k: v[:0] for k, v in f["walls"].items()}
    with ResultWriter(tmp_path / "o.h5", PROVENANCE, walls_meta=WALLS_META, compression=compression) as w:
        for f in frames:
            w.append(f)
    assert_same(read_store(tmp_path / "o.h5"), Results.from_frames(frames, PROVENANCE, WALLS_META))
    for name, (values, _) in stored_columns(tmp_path / "o.h5").items():
        table, col = name.split("/")
        expected = np.concatenate([np.asarray(f[table][col]) for f in frames]).astype(values.dtype)
        np.testing.assert_array_equal(values, expected, err_msg=name)


def test_h5dump_reads_an_auto_store(tmp_path, monkeypatch):
    """The HDF5 library's own tool decodes the gzip and unfiltered datasets alike."""
    import shutil as sh

    if sh.which("h5dump") is None:
        pytest.skip("h5dump not installed (apt-get install hdf5-tools)")
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)
    f = low_variety_frame(0, n_particles=700, n_pairs=1300)
    with ResultWriter(tmp_path / "o.h5", PROVENANCE) as w:
        w.append(f)
    for col, comp in (("step", "gzip"), ("share_n1", "gzip"), ("u_n", None)):
        assert stored_columns(tmp_path / "o.h5")[f"contacts/{col}"][1] == comp
        header = subprocess.run(
            ["h5dump", "-p", "-H", "-d", f"/contacts/{col}", str(tmp_path / "o.h5")],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        assert (f"COMPRESSION DEFLATE {{ LEVEL {chunks.GZIP_LEVEL} }}" in header) == (comp == "gzip"), header
        raw = tmp_path / f"{col}.bin"  # the values as h5dump decodes them, little-endian binary
        subprocess.run(
            ["h5dump", "-d", f"/contacts/{col}", "-b", "LE", "-o", str(raw), str(tmp_path / "o.h5")],
            capture_output=True,
            check=True,
        )
        expected = np.asarray(f["contacts"][col])
        np.testing.assert_array_equal(np.fromfile(raw, expected.dtype.newbyteorder("<")), expected, err_msg=col)


def test_work_directory_holds_a_readable_store_and_its_commit_record(tmp_path, monkeypatch):
    """Mid-run, .out.h5.partial/ holds the store written so far (a valid HDF5
    file, in SWMR mode) and the commit record: the frames' steps and offsets
    and the rows not yet in a whole chunk. Other layouts are not resumed."""
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 128)
    out = tmp_path / "out.h5"
    w = ResultWriter(out, PROVENANCE)
    for s in (7, 8):
        w.append(synthetic_frame(s, n_particles=300, n_pairs=500))
    work = tmp_path / ".out.h5.partial"
    assert writer.committed_steps(out) == [7, 8]
    header, carry = writer._read_records(work / "commit.npys")
    expected = np.concatenate([synthetic_frame(s, n_particles=300, n_pairs=500)["contacts"]["u_n"] for s in (7, 8)])
    n = len(expected) // 2
    assert header["rows"]["contacts"] == [0, n, 2 * n] and header["written"]["contacts"] == 2 * n // 128 * 128
    with h5py.File(work / "store.h5", "r", swmr=True) as h5:  # readable while the writer has it open
        np.testing.assert_array_equal(h5["contacts/u_n"][()], expected[: header["written"]["contacts"]])
    np.testing.assert_array_equal(carry["contacts"]["u_n"], expected[header["written"]["contacts"] :])
    w.abandon()

    commit = work / "commit.npys"
    intact = commit.read_bytes()
    commit.write_bytes(intact[:-8])  # a record cut short (a power cut): named, not read
    with pytest.raises(StoreError, match="cannot read the commit record: the file ends at byte"):
        ResultWriter(out, PROVENANCE, resume=True)
    commit.write_bytes(intact)
    manifest = json.loads((work / "run.json").read_text())
    (work / "run.json").write_text(json.dumps({**manifest, "work_version": 2}))
    with pytest.raises(StoreError, match="no readable run manifest"):
        ResultWriter(out, PROVENANCE, resume=True)


KILL_SCRIPT = """
import os, signal, sys
sys.path.insert(0, {tests!r})
from result_frames import synthetic_frame, PROVENANCE, WALLS_META
import demsplit.results.chunks as chunks, demsplit.results.writer as writer
chunks.CHUNK_ROWS = 128
calls = {{"n": 0}}
real = getattr(writer, {target!r}) if {target!r} != "TableSink._write" else chunks.TableSink._write

def dying(*args, **kwargs):
    calls["n"] += 1
    if calls["n"] == {at}:
        if {target!r} == "_write_records":  # die with the record half written under its temporary name
            path = args[0]
            path.with_name(path.name + ".tmp").write_bytes(b"\\x93NUMPY half")
        os.kill(os.getpid(), signal.SIGKILL)
    return real(*args, **kwargs)

if {target!r} == "TableSink._write":
    chunks.TableSink._write = dying
else:
    setattr(writer, {target!r}, dying)
w = writer.ResultWriter({out!r}, PROVENANCE, walls_meta=WALLS_META)
for s in range(6):
    w.append(synthetic_frame(s, n_particles=300, n_pairs=500))
w.close()
"""


# TableSink._write is called once per column per frame: 42 calls a frame (particles 1-10,
# contacts 11-28, walls 29-34, frames 35-42), so call 54 is frame 1's contacts, 99 frame 2's
# contacts and 131 frame 3's particles, each with chunks written past the last commit.
@pytest.mark.parametrize(
    "target, at",
    [
        ("TableSink._write", 5),
        ("TableSink._write", 54),
        ("TableSink._write", 99),
        ("TableSink._write", 131),
        ("_write_records", 1),
        ("_write_records", 4),
    ],
)
@pytest.mark.slow
def test_killed_at_any_point_of_a_frame_resumes_to_the_same_store(tmp_path, target, at):
    """SIGKILL inside a frame (between chunk writes, or with the commit record
    half written): the resumed run equals an uninterrupted one."""
    frames6 = [synthetic_frame(s, n_particles=300, n_pairs=500) for s in range(6)]
    out = tmp_path / "out.h5"
    script = KILL_SCRIPT.format(tests=os.path.dirname(__file__), target=target, at=at, out=str(out))
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True)
    assert proc.returncode == -9, proc.stderr.decode()
    assert not out.exists()
    done = writer.committed_steps(out)
    assert done == list(range(len(done))) and len(done) < 6
    import unittest.mock

    with (
        unittest.mock.patch.object(chunks, "CHUNK_ROWS", 128),
        ResultWriter(out, PROVENANCE, walls_meta=WALLS_META, resume=True) as w,
    ):
        assert w.done_steps == set(done)
        for f in frames6[len(done) :]:
            w.append(f)
    assert not (tmp_path / ".out.h5.partial").exists()
    assert_same(load_results(out), Results.from_frames(frames6, PROVENANCE, WALLS_META))


def test_unknown_compression_is_an_error(tmp_path):
    with pytest.raises(StoreError, match="unknown compression 'zstd'"):
        ResultWriter(tmp_path / "o.h5", PROVENANCE, compression="zstd")
    assert not (tmp_path / ".o.h5.partial").exists()


def test_demsplit_run_defaults_to_auto_and_equals_none(tmp_path):
    """The CLI's default store is auto; --compression none holds the same values."""
    from demsplit import cli

    script = os.path.join(os.path.dirname(__file__), "..", "sample_dumps", "liggghts", "packing", "in.packing")
    assert cli.main(["run", script, "-o", str(tmp_path / "auto.h5"), "-q"]) == 0
    assert cli.main(["run", script, "-o", str(tmp_path / "none.h5"), "-q", "--compression", "none"]) == 0
    with h5py.File(tmp_path / "auto.h5") as h5:
        assert h5.attrs["compression"] == "auto"
        assert h5["contacts/step"].compression == "gzip" and h5["contacts/u_n"].compression is None
    auto, none = read_store(tmp_path / "auto.h5"), read_store(tmp_path / "none.h5")
    for name in TABLES:
        pdt.assert_frame_equal(getattr(auto, name), getattr(none, name), check_exact=True)


def test_auto_decides_once_from_the_first_chunk(tmp_path, monkeypatch):
    """A column constant over its first chunk stays gzip when later rows are random;
    a random first chunk leaves the column unfiltered when later rows are constant."""
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 512)
    frames = [synthetic_frame(s, n_particles=300, n_pairs=700) for s in (0, 1)]
    frames[0]["contacts"]["u_n"] = np.full(710, 1e-6)  # first chunk constant, second frame random
    frames[1]["contacts"]["u_t"] = np.full(710, 1e-6)  # first chunk random (frame 0), then constant
    with ResultWriter(tmp_path / "o.h5", PROVENANCE) as w:
        for f in frames:
            w.append(f)
    columns = stored_columns(tmp_path / "o.h5")
    assert columns["contacts/u_n"][1] == "gzip" and columns["contacts/u_t"][1] is None
    for col in ("u_n", "u_t"):
        np.testing.assert_array_equal(
            columns[f"contacts/{col}"][0], np.concatenate([f["contacts"][col] for f in frames])
        )


def test_small_tables_get_small_chunks(tmp_path):
    """A table's chunks hold its first frame's rows rounded up to a power of two
    (1024 to CHUNK_ROWS), so that a small run is not stored as mostly padding."""
    assert [chunks.chunk_rows(n) for n in (0, 1, 300, 1024, 1025, 40_000, 10**7)] == [
        1024,
        1024,
        1024,
        1024,
        2048,
        65536,
        65536,
    ]
    frames_small = [synthetic_frame(s, n_particles=300, n_pairs=700) for s in range(3)]
    with ResultWriter(tmp_path / "o.h5", PROVENANCE, walls_meta=WALLS_META, compression="none") as w:
        for f in frames_small:
            w.append(f)
    with h5py.File(tmp_path / "o.h5") as h5:
        assert h5["particles/u"].chunks == (1024,) and h5["frames/step"].chunks == (1024,)
    raw = sum(np.asarray(v).nbytes for f in frames_small for t in f.values() for v in t.values())
    assert os.path.getsize(tmp_path / "o.h5") < 3 * raw  # a 65 536-row chunk per column would be ~60x
    assert_same(read_store(tmp_path / "o.h5"), Results.from_frames(frames_small, PROVENANCE, WALLS_META))


@pytest.mark.slow
def test_a_commit_record_replaced_while_it_is_read_is_read_whole(tmp_path):
    """A reader (``committed_steps``, a resume) that opens the commit record
    while the running writer renames its next one into place reads one record
    or the other, never the header of one with the columns of the other."""
    import threading

    path = tmp_path / "commit.npys"
    records = [
        ({"steps": list(range(n))}, {"t": {"a": np.arange(n, dtype=np.float64), "b": np.arange(2 * n)}})
        for n in (3, 3000)
    ]
    writer._write_records(path, *records[0])
    stop = threading.Event()

    def rewrite():
        k = 0
        while not stop.is_set():
            k += 1
            writer._write_records(path, *records[k % 2])

    thread = threading.Thread(target=rewrite)
    thread.start()
    try:
        for _ in range(400):
            header, tables = writer._read_records(path)
            n = len(header["steps"])
            assert tables["t"]["a"].tolist() == list(range(n)) and len(tables["t"]["b"]) == 2 * n
    finally:
        stop.set()
        thread.join()


def test_parquet_export_keeps_units_and_wall_names_where_pandas_users_look(tmp_path):
    """pd.read_parquet(...).attrs holds the units and the walls (they were only in field metadata and JSON)."""
    import pandas as pd
    from demsplit.pipeline import run_to_store

    sample = Path(__file__).resolve().parents[1] / "sample_dumps" / "yade" / "mindlin_box.h5"
    run_to_store(sample, tmp_path / "out.h5", progress=False)
    export_tables(load_results(tmp_path / "out.h5"), tmp_path / "pq", fmt="parquet")
    particles = pd.read_parquet(tmp_path / "pq" / "particles.parquet")
    walls = pd.read_parquet(tmp_path / "pq" / "walls.parquet")
    assert particles.attrs["units"]["u"] == "J" and particles.attrs["units"]["x"] == "m"
    assert [w["name"] for w in walls.attrs["walls"]][:1] == ["body 160 (yade_wall)"]


def test_no_stored_number_is_nan_or_inf(tmp_path):
    """The store's last guard: a table with a NaN or inf is refused by name, nothing is left behind."""
    frame = synthetic_frame(0)
    frame["contacts"]["u_n"][3] = np.nan
    out = tmp_path / "out.h5"
    with pytest.raises(StoreError, match="table contacts, column u_n, row 3 is nan"):
        with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META) as w:
            w.append(frame)
    assert list(tmp_path.iterdir()) == []


def test_unknown_frame_values_are_stored_as_the_documented_sentinel(tmp_path, run_dir):
    """A run without a timestep (time unknown) whose overlaps all come from dumps (no error bound): both
    frames columns hold UNKNOWN (-1), not NaN; a store written with NaN there reads back as UNKNOWN."""
    from demsplit.cli import main
    from demsplit.results.schema import UNKNOWN

    script = run_dir / "in.packing"
    script.write_text("\n".join(line for line in script.read_text().split("\n") if not line.startswith("timestep")))
    yade = Path(__file__).resolve().parent.parent / "sample_dumps" / "yade" / "mindlin_box.npys"
    for path, out in ((script, tmp_path / "liggghts.h5"), (yade, tmp_path / "yade.h5")):
        assert main(["run", str(path), "-o", str(out), "-q"]) == 0
        with h5py.File(out, "r") as h5:
            for col in ("time", "overlap_max_rel_error"):
                values = h5["frames"][col][()]
                assert np.all(np.isfinite(values))
    with h5py.File(tmp_path / "liggghts.h5", "r") as h5:
        assert np.all(h5["frames/time"][()] == UNKNOWN)
    with h5py.File(tmp_path / "yade.h5", "r+") as h5:
        assert np.all(h5["frames/overlap_max_rel_error"][()] == UNKNOWN) and np.all(h5["frames/time"][()] > 0)
        h5["frames/overlap_max_rel_error"][...] = np.nan  # as stores written before the sentinel hold it
    assert np.all(load_results(tmp_path / "yade.h5").frames["overlap_max_rel_error"] == UNKNOWN)


# --- a store is an input too: checked before any value is used -----------------------------------------------


@pytest.fixture(scope="module")
def clean_store(tmp_path_factory):
    """A store of the YADE sample, written once."""
    from demsplit.cli import main

    path = tmp_path_factory.mktemp("clean") / "store.h5"
    assert (
        main(
            [
                "run",
                str(Path(__file__).parent.parent / "sample_dumps" / "yade" / "mindlin_box.h5"),
                "-o",
                str(path),
                "-q",
            ]
        )
        == 0
    )
    return path


def _replace(h5, name: str, **dataset) -> None:
    del h5[name]
    h5.create_dataset(name, **dataset)


def _damage(h5, how: str, secret: Path) -> None:
    n = h5["particles/u"].shape[0]
    if how == "string column":
        _replace(h5, "particles/u", data=np.array([b"1.0"] * n))
    elif how == "compound column":
        _replace(h5, "particles/u", data=np.zeros(n, dtype=[("a", "f8"), ("b", "i4")]))
    elif how == "huge declared shape":  # every particle column 2^40 rows long, none of them stored
        rows = 1 << 40
        h5["index/particles"][-1] = rows
        for col in json.loads(h5["particles"].attrs["columns"]):
            h5["particles"][col].resize((rows,))
    elif how == "soft-link loop":
        del h5["particles/u"]
        h5["particles/u"] = h5py.SoftLink("/particles/u")
    elif how in ("nan", "inf"):
        u = h5["particles/u"][()]
        u[3] = np.nan if how == "nan" else np.inf
        h5["particles/u"][...] = u
    elif how == "external storage":
        secret.write_bytes(np.full(n, 7.0).tobytes())
        _replace(h5, "particles/u", shape=(n,), dtype="f8", external=[(str(secret), 0, 8 * n)])
    elif how == "a step twice":
        steps = h5["index/step"][()]
        steps[-1] = steps[0]
        h5["index/step"][...] = steps
    elif how == "a particle twice":
        ids = h5["particles/id"][()]
        ids[1] = ids[0]
        h5["particles/id"][...] = ids
    elif how == "a short column":
        u = h5["particles/u"][()]
        _replace(h5, "particles/u", data=u[:-1], chunks=True, maxshape=(None,))
    elif how == "provenance of another shape":
        h5.attrs["provenance"] = json.dumps({"inputs": 5, "notes": "x"})


VALUES = ("nan", "inf", "a particle twice")
"""Damage of the values, which info (the layout) does not read."""
DAMAGE = [
    "string column",
    "compound column",
    "huge declared shape",
    "soft-link loop",
    "nan",
    "inf",
    "external storage",
    "a step twice",
    "a particle twice",
    "a short column",
    "provenance of another shape",
]


@pytest.mark.parametrize(
    "how, command",
    [
        (how, command)
        for how in DAMAGE
        for command in (["report"], ["export", "--csv", "{tmp}/csv"], ["info"])
        if command != ["info"] or how not in VALUES
    ],
)
def test_a_damaged_store_is_one_refusal_naming_it(clean_store, tmp_path, capsys, how, command):
    """report, export and info read a store as an input: a column of strings or records, a declared shape
    the file does not hold, a soft-link loop (exit 3), NaN or inf (printed, exit 0), a column stored in
    another file (its bytes printed, exit 0), a frame or a particle listed twice, a column shorter than the
    index: exit 2, one line naming the store and what is wrong, nothing printed or written (info checks
    the layout it describes, not the values)."""
    import shutil

    from demsplit.cli import main

    store = tmp_path / "store.h5"
    shutil.copy(clean_store, store)
    with h5py.File(store, "a") as h5:
        _damage(h5, how, tmp_path / "secret.bin")
    argv = [command[0], str(store), *(a.format(tmp=tmp_path) for a in command[1:]), "-q"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith(f"demsplit: error: {store}: ") and err.count("\n") == 1, err
    assert not (tmp_path / "csv").exists()
