"""The reader registry: readers register themselves, open_run asks their detect, and every registered
reader is held to the shared contract (tests/reader_contract.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
import test_cache
import test_lammps_run
import test_liggghts_run
import test_yade_readers
import test_yade_state
from demsplit.errors import InputFormatError
from demsplit.readers import REGISTRY, open_run, reader_for, readers
from demsplit.readers.base import Run
from reader_contract import ReaderContract

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


def test_every_registered_reader_keeps_the_contract():
    """Every reader of the package has a test class inheriting the contract (a reader a test defines for
    itself has one too, but is registered only while its tests run)."""
    tested = {getattr(cls, "reader", None) for cls in ReaderContract.__subclasses__()}
    assert test_cache and test_lammps_run and test_liggghts_run and test_yade_readers and test_yade_state  # contract
    assert set(readers()) <= tested


def test_a_new_reader_registers_itself_and_is_found_by_its_detect(tmp_path):
    class ToyRun(Run):
        format_name = "toy"
        formats = ("a toy file",)
        priority = 100

        @classmethod
        def detect(cls, path, head):
            return head.startswith(b"TOY")

        def __init__(self, path):
            self.path = path

        def __len__(self):
            return 0

        def frame(self, k):
            raise IndexError(k)

    try:
        toy = tmp_path / "run.toy"
        toy.write_bytes(b"TOY v1\n")
        assert REGISTRY["toy"] is ToyRun and readers()[0] is ToyRun
        run = open_run(toy)
        assert isinstance(run, ToyRun) and run.spec == {"path": str(toy)}
        assert reader_for(SAMPLES / "yade" / "mindlin_box.h5") is not ToyRun
    finally:
        del REGISTRY["toy"]


def test_an_option_the_reader_does_not_take_is_one_message():
    with pytest.raises(InputFormatError, match=r"option\(s\) \['atoms'\] do not apply") as err:
        open_run(SAMPLES / "yade" / "mindlin_box.h5", atoms="x.txt")
    assert "plane_as_plane" in str(err.value)


def test_an_unrecognised_binary_file_lists_the_formats(tmp_path):
    junk = tmp_path / "junk.dat"
    junk.write_bytes(b"\0\1\2" * 100)
    with pytest.raises(InputFormatError, match="no reader reads it") as err:
        open_run(junk)
    assert "demsplit.yade.snapshot" in str(err.value) and "LIGGGHTS input script" in str(err.value)


def test_a_directory_is_answered_with_the_runs_it_holds():
    with pytest.raises(InputFormatError, match="a directory, not a run") as err:
        open_run(SAMPLES / "yade")
    assert "mindlin_box.h5" in str(err.value) and "mindlin_box-spheres-00024000.vtk" in str(err.value)
    assert "intrs" not in str(err.value)  # an interactions file is not a run of its own
    with pytest.raises(InputFormatError, match="in.packing"):
        open_run(SAMPLES / "liggghts" / "packing")


def test_version(capsys):
    from demsplit import __version__
    from demsplit.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"demsplit {__version__}"
