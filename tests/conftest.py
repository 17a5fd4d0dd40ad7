"""Shared test fixtures.

Simulator tests (Debian's ``liggghts``, ``yade``, ``lmp``) skip with a stated reason when
the program is absent, and fail instead when ``DEMSPLIT_REQUIRE_SIMULATORS=1``
(as ``.ci/run`` sets after installing them).
"""

from __future__ import annotations

import gzip
import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
SAMPLES = REPO / "sample_dumps"


def require_program(name: str, package: str | None = None) -> str:
    """Path of program ``name`` (Debian package ``package``, default the name's first part); skip (or fail under
    DEMSPLIT_REQUIRE_SIMULATORS=1) if absent."""
    path = shutil.which(name)
    if path is None:
        reason = f"{name} is not installed (apt-get install {package or name.split('-')[0]})"
        if os.environ.get("DEMSPLIT_REQUIRE_SIMULATORS") == "1":
            pytest.fail(f"DEMSPLIT_REQUIRE_SIMULATORS=1 but {reason}")
        pytest.skip(reason)
    return path


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """A test that runs a simulator is slow: ``pytest -m "not slow"`` (the quick suite) leaves it out."""
    for item in items:
        if item.get_closest_marker("simulator") is not None and item.get_closest_marker("slow") is None:
            item.add_marker(pytest.mark.slow)


@pytest.fixture
def liggghts() -> str:
    return require_program("liggghts")


@pytest.fixture
def yade() -> str:
    return require_program("yade")


@pytest.fixture
def samples() -> Path:
    return SAMPLES


@pytest.fixture
def run_dir(tmp_path: Path) -> Path:
    """A plain-text copy of the LIGGGHTS packing run in tmp_path: in.packing, floor.stl,
    atoms_full.txt (full precision), pairs.txt and wall.txt (%g, with the delta column)."""
    packing = SAMPLES / "liggghts" / "packing"
    for name in ("in.packing", "floor.stl", "pairs.txt", "wall.txt"):
        shutil.copy(packing / name, tmp_path / name)
    with gzip.open(packing / "atoms_full.txt.gz", "rb") as f:
        (tmp_path / "atoms_full.txt").write_bytes(f.read())
    return tmp_path
