"""The store's write-back runs on idle cores, asks the kernel to start writing the
whole file, and never holds up or breaks the writer."""

from __future__ import annotations

import os
import threading

import pytest
from demsplit.results.store import load_results
from demsplit.results.writer import ResultWriter
from demsplit.runtime import writeback
from result_frames import PROVENANCE, WALLS_META, synthetic_frame


@pytest.mark.skipif(writeback._sync_file_range() is None, reason="sync_file_range is Linux's")
def test_start_write_back_asks_the_kernel_for_the_whole_file(tmp_path, monkeypatch):
    calls = []
    real = writeback._sync_file_range()

    def recorder(fd, offset, nbytes, flags):
        calls.append((os.fstat(fd).st_ino, offset, nbytes, flags))
        return real(fd, offset, nbytes, flags)

    monkeypatch.setattr(writeback, "_sync_file_range", lambda: recorder)
    path = tmp_path / "store.h5"
    path.write_bytes(b"x" * 100_000)
    writeback.start_write_back(path)
    assert calls == [(path.stat().st_ino, 0, 0, writeback.SYNC_FILE_RANGE_WRITE)]
    writeback.start_write_back(tmp_path / "renamed-meanwhile.h5")  # gone: skipped, no error
    assert len(calls) == 1


def test_the_store_requests_a_write_back_after_every_frame_on_an_idle_core(tmp_path, monkeypatch):
    """Write-backs of the store being written, at least one per appended frame, by a thread that asked for
    SCHED_IDLE (Linux); it ends with the writer, and the store is the same as without it."""
    seen, policies, started = [], [], threading.Semaphore(0)

    def recorder(path):
        policies.append(os.sched_getscheduler(0) if hasattr(os, "SCHED_IDLE") else None)
        seen.append(os.path.basename(path))
        started.release()

    monkeypatch.setattr(writeback, "start_write_back", recorder)
    out = tmp_path / "out.h5"
    w = ResultWriter(out, PROVENANCE, walls_meta=WALLS_META)
    for step in (0, 1000, 2000):
        w.append(synthetic_frame(step))
        assert started.acquire(timeout=60)  # the writer does not wait; the test does, for each frame's
    thread = w._write_back._thread
    w.close()
    thread.join(60)
    assert set(seen) == {"store.h5"} and len(seen) >= 3 and not thread.is_alive()
    assert set(policies) == ({os.SCHED_IDLE} if hasattr(os, "SCHED_IDLE") else {None})
    plain = tmp_path / "plain.h5"
    monkeypatch.setattr(writeback, "start_write_back", lambda path: None)
    with ResultWriter(plain, PROVENANCE, walls_meta=WALLS_META) as w:
        for step in (0, 1000, 2000):
            w.append(synthetic_frame(step))
    for name in ("particles", "contacts", "walls", "frames"):
        assert getattr(load_results(out), name).equals(getattr(load_results(plain), name))


def test_a_failing_write_back_does_not_stop_the_store(tmp_path, monkeypatch):
    """The write-back is a hint: a call that fails (here a file system that refuses it) is ignored."""
    monkeypatch.setattr(writeback, "_sync_file_range", lambda: lambda fd, offset, nbytes, flags: -1)
    out = tmp_path / "out.h5"
    with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META) as w:
        w.append(synthetic_frame(0))
    assert len(load_results(out).frames) == 1


@pytest.mark.parametrize("final", [True, False])
def test_the_final_frame_asks_for_a_write_back_after_each_column(tmp_path, monkeypatch, final):
    """The frame at ``final_step`` asks for the write-back after each column's chunks are written, so that
    its pages are on their way to disk before ``close``'s fsync; any other frame once, after the frame."""
    asked = []
    monkeypatch.setattr(writeback.WriteBack, "request", lambda self, path: asked.append(os.path.basename(path)))
    with ResultWriter(tmp_path / "out.h5", PROVENANCE, walls_meta=WALLS_META, final_step=1000 if final else 2000) as w:
        w.append(synthetic_frame(0, n_particles=1500, n_pairs=1500))  # fewer rows than a chunk: carried
        assert len(asked) == 1
        w.append(synthetic_frame(1000, n_particles=1500, n_pairs=1500))  # completes a chunk of two tables
        columns = sum(len(sink.schema) for sink in w._sinks.values() if sink.written)
        assert columns > 0 and len(asked) - 1 == (columns + 1 if final else 1)  # each column's, the frame's
    assert set(asked) == {"store.h5"}
