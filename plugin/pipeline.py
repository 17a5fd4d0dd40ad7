"""The pipeline: run files -> frames -> per-frame tables -> Results or a store.

:func:`demsplit.compute.frame_tables` is the whole computation for one frame;
:func:`process_run` runs it over a run's frames on an executor
(:mod:`demsplit.executors`: this process, worker processes with ``jobs``, or a
Dask cluster with ``dask``, with identical results); :func:`analyze` collects
the tables in memory as :class:`~demsplit.results.Results`, and
:func:`run_to_store` streams them into an HDF5 store.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path

from .compute import DEFAULT_OPTIONS, Options, Tables, missing_walls, refuse_missing_walls
from .errors import DemsplitError, InputFormatError
from .executors import MIN_THREADS_PER_WORKER, dask_cluster, processes, serial, worker_processes
from .outputs import check_output_path
from .readers.base import Run
from .runtime import command, threads
from .runtime.hashing import hash_in_background
from .runtime.prefault import first_frame_prefaulted
from .scene import Scene


@dataclass
class RunReport:
    """What a run did: frames written, frames skipped (with the reason), what
    could not be computed, and notes from the readers."""

    frames_done: int = 0
    frames_resumed: int = 0
    bad_frames: list[dict] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def process_run(
    run: Run,
    options: Options = DEFAULT_OPTIONS,
    *,
    jobs: int = 1,
    dask: str | None = None,
    on_bad_frame: str = "stop",
    skip_steps: set[int] | None = None,
    steps: list[int] | None = None,
    progress: bool | None = None,
    report: RunReport | None = None,
) -> Iterator[Tables]:
    """Yield the tables of every frame of ``run`` in order.

    jobs : worker processes (1: in this process), at most :func:`worker_processes` of them (a note
        says when fewer are used). dask : a Dask scheduler
        address (``tcp://HOST:PORT``), a scheduler file, or ``local:N`` to
        start a local cluster of N workers.
    on_bad_frame : ``"stop"`` raises the first frame's error; ``"skip"`` leaves
        the frame out and lists it in ``report.bad_frames``.
    skip_steps : steps already done (``--resume``); steps : restrict to these.
    """
    if on_bad_frame not in ("stop", "skip"):
        raise ValueError(f"on_bad_frame must be 'stop' or 'skip', not {on_bad_frame!r}")
    report = report if report is not None else RunReport()
    refuse_missing_walls(run.scene, options)
    for _, wall in missing_walls(run.scene):
        report.notes.insert(0, f"wall {wall.name!r} NOT COMPUTED (--allow-missing {wall.name}): {wall.missing}")
    for note in run.notes:  # what the reader found it could not provide
        if note not in report.notes:
            report.notes.append(note)
    all_steps = run_steps(run)
    wanted = set(steps) if steps is not None else None
    indices = [
        k for k, s in enumerate(all_steps) if (wanted is None or s in wanted) and not (skip_steps and s in skip_steps)
    ]
    damaged = [k for k in indices if all_steps[k] is None]
    if damaged and on_bad_frame == "stop":  # known bad at opening: the run is refused before any frame is computed
        run.frame(damaged[0])  # raises that frame's error
    report.frames_resumed = len(skip_steps or ())
    workers = worker_processes(jobs)
    if workers < jobs and not dask:
        used = "the frames computed in this process" if workers == 1 else f"{workers} worker processes"
        report.notes.append(
            f"--jobs {jobs} on {threads.THREADS} cores: {used}; a worker process needs "
            f"{MIN_THREADS_PER_WORKER} cores to be faster than the serial path, which parses and "
            "compresses on every core (measured: docs/performance.md)."
        )
    if dask:
        results = dask_cluster(run, indices, options, dask)
    elif workers > 1:
        results = processes(run, indices, options, workers)
    else:
        results = serial(run, indices, options)
    from tqdm import tqdm

    show = sys.stderr.isatty() if progress is None else progress
    # a bar updated by hand: tqdm's iterator wrapper would keep each frame's tables alive
    # while the next frame is computed
    bar = tqdm(total=len(indices), unit="frame", disable=not show, desc="demsplit")
    try:
        for k, out, notes in results:
            bar.update()
            if isinstance(out, DemsplitError):
                if on_bad_frame == "stop":
                    raise out
                report.bad_frames.append(
                    {"frame": k, "step": int(all_steps[k]) if all_steps[k] is not None else None, "error": str(out)}
                )
                continue
            for note in notes:
                if note not in report.notes:
                    report.notes.append(note)
            report.frames_done += 1
            yield out
            del out  # not kept alive while the next frame is computed (peak memory: one frame in flight)
    finally:
        bar.close()


def run_steps(run: Run) -> list[int | None]:
    """Timestep of every frame of ``run``: ``run.steps``, then ``None`` for the damaged frames past them
    (a LIGGGHTS frame with a damaged header, a YADE snapshot cut short), whose step cannot be read."""
    steps = [int(s) for s in run.steps]
    return steps + [None] * (len(run) - len(steps))


def analyze(
    path: str | Path,
    *,
    options: Options = DEFAULT_OPTIONS,
    jobs: int = 1,
    dask: str | None = None,
    on_bad_frame: str = "stop",
    progress: bool | None = False,
    type_names: Mapping[int, str] | None = None,
    **reader_options,
):
    """Analyse a run in memory and return :class:`~demsplit.results.Results`.

    ``path``: any input a reader of :mod:`demsplit.readers` takes (a LIGGGHTS or LAMMPS input script, YADE
    saved states, a ``demsplit.yade`` snapshot, an ingest cache);
    ``type_names``: material names of particle types, kept in the provenance (``type_names``) for
    reports and exports; ``reader_options`` go to :func:`demsplit.readers.open_run` (e.g.
    ``atoms=``, ``contacts=``, ``walls=``, ``overlap_tolerance=``).
    """
    from .readers import open_run
    from .results import Results, walls_meta_from_scene
    from .results.store import build_provenance

    run = open_run(path, **reader_options)
    try:
        report = RunReport()
        hash_in_background(run.sources)  # the provenance's digests, while frames are computed
        frames = list(
            process_run(run, options, jobs=jobs, dask=dask, on_bad_frame=on_bad_frame, progress=progress, report=report)
        )
        provenance = build_provenance(
            run.sources,
            scene=run.scene,
            options=asdict(options),
            type_names=_type_names(type_names),
            **_report_provenance(run, report),
        )
        return Results.from_frames(frames, provenance, walls_meta_from_scene(run.scene))
    finally:
        run.close()


def _type_names(names: Mapping[int, str] | None) -> dict[str, str]:
    """``names`` as the provenance keeps them (JSON: string keys)."""
    return {str(int(t)): str(n) for t, n in (names or {}).items()}


def _given_files(path: str | Path | list | None, reader_options: Mapping) -> list[str | Path]:
    """The run's files named on the command line: the input (one or several) and the dumps given as options."""
    given = list(path) if isinstance(path, (list, tuple)) else [] if path is None else [path]
    return given + [reader_options[k] for k in ("atoms", "contacts", "walls") if reader_options.get(k)]


def _absolute(paths) -> list[str]:
    """``paths`` as absolute path strings, each once: the provenance's ``named_files``, the files of the run that
    ``report`` and ``export`` never write over."""
    return list(dict.fromkeys(str(Path(p).absolute()) for p in paths))


def _report_provenance(run: Run, report: RunReport) -> dict:
    return {"run": run.describe(), "bad_frames": report.bad_frames, "notes": report.notes}


def _first_frame_rows(path: str | Path | list | None, options: Mapping) -> tuple[int, int] | None:
    """The first frame's rows as the run's reader tells them before it opens the run
    (:meth:`~demsplit.readers.base.Run.first_frame_rows`), for the memory warm-up; None when it cannot."""
    from .readers import reader_for

    if isinstance(path, (list, tuple)):
        return None
    try:
        options = dict(options)
        return reader_for(path, options.pop("simulator", None)).first_frame_rows(
            None if path is None else Path(path), **options
        )
    except DemsplitError:  # the opening that follows reports it
        return None


def run_to_store(
    path: str | Path,
    out: str | Path,
    *,
    options: Options = DEFAULT_OPTIONS,
    jobs: int = 1,
    dask: str | None = None,
    resume: bool = False,
    on_bad_frame: str = "stop",
    progress: bool | None = None,
    compression: str | None = "auto",
    type_names: Mapping[int, str] | None = None,
    overwrite: bool = False,
    **reader_options,
) -> tuple[RunReport, Scene]:
    """Analyse a run and stream the results into the HDF5 store ``out``
    (written to a temporary name and renamed when complete; ``resume``
    continues an interrupted run from its last complete frame).

    compression : ``"auto"`` (gzip only for the columns that compress well,
        readable by every HDF5 tool), ``"gzip"`` (every column; smallest,
        slowest), ``"lzf"`` (h5py only) or ``"none"``/``None`` (fastest,
        largest); see ``docs/performance.md``, "Standing decisions", for the measured cost of each.
    type_names : material names of particle types, as for :func:`analyze`.
    overwrite : replace ``out`` when it is an existing file that is not a result store (never one of the
        run's files: :mod:`demsplit.outputs`).
    """
    from .readers import open_run
    from .results import walls_meta_from_scene
    from .results.store import STORE, build_provenance
    from .results.writer import ResultWriter, check_output

    # before any work: an unwritable output, an interrupted run; whether an existing file is one of the run's
    # files or a foreign one is known once the run is open (the files its script names), and checked then
    check_output(out, resume=resume, overwrite=True, inputs=_given_files(path, reader_options))
    in_process = command.FREED_MEMORY_KEPT and not dask and worker_processes(jobs) == 1  # frames computed here
    with first_frame_prefaulted(_first_frame_rows(path, reader_options) if in_process else None):
        run = open_run(path, **reader_options)
    try:
        sources = run.sources
        named = run.named_files()
        check_output_path(out, named, kind=STORE, overwrite=overwrite)  # before anything is written
        report = RunReport()
        hash_in_background(sources)  # on idle cores; the writer fills the digests in when they are known
        provenance = build_provenance(
            sources,
            scene=run.scene,
            options=asdict(options),
            run=run.describe(),
            type_names=_type_names(type_names),
            named_files=_absolute(named),
            wait=False,
        )
        with ResultWriter(
            out,
            provenance,
            resume=resume,
            overwrite=overwrite,
            walls_meta=walls_meta_from_scene(run.scene),
            compression=compression,
            final_step=int(run.steps[-1]) if len(run.steps) else None,
        ) as writer:
            for tables in process_run(
                run,
                options,
                jobs=jobs,
                dask=dask,
                on_bad_frame=on_bad_frame,
                skip_steps=writer.done_steps,
                progress=progress,
                report=report,
            ):
                writer.append(tables)
                del tables  # stored: free it before the next frame is computed
            if report.bad_frames and not writer.done_steps:  # nothing to store: a failed run, with or without -q
                listed = "; ".join(
                    f"frame {b['frame']} (step {b['step']}): {b['error']}" for b in report.bad_frames[:3]
                )
                raise InputFormatError(
                    f"every frame of the run is bad ({len(report.bad_frames)}), so there is "
                    f"nothing to store: {listed}.",
                    file=sources[0] if sources else None,
                    fix="fix the first bad frame; --on-bad-frame skip only leaves out some.",
                )
            writer.provenance.update(bad_frames=report.bad_frames, notes=report.notes)
        return report, run.scene
    finally:
        run.close()
