"""The HDF5 result store: round trip, frame index, atomicity, resume, export."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pandas as pd
import pandas.testing as pdt
import pytest
from result_frames import PROVENANCE, WALLS_META, synthetic_frame

import demsplit.store as store
from demsplit.errors import StoreError
from demsplit.results import TABLES, Results, load_results
from demsplit.store import ResultWriter, export_tables, file_fingerprint, read_store

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
    assert sorted(os.listdir(tmp_path)) == ["out.h5"]  # parts and temporaries removed


def test_layout_and_frame_index(tmp_path):
    out = tmp_path / "out.h5"
    with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META) as w:
        for f in frames():
            w.append(f)
    with h5py.File(out) as h5:
        assert h5.attrs["format"] == "demsplit-results"
        assert json.loads(h5.attrs["provenance"]) == PROVENANCE
        ds = h5["particles/u"]
        assert ds.maxshape == (None,) and ds.compression == store.COMPRESSION and ds.chunks is not None
        assert ds.attrs["unit"] == "J"
        np.testing.assert_array_equal(h5["index/step"][()], sorted(STEPS))
        off = h5["index/contacts"][()]
        k = list(sorted(STEPS)).index(1000)
        np.testing.assert_array_equal(h5["contacts/step"][off[k]:off[k + 1]], 1000)
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


def test_sigkill_mid_run_then_resume(tmp_path):
    """A writer killed with SIGKILL after two frames: no store, two parts."""
    out = tmp_path / "out.h5"
    script = textwrap.dedent(f"""
        import os, signal, sys
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from result_frames import synthetic_frame, PROVENANCE, WALLS_META
        from demsplit.store import ResultWriter
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
    other_input = {**PROVENANCE, "inputs": [{"path": "/data/run.dump", "size": 123, "sha256": "cd" * 32}]}
    with pytest.raises(StoreError, match="different inputs") as err:
        ResultWriter(out, other_input, resume=True)
    assert "Fix:" in str(err.value) and str(out) in str(err.value)
    with pytest.raises(StoreError, match="different options"):
        ResultWriter(out, {**PROVENANCE, "options": {"split": "equal"}}, resume=True)
    moved = {**PROVENANCE, "inputs": [{"path": "/elsewhere/run.dump", "size": 123, "sha256": "ab" * 32}]}
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


def test_file_fingerprint(tmp_path):
    p = tmp_path / "in.txt"
    p.write_bytes(b"abc")
    fp = file_fingerprint(p)
    assert fp["size"] == 3
    assert fp["sha256"] == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"  # FIPS 180-2 "abc"
    with pytest.raises(StoreError, match="cannot read input"):
        file_fingerprint(tmp_path / "missing")


def test_assembly_memory_does_not_grow_with_frames(tmp_path, monkeypatch):
    """close() streams part by part: its peak allocation is the same for 3 and 12 frames."""
    import tracemalloc

    monkeypatch.setattr(store, "BUFFER_ROWS", 512)
    monkeypatch.setattr(store, "CHUNK_ROWS", 512)  # whole chunks are written as soon as they are full
    peaks = []
    for n in (3, 12):
        w = ResultWriter(tmp_path / f"out{n}.h5", PROVENANCE)
        for s in range(n):
            w.append(synthetic_frame(s, n_particles=300, n_pairs=1000))
        tracemalloc.start()
        w.close()
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        assert len(read_store(tmp_path / f"out{n}.h5").frames) == n
    assert peaks[1] < 1.5 * peaks[0], peaks


def test_gzip_chunks_compressed_in_threads_decode_as_ordinary_hdf5(tmp_path, monkeypatch):
    """The gzip store writes pre-filtered chunks (shuffle + zlib, in a thread pool):
    HDF5 itself must decode them to the same values, across whole and partial chunks."""
    monkeypatch.setattr(store, "CHUNK_ROWS", 512)
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
