"""YADE saved states (``O.save``) analysed post hoc: a script that never imported demsplit.

sample_dumps/yade/saved_states.py saves its state (binary .yade.gz and XML .xml.bz2) from a PyRunner
between the InteractionLoop and the integrator; run with DEMSPLIT_SITE it also writes demsplit's in-run
snapshot at the same instant, and the two paths give the same tables: the integers exactly, the reals to
rounding (a state's overlap is recovered from the stiffness kn Hertz-Mindlin stored, the snapshot's is
YADE's penetrationDepth). tests/test_yade_instants.py checks every law and every place a state is saved from.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import demsplit
import numpy as np
import pytest
from conftest import require_program
from demsplit.cli import main
from demsplit.readers.yade_state import YadeStateRun
from reader_contract import ReaderContract
from test_yade_simulator import SAMPLE_SCRIPTS, SITE, run_yade

pytestmark = pytest.mark.simulator


@pytest.fixture(scope="module")
def states(tmp_path_factory) -> Path:
    yade = require_program("yade")
    out = tmp_path_factory.mktemp("states")
    run_yade(yade, SAMPLE_SCRIPTS / "saved_states.py", out)
    assert sorted(p.name for p in out.glob("state-*")) == ["state-010000.yade.gz", "state-020000.xml.bz2"]
    return out


@pytest.mark.slow
def test_saved_states_give_the_in_run_snapshot(states, tmp_path):
    in_run = demsplit.analyze(states / "saved_states.h5")
    saved = demsplit.analyze(states, state_cache=tmp_path / "cache")  # a directory of states
    assert saved.steps.tolist() == in_run.steps.tolist() == [10000, 20000]
    for table in ("particles", "contacts", "walls", "frames"):
        a, b = getattr(in_run, table), getattr(saved, table)
        assert list(a.columns) == list(b.columns) and len(a) == len(b) > 0
        for c in a.columns:
            if a[c].dtype.kind in "iub":
                np.testing.assert_array_equal(b[c].to_numpy(), a[c].to_numpy(), err_msg=f"{table}.{c}")
            else:  # to 1e-12 of the column's largest value (a coordinate near 0 differs in its last bits)
                scale = np.abs(a[c].to_numpy()).max()
                np.testing.assert_allclose(
                    b[c].to_numpy(), a[c].to_numpy(), rtol=0, atol=1e-12 * scale, err_msg=f"{table}.{c}"
                )


@pytest.mark.slow
def test_run_keeps_converted_states_next_to_the_output(states, tmp_path):
    assert main(["run", str(states / "state-010000.yade.gz"), "-o", str(tmp_path / "r.h5"), "-q"]) == 0
    assert len(list((tmp_path / "r.h5.states").glob("*.npys"))) == 1


@pytest.mark.slow
def test_one_state_by_name_and_by_glob(states, tmp_path):
    cache = tmp_path / "cache"
    assert (
        main(
            [
                "run",
                str(states / "state-010000.yade.gz"),
                "-o",
                str(tmp_path / "one.h5"),
                "-q",
                "--state-cache",
                str(cache),
            ]
        )
        == 0
    )
    assert demsplit.load_results(tmp_path / "one.h5").steps.tolist() == [10000]
    assert (
        main(["run", str(states / "state-*"), "-o", str(tmp_path / "glob.h5"), "-q", "--state-cache", str(cache)]) == 0
    )
    assert demsplit.load_results(tmp_path / "glob.h5").steps.tolist() == [10000, 20000]
    listed = [str(states / "state-020000.xml.bz2"), str(states / "state-010000.yade.gz")]  # any order
    assert main(["run", *listed, "-o", str(tmp_path / "list.h5"), "-q", "--state-cache", str(cache)]) == 0
    assert demsplit.load_results(tmp_path / "list.h5").steps.tolist() == [10000, 20000]


def cli(*args: str, path: str | None = None, address_space: int | None = None) -> subprocess.CompletedProcess:
    """``demsplit ARGS`` in a process of its own; ``address_space``: its limit (bytes, RLIMIT_AS), which the YADE
    it starts inherits."""
    import resource

    env = {**os.environ, **({"PATH": path} if path is not None else {})}
    limit = None if address_space is None else lambda: resource.setrlimit(resource.RLIMIT_AS, (address_space,) * 2)
    return subprocess.run(
        [sys.executable, "-m", "demsplit.cli", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
        preexec_fn=limit,
    )


DAMAGED_STATE_MEMORY = 3 << 30
"""Address space (bytes) of the process that converts a damaged state: YADE's loader, reading the lengths of a
cut file, allocated 8.6 GB of it before it gave up; with the limit the allocation fails instead, the same
error."""


@pytest.mark.slow
def test_info_describes_a_state(states, tmp_path):
    proc = cli("info", str(states / "state-020000.xml.bz2"))
    assert proc.returncode == 0, proc.stderr
    for word in (
        "YADE saved state",
        "iterations: [20000]",
        "spheres",
        "real",
        "Law2_ScGeom_MindlinPhys_Mindlin",
        "E=2e+07 Pa nu=0.3",
        "facet",
    ):
        assert word in proc.stdout, word


@pytest.mark.slow
def test_a_second_run_reads_the_cache_without_yade(states, tmp_path):
    cache = tmp_path / "cache"
    no_yade = str(Path(sys.executable).parent)  # this Python's bin: no yade on this PATH
    first = cli(
        "run",
        str(states / "state-010000.yade.gz"),
        "-o",
        str(tmp_path / "a.h5"),
        "-q",
        "--state-cache",
        str(cache),
        path=no_yade,
    )
    assert first.returncode == 2 and "apt-get install yade" in first.stderr  # nothing cached: YADE is needed
    assert (
        main(
            [
                "run",
                str(states / "state-010000.yade.gz"),
                "-o",
                str(tmp_path / "b.h5"),
                "-q",
                "--state-cache",
                str(cache),
            ]
        )
        == 0
    )
    assert len(list(cache.iterdir())) == 1
    again = cli(
        "run",
        str(states / "state-010000.yade.gz"),
        "-o",
        str(tmp_path / "c.h5"),
        "-q",
        "--state-cache",
        str(cache),
        path=no_yade,
    )
    assert again.returncode == 0, again.stderr


@pytest.mark.slow
def test_a_damaged_state_is_one_clear_error(states, tmp_path):
    data = (states / "state-010000.yade.gz").read_bytes()
    cut = tmp_path / "cut.yade.gz"
    cut.write_bytes(data[: len(data) // 2])
    proc = cli(
        "run",
        str(cut),
        "-o",
        str(tmp_path / "x.h5"),
        "-q",
        "--state-cache",
        str(tmp_path / "cache"),
        address_space=DAMAGED_STATE_MEMORY,
    )
    assert proc.returncode == 2 and "gzip stream is cut short" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "x.h5").exists()
    assert not (tmp_path / "cache").exists()  # nothing half-converted is cached


def test_site_is_where_demsplit_is_installed():
    assert Path(SITE).is_dir()


@pytest.mark.slow
class TestSavedStates(ReaderContract):
    reader = YadeStateRun

    @pytest.fixture
    def run_path(self, states, tmp_path_factory) -> Path:
        self.options = {"state_cache": str(tmp_path_factory.mktemp("contract-cache"))}
        return states


@pytest.mark.slow
def test_a_state_saved_by_yade_mpfr150_is_read_by_that_build(tmp_path):
    """yade cannot load it; demsplit falls back to the high-precision build that can."""
    mpfr = require_program("yade-mpfr150")
    run_yade(
        mpfr,
        SAMPLE_SCRIPTS / "saved_states.py",
        tmp_path,
        DEMSPLIT_ITER="2000",
        DEMSPLIT_EVERY="2000",
        DEMSPLIT_SITE="",
    )
    state = tmp_path / "state-002000.yade.gz"
    assert main(["run", str(state), "-o", str(tmp_path / "r.h5"), "-q", "--state-cache", str(tmp_path / "c")]) == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert res.steps.tolist() == [2000] and res.frames["u_n"].iloc[0] > 0
    info = cli("info", str(state))
    assert "PrecisionBoostBinFloat150" in info.stdout
