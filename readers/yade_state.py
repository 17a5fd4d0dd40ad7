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

Converted states are cached (``state_cache``, default ``$XDG_CACHE_HOME/demsplit/yade-states``),
keyed by the state file's BLAKE3 digest (its provenance fingerprint) and the snapshot format, so a
second run does not start YADE. A state saved by ``yade-mpfr150`` or ``yade-float128`` is
converted by the YADE that reads it: ``yade`` is tried first, then the
high-precision builds (``yade=`` names one). Frames are ordered by iteration.
"""

from __future__ import annotations

import bz2
import gzip
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

import numpy as np

from ..errors import DemsplitError, InputFormatError, ScriptError
from ..fingerprint import DIGEST, file_fingerprint
from ..frame import Frame
from ..scene import Material
from ..yade import FORMAT_VERSION
from .base import MATERIALS, Option, Run
from .yade_snapshot import PLANE_AS_PLANE, YadeSnapshotRun, material_list

SIGNATURES = (b"serialization::archive", b"<!DOCTYPE boost_serialization>")
"""What a boost archive (binary, then XML) holds in its first bytes, once decompressed."""
BUILDS = ("yade", "yade-mpfr150", "yade-float128")
"""YADE executables of Debian's ``yade`` package, in the order they are tried."""
SUFFIXES = (".yade", ".xml")

CONVERTER = r'''
import json, os, site, sys, traceback
site.addsitedir(os.environ["DEMSPLIT_SITE"])
try:
    import demsplit.yade
    for src, dst in json.loads(os.environ["DEMSPLIT_STATES"]):
        O.load(src)
        meta, tables = demsplit.yade.collect(loaded=True)  # as saved: nothing runs
        demsplit.yade.write_snapshot(dst, meta, tables, format="npy")
        sys.stderr.write("DEMSPLIT-CONVERTED %s %d\n" % (src, O.iter))
        sys.stderr.flush()
except BaseException:
    sys.stderr.write("DEMSPLIT-FAILED\n")
    traceback.print_exc()
    sys.stderr.flush()
    os._exit(1)
os._exit(0)
'''


def _decompressed_head(path: Path, size: int = 256) -> bytes:
    opener = gzip.open if path.name.endswith(".gz") else bz2.open if path.name.endswith(".bz2") else open
    try:
        with opener(path, "rb") as f:
            return f.read(size)
    except (OSError, EOFError, ValueError):
        return b""


def is_state(path: Path) -> bool:
    """Whether ``path`` is a file YADE's ``O.save`` wrote (a boost archive, possibly compressed)."""
    return path.is_file() and any(s in _decompressed_head(path) for s in SIGNATURES)


def state_files(path: Path) -> list[Path]:
    """The state files a path names: the file itself, the states in a directory, or a glob's matches."""
    if path.is_dir():
        return sorted(p for p in path.iterdir() if is_state(p))
    if any(c in str(path) for c in "*?[") and not path.exists():
        return sorted(p for p in path.parent.glob(path.name) if is_state(p))
    return [path] if is_state(path) else []


def default_cache() -> Path:
    """``$XDG_CACHE_HOME/demsplit/yade-states`` (``~/.cache`` without XDG_CACHE_HOME)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "demsplit" / "yade-states"


class YadeStateRun(Run):
    """Frames of YADE saved states, converted by YADE itself (module docstring)."""

    format_name = "yade-state"
    formats = ("a YADE saved state (O.save: .yade, .xml, .gz, .bz2), a directory or a glob of them",)
    priority = 5
    several_files = True
    cli_group = "YADE inputs"
    cli_options = (
        PLANE_AS_PLANE, MATERIALS,
        Option("yade", ("--yade",), "the YADE build that saved the states (yade, yade-mpfr150, yade-float128; "
               "default: the first that loads them)", {"metavar": "EXE"}),
        Option("state_cache", ("--state-cache",), "where converted YADE saved states are kept (default for run: "
               "OUTPUT.states next to the output; for info and check: $XDG_CACHE_HOME/demsplit/yade-states)",
               {"metavar": "DIR"}),
    )

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is not None and bool(state_files(path))

    @classmethod
    def output_options(cls, output: Path) -> dict:
        """Converted states are kept next to the output (``OUTPUT.states``), where a rerun finds them."""
        return {"state_cache": str(output.with_name(output.name + ".states"))}

    def __init__(self, path: Path | list[Path], yade: str | None = None, state_cache: str | Path | None = None,
                 plane_as_plane: bool = False, materials: dict[int, Material] | None = None) -> None:
        states = []
        for p in (path if isinstance(path, list) else [path]):
            found = state_files(p)
            if not found:
                raise InputFormatError("no YADE saved state here.", file=p,
                                       fix="give files written by O.save, a directory or a glob of them.")
            states += [s for s in found if s not in states]
        cache = Path(state_cache) if state_cache is not None else default_cache()
        targets = converted(states, cache, yade=yade)
        runs = [YadeSnapshotRun(t, plane_as_plane=plane_as_plane, materials=materials) for t in targets]
        order = np.argsort([int(r.steps[0]) if len(r.steps) else -1 for r in runs], kind="stable")
        self._runs = [runs[i] for i in order]
        self._states = [states[i] for i in order]
        first = self._runs[0].scene
        for state, run in zip(self._states, self._runs):
            if run.scene.model != first.model or run.scene.materials != first.materials:
                raise InputFormatError("this state's contact law or materials differ from those of "
                                       f"{self._states[0].name}.", file=state,
                                       fix="analyse the states of one simulation together.")
        self.scene = first
        self.steps = np.array([int(r.steps[0]) for r in self._runs], dtype=np.int64)
        self.sources = list(self._states)
        self.notes = [f"YADE saved states converted by YADE (cached in {cache}): the interactions as saved, their "
                      "overlaps from the forces and stiffnesses the law stored (YADE does not save them)",
                      *first_notes(self._runs)]

    def __len__(self) -> int:
        return len(self._runs)

    def frame(self, k: int) -> Frame:
        try:
            frame = self._runs[k].frame(0)
        except DemsplitError as exc:  # named by the state, not by its converted copy in the cache
            raise type(exc)(exc.message, file=self._states[k], step=exc.step, line=exc.line, fix=exc.fix) from None
        frame.source = (str(self._states[k]),)
        return frame

    def describe(self) -> dict:
        """The states, their iterations and YADE's own elastic energies saved with them (``O.energy``)."""
        return {"kind": self.format_name, "states": [str(s) for s in self._states], "steps": self.steps.tolist(),
                "yade_energies": [e for run in self._runs for e in run.yade_energies]}

    @classmethod
    def describe_file(cls, path: Path) -> str:
        with cls.open(path) as run:
            meta = run._runs[-1].meta(0)
            bodies = run._runs[-1]._read(0)[1]["bodies"]
            kinds = bodies["kind"].astype(str).tolist()
            walls = {k: kinds.count(k) for k in ("wall", "facet", "box") if k in kinds}
            try:
                contacts = f"{run.frame(len(run) - 1).n_contacts} read as contacts"
            except DemsplitError as exc:
                contacts = f"not analysable as they are: {exc}"
            lines = [f"{path}: YADE saved state(s), {len(run)} ({', '.join(s.name for s in run._states)})",
                     f"  iterations: {run.steps.tolist()}",
                     f"  bodies:     {kinds.count('sphere')} spheres, walls "
                     + (", ".join(f"{n} {k}" for k, n in sorted(walls.items())) or "none"),
                     f"  interactions (last state): {meta['n_interactions_real']} real, {contacts}",
                     f"  law:        {run.scene.model.describe()}",
                     "  materials:  " + material_list(run._runs[-1]),
                     f"  YADE:       {meta.get('yade_version', '?')} {meta.get('precision_name', '?')}"]
        return "\n".join(lines)

    def close(self) -> None:
        for run in self._runs:
            run.close()


def converted(states: list[Path], cache: Path, *, yade: str | None = None) -> list[Path]:
    """The converted snapshot of each state in ``cache`` (keyed by the state's BLAKE3 digest), converting
    those not there yet with one YADE process (``yade``: the build; default: the first that loads them)."""
    cache.mkdir(parents=True, exist_ok=True)
    # the provenance fingerprints the same files: each is hashed once
    targets = [cache / f"{file_fingerprint(s)[DIGEST]}-v{FORMAT_VERSION}.npys" for s in states]
    todo = [(s, t) for s, t in zip(states, targets) if not t.is_file()]
    if todo:
        _convert(todo, yade)
    return targets


def first_notes(runs: list[YadeSnapshotRun]) -> list[str]:
    """The notes of the states' readers (the split's moduli), each once."""
    return list(dict.fromkeys(note for run in runs for note in run.notes))


def _convert(todo: list[tuple[Path, Path]], yade: str | None) -> None:
    """Convert the states with the first YADE build that loads them (one process for all)."""
    builds = [yade] if yade else [b for b in BUILDS if shutil.which(b)]
    if not builds or not shutil.which(builds[0]):
        raise InputFormatError(f"reading a YADE saved state needs YADE, and {yade or 'yade'} is not installed.",
                               file=todo[0][0], fix="install Debian's yade (apt-get install yade), or give the "
                               "executable that saved the state with --yade.")
    errors = []
    with tempfile.TemporaryDirectory(prefix="demsplit-yade-") as tmp:
        script = Path(tmp) / "convert.py"
        script.write_text(CONVERTER)
        pairs = [(str(s.resolve()), str(Path(tmp) / f"{k}.npys")) for k, (s, _) in enumerate(todo)]
        # YADE's own Python imports demsplit from this Python's site-packages (appended: its numpy stays first)
        env = {**os.environ, "DEMSPLIT_SITE": sysconfig.get_paths()["purelib"], "DEMSPLIT_STATES": json.dumps(pairs)}
        for build in builds:
            returncode, err = _run_converter(build, script, tmp, env, len(todo))
            done = err.count("DEMSPLIT-CONVERTED")
            if returncode == 0 and done == len(todo):
                for (_, target), (_, made) in zip(todo, pairs):
                    shutil.move(made, target)  # complete files only: a conversion that failed leaves none
                return
            last = [line for line in err.splitlines() if line.strip() and "DEMSPLIT-" not in line][-1:]
            errors.append(f"{build}: {last[0] if last else 'exit ' + str(returncode)}")
            for made in pairs:
                Path(made[1]).unlink(missing_ok=True)
    raise ScriptError(f"YADE could not load the saved state(s) ({'; '.join(errors)}).", file=todo[0][0],
                      fix="check that the file is complete (a state cut short does not load) and give the YADE "
                          "build that saved it with --yade (yade, yade-mpfr150 or yade-float128).")



def _run_converter(build: str, script: Path, cwd: str, env: dict, total: int) -> tuple[int, str]:
    """Run the converter with one YADE build; show progress per state on a terminal; return the exit
    code and YADE's error output."""
    show = sys.stderr.isatty()
    lines = []
    with subprocess.Popen([build, "-n", "-j1", "-x", str(script)], cwd=cwd, env=env, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True) as proc:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append(line)
            if show and line.startswith("DEMSPLIT-CONVERTED"):
                k = sum(x.startswith("DEMSPLIT-CONVERTED") for x in lines)
                sys.stderr.write(f"demsplit: {build} converted state {k}/{total}: {line.split()[1]}\n")
    return proc.returncode, "".join(lines)
