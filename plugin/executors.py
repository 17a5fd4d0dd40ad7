"""Where the frames of a run are computed: in this process, in worker processes, or on a Dask cluster.

Each executor yields ``(k, tables or the frame's error, notes)`` for the frames ``indices`` of a run in
frame order, with at most a few frames in flight (:func:`_windowed`), so that memory stays a few frames
whatever the number of frames. A frame's error is returned, not raised: the caller decides whether to stop
or skip it. Worker processes open the run again from its ``spec`` (the path and reader options
:func:`demsplit.readers.open_run` got), once per worker.
"""

from __future__ import annotations

import os
import sys
from collections import deque
from collections.abc import Callable, Iterator
from pathlib import Path

from .compute import Options, Tables, frame_tables
from .errors import DemsplitError
from .readers.base import Run
from .runtime import threads

Result = tuple[int, "Tables | DemsplitError", list]
"""What an executor yields per frame: its index, its tables (or its error) and the frame's notes."""


def _open(spec: dict) -> Run:
    from .readers import open_run

    spec = dict(spec)
    return open_run(spec.pop("path"), **spec)


_WORKER_RUN: dict = {}


def _worker_frame(spec_key: tuple, spec: dict, k: int, options: Options) -> tuple[int, Tables | DemsplitError, list]:
    """Process frame ``k`` of the run ``spec`` in a worker (the run is opened once per worker)."""
    run = _WORKER_RUN.get(spec_key)
    if run is None:
        _WORKER_RUN.clear()
        run = _WORKER_RUN[spec_key] = _open(spec)
    try:
        frame = run.frame(k)
        return k, frame_tables(frame, run.scene, options), frame.notes
    except DemsplitError as exc:  # returned, not raised: the parent decides (stop or skip)
        return k, exc, []


def _exit_with_parent(parent: int) -> None:
    """Worker initializer: a daemon thread ends the worker when ``parent`` (the process running the pool)
    is gone. A worker's own parent is multiprocessing's fork server, which outlives a killed main process,
    so without this a SIGKILLed ``demsplit run -j N`` left its workers, the fork server and the resource
    tracker running."""
    import threading
    import time

    def watch() -> None:
        while True:
            time.sleep(0.5)
            try:
                os.kill(parent, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:  # alive, owned by someone else: cannot be ours, but keep waiting
                pass

    threading.Thread(target=watch, name="demsplit-parent-watch", daemon=True).start()


def _spec_key(spec: dict) -> tuple:
    return tuple(sorted((k, repr(v)) for k, v in spec.items()))


def serial(run: Run, indices: list[int], options: Options) -> Iterator[tuple[int, Tables | DemsplitError, list]]:
    for k in indices:
        try:
            held = [run.frame(k)]
            notes = held[0].notes  # frame_tables adds its notes to this list
            # the frame handed over with its only reference: the columns frame_tables has used go at once
            out: Tables | DemsplitError = frame_tables(held.pop(), run.scene, options)
        except DemsplitError as exc:
            out, notes = exc, []
        yield k, out, notes
        del out  # held by the consumer until it is done with it; not by this generator


def _windowed(
    submit: Callable[[int], object], result: Callable[[object], tuple], indices: list[int], window: int
) -> Iterator[tuple]:
    """Submit frames ahead but at most ``window`` at a time, yield results in frame order
    (memory stays a few frames, whatever the number of frames)."""
    pending: deque = deque()
    it = iter(indices)
    for k in it:
        pending.append(submit(k))
        if len(pending) >= window:
            break
    while pending:
        fut = pending.popleft()
        nxt = next(it, None)
        if nxt is not None:
            pending.append(submit(nxt))
        yield result(fut)
        del fut  # its result is the consumer's now


MIN_THREADS_PER_WORKER = 2
"""A worker process runs only where each gets at least this many cores (see :func:`worker_processes`)."""


def worker_processes(jobs: int) -> int:
    """How many of the ``jobs`` worker processes asked for are used: at most one per
    :data:`MIN_THREADS_PER_WORKER` cores, so 1 (this process alone) on fewer than 4. The serial path
    already runs its parse and its store compression on every core, so on fewer cores the workers' start,
    their thread pools competing for the same cores and the frames' transfer to the writing process cost
    more than the per-frame physics they share out (docs/performance.md, "Standing decisions")."""
    return max(1, min(jobs, threads.THREADS // MIN_THREADS_PER_WORKER))


def _worker_init(parent: int, threads_per_worker: int) -> None:
    """Worker initializer: its share of the cores, an end with its parent (:func:`_exit_with_parent`), and
    numpy's floating-point warnings off, as in the command's process (every number is checked explicitly:
    :mod:`demsplit.validate`)."""
    import numpy as np

    np.seterr(all="ignore")
    threads.limit(threads_per_worker)
    _exit_with_parent(parent)


def processes(run: Run, indices: list[int], options: Options, jobs: int) -> Iterator[tuple]:
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    spec = run.spec
    key = _spec_key(spec)
    ctx = mp.get_context("forkserver" if sys.platform != "win32" else "spawn")
    with ProcessPoolExecutor(
        max_workers=jobs, mp_context=ctx, initializer=_worker_init, initargs=(os.getpid(), threads.THREADS // jobs)
    ) as pool:
        yield from _windowed(
            lambda k: pool.submit(_worker_frame, key, spec, k, options), lambda fut: fut.result(), indices, 2 * jobs
        )


def dask_cluster(run: Run, indices: list[int], options: Options, address: str) -> Iterator[tuple]:
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise DemsplitError(
            "--dask needs dask.distributed, which is not installed.",
            fix="pip install 'demsplit[dask]', or use --jobs N (local cores).",
        ) from None

    spec = run.spec
    key = _spec_key(spec)
    if address.startswith("local:"):
        cluster = LocalCluster(
            n_workers=int(address.split(":", 1)[1]), threads_per_worker=1, processes=True, dashboard_address=":0"
        )
        client = Client(cluster)
    elif Path(address).is_file():  # a scheduler file written by `dask scheduler --scheduler-file`
        cluster, client = None, Client(scheduler_file=address)
    else:
        cluster, client = None, Client(address)
    try:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        yield from _windowed(
            lambda k: client.submit(_worker_frame, key, spec, k, options, pure=False),
            lambda fut: fut.result(),
            indices,
            2 * workers,
        )
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
