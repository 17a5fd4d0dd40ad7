"""The harness every timing script of ``benchmarks/`` shares: fresh processes, best of N, peak memory, the machine.

Standard library only, so that a child can import it before numpy (a measured setting such as
``NUMPY_MADVISE_HUGEPAGE`` must be made before numpy loads).

* :func:`fresh` runs a command in a new process the way every measurement of a whole process is taken here:
  the dirty pages of earlier children written back first (``os.sync``, untimed, so that no child pays for an
  earlier one's output), the child's inputs read once into the page cache (:func:`warm`, untimed: a page
  cache may drop a file within a minute of its last read, and a child's time would then depend on what ran
  before it), then the wall seconds of the child, its user and system CPU seconds, and its report: the last
  line of its standard output, read as JSON when it is.
* :func:`report` is the child's side: it prints its fields and ``peak_mib``, the child's own peak resident
  memory (``VmHWM``, MiB; ``ru_maxrss`` of a waited child also counts the parent's memory at the fork).
  :data:`PRELUDE` gives a ``python -c`` child the same :func:`report`.
* :func:`rounds` interleaves variants over repeated rounds, each round in a rotated order, so that no variant
  always runs in the same place after the same neighbours; :func:`best_of` times a call in this process.
* :func:`machine` and :func:`load` say what the figures were taken on; :func:`ratio` prints one ratio.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
SAMPLE = REPO / "sample_dumps" / "liggghts" / "packing" / "in.packing"
"""A small real run: what a warm-up runs, so that numba's cached kernels are compiled before anything is timed."""

PRELUDE = f"import sys\nsys.path.insert(0, {str(HERE)!r})\nfrom harness import report\n"
"""Prepended to the code of a ``python -c`` child: ``sys``, and :func:`report` (nothing else is imported)."""


def peak_mib() -> float:
    """This process's peak resident memory, MiB (``VmHWM``), or NaN where /proc does not say."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")


def report(**fields) -> None:
    """The child's report to :func:`fresh`: ``fields`` and ``peak_mib`` as one JSON line on standard output."""
    print(json.dumps({**fields, "peak_mib": peak_mib()}), flush=True)


def warm(paths: Iterable[Path]) -> None:
    """Read ``paths`` once, into the page cache (what a child then reads comes from memory)."""
    buf = bytearray(1 << 24)
    for path in paths:
        if Path(path).is_file():
            with open(path, "rb", buffering=0) as f:
                while f.readinto(buf):
                    pass


@dataclass
class Fresh:
    """One process: wall, user and system seconds, exit status, output and the report it printed."""

    seconds: float
    user: float
    system: float
    returncode: int
    stdout: str
    stderr: str
    report: dict = field(default_factory=dict)

    @property
    def peak_mib(self) -> float:
        return self.report.get("peak_mib", float("nan"))


def fresh(
    argv: Sequence[str], *, inputs: Iterable[Path] = (), env: dict | None = None, pause: float = 0.0, check: bool = True
) -> Fresh:
    """Run ``argv`` in a new process, timed as the module docstring says; ``pause`` seconds of nothing between
    the untimed preparation and the start. ``check``: a failed child raises, with the end of its errors."""
    os.sync()
    warm(inputs)
    time.sleep(pause)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    proc = subprocess.run(list(argv), capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if check and proc.returncode != 0:
        shown = " ".join(a if len(a) < 80 else a[:60].replace("\n", "; ") + "..." for a in map(str, argv))
        raise RuntimeError(f"{shown} exited {proc.returncode}: {proc.stderr[-2000:]}")
    lines = proc.stdout.strip().splitlines()
    try:
        parsed = json.loads(lines[-1]) if lines else {}
    except json.JSONDecodeError:
        parsed = {}
    return Fresh(
        seconds,
        after.ru_utime - before.ru_utime,
        after.ru_stime - before.ru_stime,
        proc.returncode,
        proc.stdout,
        proc.stderr,
        parsed if isinstance(parsed, dict) else {},
    )


def python(code: str, *args, **kwargs) -> Fresh:
    """:func:`fresh` of ``python -c PRELUDE + code args...`` (keyword arguments as :func:`fresh`'s)."""
    return fresh([sys.executable, "-c", PRELUDE + code, *map(str, args)], **kwargs)


def rounds(names: Sequence[str], repeat: int, fixed: Sequence[str] = ()) -> Iterator[list[str]]:
    """The order of each of ``repeat`` rounds: ``fixed`` first (a warm-up), the others rotated by 1/``repeat``
    of their number per round, so that no measurement always runs in the same place."""
    first = [n for n in names if n in fixed]
    rest = [n for n in names if n not in fixed]
    for r in range(repeat):
        k = (r * len(rest)) // max(repeat, 1) if rest else 0
        yield first + rest[k:] + rest[:k]


def best_of(f: Callable[[], object], repeat: int = 3, min_time: float = 0.0) -> float:
    """The shortest of ``repeat`` timed calls of ``f`` in this process, repeating until ``min_time`` seconds
    were spent (the first call should be made untimed by the caller when it compiles or loads something)."""
    best, spent, n = float("inf"), 0.0, 0
    while n < repeat or spent < min_time:
        t = time.perf_counter()
        f()
        dt = time.perf_counter() - t
        best, spent, n = min(best, dt), spent + dt, n + 1
    return best


def median(values: Sequence[float]) -> float:
    return statistics.median(values)


def load() -> float:
    """The one-minute load average (a quiet machine: below 1 before a measurement starts)."""
    return os.getloadavg()[0]


def machine() -> str:
    """What a figure was taken on, in one line: cores this process may use (of the machine's), memory, load
    average, the processor and Python."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    try:
        cpu = next(
            line.split(":", 1)[1].strip()
            for line in Path("/proc/cpuinfo").read_text().splitlines()
            if line.startswith("model name")
        )
    except (OSError, StopIteration):
        cpu = platform.machine()
    return (
        f"{cores} cores (of {os.cpu_count()}), {memory:.0f} GiB, load average {load():.2f}; {cpu}; "
        f"Python {platform.python_version()}"
    )


def ratio(label: str, fast: float | None, slow: float | None, width: int = 58) -> str:
    """``slow / fast`` as a printed ratio (> 1: the first is faster), or n/a when one was not measured."""
    if fast and slow:
        return f"  {label:{width}s} {slow / fast:6.2f}x"
    return f"  {label:{width}s}   n/a"
