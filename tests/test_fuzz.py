"""Fuzz: damaged copies of a sample run either read to finite results or raise
a DemsplitError, never anything else (bounded hypothesis run; the long
version is ``python benchmarks/fuzz.py --seconds N``, which shares the
mutations and the check)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

_spec = importlib.util.spec_from_file_location(
    "demsplit_fuzz", Path(__file__).resolve().parent.parent / "benchmarks" / "fuzz.py")
fuzz = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fuzz)


@pytest.fixture(scope="module")
def fuzz_run(tmp_path_factory) -> tuple[Path, dict[str, bytes]]:
    base = fuzz.make_run(tmp_path_factory.mktemp("fuzz") / "run")
    return base.parent, {t: (base.parent / t).read_bytes() for t in fuzz.TARGETS}


def test_unmutated_copy_reads(fuzz_run):
    directory, _ = fuzz_run
    assert fuzz.check_run(directory / "in.packing") == "ok"


@pytest.mark.parametrize("kind", fuzz.KINDS)
def test_mutations_change_the_file(kind):
    data = b"ITEM: TIMESTEP\n100\nITEM: NUMBER OF ATOMS\n2\n1 2 0.5\n3 4 0.25\n"
    assert fuzz.mutate(data, kind, 0.7, 3, 0) != data


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture],
          derandomize=True)
@given(target=st.sampled_from(fuzz.TARGETS), kind=st.sampled_from(fuzz.KINDS),
       where=st.floats(0.0, 1.0, exclude_max=True), size=st.integers(1, 8),
       token=st.integers(0, len(fuzz.TOKENS) - 1))
def test_damaged_input_reads_or_raises_a_demsplit_error(fuzz_run, target, kind, where, size, token):
    directory, originals = fuzz_run
    (directory / target).write_bytes(fuzz.mutate(originals[target], kind, where, size, token))
    try:
        outcome = fuzz.check_run(directory / "in.packing")  # anything but a DemsplitError propagates
    finally:
        (directory / target).write_bytes(originals[target])
    assert outcome == "ok" or outcome.endswith("Error")
