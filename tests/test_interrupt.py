"""Interrupted runs: ``demsplit run`` killed (SIGKILL), terminated (SIGTERM) or
interrupted (SIGINT) while it writes never leaves a file at the output path
that is not complete, and ``--resume`` then finishes with results equal to
an uninterrupted run's.

The run: 60 frames made from the packing sample's 3 (frame j is sample frame
j mod 3 at step 200000 + 2000 j), in plain text, so that ``demsplit run``
takes a few seconds and can be interrupted after its first frames.
"""

from __future__ import annotations

import collections
import gzip
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import demsplit
import demsplit.results.store
import demsplit.results.writer
import h5py
import numpy as np
import pandas as pd
import pytest

PACKING = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts" / "packing"
N_FRAMES = 60
TABLES = ("particles", "contacts", "walls", "frames")


def repeat_frames(text: bytes, n: int) -> bytes:
    """A dump of ``n`` frames: frame j is frame (j mod len) of ``text`` at step 200000 + 2000 j."""
    frames = [b"ITEM: TIMESTEP" + f for f in text.split(b"ITEM: TIMESTEP")[1:]]
    out = []
    for j in range(n):
        lines = frames[j % len(frames)].split(b"\n", 2)
        out.append(b"\n".join([lines[0], str(200000 + 2000 * j).encode(), lines[2]]))
    return b"".join(out)


@pytest.fixture(scope="module")
def long_run(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("long")
    for name in ("in.packing", "floor.stl"):
        shutil.copy(PACKING / name, d / name)
    for name in ("atoms_full.txt", "pairs_full.txt", "wall_full.txt"):
        with gzip.open(PACKING / f"{name}.gz", "rb") as f:
            (d / name).write_bytes(repeat_frames(f.read(), N_FRAMES))
    return d / "in.packing"


def demsplit_run(script: Path, out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "demsplit.cli", "run", str(script), "-o", str(out), "-q", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.fixture(scope="module")
def reference(long_run, tmp_path_factory) -> demsplit.Results:
    out = tmp_path_factory.mktemp("ref") / "ref.h5"
    proc = demsplit_run(long_run, out)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    return demsplit.load_results(out)


def work_of(out: Path) -> Path:
    return demsplit.results.store.work_dir_of(out)


def done_steps(out: Path) -> list[int]:
    """The frames the interrupted store holds (its commit record; a record being written is a .tmp)."""
    return demsplit.results.writer.committed_steps(out)


def wait_for_frames(proc: subprocess.Popen, out: Path, n: int) -> None:
    """Wait until the run has committed at least ``n`` frames (and is still running)."""
    deadline = time.monotonic() + 120
    while len(done_steps(out)) < n:
        assert proc.poll() is None, f"the run ended before it could be interrupted: {proc.communicate()}"
        assert time.monotonic() < deadline
        time.sleep(0.01)


def assert_complete_or_absent(out: Path) -> None:
    """Nothing at ``out``, or a store whose frame index is consistent."""
    if not out.exists():
        return
    with h5py.File(out, "r") as h5:
        steps = h5["index/step"][()]
        for name in TABLES:
            offsets = h5[f"index/{name}"][()]
            assert len(offsets) == len(steps) + 1 and offsets[0] == 0 and np.all(np.diff(offsets) >= 0)
            for col in h5[name]:
                assert h5[name][col].shape[0] == offsets[-1]


def assert_same_results(a: demsplit.Results, b: demsplit.Results) -> None:
    for name in TABLES:
        pd.testing.assert_frame_equal(getattr(a, name), getattr(b, name), check_exact=True)


@pytest.mark.parametrize(
    "sig, code, words",
    [
        (signal.SIGKILL, -signal.SIGKILL, None),
        (signal.SIGTERM, 143, "terminated (SIGTERM); run again with --resume"),
        (signal.SIGINT, 130, "interrupted; run again with --resume"),
    ],
)
@pytest.mark.slow
def test_interrupted_run_resumes_to_the_same_results(long_run, reference, tmp_path, sig, code, words):
    out = tmp_path / "out.h5"
    proc = demsplit_run(long_run, out)
    wait_for_frames(proc, out, 3)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    if words is not None:  # a handled signal: one message, no traceback
        assert words in err and "Traceback" not in err and err.count("\n") == 1
    assert_complete_or_absent(out)
    assert not out.exists()
    done = done_steps(out)
    assert 3 <= len(done) < N_FRAMES
    assert not list(work_of(out).glob("*.tmp")) or sig == signal.SIGKILL

    again = demsplit_run(long_run, out)  # without --resume: refused, the interrupted frames untouched
    _, err = again.communicate(timeout=120)
    assert again.returncode == 2 and "--resume" in err
    assert done_steps(out) == done

    resumed = subprocess.run(
        [sys.executable, "-m", "demsplit.cli", "run", str(long_run), "-o", str(out), "--resume"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"{len(done)} resumed" in resumed.stdout
    assert not work_of(out).exists()
    assert_complete_or_absent(out)
    assert_same_results(demsplit.load_results(out), reference)
    assert len(reference.frames) == N_FRAMES


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="needs Linux /proc")
def test_sigkill_of_a_parallel_run_leaves_no_process_behind(tmp_path):
    """demsplit run -j 2 killed with SIGKILL: its workers, the fork server and the resource tracker are
    gone within 5 s (they were left running); the run then completes with --resume when it had committed
    frames, and with a plain rerun (not refused) when it had none."""
    import uuid

    mark = f"DEMSPLIT_TEST_MARK={uuid.uuid4().hex}".encode()

    def marked() -> list[int]:
        found = []
        for p in Path("/proc").iterdir():
            try:
                if p.name.isdigit() and mark in (p / "environ").read_bytes():
                    found.append(int(p.name))
            except OSError:
                continue
        return found

    repo = Path(__file__).resolve().parents[1]
    subprocess.run(
        [
            sys.executable,
            str(repo / "benchmarks" / "generate.py"),
            str(tmp_path / "run"),
            "--particles",
            "20000",
            "--contacts",
            "40000",
            "--frames",
            "6",
        ],
        check=True,
        capture_output=True,
    )
    script = tmp_path / "run" / "in.bench"  # a run long enough to be killed while its workers compute
    # DEMSPLIT_THREADS: as on 4 cores, where -j 2 starts two workers (on fewer it runs serially)
    env = dict(os.environ, DEMSPLIT_TEST_MARK=mark.split(b"=")[1].decode(), DEMSPLIT_THREADS="4")
    proc = subprocess.Popen(
        [sys.executable, "-m", "demsplit.cli", "run", str(script), "-o", str(tmp_path / "o.h5"), "-j", "2", "-q"],
        env=env,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 30
    while len(marked()) < 4 and time.monotonic() < deadline:  # the run, the fork server, two workers
        time.sleep(0.05)
    assert len(marked()) >= 4
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 5
    while marked() and time.monotonic() < deadline:
        time.sleep(0.1)
    left = marked()
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert left == []
    out = tmp_path / "o.h5"
    resume = ["--resume"] if done_steps(out) else []
    again = subprocess.run(
        [sys.executable, "-m", "demsplit.cli", "run", str(script), "-o", str(out), "-j", "2", "-q", *resume],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert again.returncode == 0, again.stderr
    assert len(demsplit.load_results(out).frames) == 6 and not work_of(out).exists()


# --- SIGKILL at every stage of the store's close() ---------------------------------------------------------

CLOSE_KILLER = r"""
import json, os, random, signal, sys, time
sys.path.insert(0, sys.argv[1])
import demsplit.outputs, demsplit.results.writer as writer
from result_frames import PROVENANCE, WALLS_META, synthetic_frame

root, steps, random_kills = sys.argv[2], [int(s) for s in sys.argv[3].split(",")], int(sys.argv[4])
watched = {writer.__file__, demsplit.outputs.__file__}
for k in range(random_kills):  # SIGKILL at a random instant of close(), inside HDF5's own calls included
    out = os.path.join(root, f"r{k}", "out.h5")
    os.makedirs(os.path.dirname(out))
    ready, go = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(ready)
        w = writer.ResultWriter(out, PROVENANCE, walls_meta=WALLS_META)
        for s in steps:
            w.append(synthetic_frame(s, n_particles=3000, n_pairs=5000))
        os.write(go, b"x")
        w.close()
        os._exit(0)
    os.close(go)  # a child that dies before it writes ends the read (EOF) instead of blocking it
    if os.read(ready, 1) != b"x":
        sys.exit(f"the writer process {pid} died before close()")
    os.close(ready)
    time.sleep(random.Random(k).uniform(0, 0.03))
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    print(json.dumps({"k": f"r{k}", "out": out, "at": "random", "n_particles": 3000}), flush=True)
k = 0
while True:
    k += 1
    out = os.path.join(root, f"k{k}", "out.h5")
    os.makedirs(os.path.dirname(out))
    pid = os.fork()
    if pid == 0:  # write every frame, then close, killed at the k-th distinct statement close() reaches
        w = writer.ResultWriter(out, PROVENANCE, walls_meta=WALLS_META)
        for s in steps:
            w.append(synthetic_frame(s, n_particles=300, n_pairs=500))
        seen = []

        def trace(frame, event, arg):
            if frame.f_code.co_filename not in watched:
                return None
            if event == "line":
                where = (frame.f_code.co_filename, frame.f_lineno)
                if where not in seen:
                    seen.append(where)
                    if len(seen) == k:
                        print(json.dumps({"k": k, "out": out, "at": f"{os.path.basename(where[0])}:{where[1]} "
                                          f"{frame.f_code.co_name}"}), flush=True)
                        os.kill(os.getpid(), signal.SIGKILL)
            return trace

        sys.settrace(trace)
        w.close()
        sys.settrace(None)
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    if os.WIFEXITED(status):  # close() ended before its k-th statement: every stage was killed
        print(json.dumps({"k": k, "out": out, "at": None}), flush=True)
        break
"""


@pytest.mark.slow
@pytest.mark.parametrize("steps", [(0, 1000, 2000, 3000), (2000, 0, 3000, 1000)], ids=["in order", "out of order"])
def test_sigkill_at_every_stage_of_close_leaves_a_resumable_run_or_a_complete_store(tmp_path, steps):
    """close() finishes the store (last rows, frame index, attributes; a copy in step order when frames came
    out of order), renames it into place and removes the work directory. Killed before any statement it reaches
    (and before any of the functions it calls in the store and atomic modules), or at 6 random instants (inside
    HDF5's calls too), the run is resumable to the same store, or the store is complete; a plain rerun is refused
    only while committed frames wait for --resume."""
    from demsplit.errors import StoreError
    from demsplit.results import Results
    from demsplit.results.store import work_dir_of
    from demsplit.results.writer import ResultWriter, check_output, committed_steps
    from result_frames import PROVENANCE, WALLS_META, synthetic_frame

    tests = Path(__file__).resolve().parent
    proc = subprocess.run(
        [sys.executable, "-c", CLOSE_KILLER, str(tests), str(tmp_path), ",".join(map(str, steps)), "6"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    kills = [json.loads(line) for line in proc.stdout.splitlines()]
    stages = [k for k in kills if k["at"] != "random"]
    assert kills[-1]["at"] is None and len(stages) > 38, kills  # every stage, then a close that ran through
    outcomes = collections.Counter()
    for kill in kills:
        n = kill.get("n_particles", 300)
        frames = [synthetic_frame(s, n_particles=n, n_pairs=5 * n // 3) for s in steps]
        expected = Results.from_frames(frames, PROVENANCE, WALLS_META)
        out = Path(kill["out"])
        if out.exists():  # complete: readable, equal, and a new run on it is not refused
            assert_same_results(demsplit.load_results(out), expected)
            check_output(out)
            assert not work_dir_of(out).exists()  # a leftover without a store is removed
            outcomes["complete"] += 1
            continue
        assert sorted(committed_steps(out)) == sorted(steps), kill
        with pytest.raises(StoreError, match="--resume"):  # committed frames are never silently discarded
            check_output(out)
        with ResultWriter(out, PROVENANCE, walls_meta=WALLS_META, resume=True) as w:
            assert w.done_steps == set(steps), kill
        assert_same_results(demsplit.load_results(out), expected)
        assert not work_dir_of(out).exists()
        outcomes["resumed"] += 1
    assert outcomes["complete"] and outcomes["resumed"], outcomes
