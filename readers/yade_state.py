"""YADE saved states (``O.save``): a finished run analysed post hoc, with no demsplit in its script.

YADE writes its state with ``O.save(name)`` as a boost serialization archive,
binary (``.yade``) or XML (``.xml``), plain or compressed (``.gz``, ``.bz2``),
and only a YADE of the same build reads it back. :class:`YadeStateRun` runs
Debian's ``yade`` headless (``yade -n -j1 -x``) on a small converter script
that loads each state (``O.load``) and writes demsplit's full-precision
snapshot of it (:func:`demsplit.yade.collect`); the snapshot reader then reads
those (:mod:`demsplit.readers.yade_snapshot`).

Nothing is stepped: the converter only loads the state and exports what YADE saved, so the contacts are
the real interactions YADE had, with their saved forces, springs, stiffnesses, normals and contact points,
and no collider or InteractionLoop makes or drops one. YADE does not save an interaction's
``penetrationDepth`` (``Attr::noSave``: NaN after ``O.load``); the snapshot reader recovers it from what
each law stored (:meth:`~demsplit.physics.laws._yade.YadeLaw.depth_from_phys`), and from the geometry at the
instant of the forces where that does not give it, and steps the positions back to that instant when the
state was saved after the NewtonIntegrator moved the bodies
(:func:`demsplit.readers.yade_snapshot.frame_from_snapshot`). A loaded law functor has no scene until the
next step (its energy functions crash YADE 2023.02a), so a state holds no law energies; ``O.energy`` is
saved with it.

Every file given is a state to read or a refusal that names it: a file named as ``O.save`` names its formats
(``STATE_SUFFIXES``) or holding a boost archive is a state; one that is empty, not such an archive, cut short
or that no YADE build loads is a bad state, refused by name (``--on-bad-frame skip`` leaves it out and lists
it). The states of a run are those of one simulation (:func:`one_simulation`): two states of the same
iteration are refused unless they are the same state (read once, with a note). Bodies may be added and erased
between states: the run's walls are every wall, facet and box of any state, each present in the frames of
the states that have it (``Frame.walls``).

Converted states are cached (``state_cache``, default ``$XDG_CACHE_HOME/demsplit/yade-states``;
``OUTPUT.states`` for ``demsplit run``) under a name made of the state file's BLAKE3 digest (the key: its
provenance fingerprint), the snapshot format and the BLAKE3 digest of the converted file itself (the check:
a cached file whose content does not give its name, cut short on a full disk or edited, is converted again),
written under a temporary name and renamed when complete. A second run does not start YADE. A state saved by
``yade-mpfr150`` or ``yade-float128`` is converted by the YADE that reads it: ``yade`` is tried first, then the
high-precision builds (``yade=`` names one). YADE has ``yade_timeout`` seconds for each state. Frames are
ordered by iteration.
"""

from __future__ import annotations

import bz2
import gzip
import json
import math
import os
import selectors
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import time
import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import DemsplitError, InputFormatError, ScriptError, StoreError, TruncatedFileError, system_error
from ..fingerprint import DIGEST, file_fingerprint
from ..frame import Frame, Table, describe_steps
from ..outputs import atomic_path
from ..runtime.hashing import digest, file_digest
from ..scene import Material
from ..yade import FORMAT_VERSION
from .base import MATERIALS, Option, Run
from .lammps_input import excerpt
from .yade_snapshot import (
    LAW_MODELS,
    PLANE_AS_PLANE,
    WALL_KINDS,
    YadeSnapshotRun,
    frame_from_snapshot,
    material_list,
    raw_snapshot,
    scene_from_snapshot,
)

SIGNATURES = (b"serialization::archive", b"<!DOCTYPE boost_serialization>")
"""What a boost archive (binary, then XML) holds in its first bytes, once decompressed."""
BUILDS = ("yade", "yade-mpfr150", "yade-float128")
"""YADE executables of Debian's ``yade`` package, in the order they are tried."""
STATE_SUFFIXES = tuple(kind + packing for kind in (".yade", ".xml") for packing in ("", ".gz", ".bz2"))
"""The names ``O.save`` gives its formats (binary or XML, plain or compressed): a file named so, in a
directory or a glob, is a state to read or a bad one to refuse by name, never passed over."""
DEFAULT_TIMEOUT = 900.0
"""Seconds YADE has to load and convert one state (``--yade-timeout``)."""
FIX_BAD = (
    "leave it out of the states given, or skip it with --on-bad-frame skip; a state cut short (a full disk, "
    "an interrupted copy) must be saved or copied again."
)
IDENTITY = ("shape_class", "material", "radius", "wall_axis")
"""What makes a body the same body in two states of one simulation (with its id): its shape, its material, its
radius (spheres) and a Wall's axis; not its clump (a script may clump bodies, or release them, as it runs)."""

CONVERTER = r"""
import json, os, site, sys


def say(*words):
    sys.stderr.write("DEMSPLIT-%s\n" % " ".join(str(w) for w in words))
    sys.stderr.flush()


try:
    site.addsitedir(os.environ["DEMSPLIT_SITE"])
    import demsplit.yade
    with open(os.environ["DEMSPLIT_STATES"]) as f:
        pairs = json.load(f)
except BaseException as exc:
    say("BROKEN", " ".join(("%s: %s" % (type(exc).__name__, exc)).split()))
    os._exit(1)
for k, (src, dst) in enumerate(pairs):
    say("START", k)
    try:
        O.load(src)
        meta, tables = demsplit.yade.collect(loaded=True)  # as saved: nothing runs
        demsplit.yade.write_snapshot(dst, meta, tables, format="npy")
    except BaseException as exc:
        say("FAILED", k, " ".join(("%s: %s" % (type(exc).__name__, exc)).split()))
    else:
        say("CONVERTED", k)
os._exit(0)
"""


def positive_seconds(text: str) -> float:
    """``--yade-timeout``'s value: a finite number of seconds > 0 (ValueError otherwise)."""
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"expected a number of seconds > 0, got {text!r}")
    return value


YADE_TIMEOUT = Option(
    "yade_timeout",
    ("--yade-timeout",),
    f"seconds YADE may take to load and convert one saved state before it is refused (default {DEFAULT_TIMEOUT:g})",
    {"type": positive_seconds, "metavar": "S"},
)


# ------------------------------------------------------------------ which files are states


def _opener(path: Path):
    name = path.name
    return gzip.open if name.endswith(".gz") else bz2.open if name.endswith(".bz2") else open


def _packing(path: Path) -> str:
    return "gzip" if path.name.endswith(".gz") else "bzip2" if path.name.endswith(".bz2") else ""


def _decompressed_head(path: Path, size: int = 256) -> bytes:
    try:
        with _opener(path)(path, "rb") as f:
            return f.read(size)
    except (OSError, EOFError, ValueError, zlib.error):
        return b""


def is_state(path: Path) -> bool:
    """Whether ``path`` is a file YADE's ``O.save`` wrote (a boost archive, possibly compressed)."""
    return path.is_file() and any(s in _decompressed_head(path) for s in SIGNATURES)


def named_like_state(path: Path) -> bool:
    """Whether ``path`` has a name ``O.save`` gives (:data:`STATE_SUFFIXES`)."""
    return path.name.endswith(STATE_SUFFIXES)


def state_files(path: Path) -> list[Path]:
    """The files a path names as states: the file itself, or the files of a directory or a glob's matches
    that are named like states or hold a boost archive (a directory's scripts, logs and exports are not)."""
    if path.is_dir():
        found = [p for p in path.iterdir() if p.is_file()]
    elif any(c in str(path) for c in "*?[") and not path.exists():
        found = [p for p in path.parent.glob(path.name) if p.is_file()]
    else:
        return [path] if path.is_file() and (named_like_state(path) or is_state(path)) else []
    return sorted(p for p in found if named_like_state(p) or is_state(p))


def head_problem(path: Path) -> DemsplitError | None:
    """Why the file ``path``, given as a state, is not one YADE may load, from its first bytes: it is empty,
    unreadable, or no boost archive (once decompressed); None when it may be one."""
    packing = _packing(path)
    try:
        if path.stat().st_size == 0:
            return InputFormatError("the file is empty: it is not a YADE saved state.", file=path, fix=FIX_BAD)
        with _opener(path)(path, "rb") as f:
            head = f.read(256)
    except OSError as exc:
        if exc.errno is not None:
            return InputFormatError(
                f"the file cannot be read ({exc.strerror}).", file=path, fix="make it readable, or " + FIX_BAD
            )
        head = None
    except (EOFError, ValueError, zlib.error):
        head = None
    if head is None:
        return InputFormatError(
            f"it is not a YADE saved state: its name says {packing}, but it is no {packing} stream.",
            file=path,
            fix=FIX_BAD,
        )
    if not any(s in head for s in SIGNATURES):
        text = head.decode("latin-1")
        return InputFormatError(
            f"it is not a YADE saved state: its content{' once decompressed' if packing else ''} is not a boost "
            f"archive, as O.save writes (it begins {excerpt(text, 40)}).",
            file=path,
            fix=FIX_BAD,
        )
    return None


def stream_problem(path: Path) -> DemsplitError | None:
    """Why the compressed state ``path`` cannot be read to its end (a gzip or bzip2 stream cut short or
    damaged, found by decompressing it whole, which checks gzip's CRC), or None."""
    packing = _packing(path)
    if not packing:
        return None
    try:
        with _opener(path)(path, "rb") as f:
            while f.read(1 << 20):
                pass
    except OSError as exc:
        if exc.errno is not None:
            return InputFormatError(
                f"the file cannot be read ({exc.strerror}).", file=path, fix="make it readable, or " + FIX_BAD
            )
        cause = exc
    except (EOFError, ValueError, zlib.error) as exc:
        cause = exc
    else:
        return None
    return TruncatedFileError(
        f"its {packing} stream is cut short or damaged ({type(cause).__name__}: "
        f"{' '.join(str(cause).split())[:120]}), so YADE cannot load it.",
        file=path,
        fix=FIX_BAD,
    )


def default_cache() -> Path:
    """``$XDG_CACHE_HOME/demsplit/yade-states`` (``~/.cache`` without XDG_CACHE_HOME)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "demsplit" / "yade-states"


# ------------------------------------------------------------------ the cache of converted states


def cache_key(state: Path) -> str:
    """The cache's key of a state: its BLAKE3 digest (the provenance's fingerprint) and the snapshot format."""
    return f"{file_fingerprint(state)[DIGEST]}-v{FORMAT_VERSION}"


def _content(converted: Path) -> str:
    """The BLAKE3 digest of a converted state that its name in the cache holds."""
    return converted.name[: -len(".npys")].rsplit("-", 1)[-1]


def _cached(cache: Path, key: str) -> Path | None:
    """The converted state of key ``key`` in ``cache`` whose content gives its name; a file of that key whose
    content does not (cut short on a full disk, edited) is removed, to be converted again."""
    if not cache.is_dir():
        return None
    for path in sorted(cache.glob(f"{key}-*.npys")):
        try:
            if digest(path)[1] == _content(path):
                return path
            path.unlink()
        except OSError:
            continue
    return None


def _keep(made: Path, cache: Path, key: str) -> Path:
    """Put the converted state ``made`` into ``cache`` under its key and content digest, written whole under a
    temporary name and renamed (:func:`demsplit.outputs.atomic_path`); an error of the system is a StoreError."""
    target = cache / f"{key}-{file_digest(made)}.npys"
    try:
        cache.mkdir(parents=True, exist_ok=True)
        with atomic_path(target) as tmp:
            shutil.copyfile(made, tmp)
    except OSError as exc:  # named by the cache's file, not by the converter's temporary one
        raise system_error(
            OSError(exc.errno, exc.strerror or str(exc)), target, doing="keeping a converted YADE state"
        ) from None
    return target


def _check_cache(cache: Path) -> None:
    if cache.exists() and not cache.is_dir():
        raise StoreError(
            "the directory of converted YADE states is a file.",
            file=cache,
            fix="move the file away, or name another directory with --state-cache DIR.",
        )


def convert_states(
    states: list[Path], cache: Path, *, yade: str | None = None, timeout: float = DEFAULT_TIMEOUT
) -> tuple[dict[Path, Path], dict[Path, DemsplitError]]:
    """The converted snapshot of each state in ``cache`` (converting those not there with YADE: ``yade`` the
    build, default the first that loads them; ``timeout`` seconds per state), and the states that could not
    be converted, with why."""
    _check_cache(cache)
    keys = {s: cache_key(s) for s in states}
    converted = {s: hit for s in states if (hit := _cached(cache, keys[s])) is not None}
    failed = {s: p for s in states if s not in converted and (p := stream_problem(s)) is not None}
    todo = [s for s in states if s not in converted and s not in failed]
    if todo:
        made, errors = _convert(todo, yade, timeout, lambda state, path: _keep(path, cache, keys[state]))
        converted.update(made)
        failed.update(errors)
    return converted, failed


# ------------------------------------------------------------------ YADE converts


def _builds(yade: str | None, first: Path) -> list[str]:
    builds = [yade] if yade else [b for b in BUILDS if shutil.which(b)]
    if not builds or not shutil.which(builds[0]):
        raise InputFormatError(
            f"reading a YADE saved state needs YADE, and {yade or 'yade'} is not installed.",
            file=first,
            fix="install Debian's yade (apt-get install yade), or give the "
            "executable that saved the state with --yade.",
        )
    return builds


def _convert(
    todo: list[Path], yade: str | None, timeout: float, keep
) -> tuple[dict[Path, Path], dict[Path, DemsplitError]]:
    """Convert the states with the first YADE build that loads each (``keep(state, file)`` stores a converted
    file). A state YADE fails on, crashes on or does not finish within ``timeout`` s is one refusal naming it;
    the others are converted by a new process. A YADE that stops or hangs before loading any state is an
    error of the run."""
    builds = _builds(yade, todo[0])
    made: dict[Path, Path] = {}
    errors: dict[Path, list[str]] = {s: [] for s in todo}
    final: dict[Path, DemsplitError] = {}
    with tempfile.TemporaryDirectory(prefix="demsplit-yade-") as tmp:
        script = Path(tmp) / "convert.py"
        script.write_text(CONVERTER)
        left, attempt = list(todo), 0
        for n, build in enumerate(builds):
            retry = []
            queue = list(left)
            while queue:
                attempt += 1  # a new file per state and attempt: the snapshot writer appends
                pairs = [(str(s.resolve()), str(Path(tmp) / f"{attempt}-{k}.npys")) for k, s in enumerate(queue)]
                done, current, why = _run_converter(build, script, pairs, timeout)
                for k, error in done.items():
                    if error is None:
                        made[queue[k]] = keep(queue[k], Path(pairs[k][1]))
                        Path(pairs[k][1]).unlink()
                    else:
                        errors[queue[k]].append(f"{build}: {error}")
                        retry.append(queue[k])
                if why is None:
                    break
                if current is None and not done:  # stopped or stuck before the first state
                    if n == 0:
                        raise ScriptError(
                            f"{build} {why} before it loaded a state.",
                            file=queue[0],
                            fix="check that 'yade -n -j1' starts, give the YADE build with --yade, or "
                            "more time with --yade-timeout S.",
                        )
                    errors.update({s: errors[s] + [f"{build} {why}"] for s in queue})
                    retry += queue
                    break
                if current is not None:
                    if why.startswith("timed out"):
                        final[queue[current]] = InputFormatError(
                            f"{build} {why} while it loaded and converted this state.",
                            file=queue[current],
                            fix=f"give more time with --yade-timeout S (a large state), or check that YADE loads it "
                            f"by hand (O.load); or {FIX_BAD}",
                        )
                    else:
                        errors[queue[current]].append(f"{build} {why} while it loaded this state")
                        retry.append(queue[current])
                queue = queue[(current if current is not None else max(done)) + 1 :]
            left = retry
    for state in left:
        if state not in made and state not in final:
            final[state] = InputFormatError(
                f"YADE could not load the saved state ({'; '.join(errors[state])[:600]}).",
                file=state,
                fix="check that the file is complete (a state cut short does not load) and give the YADE build that "
                "saved it with --yade (yade, yade-mpfr150 or yade-float128); or " + FIX_BAD,
            )
    return made, {s: final[s] for s in todo if s in final}


def _stopped(returncode: int) -> str:
    if returncode < 0:
        try:
            return f"was killed by signal {signal.Signals(-returncode).name}"
        except ValueError:
            return f"was killed by signal {-returncode}"
    return f"stopped (exit status {returncode})"


def _run_converter(
    build: str, script: Path, pairs: list[tuple[str, str]], timeout: float
) -> tuple[dict[int, str | None], int | None, str | None]:
    """Run one YADE process of ``build`` converting ``pairs`` (state, converted file); YADE has ``timeout`` s
    for each state (and for its start). Returns what became of each state it reached (index -> None: converted,
    else YADE's error), the index of the state it was converting when it stopped (None: none), and why it
    stopped early (None: it went through every state). Progress per state is shown on a terminal."""
    listing = script.with_name("states.json")
    listing.write_text(json.dumps(pairs))
    env = {**os.environ, "DEMSPLIT_SITE": sysconfig.get_paths()["purelib"], "DEMSPLIT_STATES": str(listing)}
    show = sys.stderr.isatty()
    done: dict[int, str | None] = {}
    current: int | None = None
    tail: list[str] = []
    broken = None
    proc = subprocess.Popen(
        [build, "-n", "-j1", "-x", str(script)],
        cwd=script.parent,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        with selectors.DefaultSelector() as selector:
            selector.register(proc.stderr, selectors.EVENT_READ)
            deadline, rest, timed_out = time.monotonic() + timeout, b"", False
            while True:
                left = deadline - time.monotonic()
                if left <= 0:
                    timed_out = True
                    break
                if not selector.select(left):
                    continue
                chunk = os.read(proc.stderr.fileno(), 1 << 16)
                if not chunk:
                    break
                *lines, rest = (rest + chunk).split(b"\n")
                rest = rest[-(1 << 16) :]
                for line in (raw.decode("utf-8", "replace") for raw in lines):
                    word, _, arg = line.partition(" ")
                    index, _, text = arg.partition(" ")
                    k = int(index) if index.isdigit() and int(index) < len(pairs) else None
                    if word == "DEMSPLIT-START" and k is not None:
                        current, deadline = k, time.monotonic() + timeout
                    elif word == "DEMSPLIT-CONVERTED" and k is not None:
                        done[k], current = None, None
                        if show:
                            sys.stderr.write(
                                f"demsplit: {build} converted state {len(done)}/{len(pairs)}: {pairs[k][0]}\n"
                            )
                    elif word == "DEMSPLIT-FAILED" and k is not None:
                        done[k], current = " ".join(text.split())[:300], None
                    elif word == "DEMSPLIT-BROKEN":
                        broken = " ".join(arg.split())[:300]
                    elif line.strip():
                        tail = [*tail[-4:], " ".join(line.split())[:200]]
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        proc.stderr.close()
    if timed_out:
        return done, current, f"timed out after {timeout:g} s (--yade-timeout)"
    if proc.returncode == 0 and len(done) == len(pairs):
        return done, None, None
    said = broken or (tail[-1] if tail else "")
    return done, current, _stopped(proc.returncode) + (f" ({said})" if said else "")


# ------------------------------------------------------------------ the states of a run


@dataclass
class StateSet:
    """The files given as YADE saved states: ``files`` (each once, in the order found), ``converted`` (state ->
    its converted snapshot in ``cache``) and ``bad`` (state -> why it is not read, in the order of ``files``)."""

    files: list[Path]
    converted: dict[Path, Path]
    bad: dict[Path, DemsplitError]
    cache: Path


def find_states(
    paths: list[Path], cache: Path, *, yade: str | None = None, timeout: float = DEFAULT_TIMEOUT
) -> StateSet:
    """The states that ``paths`` (files, directories, globs) name, converted into ``cache`` where they can be."""
    files: list[Path] = []
    for p in paths:
        found = state_files(Path(p))
        if not found:
            raise InputFormatError(
                "no YADE saved state here.", file=p, fix="give files written by O.save, a directory or a glob of them."
            )
        files += [f for f in found if f not in files]
    bad = {f: problem for f in files if (problem := head_problem(f)) is not None}
    converted, failed = (
        convert_states([f for f in files if f not in bad], cache, yade=yade, timeout=timeout)
        if len(bad) < len(files)
        else ({}, {})
    )
    bad.update(failed)
    return StateSet(files, converted, {f: bad[f] for f in files if f in bad}, cache)


def named(exc: DemsplitError, state: Path, converted: Path) -> DemsplitError:
    """``exc`` of a converted state, naming the state the user gave instead of its copy in the cache."""
    return type(exc)(
        exc.message.replace(str(converted), str(state)), file=state, step=exc.step, line=exc.line, fix=exc.fix
    )


def _body(bodies: dict[str, np.ndarray], row: int, materials: dict[int, str]) -> str:
    """A body of a bodies table in words, with what makes it the same body (:data:`IDENTITY`)."""
    shape = bodies["shape_class"][row].decode(errors="replace")
    text = f"a {shape} of material {int(bodies['material'][row])} ({materials.get(int(bodies['material'][row]), '?')})"
    if np.isfinite(bodies["radius"][row]):
        text += f", radius {float(bodies['radius'][row]):.9g} m"
    if bodies["clump"][row] >= 0:
        text += f", in clump {int(bodies['clump'][row])}"
    return text


def _material(m: dict) -> str:
    """A YADE material of a snapshot's metadata in words: its class, label, young and poisson."""

    def number(key: str) -> str:
        value = m.get(key)
        return f"{value:g}" if isinstance(value, (int, float)) and not isinstance(value, bool) else "?"

    label = f" {m['label']!r}" if m.get("label") else ""
    return f"{m.get('class', '?')}{label} (young {number('young')}, poisson {number('poisson')})"


class Simulation:
    """The union of the states of one simulation, built state by state in iteration order (:meth:`add`): every
    body any state has (its id and :data:`IDENTITY`, and its clump and position where it first appears), every material
    (by id), the law and whether the cell is periodic. A state of another simulation is refused (module
    docstring)."""

    def __init__(self) -> None:
        self.bodies: dict[str, np.ndarray] = {}
        self.first: np.ndarray = np.zeros(0, np.int64)  # the state where each body first appears
        self.materials: dict[int, dict] = {}
        self.material_from: dict[int, int] = {}
        self.states: list[Path] = []
        self.model = None
        self.periodic = None
        self.walls: list[frozenset[int]] = []  # the ids of the walls each state has

    def add(self, state: Path, meta: dict, bodies: dict[str, np.ndarray], model) -> None:
        """Add a state; an InputFormatError names it and the earlier state it differs from when it is not of
        the same simulation."""
        k = len(self.states)
        fix = (
            "give the states of one simulation (one run of one script): bodies may be added and erased, but a "
            "body keeps its id, shape, material and radius, and the law, the materials and the periodic "
            "cell stay; the states of another simulation are analysed in a run of their own."
        )
        if self.states and model != self.model:
            raise InputFormatError(
                f"its contact law ({model.law} {model.params}) is not that of {self.states[0]} "
                f"({self.model.law} {self.model.params}): the states are of two simulations.",
                file=state,
                step=int(meta["iter"]),
                fix=fix,
            )
        if self.states and bool(meta["periodic"]) != self.periodic:
            raise InputFormatError(
                f"its cell is {'' if meta['periodic'] else 'not '}periodic, that of "
                f"{self.states[0]} is {'' if self.periodic else 'not '}: the states are of two "
                "simulations.",
                file=state,
                step=int(meta["iter"]),
                fix=fix,
            )
        for m in meta["materials"]:
            t, canonical = int(m["id"]), json.dumps(m, sort_keys=True)
            if t in self.materials and json.dumps(self.materials[t], sort_keys=True) != canonical:
                raise InputFormatError(
                    f"its material {t} is {_material(m)}, but material {t} of {self.states[self.material_from[t]]} "
                    f"is {_material(self.materials[t])}: the states are of two simulations.",
                    file=state,
                    step=int(meta["iter"]),
                    fix=fix,
                )
            self.materials.setdefault(t, m)
            self.material_from.setdefault(t, k)
        names = {int(m["id"]): str(m.get("label") or m.get("class")) for m in meta["materials"]}
        ids = bodies["id"]
        columns = {c: bodies[c] for c in ("id", "kind", *IDENTITY, "clump", "x", "y", "z")}
        if self.states:
            union = self.bodies["id"]
            at = np.clip(np.searchsorted(union, ids), 0, max(len(union) - 1, 0))
            shared = (union[at] == ids) if len(union) else np.zeros(len(ids), bool)
            rows, there = np.flatnonzero(shared), at[shared]
            differ = np.zeros(len(rows), bool)
            for c in IDENTITY:
                a, b = columns[c][rows], self.bodies[c][there]
                same = (a == b) | (np.isnan(a) & np.isnan(b)) if a.dtype.kind == "f" else a == b
                differ |= ~same
            if differ.any():
                i = int(np.flatnonzero(differ)[0])
                row, old = int(rows[i]), int(there[i])
                earlier = self.states[int(self.first[old])]
                before = {t: str(m.get("label") or m.get("class")) for t, m in self.materials.items()}
                raise InputFormatError(
                    f"body {int(ids[row])} is {_body(columns, row, names)} here, but "
                    f"{_body(self.bodies, old, before)} in {earlier}: the states are of two simulations.",
                    file=state,
                    step=int(meta["iter"]),
                    fix=fix,
                )
            new = ~shared
            if new.any():  # bodies added since the earlier states
                merged = {c: np.concatenate([self.bodies[c], columns[c][new]]) for c in columns}
                first = np.concatenate([self.first, np.full(int(new.sum()), k)])
                order = np.argsort(merged["id"], kind="stable")
                self.bodies = {c: v[order] for c, v in merged.items()}
                self.first = first[order]
        else:
            order = np.argsort(ids, kind="stable")
            self.bodies = {c: v[order] for c, v in columns.items()}
            self.first = np.zeros(len(ids), np.int64)
            self.model, self.periodic = model, bool(meta["periodic"])
        self.states.append(state)
        self.walls.append(frozenset(ids[np.isin(bodies["kind"].astype(str), list(WALL_KINDS))].tolist()))


class YadeStateRun(Run):
    """Frames of YADE saved states, converted by YADE itself (module docstring)."""

    format_name = "yade-state"
    formats = ("a YADE saved state (O.save: .yade, .xml, .gz, .bz2), a directory or a glob of them",)
    priority = 5
    several_files = True
    cli_group = "YADE inputs"
    cli_options = (
        PLANE_AS_PLANE,
        MATERIALS,
        Option(
            "yade",
            ("--yade",),
            "the YADE build that saved the states (yade, yade-mpfr150, yade-float128; "
            "default: the first that loads them)",
            {"metavar": "EXE"},
        ),
        Option(
            "state_cache",
            ("--state-cache",),
            "where converted YADE saved states are kept (default for run: "
            "OUTPUT.states next to the output; for info and check: $XDG_CACHE_HOME/demsplit/yade-states)",
            {"metavar": "DIR"},
        ),
        YADE_TIMEOUT,
    )

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is not None and bool(state_files(path))

    @classmethod
    def output_options(cls, output: Path) -> dict:
        """Converted states are kept next to the output (``OUTPUT.states``), where a rerun finds them."""
        return {"state_cache": str(output.with_name(output.name + ".states"))}

    def __init__(
        self,
        path: Path | list[Path],
        yade: str | None = None,
        state_cache: str | Path | None = None,
        yade_timeout: float | None = None,
        plane_as_plane: bool = False,
        materials: dict[int, Material] | None = None,
    ) -> None:
        timeout = DEFAULT_TIMEOUT if yade_timeout is None else yade_timeout
        if not (isinstance(timeout, (int, float)) and math.isfinite(timeout) and timeout > 0):
            raise InputFormatError(
                f"the time YADE has per state must be a number of seconds > 0, not {timeout!r}.",
                fix="give --yade-timeout S with S > 0.",
            )
        cache = Path(state_cache) if state_cache is not None else default_cache()
        states = find_states(path if isinstance(path, list) else [path], cache, yade=yade, timeout=timeout)
        self._open(states, plane_as_plane=plane_as_plane, materials=materials)

    @classmethod
    def _from_states(cls, states: StateSet, **options) -> YadeStateRun:
        """The run of states found and converted already (``demsplit info``)."""
        run = cls.__new__(cls)
        run._open(states, **options)
        return run

    def _open(
        self, states: StateSet, *, plane_as_plane: bool = False, materials: dict[int, Material] | None = None
    ) -> None:
        self.states = states
        self._plane_as_plane = plane_as_plane
        self._runs: list[YadeSnapshotRun] = []
        try:
            self._read_states(plane_as_plane, materials)
        except DemsplitError as exc:
            self.close()
            raise self._kept(exc) from None

    def _read_states(self, plane_as_plane: bool, materials: dict[int, Material] | None) -> None:
        states = self.states
        good = [s for s in states.files if s in states.converted]
        if not good:
            first = next(iter(states.bad.values()))
            raise type(first)(
                first.message
                + (
                    f" (The {len(states.bad) - 1} other file(s) given are not read either.)"
                    if len(states.bad) > 1
                    else ""
                ),
                file=first.file,
                step=first.step,
                line=first.line,
                fix=first.fix,
            )
        runs, steps = {}, {}
        for s in good:
            try:
                run = YadeSnapshotRun(states.converted[s], plane_as_plane=plane_as_plane)
            except DemsplitError as exc:
                raise named(exc, s, states.converted[s]) from None
            self._runs.append(run)
            if len(run.steps) != 1:
                raise InputFormatError(
                    "its converted copy holds no complete snapshot.",
                    file=s,
                    fix=f"delete {states.converted[s]} and run again.",
                )
            runs[s], steps[s] = run, int(run.steps[0])
        used, twins, notes = [], [], []
        simulation = Simulation()
        for s in sorted(good, key=lambda s: steps[s]):  # stable: in the order found within an iteration
            twin = next((u for u in used if steps[u] == steps[s]), None)
            if twin is not None and _content(states.converted[twin]) == _content(states.converted[s]):
                twins.append(s)
                notes.append(
                    f"{s} is the same state as {twin} (iteration {steps[s]}, the same content once "
                    "converted): it is read once"
                )
                continue
            meta, tables = runs[s].read(0)
            try:
                simulation.add(s, meta, tables["bodies"], runs[s].scene.model)  # of another simulation: refused
            except DemsplitError as exc:
                raise named(exc, s, states.converted[s]) from None
            if twin is not None:
                raise InputFormatError(
                    f"iteration {steps[s]} is in two different states, {twin} and this one.",
                    file=s,
                    step=steps[s],
                    fix="give one state per iteration: a state changed after it was saved, or a run "
                    "restarted from an earlier state, is analysed in a run of its own.",
                )
            used.append(s)
        first_meta = runs[used[0]].meta(0)
        merged = {**first_meta, "materials": [simulation.materials[t] for t in sorted(simulation.materials)]}
        parts = scene_from_snapshot(
            merged, simulation.bodies, path=used[0], plane_as_plane=plane_as_plane, materials=materials
        )
        what = str(used[0]) if len(used) == 1 else f"{len(used)} YADE saved states, {used[0]} to {used[-1]}"
        self.scene = replace(
            parts.scene,
            source=f"{what} (YADE {first_meta.get('yade_version', '?')}, {first_meta.get('precision_name', '?')})",
        )
        self._unusable = parts.unusable
        kinds = simulation.bodies["kind"].astype(str)
        wall_ids = simulation.bodies["id"][np.isin(kinds, list(WALL_KINDS))]
        self._wall_index = {int(b): k for k, b in enumerate(wall_ids)}
        self._used = used
        self._state_runs = [runs[s] for s in used]
        self._bad = list(states.bad.items())
        self.steps = np.array([steps[s] for s in used], dtype=np.int64)
        self.sources = used + twins
        changing = [
            (w, [steps[s] for s, present in zip(used, simulation.walls) if b in present])
            for w, b in zip(self.scene.walls, wall_ids.tolist())
        ]
        changing = [f"{w.name} at iterations {describe_steps(at)}" for w, at in changing if len(at) < len(used)]
        self.notes = [
            f"YADE saved states converted by YADE (kept in {states.cache}, by the content of each "
            "state): the interactions as saved, their overlaps from the forces and stiffnesses the law "
            "stored (YADE does not save them)",
            *notes,
            *parts.notes,
        ]
        if changing:
            self.notes.append(
                "walls added or erased between the states (each is in the frames of the states that "
                "have it): " + "; ".join(changing)
            )

    def _kept(self, exc: DemsplitError) -> DemsplitError:
        """``exc``, saying where the states converted for this run stay (a rerun reads them without YADE)."""
        if not self.states.converted:
            return exc
        return type(exc)(
            exc.message,
            file=exc.file,
            step=exc.step,
            line=exc.line,
            fix=f"{exc.fix or ''} (Converted states are kept in {self.states.cache}.)".strip(),
        )

    def __len__(self) -> int:
        return len(self._used) + len(self._bad)

    def frame(self, k: int) -> Frame:
        """Frame ``k``: the state of the ``k``-th iteration with the run's walls that it has; past the states
        read, the bad states, whose frame raises why they are not read."""
        if k >= len(self._used):
            raise self._kept(self._bad[k - len(self._used)][1])
        state, run = self._used[k], self._state_runs[k]
        try:
            meta, tables = run.read(0)
            bodies = tables["bodies"]
            ids = bodies["id"][np.isin(bodies["kind"].astype(str), list(WALL_KINDS))]
            walls = {int(b): self._wall_index[int(b)] for b in ids}
            frame = frame_from_snapshot(
                meta,
                tables,
                walls,
                path=state,
                law=self.scene.model.contact_law,
                plane_as_plane=self._plane_as_plane,
                unusable=self._unusable,
            )[0]
        except DemsplitError as exc:
            raise self._kept(named(exc, state, run.path)) from None
        if len(walls) < len(self._wall_index):
            frame.walls = tuple(sorted(walls.values()))
        return frame

    def materials_without_moduli(self) -> dict[int, str]:
        """The materials the split has no moduli for (id -> why): refused when a contact touches one."""
        return dict(self._unusable)

    def named_files(self) -> list[Path]:
        """Every file given as a state, read or not: an output never replaces one."""
        return list(self.states.files)

    def describe(self) -> dict:
        """The states read, their iterations, their converted copies (named by the digests of the state and of
        the copy) and YADE's own elastic energies saved with them (``O.energy``)."""
        return {
            "kind": self.format_name,
            "states": [str(s) for s in self._used],
            "steps": self.steps.tolist(),
            "converted": [self.states.converted[s].name for s in self._used],
            "cache": str(self.states.cache),
            "yade_energies": [e for run in self._state_runs for e in run.yade_energies],
        }

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """What each state holds (iteration, time, bodies, interactions), the law, the materials and the YADE
        build, whether or not demsplit analyses them; a bad state is listed with why it is not read."""
        states = find_states([path], default_cache())
        lines = [f"{path}: YADE saved state(s), {len(states.files)} ({', '.join(s.name for s in states.files)})"]
        raw: dict[Path, tuple[dict, dict[str, Table]]] = {}
        for s in states.files:
            if s in states.converted:
                try:
                    raw[s] = raw_snapshot(states.converted[s])
                except DemsplitError as exc:
                    states.bad[s] = named(exc, s, states.converted[s])
        lines.append(f"  iterations: {sorted(int(meta['iter']) for meta, _ in raw.values())}")
        for s in states.files:
            if s in raw:
                meta, tables = raw[s]
                kinds = tables["bodies"]["kind"].astype(str).tolist()
                walls = {k: kinds.count(k) for k in WALL_KINDS if k in kinds}
                lines.append(
                    f"  {s.name}: iteration {meta['iter']}, t = {meta['time']:.6g} s, "
                    f"bodies: {kinds.count('sphere')} spheres, walls "
                    + (", ".join(f"{n} {k}" for k, n in sorted(walls.items())) or "none")
                    + f"; interactions: {meta['n_interactions_real']} real"
                )
            else:
                lines.append(f"  {s.name}: NOT READ: {states.bad[s].message}")
        if raw:
            meta = max(raw.values(), key=lambda r: int(r[0]["iter"]))[0]
            lines.append(
                "  law (Law2): "
                + ", ".join(
                    f["class"] + ("" if f["class"] in LAW_MODELS else " (not one demsplit analyses)")
                    for f in meta["functors"]["law"]
                )
            )
            lines.append("  YADE materials: " + "; ".join(f"{int(m['id'])}: {_material(m)}" for m in meta["materials"]))
            lines.append(f"  YADE:       {meta.get('yade_version', '?')} {meta.get('precision_name', '?')}")
        try:
            with cls._from_states(states) as run:
                lines.append(f"  law:        {run.scene.model.describe()}")
                lines.append("  materials:  " + material_list(run))
                try:
                    contacts = f"{run.frame(len(run.steps) - 1).n_contacts} read as contacts"
                except DemsplitError as exc:
                    contacts = f"not analysable as they are: {exc}"
                lines.append(f"  interactions (last state): {contacts}")
        except DemsplitError as exc:
            lines.append(f"  analysis:   refused: {exc}")
        return "\n".join(lines)

    def close(self) -> None:
        for run in self._runs:
            run.close()
