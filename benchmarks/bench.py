"""demsplit against the bare parsers and the usual tools, on the same files, in the same run.

Run (the dumps come from ``benchmarks/generate.py``)::

    python benchmarks/generate.py /tmp/bench_big          # 1e6 particles, 2e6 contacts, 3 frames
    python benchmarks/bench.py /tmp/bench_big [--repeat 1] [--skip ovito,mdanalysis]

Every measurement runs in its own Python process, started fresh by ``harness.fresh`` (the dirty pages of
earlier children written back and the child's inputs read into the page cache first, untimed); its wall
time, interpreter start and imports included (what a user waits for), is taken by this parent, its peak
resident memory is the child's own ``VmHWM``. With ``--repeat N`` the rounds are interleaved, each in a
rotated order (``harness.rounds``: warm-up and imports first), and the best time of each measurement is
kept. Measurements:

``warm-up``
    runs first: ``demsplit run`` on the packing sample in a fresh process, so
    that numba compiles the kernels once and caches them (what the first run
    after an install does); its time is printed, and every later process loads
    the cached machine code.
``demsplit run`` / ``--compression gzip|lzf|none`` / ``--no-compare`` / ``--no-contacts``
    the command's process (``sys.argv[0]`` is ``demsplit``, so :mod:`demsplit.runtime.command`'s settings
    apply as they do to the console script, and it ends as the console script does, without the
    interpreter's teardown: ``demsplit.runtime.command.exit_now``), end to end: read, partition,
    aggregate, write the HDF5 store (the store's default ``auto`` compression: gzip on the columns whose
    first chunk compresses, none on the others; ``--no-contacts`` leaves out the per-contact table, by
    far the largest).
``pipeline (no store)``
    not a command: the pipeline of ``demsplit run`` without the store: every frame's tables computed
    (``demsplit.pipeline.process_run``) and dropped.
``demsplit dumps``
    the dump reader alone on both dumps, every frame, the columns ``demsplit run`` reads (by name, as
    ``polars-needed`` reads them by index), every row checked and every real correctly rounded: the
    like-for-like of ``polars-needed`` (what issue 19's reader goal compares).
``demsplit read``
    the run's reader: every Frame of the run, which is the dump reader plus the join of atoms and
    contacts, the pair geometry and the checks against it (more work than a parse).
``demsplit atoms``
    the reader alone on the atom dump (the like-for-like of MDAnalysis).
``polars`` / ``pandas-c``
    bare parse of both dumps, every frame, every column, to numpy arrays; the
    frames' byte ranges are handed over for free (found by demsplit's index in
    this parent).
``polars-needed``
    the same with polars reading only the columns demsplit reads (``columns=``,
    the indices demsplit's reader asks for): the fastest parse a user could
    write with the ecosystem's tools, and demsplit's like-for-like baseline.
``limits``
    what the machine itself allows, in the same run: reading both files from
    the page cache into a reused buffer (``readinto``), and counting their
    newlines a word (8 bytes) at a time over a memory map (compiled, one
    thread): no text reader can beat either; demsplit's read throughput is
    printed as a fraction of each.
``ovito``
    ``ovito.io.import_file`` of the atom dump plus a ``LoadTrajectoryModifier``
    with OVITO's LAMMPS dump local reader for the contacts (every column
    mapped; ids to the bond property ``Particle Identifiers.1/.2``), every frame
    computed and its arrays taken to numpy.
``mdanalysis``
    ``MDAnalysis.Universe(atoms, format="LAMMPSDUMP")``, every frame's positions.
``convert`` / ``cache read`` / ``text read``
    ``demsplit convert`` to the ingest cache, then every Frame from the cache
    and from the text (the same as ``demsplit read``).
``imports``
    a process that imports what ``demsplit run`` imports and exits: its peak
    RSS is subtracted to give the memory above the interpreter and libraries.
``kernel`` (in one process, after loading frame 0 into memory)
    ``partition`` + ``per_particle`` on the arrays, ``frame_tables`` without
    and with the comparison splits: contacts per second, one core (the pieces of the per-contact loops
    run on one thread here), best of ``KERNEL_REPEAT``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import harness

CHILDREN = (
    "warm-up",
    "imports",
    "demsplit-run",
    "demsplit-run-gzip",
    "demsplit-run-lzf",
    "demsplit-run-nocompress",
    "demsplit-run-nocompare",
    "demsplit-run-nocontacts",
    "pipeline-nostore",
    "demsplit-read",
    "demsplit-dumps",
    "demsplit-atoms",
    "polars",
    "polars-needed",
    "pandas-c",
    "limits",
    "ovito",
    "mdanalysis",
    "convert",
    "cache-read",
    "kernel",
)
KERNEL_REPEAT = 7  # timings of each in-memory kernel measurement, the best kept (a shared machine: more samples,
# a minimum nearer the uncontended time)


# --------------------------------------------------------------------------- children


def _frames(index_file: str, name: str) -> list[tuple[int, int]]:
    return [tuple(r) for r in json.loads(Path(index_file).read_text())[name]]


def child(name: str, d: Path, work: Path, index_file: str) -> dict:
    """Run one measurement in this (fresh) process; return what it wants reported."""
    script, atoms, pairs = d / "in.bench", d / "atoms.txt", d / "pairs.txt"
    if name == "imports":  # what demsplit run -q imports (its kernel modules import numba)
        import demsplit.cli  # noqa: F401
        import demsplit.kernels  # noqa: F401
        import demsplit.pipeline  # noqa: F401
        import demsplit.readers.fastparse  # noqa: F401
        import demsplit.readers.liggghts  # noqa: F401
        import demsplit.results.store  # noqa: F401
        import h5py  # noqa: F401

        return {}
    if name == "warm-up":
        sys.argv[0] = "demsplit"
        from demsplit.cli import main

        return {"rc": main(["run", str(harness.SAMPLE), "-o", str(work / "warm-up.h5"), "-q"])}
    if name.startswith("demsplit-run"):
        sys.argv[0] = "demsplit"  # as the console script: this process is the command (demsplit.runtime.command)
        from demsplit.cli import main

        out = work / f"{name}.h5"
        extra = {
            "demsplit-run": [],
            "demsplit-run-gzip": ["--compression", "gzip"],
            "demsplit-run-lzf": ["--compression", "lzf"],
            "demsplit-run-nocompress": ["--compression", "none"],
            "demsplit-run-nocompare": ["--no-compare"],
            "demsplit-run-nocontacts": ["--no-contacts"],
        }[name]
        return {"rc": main(["run", str(script), "-o", str(out), "-q", *extra])}  # deleted by the parent, untimed
    if name == "pipeline-nostore":
        from demsplit.pipeline import process_run
        from demsplit.readers import open_run

        frames = 0
        for tables in process_run(open_run(script), progress=False):
            frames += 1
            del tables  # as demsplit run: one frame's tables alive at a time
        return {"frames": frames}
    if name in ("demsplit-read", "cache-read"):
        from demsplit.readers import open_run

        run = open_run(work / "cache.h5" if name == "cache-read" else script)
        n = 0
        for k in range(len(run)):
            frame = run.frame(k)
            n += len(frame.contacts["delta"])
            del frame  # one frame alive at a time
        return {"contacts": n}
    if name == "demsplit-dumps":
        from demsplit.readers.lammps_dump import open_dump

        names = json.loads(Path(index_file).read_text())["needed_names"]
        n = sum(f.n_rows for dump in ("atoms", "pairs") for f in open_dump(d / f"{dump}.txt").frames(names[dump]))
        return {"rows": n}
    if name == "demsplit-atoms":
        from demsplit.readers.lammps_dump import open_dump

        n = sum(f.n_rows for f in open_dump(atoms).frames(["id", "type", "x", "y", "z", "radius"]))
        return {"rows": n}
    if name == "convert":
        from demsplit.cli import main

        return {"rc": main(["convert", str(script), "-o", str(work / "cache.h5"), "-q"])}
    if name in ("polars", "pandas-c", "polars-needed"):
        needed = json.loads(Path(index_file).read_text())["needed"] if name == "polars-needed" else {}
        return _bare_parse(
            name,
            {atoms: _frames(index_file, "atoms"), pairs: _frames(index_file, "pairs")},
            {atoms: needed.get("atoms"), pairs: needed.get("pairs")},
        )
    if name == "limits":
        return _limits([atoms, pairs])
    if name == "ovito":
        return _ovito(atoms, pairs)
    if name == "mdanalysis":
        import MDAnalysis as mda

        u = mda.Universe(str(atoms), format="LAMMPSDUMP")
        total = 0.0
        for ts in u.trajectory:
            total += float(ts.positions[:, 0].sum())
        return {"frames": len(u.trajectory), "atoms": len(u.atoms)}
    if name == "kernel":
        return _kernel(script, work)
    raise ValueError(name)


def _bare_parse(
    engine: str, files: dict[Path, list[tuple[int, int]]], columns: dict[Path, list[int] | None] | None = None
) -> dict:
    """Every frame of ``files`` (byte ranges of their rows) parsed by ``engine``; ``columns``: per file,
    the indices of the columns polars reads (None: all)."""
    import io

    import numpy as np

    rows = 0
    for path, ranges in files.items():
        with open(path, "rb") as f:
            for start, end in ranges:
                f.seek(start)
                data = f.read(end - start)
                if engine.startswith("polars"):
                    import polars as pl

                    df = pl.read_csv(
                        data, separator=" ", has_header=False, quote_char=None, columns=(columns or {}).get(path)
                    )
                    arrays = [s.to_numpy() for s in df.iter_columns()]
                else:
                    import pandas as pd

                    df = pd.read_csv(io.BytesIO(data), sep=" ", header=None, engine="c")
                    arrays = [df[c].to_numpy() for c in df.columns]
                rows += len(arrays[0])
                del data, df, arrays
    return {"rows": rows, "numpy": np.__version__}


def _limits(paths: list[Path]) -> dict:
    """The machine's limits for a text reader on ``paths`` (module docstring, ``limits``): seconds for a
    page-cache read into a reused 16 MiB buffer, and for a word-at-a-time newline count over a memory
    map (compiled, one thread; best of 3 each)."""
    import mmap

    import numba
    import numpy as np

    @numba.njit(nogil=True)
    def newlines(words):  # exact count of 0x0a bytes, 8 per step (x ^ 0x0a..0a has a zero byte per newline)
        ones, low7 = np.uint64(0x0101010101010101), np.uint64(0x7F7F7F7F7F7F7F7F)
        nl = np.uint64(0x0A0A0A0A0A0A0A0A)
        total = np.uint64(0)
        for i in range(words.size):
            x = words[i] ^ nl
            zero = ~(((x & low7) + low7) | x | low7)
            total += ((zero >> np.uint64(7)) * ones) >> np.uint64(56)
        return total

    def read_all():
        buf = bytearray(1 << 24)
        for path in paths:
            with open(path, "rb", buffering=0) as f:
                while f.readinto(buf):
                    pass

    def count_all():
        n = 0
        for path in paths:
            with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
                a = np.frombuffer(m, dtype=np.uint8)
                cut = a.size - a.size % 8
                n += int(newlines(a[:cut].view(np.uint64))) + int(np.count_nonzero(a[cut:] == 10))
                del a
        return n

    newlines(np.zeros(8, np.uint64))  # compiled before it is timed
    out = {"bytes": sum(p.stat().st_size for p in paths)}
    for label, f in (("page_cache_read", read_all), ("newline_count", count_all)):
        out[label] = harness.best_of(f, 3)
    return out


def _ovito(atoms: Path, pairs: Path) -> dict:
    import numpy as np
    from ovito.io import import_file
    from ovito.modifiers import LoadTrajectoryModifier

    pipeline = import_file(str(atoms))
    traj = LoadTrajectoryModifier()
    columns = [f"c{k}" for k in range(1, 42)]
    columns[12], columns[13] = "Particle Identifiers.1", "Particle Identifiers.2"
    traj.source.load(str(pairs), columns=columns)
    pipeline.modifiers.append(traj)
    bonds = 0
    for frame in range(pipeline.source.num_frames):
        data = pipeline.compute(frame)
        arrays = [np.asarray(data.particles[p]) for p in data.particles.keys()]
        b = data.particles.bonds
        arrays += [np.asarray(b[p]) for p in b.keys()]
        bonds += b.count
    import ovito

    return {"bonds": bonds, "version": ".".join(map(str, ovito.version))}


def _kernel(script: Path, work: Path) -> dict:
    import numpy as np
    from demsplit.compute import Options, frame_tables
    from demsplit.physics.bodies import FrameContacts
    from demsplit.physics.partition import body_tables, law_energies, split_energies
    from demsplit.readers import open_run
    from demsplit.runtime import threads

    cache = work / "cache.h5"
    run = open_run(cache if cache.exists() else script)
    frame = run.frame(0)
    threads.limit(1)  # the kernels' pieces (threads.map_ranges) on one thread: contacts per second per core
    scene, p, c = run.scene, frame.particles, frame.contacts
    n = len(c["delta"])
    frame_bytes = sum(v.nbytes for v in p.values()) + sum(v.nbytes for v in c.values())

    def kernels():
        frame = FrameContacts(c, scene, p)
        e = split_energies(frame, law_energies(frame))
        body_tables(frame, e, n_walls=len(scene.walls))

    out = {
        "contacts": n,
        "particles": len(p["id"]),
        "frame_bytes": frame_bytes,
        "frame_columns": {"particles": list(p), "contacts": list(c)},
    }
    for label, f in (
        ("partition+per_particle", kernels),
        ("frame_tables --no-compare", lambda: frame_tables(frame, scene, Options(compare=False))),
        ("frame_tables", lambda: frame_tables(frame, scene, Options())),
    ):
        t = harness.best_of(f, KERNEL_REPEAT)
        out[label] = {"seconds": t, "contacts_per_s": n / t}
    np.seterr(all="ignore")
    return out


# --------------------------------------------------------------------------- parent


def measure(name: str, d: Path, work: Path, index_file: str) -> dict:
    """Run child ``name`` in a fresh process (``harness.fresh``): wall time, peak memory, its report. The
    stores a ``demsplit run`` child wrote are deleted after its time is taken."""
    cmd = [sys.executable, __file__, "--child", name, str(d), "--work", str(work), "--index", index_file]
    proc = harness.fresh(cmd, inputs=inputs(name, d, work), check=False)
    for store in [*work.glob("demsplit-run*.h5"), work / "warm-up.h5"]:
        store.unlink(missing_ok=True)  # here, untimed: deleting an 860 MB store takes a tenth of a second
    if proc.returncode != 0:
        return {"name": name, "error": proc.stderr.strip().splitlines()[-1:] or ["failed"]}
    return {"name": name, **proc.report, "seconds": proc.seconds}


def inputs(name: str, d: Path, work: Path) -> list[Path]:
    """The files child ``name`` reads."""
    if name == "cache-read":
        return [work / "cache.h5"]
    if name in ("warm-up", "imports"):
        return []
    if name in ("demsplit-atoms", "mdanalysis"):
        return [d / "atoms.txt"]
    return [d / "atoms.txt", d / "pairs.txt"]


def frame_ranges(d: Path) -> dict:
    """Byte range of every frame's rows in both dumps (demsplit's index), and ``needed``: per dump, the
    indices of the columns demsplit's reader reads (for ``polars-needed``; ``needed_names``: their names,
    for ``demsplit-dumps``)."""
    from demsplit.readers import open_run
    from demsplit.readers.lammps_dump import open_dump

    out: dict = {}
    for name in ("atoms", "pairs"):
        dump = open_dump(d / f"{name}.txt")
        out[name] = [(e.data_start, e.data_end) for e in dump._index()]
    run = open_run(d / "in.bench")
    try:
        names = {"atoms": run._atom_columns(), "pairs": run._wanted(run._pair_names)}
        out["needed_names"] = names
        out["needed"] = {
            "atoms": sorted(run.atoms.columns.index(c) for c in names["atoms"]),
            "pairs": sorted(run.pairs.columns.index(c) for c in names["pairs"]),
        }
    finally:
        run.close()
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path, help="directory written by benchmarks/generate.py")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--skip", default="", help="comma-separated measurements to leave out")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--work", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("--index", help=argparse.SUPPRESS)
    ap.add_argument("--json", type=Path, help="also write the raw measurements here")
    a = ap.parse_args(argv)
    if a.child:
        harness.report(**child(a.child, a.dir, a.work, a.index))
        if a.child.startswith("demsplit-run"):  # ends as the console script does (cli.command)
            from demsplit.runtime.command import exit_now

            exit_now(0)
        return
    skip = set(filter(None, a.skip.split(",")))
    names = [n for n in CHILDREN if n not in skip]
    with tempfile.TemporaryDirectory(prefix="demsplit-bench-") as work:
        index_file = str(Path(work) / "index.json")
        Path(index_file).write_text(json.dumps(frame_ranges(a.dir)))
        before = harness.machine()
        rounds = []
        for order in harness.rounds(names, a.repeat, fixed=("warm-up", "imports")):
            rounds.append({n: measure(n, a.dir, Path(work), index_file) for n in order})
            print(
                f"round {len(rounds)}: "
                + ", ".join(f"{n} {r.get('seconds', float('nan')):.1f} s" for n, r in rounds[-1].items()),
                file=sys.stderr,
            )
        after = harness.load()
    best = {n: min((r[n] for r in rounds), key=lambda x: x.get("seconds", float("inf"))) for n in names}
    report(best, a.dir, before, after, a.repeat)
    if a.json:
        a.json.write_text(json.dumps({"rounds": rounds, "machine": before, "load_after": after}, indent=1, default=str))


def report(m: dict, d: Path, before: str, load_after: float, repeat: int) -> None:
    sizes = {f: (d / f).stat().st_size / 1e6 for f in ("atoms.txt", "pairs.txt")}
    k = m.get("kernel", {})
    print(f"machine before: {before}; load average after {load_after:.2f}; best of {repeat}")
    print(
        f"files: atoms.txt {sizes['atoms.txt']:.0f} MB, pairs.txt {sizes['pairs.txt']:.0f} MB; "
        f"{k.get('particles', '?')} particles, {k.get('contacts', '?')} contacts per frame"
    )
    print()
    print(f"{'measurement':28s} {'wall s':>8s} {'peak MiB':>12s}")
    for n, r in m.items():
        if n == "kernel":
            continue
        if "error" in r:
            print(f"{n:28s} failed: {r['error']}")
        else:
            print(f"{n:28s} {r['seconds']:8.2f} {r['peak_mib']:12.0f}")

    def t(n):
        return m.get(n, {}).get("seconds")

    def ratio(label, a, b):
        print(harness.ratio(label, t(a), t(b)))

    print("\nspeed ratios (> 1: demsplit faster)")
    ratio("demsplit run vs polars bare parse of both files", "demsplit-run", "polars")
    ratio("demsplit run vs OVITO loading atoms + contacts", "demsplit-run", "ovito")
    ratio("demsplit run vs MDAnalysis reading the atom dump only", "demsplit-run", "mdanalysis")
    ratio("demsplit run --compression gzip vs polars bare parse", "demsplit-run-gzip", "polars")
    ratio("demsplit run --compression gzip vs OVITO", "demsplit-run-gzip", "ovito")
    ratio("demsplit run --compression lzf vs polars bare parse", "demsplit-run-lzf", "polars")
    ratio("demsplit run --compression none vs polars bare parse", "demsplit-run-nocompress", "polars")
    ratio("demsplit run --no-compare vs polars bare parse", "demsplit-run-nocompare", "polars")
    ratio("demsplit run --no-contacts vs polars bare parse", "demsplit-run-nocontacts", "polars")
    ratio("pipeline (no store) vs polars bare parse", "pipeline-nostore", "polars")
    ratio("demsplit dump reader (needed columns) vs polars, the same columns", "demsplit-dumps", "polars-needed")
    ratio("demsplit dump reader (needed columns) vs polars bare parse", "demsplit-dumps", "polars")
    ratio("demsplit reader (every Frame) vs polars bare parse", "demsplit-read", "polars")
    ratio("demsplit reader (every Frame) vs polars, only the needed columns", "demsplit-read", "polars-needed")
    ratio("demsplit run vs polars, only the needed columns", "demsplit-run", "polars-needed")
    ratio("demsplit run vs pandas C engine bare parse", "demsplit-run", "pandas-c")
    ratio("pipeline (no store) vs OVITO", "pipeline-nostore", "ovito")
    ratio("demsplit reader on the atom dump vs MDAnalysis (like for like)", "demsplit-atoms", "mdanalysis")
    ratio("cache read vs text read (every Frame)", "cache-read", "demsplit-read")
    lim = m.get("limits", {})
    if "page_cache_read" in lim and t("demsplit-read"):
        gb = lim["bytes"] / 1e9
        print(f"\nthroughput over both files ({gb:.2f} GB), GB/s, and demsplit's read as a fraction of each limit")
        print(f"  page-cache read (readinto)           {gb / lim['page_cache_read']:6.2f}")
        print(f"  newline count, 8 bytes a step        {gb / lim['newline_count']:6.2f}")
        for n in ("demsplit-dumps", "demsplit-read", "polars-needed", "polars"):
            if t(n):
                print(
                    f"  {n:36s} {gb / t(n):6.2f}   ({lim['page_cache_read'] / t(n):.0%} of the page-cache read, "
                    f"{lim['newline_count'] / t(n):.0%} of the newline count; process start and imports "
                    "included)"
                )
    if k and "frame_bytes" in k and "imports" in m and "error" not in m["imports"]:
        fb = k["frame_bytes"] / 2**20
        base = m["imports"]["peak_mib"]
        print(
            f"\npeak memory above imports ({base:.0f} MiB), in units of one frame's arrays "
            f"({fb:.0f} MiB: particles + contacts tables)"
        )
        for n in (
            "demsplit-run",
            "demsplit-run-gzip",
            "demsplit-run-lzf",
            "demsplit-run-nocompress",
            "demsplit-run-nocompare",
            "demsplit-run-nocontacts",
            "pipeline-nostore",
            "demsplit-read",
            "cache-read",
            "convert",
        ):
            if n in m and "error" not in m[n]:
                print(f"  {n:28s} {(m[n]['peak_mib'] - base) / fb:6.2f}x")
    if k and "error" not in k:
        print(f"\nin-memory kernels, frame 0, one core (best of {KERNEL_REPEAT})")
        for label in ("partition+per_particle", "frame_tables --no-compare", "frame_tables"):
            r = k[label]
            print(f"  {label:28s} {r['seconds']:7.3f} s  {r['contacts_per_s'] / 1e6:6.2f} M contacts/s")
    elif k:
        print(f"\nkernel failed: {k['error']}")


if __name__ == "__main__":
    main()
