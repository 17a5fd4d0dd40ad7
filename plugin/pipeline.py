"""The pipeline: run files -> frames -> partition -> per-frame tables -> Results or a store.

:func:`frame_tables` is the whole computation for one frame, a pure function
of a :class:`~demsplit.frame.Frame` and a :class:`~demsplit.scene.Scene`.
:func:`analyze` runs it over a run in memory and returns
:class:`~demsplit.results.Results`; :func:`run_to_store` streams it into an
HDF5 store, serially, in worker processes (``jobs``) or on a Dask cluster
(``dask``), with identical results.
"""

from __future__ import annotations

import os
import sys
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from .runtime import command, threads
from .errors import DemsplitError, IncompleteRunError, InputFormatError
from .runtime.hashing import hash_in_background
from .outputs import check_output_path
from .runtime.prefault import first_frame_prefaulted
from .validate import check_finite_energies, validated_frame
from .frame import CONTACT_REQUIRED, PARTICLE_REQUIRED, Frame, ParticleIndex, Table, require_columns
from .physics.accuracy import contact_radius_ratios, corrected_share, expected_share_error
from .physics.bodies import ContactBodies
from .physics.modes import ADHESION_COLUMN, NOT_COMPUTED_BITS
from .physics.partition import ContactEnergy, contact_energies, particle_energy, partition, per_particle
from .readers.base import Run
from .results.schema import UNBOUNDED, UNKNOWN
from .scene import Scene, Wall

Tables = dict[str, dict[str, np.ndarray]]


@dataclass(frozen=True)
class Options:
    """What to compute.

    tangential_rule : ``"mindlin"`` (default) or ``"paper"`` (see
        :func:`demsplit.physics.shares.tangential_share`).
    compare : also compute the 50/50 (``u_equal``) and radius-weighted
        (``u_radius``) splits per particle, and YADE's series-spring split
        (``u_springs``) for its linear law.
    contacts : keep the per-contact table (the largest table by far).
    allow_missing : what the run may go on without (``--allow-missing``): energy modes
        (``u_t``, ``u_r``, ...) whose columns were not dumped, and walls (by name) whose contacts
        were not dumped; their values are then marked "not computed" (never 0), else the run is
        refused. ``all`` allows everything.
    accuracy : add the expected error of the split (``a_over_r1 a_over_r2 share_n1_error`` per
        contact, ``u_n_error`` per particle) from the finite-element error model (docs/accuracy.md).
    split : ``"material"`` (the law, default) or ``"corrected"``: the normal energy split by the
        law corrected for finite bodies (:func:`demsplit.physics.accuracy.corrected_share`), an option
        until the evidence makes it the default (docs/accuracy.md).
    """

    tangential_rule: str = "mindlin"
    compare: bool = True
    contacts: bool = True
    allow_missing: tuple[str, ...] = ()
    accuracy: bool = True
    split: str = "material"

    def allows(self, name: str) -> bool:
        """True when the run may go on without ``name`` (a mode column or a wall name)."""
        return name in self.allow_missing or "all" in self.allow_missing


def comparison_splits(scene: Scene) -> tuple[str, ...]:
    """The naive splits reported beside the distribution law for this scene (the scene's law says which)."""
    return scene.model.contact_law.comparison_splits


def frame_tables(frame: Frame, scene: Scene, options: Options = Options()) -> Tables:
    """Everything demsplit computes for one frame, as the store's tables.

    ``particles``: per-particle energies under the distribution law (``u
    u_n u_t``) and, with ``options.compare``, under the comparison splits;
    ``contacts``: per-contact energies, shares, depth and contact points
    (``cp*_sim``: the simulator's own point, when the input has it);
    ``walls``: energy stored in each wall; ``frames``: one row of totals (contact
    energies, and the sums over particles and walls that the energy balance
    compares them with).
    """
    source = frame.source[0] if frame.source else None
    require_columns(frame.particles, PARTICLE_REQUIRED, "particles", file=source, step=frame.step)
    require_columns(frame.contacts, CONTACT_REQUIRED, "contacts", file=source, step=frame.step)
    frame = validated_frame(frame)  # canonical dtypes; every number finite, in range and plausible
    particles, contacts = frame.particles, frame.contacts
    index = ParticleIndex(particles["id"], file=source, step=frame.step)
    try:
        bodies = ContactBodies.build(contacts, scene, particles, index)
        energies = contact_energies(contacts, scene, particles, bodies, index)
        check_finite_energies(energies.u, contacts, file=frame.source[-1] if frame.source else None,
                              step=frame.step)
        ratios = _radius_ratios(contacts) \
            if options.accuracy or options.split == "corrected" else None  # a/R1, a/R2, once for both
        corrected = None
        if options.split == "corrected":
            x1, x2 = ratios
            corrected = np.broadcast_to(corrected_share(x1, x2, bodies.nu1, bodies.nu2, bodies.E1, bodies.E2),
                                        x1.shape)
        main = partition(contacts, scene, particles, split="material", tangential_rule=options.tangential_rule,
                         energies=energies, bodies=bodies, index=index, normal_shares=corrected)
        contacts = _without(contacts, _used_up(scene))  # what the partition used up: freed before the tables
        frame = replace(frame, contacts=contacts)  # (when the caller handed over its only reference)
        ptable, wtable = per_particle(contacts, main, particles, n_walls=len(scene.walls), index=index)
        if "clump" in particles:  # YADE clump membership, for per-clump sums
            ptable["clump"] = np.asarray(particles["clump"], dtype=np.int64)
        if options.compare:
            for split in comparison_splits(scene):
                ptable[f"u_{split}"] = particle_energy(contacts, energies, bodies, particles, split=split,
                                                       index=index)
    except DemsplitError as exc:
        raise exc.located(file=source, step=frame.step) from None
    refused = {mode: why for mode, why in main.missing.items() if not options.allows(mode)}
    if refused:
        mode, why = next(iter(refused.items()))
        raise IncompleteRunError(
            f"{why}. The run has this energy but its files do not hold it"
            + (f" (also missing: {', '.join(list(refused)[1:])})" if len(refused) > 1 else "") + ".",
            file=source, step=frame.step,
            fix=f"dump the columns it needs (docs/liggghts-output.md lists them per model; 'demsplit check' "
                f"names the lines), or go on without it with --allow-missing {mode}: its values are then "
                "marked not computed.")
    for what, why in main.skipped.items():
        note = f"{what} is 0: {why}"
        if note not in frame.notes:
            frame.notes.append(note)
    for what, why in main.missing.items():
        note = f"{what} NOT COMPUTED (--allow-missing {what}): {why}"
        if note not in frame.notes:
            frame.notes.append(note)
    n = len(contacts["delta"])
    step = np.int64(frame.step)
    _mark_missing_walls(scene, main, ptable, wtable, n)
    accuracy = _accuracy(contacts, ratios, bodies, main, ptable, index) if options.accuracy else {}
    tables: Tables = {"particles": {"step": np.full(len(ptable["id"]), step), **ptable},
                      "walls": {"step": np.full(len(wtable["wall"]), step), **wtable}}
    if options.contacts:
        if frame.box is not None and frame.box.any_periodic:
            main.cp = frame.box.wrap(main.cp)  # contact points of contacts across a boundary, back in the box
        ctable = {"step": np.full(n, step), "id1": contacts["id1"], "id2": contacts["id2"],
                  "wall": contacts["wall"], "delta": contacts["delta"], **main.table(),
                  **accuracy}
        if "cpx" in contacts:
            ctable.update(cpx_sim=contacts["cpx"], cpy_sim=contacts["cpy"], cpz_sim=contacts["cpz"])
        tables["contacts"] = ctable
    err = frame.overlap_error
    tables["frames"] = {
        "step": np.array([step]),
        "time": np.array([UNKNOWN if frame.time is None else frame.time]),
        "n_particles": np.array([len(ptable["id"])], dtype=np.int64),
        "n_contacts": np.array([n], dtype=np.int64),
        "n_wall_contacts": np.array([int(np.count_nonzero(contacts["wall"] >= 0))], dtype=np.int64),
        **({"n_not_computed": np.array([int(np.count_nonzero(main.not_computed))], dtype=np.int64)}
           if main.not_computed is not None else {}),
        **{mode.column: np.array([main.u[k].sum()]) for k, mode in enumerate(main.modes)},
        **({ADHESION_COLUMN: np.array([main.u_adh.sum()])} if main.u_adh is not None else {}),
        "u_particles": np.array([ptable["u"].sum()]),
        "u_walls": np.array([wtable["u"].sum()]),
        "overlap_max_rel_error": np.array([UNKNOWN if err is None or len(err) == 0 else
                                           min(float(np.max(err)), UNBOUNDED)]),
    }
    return tables


_KEPT = ("id1", "id2", "wall", "delta", "r1", "r2", "cpx", "cpy", "cpz", "history_unknown")
"""Contact columns read after the partition: the contacts table, the comparison splits (the radii) and the
accuracy columns."""


def _used_up(scene: Scene) -> tuple[str, ...]:
    """Contact columns nothing after the partition reads: body 1's centre and the normal (which gave the
    contact point) and the laws' own columns (their histories, which gave the energies)."""
    laws = [scene.model.contact_law] + [w.model.contact_law for w in scene.walls if w.model is not None]
    own = [c for law in laws for c in law.needs()]
    return tuple(dict.fromkeys(c for c in ("x1", "y1", "z1", "nx", "ny", "nz", *own) if c not in _KEPT))


def _without(table: Table, columns: tuple[str, ...]) -> Table:
    """``table`` without ``columns`` (a new dict: the caller's frame keeps its own)."""
    return {c: v for c, v in table.items() if c not in columns}


def _radius_ratios(contacts: Table) -> tuple[np.ndarray, np.ndarray]:
    """a/R1 and a/R2 of every contact (:func:`~demsplit.physics.accuracy.contact_radius_ratios`), in pieces
    of ``ACCURACY_ROWS`` contacts on the pool's threads."""
    n = len(contacts["delta"])
    x1, x2 = np.empty(n), np.empty(n)

    def piece(lo: int, hi: int) -> None:
        x1[lo:hi], x2[lo:hi] = contact_radius_ratios(*(contacts[c][lo:hi] for c in ("delta", "r1", "r2")))
    threads.map_ranges(piece, n, max_rows=ACCURACY_ROWS)
    return x1, x2


ACCURACY_ROWS = 1 << 16
"""Contacts per piece of the error model's evaluation: its two dozen temporaries stay a few MB a thread."""


def _accuracy(contacts: Table, ratios: tuple[np.ndarray, np.ndarray], bodies: ContactBodies,
              main: ContactEnergy, ptable: Table, index: ParticleIndex) -> Table:
    """How far the split can be trusted, from the fitted finite-element error model
    (:mod:`demsplit.physics.accuracy`, docs/accuracy.md): per contact ``a_over_r1 a_over_r2`` (the Hertz
    contact radius over each radius) and ``share_n1_error`` (expected FE share minus the law's share of
    body 1's normal energy), returned; per particle ``u_n_error`` (J), the expected error of its normal
    energy, the sum over its contacts of +-share_n1_error u_n, added to ``ptable``. ``ratios``: a/R1, a/R2
    (:func:`~demsplit.physics.accuracy.contact_radius_ratios`)."""
    x1, x2 = ratios
    err = np.empty(x1.shape)

    def piece(lo: int, hi: int) -> None:  # numpy releases the GIL: pieces of the contacts on every core
        E1, nu1, E2, nu2 = bodies.constants(lo, hi)
        err[lo:hi] = expected_share_error(x1[lo:hi], x2[lo:hi], nu1, nu2, E1, E2)
    threads.map_ranges(piece, len(err), max_rows=ACCURACY_ROWS)
    from .kernels import signed_particle_sums  # compiled, lazily

    rows1, rows2 = index.contact_rows(contacts["id1"], contacts["id2"], contacts["wall"])
    ptable["u_n_error"] = signed_particle_sums(rows1, rows2, err, main.u[0], len(ptable["id"]))
    return {"a_over_r1": x1, "a_over_r2": x2, "share_n1_error": err}


def missing_walls(scene: Scene) -> list[tuple[int, Wall]]:
    """The walls whose contacts the run's files lack (``Wall.missing``), with their indices."""
    return [(i, w) for i, w in enumerate(scene.walls) if w.missing]


def refuse_missing_walls(scene: Scene, options: Options) -> None:
    """Raise :class:`IncompleteRunError` for the first wall whose contacts the files lack and which
    the user did not let go (``--allow-missing NAME``)."""
    refused = [w for _, w in missing_walls(scene) if not options.allows(w.name)]
    if refused:
        w = refused[0]
        others = f" (and {', '.join(x.name for x in refused[1:])})" if len(refused) > 1 else ""
        raise IncompleteRunError(
            f"the {w.kind} wall {w.name!r}{others} is part of this run, but {w.missing}",
            file=scene.source or None,
            fix=f"write its contacts as said above and rerun the simulation, or go on without them with "
                f"--allow-missing {w.name}: the wall's energy is then marked not computed.")


def _mark_missing_walls(scene: Scene, main: ContactEnergy, ptable: Table, wtable: Table, n: int) -> None:
    """Give every table a ``not_computed`` column when a wall's contacts are missing, with every mode's
    bit set on that wall (its contacts, and so its particles, are unknown)."""
    walls = missing_walls(scene)
    if not walls:
        return
    if main.not_computed is None:
        main.not_computed = np.zeros(n, dtype=np.int32)
        ptable["not_computed"] = np.zeros(len(ptable["id"]), dtype=np.int32)
        wtable["not_computed"] = np.zeros(len(wtable["wall"]), dtype=np.int32)
    every = sum(NOT_COMPUTED_BITS[m.column] for m in main.modes) + (
        NOT_COMPUTED_BITS[ADHESION_COLUMN] if main.u_adh is not None else 0)
    for i, _ in walls:
        wtable["not_computed"][i] |= every


# --- running over a whole run ---------------------------------------------------------------

@dataclass
class RunReport:
    """What a run did: frames written, frames skipped (with the reason), what
    could not be computed, and notes from the readers."""

    frames_done: int = 0
    frames_resumed: int = 0
    bad_frames: list[dict] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


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


def _serial(run: Run, indices: list[int], options: Options) -> Iterator[tuple[int, Tables | DemsplitError, list]]:
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


def _windowed(submit: Callable[[int], object], result: Callable[[object], tuple], indices: list[int],
              window: int) -> Iterator[tuple]:
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
    already runs its parse and its store compression on every core; measured on 2 cores,
    ``--jobs 2`` was 1.47-2.5x slower than serial from 1e4 to 1e6 particles (under a load of 2.7-3.1)
    (``python benchmarks/scaling.py``, docs/performance.md), as the workers' start, their
    thread pools competing for the same cores and the frames' transfer to the writing process
    cost more than the per-frame physics they share out."""
    from .runtime import threads

    return max(1, min(jobs, threads.THREADS // MIN_THREADS_PER_WORKER))


def _worker_init(parent: int, threads_per_worker: int) -> None:
    """Worker initializer: its share of the cores, and an end with its parent (:func:`_exit_with_parent`)."""
    from .runtime import threads

    threads.limit(threads_per_worker)
    _exit_with_parent(parent)


def _processes(run: Run, indices: list[int], options: Options, jobs: int) -> Iterator[tuple]:
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    from .runtime import threads

    spec = run.spec
    key = _spec_key(spec)
    ctx = mp.get_context("forkserver" if sys.platform != "win32" else "spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_worker_init,
                             initargs=(os.getpid(), threads.THREADS // jobs)) as pool:
        yield from _windowed(lambda k: pool.submit(_worker_frame, key, spec, k, options),
                             lambda fut: fut.result(), indices, 2 * jobs)


def _dask(run: Run, indices: list[int], options: Options, address: str) -> Iterator[tuple]:
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise DemsplitError("--dask needs dask.distributed, which is not installed.",
                            fix="pip install 'demsplit[dask]', or use --jobs N (local cores).") from None

    spec = run.spec
    key = _spec_key(spec)
    if address.startswith("local:"):
        cluster = LocalCluster(n_workers=int(address.split(":", 1)[1]), threads_per_worker=1,
                               processes=True, dashboard_address=":0")
        client = Client(cluster)
    elif Path(address).is_file():  # a scheduler file written by `dask scheduler --scheduler-file`
        cluster, client = None, Client(scheduler_file=address)
    else:
        cluster, client = None, Client(address)
    try:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        yield from _windowed(lambda k: client.submit(_worker_frame, key, spec, k, options, pure=False),
                             lambda fut: fut.result(), indices, 2 * workers)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def process_run(run: Run, options: Options = Options(), *, jobs: int = 1, dask: str | None = None,
                on_bad_frame: str = "stop", skip_steps: set[int] | None = None,
                steps: list[int] | None = None, progress: bool | None = None,
                report: RunReport | None = None) -> Iterator[Tables]:
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
    indices = [k for k, s in enumerate(all_steps)
               if (wanted is None or s in wanted) and not (skip_steps and s in skip_steps)]
    report.frames_resumed = len(skip_steps or ())
    workers = worker_processes(jobs)
    if workers < jobs and not dask:
        from .runtime import threads

        used = "the frames computed in this process" if workers == 1 else f"{workers} worker processes"
        report.notes.append(f"--jobs {jobs} on {threads.THREADS} cores: {used}; a worker process needs "
                            f"{MIN_THREADS_PER_WORKER} cores to be faster than the serial path, which parses and "
                            "compresses on every core (measured: docs/performance.md).")
    if dask:
        results = _dask(run, indices, options, dask)
    elif workers > 1:
        results = _processes(run, indices, options, workers)
    else:
        results = _serial(run, indices, options)
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
                report.bad_frames.append({"frame": k, "step": int(all_steps[k]) if all_steps[k] is not None else None,
                                          "error": str(out)})
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


def analyze(path: str | Path, *, options: Options = Options(), jobs: int = 1, dask: str | None = None,
            on_bad_frame: str = "stop", progress: bool | None = False,
            type_names: Mapping[int, str] | None = None, **reader_options):
    """Analyse a run in memory and return :class:`~demsplit.results.Results`.

    ``path``: a LIGGGHTS input script or a ``demsplit.yade`` snapshot file;
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
        frames = list(process_run(run, options, jobs=jobs, dask=dask, on_bad_frame=on_bad_frame,
                                  progress=progress, report=report))
        provenance = build_provenance(run.sources, scene=run.scene, options=asdict(options),
                                      type_names=_type_names(type_names), **_report_provenance(run, report))
        return Results.from_frames(frames, provenance, walls_meta_from_scene(run.scene))
    finally:
        run.close()


def _type_names(names: Mapping[int, str] | None) -> dict[str, str]:
    """``names`` as the provenance keeps them (JSON: string keys)."""
    return {str(int(t)): str(n) for t, n in (names or {}).items()}


def _report_provenance(run: Run, report: RunReport) -> dict:
    return {"run": run.describe(), "bad_frames": report.bad_frames, "notes": report.notes}


def _first_frame_rows(path: str | Path | list | None, options: Mapping) -> tuple[int, int] | None:
    """The first frame's rows as the run's reader tells them before it opens the run
    (:meth:`~demsplit.readers.base.Run.first_frame_rows`), for the memory warm-up; None when it cannot."""
    from .readers import reader_for

    if isinstance(path, (list, tuple)):
        return None
    try:
        return reader_for(path).first_frame_rows(None if path is None else Path(path), **options)
    except DemsplitError:  # the opening that follows reports it
        return None


def run_to_store(path: str | Path, out: str | Path, *, options: Options = Options(), jobs: int = 1,
                 dask: str | None = None, resume: bool = False, on_bad_frame: str = "stop",
                 progress: bool | None = None, compression: str | None = "auto",
                 type_names: Mapping[int, str] | None = None, **reader_options) -> tuple[RunReport, Scene]:
    """Analyse a run and stream the results into the HDF5 store ``out``
    (written to a temporary name and renamed when complete; ``resume``
    continues an interrupted run from its last complete frame).

    compression : ``"auto"`` (gzip only for the columns that compress well,
        readable by every HDF5 tool), ``"gzip"`` (every column; smallest,
        slowest), ``"lzf"`` (h5py only) or ``"none"``/``None`` (fastest,
        largest); see ``docs/performance.md``, "The result store", for the measured cost of each.
    type_names : material names of particle types, as for :func:`analyze`.
    """
    from .readers import open_run
    from .results import walls_meta_from_scene
    from .results.store import build_provenance
    from .results.writer import ResultWriter, check_output

    check_output(out, resume=resume)  # before any work: no output directory, or an unresumed interrupted run
    in_process = command.FREED_MEMORY_KEPT and not dask and worker_processes(jobs) == 1  # frames computed here
    with first_frame_prefaulted(_first_frame_rows(path, reader_options) if in_process else None):
        run = open_run(path, **reader_options)
    try:
        sources = run.sources
        check_output_path(out, run.named_files())  # before anything is written: never over a file of the run
        report = RunReport()
        hash_in_background(sources)  # on idle cores; the writer fills the digests in when they are known
        provenance = build_provenance(sources, scene=run.scene, options=asdict(options), run=run.describe(),
                                      type_names=_type_names(type_names), wait=False)
        with ResultWriter(out, provenance, resume=resume, walls_meta=walls_meta_from_scene(run.scene),
                          compression=compression, final_step=int(run.steps[-1]) if len(run.steps) else None) as writer:
            for tables in process_run(run, options, jobs=jobs, dask=dask, on_bad_frame=on_bad_frame,
                                      skip_steps=writer.done_steps, progress=progress, report=report):
                writer.append(tables)
                del tables  # stored: free it before the next frame is computed
            if report.bad_frames and not writer.done_steps:  # nothing to store: a failed run, with or without -q
                listed = "; ".join(f"frame {b['frame']} (step {b['step']}): {b['error']}"
                                   for b in report.bad_frames[:3])
                raise InputFormatError(f"every frame of the run is bad ({len(report.bad_frames)}), so there is "
                                       f"nothing to store: {listed}.", file=sources[0] if sources else None,
                                       fix="fix the first bad frame; --on-bad-frame skip only leaves out some.")
            writer.provenance.update(bad_frames=report.bad_frames, notes=report.notes)
        return report, run.scene
    finally:
        run.close()
