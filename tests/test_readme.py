"""The README's commands run: every ``demsplit`` command line of its ```sh blocks runs on the samples and
exits 0, its ```python block runs, every ``demsplit WORD`` it names in code is a real command, and no
Markdown link of the README or docs/ leaves the repository.

The commands run in README order in one scratch directory holding a copy of the LIGGGHTS packing sample,
with the README's placeholder file names mapped to sample files (``NAMES``). A command the mapping cannot
serve makes the test fail, so a new README command needs a mapping here. Commands that need a simulator
(a YADE saved state, a prepared script run in LIGGGHTS) run in the simulator test, which fails instead of
skipping under DEMSPLIT_REQUIRE_SIMULATORS=1.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO, SAMPLES, require_program

README = REPO / "README.md"
PACKING = SAMPLES / "liggghts" / "packing"

NAMES = {"in.script": "in.packing", "snapshots.h5": str(SAMPLES / "yade" / "mindlin_box.h5")}
"""README placeholder -> file of the scratch directory or sample (files of the packing sample are copied
there under their own names: atoms_full.txt.gz, pairs.txt, wall.txt)."""

SIMULATOR_WORDS = ("state.yade.gz", "in.myrun")
"""Placeholders only a simulator run makes (a YADE O.save state, a user's LIGGGHTS script run in LIGGGHTS)."""


def blocks(language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", README.read_text(), re.S | re.M)


def command_lines(block: str) -> list[str]:
    """The block's shell lines (continuations joined, comments dropped), each ``&&`` part apart."""
    out = []
    for line in block.replace("\\\n", " ").splitlines():
        line = re.sub(r"(^|\s)#.*$", "", line).strip()  # the README's '#' only start comments
        out += [part.strip() for part in line.split("&&") if part.strip()]
    return out


def demsplit_commands() -> list[str]:
    """Every ``demsplit ...`` or ``.venv/bin/demsplit ...`` command line of the sh blocks."""
    return [
        line
        for block in blocks("sh")
        for line in command_lines(block)
        if line.split()[0] in ("demsplit", ".venv/bin/demsplit")
    ]


def demsplit_exe() -> list[str]:
    exe = Path(sys.executable).with_name("demsplit")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "demsplit.cli"]


def run(line: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run one README command line in ``cwd``: placeholders mapped, ``sample_dumps/`` made absolute; a
    line with shell variables runs in bash with ``demsplit`` first on PATH."""
    if "$" in line:
        bindir = Path(demsplit_exe()[0]).parent
        env = {**os.environ, "PATH": f"{bindir}:{os.environ['PATH']}"}
        return subprocess.run(["bash", "-c", line], cwd=cwd, capture_output=True, text=True, timeout=600, env=env)
    words = shlex.split(line)
    argv = [*demsplit_exe(), *[NAMES.get(w, w) for w in words[1:]]]
    argv = [str(REPO / a) if a.startswith("sample_dumps/") else a for a in argv]
    return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=600)


def needs_simulator(line: str) -> bool:
    return any(word in line for word in SIMULATOR_WORDS)


@pytest.fixture
def scratch(tmp_path: Path) -> Path:
    for f in PACKING.iterdir():
        shutil.copy(f, tmp_path / f.name)
    return tmp_path


def test_the_readme_has_the_commands_this_test_runs():
    commands = demsplit_commands()
    firsts = {c.split()[1] for c in commands}
    assert {"run", "info", "check", "report", "export", "convert", "prepare"} <= firsts
    assert commands[0].startswith(".venv/bin/demsplit run ")  # the first command, after the install
    assert any(map(needs_simulator, commands)) and not all(map(needs_simulator, commands))


@pytest.mark.slow
def test_every_readme_command_runs_on_the_samples(scratch):
    """In README order; the cluster loop's command runs for one script on a local Dask cluster in place
    of the scheduler file (no scheduler is started)."""
    (scratch / "runs" / "packing").mkdir(parents=True)
    for f in PACKING.iterdir():
        shutil.copy(f, scratch / "runs" / "packing" / f.name)
    (scratch / "results").mkdir()
    failures = []
    for line in demsplit_commands():
        if needs_simulator(line):
            continue
        if "$script" in line:
            line = "script=runs/packing/in.packing; " + line.replace("$SCRATCH/sched.json", "local:1")
        proc = run(line, scratch)
        if proc.returncode != 0:
            failures.append(f"{line}: exit {proc.returncode}: {proc.stderr.strip()[-500:]}")
    assert not failures, "\n".join(failures)
    assert (scratch / "report.html").stat().st_size > 100_000 and (scratch / "packing.h5").exists()
    assert (scratch / "results" / "packing.h5").exists() and (scratch / "csv" / "units.csv").exists()


@pytest.mark.slow
def test_the_readme_python_block_runs(scratch):
    (python,) = blocks("python")
    assert (
        run(".venv/bin/demsplit run sample_dumps/liggghts/packing/in.packing -o packing.h5 -q", scratch).returncode == 0
    )
    code = python.replace('"sample_dumps/', f'"{REPO}/sample_dumps/')
    proc = subprocess.run([sys.executable, "-c", code], cwd=scratch, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]


@pytest.mark.slow
@pytest.mark.simulator
def test_readme_commands_that_need_a_simulator(scratch):
    """The YADE saved-state run (a state saved by Debian's YADE) and the prepare block, liggghts included."""
    from test_yade_simulator import SAMPLE_SCRIPTS, run_yade

    yade = require_program("yade")
    states = scratch / "states"
    states.mkdir()
    run_yade(yade, SAMPLE_SCRIPTS / "saved_states.py", states)
    shutil.copy(states / "state-010000.yade.gz", scratch / "state.yade.gz")
    liggghts = require_program("liggghts")
    from test_prepare import user_script

    (scratch / "user").mkdir()
    user = user_script(scratch / "user")
    shutil.copy(user, scratch / "in.myrun")
    shutil.copy(user.with_name("floor.stl"), scratch / "floor.stl")
    simulator = [b for b in blocks("sh") if "liggghts -in" in b]
    assert len(simulator) == 1
    ran = 0
    for line in demsplit_commands():
        if needs_simulator(line) and "in.myrun" not in line:
            proc = run(line, scratch)
            assert proc.returncode == 0, f"{line}: {proc.stderr}"
            ran += 1
    for line in command_lines(simulator[0]):  # in order: prepare, liggghts, run
        if line.startswith("liggghts "):
            proc = subprocess.run(
                [liggghts, *shlex.split(line)[1:]], cwd=scratch, capture_output=True, text=True, timeout=600
            )
            assert proc.returncode == 0, proc.stdout[-2000:]
        else:
            proc = run(line, scratch)
            assert proc.returncode == 0, f"{line}: {proc.stderr}"
            ran += 1
    assert ran == sum(map(needs_simulator, demsplit_commands()))


def test_the_readme_names_only_real_commands():
    from test_cli_conventions import subparsers

    real = set(subparsers()) - {""}
    text = README.read_text()
    code = re.findall(r"`([^`\n]+)`", text) + [line for b in blocks("sh") for line in b.splitlines()]
    named = {m for span in code for m in re.findall(r"(?:^|[\s/])demsplit ([a-z][a-z-]*)", span)}
    assert named and named <= real, f"the README names {sorted(named - real)}, not commands of demsplit"


def test_docs_link_only_inside_the_repository():
    docs = [README, *(REPO / "docs").glob("*.md"), *SAMPLES.rglob("README.md")]
    bad = []
    for doc in docs:
        text = doc.read_text()
        for target in re.findall(r"\]\(([^)\s#]+)", text):
            if re.match(r"[a-z]+://", target):
                continue
            path = (doc.parent / target).resolve()
            if not path.exists() or REPO not in path.parents:
                bad.append(f"{doc.relative_to(REPO)}: {target}")
        bad += [
            f"{doc.relative_to(REPO)}: {p}"
            for p in re.findall(r"(?:/root|/home|/work|/Users|\.pyenv)/[^\s`)\"']*", text)
        ]
    assert not bad, bad
