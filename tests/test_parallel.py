"""Worker processes (``jobs``) and Dask (``dask``) give the serial results exactly.

Each path processes every frame of a real LIGGGHTS run (the packing sample:
mesh floor, primitive walls, two materials) and of both YADE snapshot samples;
the per-particle, per-contact, per-wall and per-frame tables must equal the
serial ones value for value, in the same order. Not timed.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from demsplit.pipeline import analyze, run_to_store
from demsplit.results import load_results

pytest.importorskip("distributed")


def _runs(samples):
    return {
        "liggghts-packing": samples / "liggghts" / "packing" / "in.packing",
        "yade-mindlin_box": samples / "yade" / "mindlin_box.h5",
        "yade-cundall_periodic": samples / "yade" / "cundall_periodic.h5",
    }


def assert_same_results(a, b) -> None:
    """Every table of two Results equal, column by column, row by row."""
    for name in ("particles", "contacts", "walls", "frames"):
        ta, tb = getattr(a, name), getattr(b, name)
        assert list(ta.columns) == list(tb.columns), name
        assert len(ta) == len(tb), name
        pd.testing.assert_frame_equal(ta.reset_index(drop=True), tb.reset_index(drop=True), check_exact=True)


@pytest.fixture(scope="module")
def serial(request):
    samples = request.config.rootpath / "sample_dumps"
    return {name: analyze(path) for name, path in _runs(samples).items()}


@pytest.fixture
def four_cores(monkeypatch):
    """A machine of 4 cores as demsplit sees it, so that --jobs 2 starts two worker processes."""
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "THREADS", 4)
    monkeypatch.setenv("DEMSPLIT_THREADS", "4")


def test_worker_processes_need_two_cores_each(monkeypatch):
    from demsplit.pipeline import worker_processes
    from demsplit.runtime import threads

    for cores, jobs, used in ((2, 2, 1), (2, 8, 1), (3, 2, 1), (4, 2, 2), (4, 8, 2), (16, 4, 4), (16, 1, 1)):
        monkeypatch.setattr(threads, "THREADS", cores)
        assert worker_processes(jobs) == used, (cores, jobs)


def test_jobs_beyond_the_cores_run_serially_with_a_note(samples, monkeypatch):
    import demsplit.pipeline as pipeline
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "THREADS", 2)
    monkeypatch.setattr(pipeline, "processes", lambda *a: pytest.fail("no worker process on 2 cores"))
    res = analyze(_runs(samples)["liggghts-packing"], jobs=2)
    notes = res.provenance["notes"]
    assert any(n.startswith("--jobs 2 on 2 cores: the frames computed in this process") for n in notes)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["liggghts-packing", "yade-mindlin_box", "yade-cundall_periodic"])
def test_worker_processes_equal_serial(name, serial, samples, four_cores, monkeypatch):
    import demsplit.pipeline as pipeline

    started = []
    processes = pipeline.processes
    monkeypatch.setattr(pipeline, "processes", lambda *a: started.append(a[-1]) or processes(*a))
    parallel = analyze(_runs(samples)[name], jobs=2)
    assert started == [2]  # two worker processes did the work
    assert len(parallel.frames) == len(serial[name].frames) > 0
    assert_same_results(parallel, serial[name])


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as c:
        yield c


@pytest.mark.slow
@pytest.mark.parametrize("name", ["liggghts-packing", "yade-mindlin_box"])
def test_dask_cluster_equals_serial(name, serial, samples, cluster):
    """A scheduler address (tcp://...) as a user would pass to --dask."""
    remote = analyze(_runs(samples)[name], dask=cluster.scheduler_address)
    assert_same_results(remote, serial[name])


@pytest.mark.slow
def test_dask_local_store_equals_serial_store(samples, tmp_path):
    """The CLI's --dask local:2 path, through the HDF5 store."""
    script = _runs(samples)["liggghts-packing"]
    run_to_store(script, tmp_path / "serial.h5", progress=False)
    run_to_store(script, tmp_path / "dask.h5", dask="local:2", progress=False)
    a, b = load_results(tmp_path / "serial.h5"), load_results(tmp_path / "dask.h5")
    assert_same_results(a, b)
    assert np.all(np.diff(b.frames["step"].to_numpy()) > 0)
