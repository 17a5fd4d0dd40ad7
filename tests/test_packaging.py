"""The package as pip installs it: `demsplit` and `demsplit.readers`, nothing else at the top level."""

from __future__ import annotations

import subprocess
import sys
import zipfile

import pytest
from conftest import REPO


@pytest.mark.slow
def test_wheel_installs_only_demsplit(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp_path), str(REPO)],
        check=True,
        cwd=tmp_path,
    )
    (wheel,) = tmp_path.glob("demsplit-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    top = {n.split("/")[0] for n in names}
    assert top == {"demsplit", next(t for t in top if t.endswith(".dist-info"))}
    for module in (
        "demsplit/__init__.py",
        "demsplit/physics/partition.py",
        "demsplit/physics/laws/liggghts_hertz.py",
        "demsplit/results/store.py",
        "demsplit/yade.py",
        "demsplit/readers/__init__.py",
        "demsplit/readers/liggghts.py",
    ):
        assert module in names
    entry = zipfile.ZipFile(wheel).read(next(n for n in names if n.endswith("entry_points.txt"))).decode()
    assert "demsplit = demsplit.cli:command" in entry


def test_import_is_light():
    """`import demsplit` loads the numpy-only core, so demsplit.yade works inside YADE's Python."""
    code = (
        "import sys, demsplit; heavy = [m for m in ('pandas', 'h5py', 'matplotlib', 'MDAnalysis', 'pyarrow') "
        "if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    assert out.strip() == "[]"
