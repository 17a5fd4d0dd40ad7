"""Peak memory of ``demsplit run`` does not grow with the number of frames.

Two runs of ``benchmarks/generate.py`` that differ only in their number of
frames (same particles, same contacts per frame) go through ``demsplit run``
in fresh processes set up as the command is (its allocator keeps freed memory
for the next frame: :mod:`demsplit.runtime.command`); each reports its peak resident memory (``VmHWM``). A
pipeline that kept every frame (or every frame's results) until the end would
need about one frame's arrays more per extra frame; streaming needs the same
peak for 2 frames as for 4. The tolerance is one frame's arrays, half of
what the 2 extra frames would add if they were kept.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PARTICLES, CONTACTS = 30_000, 60_000

CHILD = r"""
import json, sys
from pathlib import Path
script, out = sys.argv[1:3]
sys.argv[0] = "demsplit"  # as the console script: the command's process settings (demsplit.runtime.command) apply
from demsplit.cli import main
rc = main(["run", script, "-o", out, "-q"])
hwm = [l for l in Path("/proc/self/status").read_text().splitlines() if l.startswith("VmHWM:")][0]
print(json.dumps({"rc": rc, "peak": int(hwm.split()[1]) * 1024}))
"""


def _generate(directory: Path, frames: int) -> Path:
    subprocess.run(
        [
            sys.executable,
            str(REPO / "benchmarks" / "generate.py"),
            str(directory),
            "--particles",
            str(PARTICLES),
            "--contacts",
            str(CONTACTS),
            "--frames",
            str(frames),
        ],
        check=True,
        capture_output=True,
    )
    return directory / "in.bench"


def _frame_bytes(script: Path) -> int:
    """Bytes of one frame's particle and contact arrays, as the reader gives them."""
    from demsplit.readers import open_run

    frame = open_run(script).frame(0)
    return sum(v.nbytes for t in (frame.particles, frame.contacts) for v in t.values())


def _peak(script: Path, out: Path) -> dict:
    """``demsplit run`` of ``script`` in a fresh process that does nothing else: its exit code, its peak RSS."""
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(script), str(out)], check=True, capture_output=True, text=True
    )
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc for VmHWM")
def test_peak_memory_does_not_grow_with_frames(tmp_path):
    short = _peak(_generate(tmp_path / "two", 2), tmp_path / "two.h5")
    long = _peak(four := _generate(tmp_path / "four", 4), tmp_path / "four.h5")
    assert short["rc"] == long["rc"] == 0
    frame = _frame_bytes(four)
    assert frame > 5e6  # the frames are large enough for the comparison to mean something
    assert long["peak"] - short["peak"] < frame, (
        f"peak RSS {long['peak'] / 2**20:.0f} MiB for 4 frames vs {short['peak'] / 2**20:.0f} MiB for 2 "
        f"(one frame's arrays: {frame / 2**20:.0f} MiB)"
    )
