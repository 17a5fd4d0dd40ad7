"""The first frame's memory mapped while the run opens (:mod:`demsplit.runtime.prefault`): the LIGGGHTS reader
tells the first frame's size without indexing its dumps, the block is written and freed, and nothing
happens without a size."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import demsplit.runtime.prefault as prefault
import pytest
from demsplit.readers import open_run
from demsplit.readers.lammps_dump import TextDump
from demsplit.readers.liggghts import LiggghtsRun
from demsplit.runtime import command


def resident_bytes() -> int:
    """The process's resident memory (``/proc/self/statm``, Linux)."""
    return int(Path("/proc/self/statm").read_text().split()[1]) * 4096


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="resident memory is read from Linux's /proc")
def test_a_block_is_written_page_by_page_then_freed():
    n = 6 * prefault.PIECE + 12345  # whole pieces and a part
    before = resident_bytes()
    block = prefault.Prefault(n)
    deadline = time.monotonic() + 60
    while block.mapped < n and time.monotonic() < deadline:  # the thread runs on idle cores: this one idles
        time.sleep(0.01)
    assert block.mapped == n
    assert resident_bytes() - before > 0.9 * n  # its pages are mapped, not just reserved
    block.release()
    assert block._block is None and block._thread is None
    block.release()  # twice: nothing


def test_release_stops_the_thread_before_the_block_is_written_whole(monkeypatch):
    """release() during the first piece: the thread finishes that piece and writes no other. The piece waits
    until release() has asked it to stop, so the test writes one piece, whatever the machine's load (the thread
    left to race release() on an 8 GiB block wrote all of it on a busy machine: an 8.6 GB test)."""
    inside, go_on = threading.Event(), threading.Event()
    memset = prefault.ctypes.memset

    def first_piece_waits(*args):
        inside.set()
        assert go_on.wait(60)
        return memset(*args)

    monkeypatch.setattr(prefault.ctypes, "memset", first_piece_waits)
    block = prefault.Prefault(64 * prefault.PIECE)  # address space; one piece of it is written
    assert inside.wait(60)
    stopping = threading.Thread(target=block.release)
    stopping.start()
    deadline = time.monotonic() + 60
    while not block._stop.is_set() and time.monotonic() < deadline:
        time.sleep(0.001)
    go_on.set()
    stopping.join(60)
    assert block._thread is None and block.mapped == prefault.PIECE


def test_nothing_is_allocated_for_no_rows():
    block = prefault.Prefault(prefault.first_frame_bytes(0, 0))
    assert block._block is None and block._thread is None
    block.release()


def test_first_frame_bytes_is_the_documented_sum():
    assert prefault.first_frame_bytes(10, 20) == 10 * prefault.BYTES_PER_PARTICLE + 20 * prefault.BYTES_PER_CONTACT


@pytest.fixture
def blocks(monkeypatch) -> list:
    """The blocks :func:`demsplit.runtime.prefault.first_frame_prefaulted` makes, recorded instead of allocated:
    ``[nbytes, released]`` each."""
    made: list[list] = []

    class Recorder:
        def __init__(self, nbytes: int) -> None:
            self.entry = [nbytes, False]
            made.append(self.entry)

        def release(self) -> None:
            self.entry[1] = True

    monkeypatch.setattr(prefault, "Prefault", Recorder)
    return made


@pytest.mark.parametrize("rows", [(10, 20), None])
def test_the_context_maps_the_first_frame_only_when_its_size_is_given(blocks, rows):
    with prefault.first_frame_prefaulted(rows):
        assert all(not released for _, released in blocks)
    assert blocks == ([[prefault.first_frame_bytes(10, 20), True]] if rows else [])


def test_a_frame_larger_than_the_heap_serves_gets_the_largest_block(blocks):
    """Above glibc's mapping threshold a block would be a mapping of its own, unmapped when freed."""
    with prefault.first_frame_prefaulted((10**7, 3 * 10**7)):
        pass
    assert prefault.first_frame_bytes(10**7, 3 * 10**7) > command.MMAP_THRESHOLD
    assert blocks == [[prefault.LARGEST, True]] and prefault.LARGEST < command.MMAP_THRESHOLD


def test_the_block_is_freed_when_the_opening_fails(blocks):
    with pytest.raises(RuntimeError), prefault.first_frame_prefaulted((10, 20)):
        raise RuntimeError("the run cannot be opened")
    assert blocks == [[prefault.first_frame_bytes(10, 20), True]]


def test_the_liggghts_reader_tells_its_first_frame_without_indexing(samples, monkeypatch):
    """(particles, contacts) of frame 0 as the dumps' headers say, walls' contacts included, without any
    dump indexed (the warm-up's window is the opening that indexes them)."""
    script = samples / "liggghts" / "packing" / "in.packing"
    indexed = []
    build = TextDump._build_index

    def indexing(self):
        indexed.append(self.path)
        return build(self)

    monkeypatch.setattr(TextDump, "_build_index", indexing)
    rows = LiggghtsRun.first_frame_rows(script)
    assert indexed == []
    with open_run(script) as run:
        walls = int(run.walls.rows[0])
        assert walls > 0  # the sample has wall contacts: they are counted
        assert rows == (int(run.atoms.rows[0]), int(run.pairs.rows[0]) + walls)


def test_a_run_whose_files_are_missing_tells_no_size(tmp_path):
    script = tmp_path / "in.nothing"
    script.write_text("units si\n")
    assert LiggghtsRun.first_frame_rows(script) is None
