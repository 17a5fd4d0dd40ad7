"""The ``demsplit`` command's own process settings (:mod:`demsplit.runtime.command`): made when the process is the
command, never in a program that imports demsplit, and with the effect they are made for."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from demsplit.runtime import command

PROBE = r"""
import gc, json, os, resource, sys
sys.argv[0] = sys.argv[1]  # the name the process was started under: "demsplit" is the console script
import demsplit
import numpy as np

def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt

a = np.ones(1 << 23)  # 64 MiB, touched, then freed
del a
before = faults()
b = np.ones(1 << 23)  # the same size again: fresh pages unless the freed ones were kept
print(json.dumps({"blas": os.environ.get("OPENBLAS_NUM_THREADS"), "faults": faults() - before,
                  "gc": gc.get_threshold(), "pages": os.environ.get("NUMPY_MADVISE_HUGEPAGE"),
                  "kept": demsplit.runtime.command.FREED_MEMORY_KEPT}))
"""


def _probe(name: str, **env: str) -> dict:
    import os

    environ = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "NUMPY_MADVISE_HUGEPAGE")} | env
    proc = subprocess.run([sys.executable, "-c", PROBE, name], capture_output=True, text=True, check=True, env=environ)
    return json.loads(proc.stdout)


@pytest.mark.parametrize(
    ("argv0", "orig", "expected"),
    [
        ("/usr/local/bin/demsplit", ["/usr/bin/python3", "/usr/local/bin/demsplit", "run"], True),
        ("-m", ["/usr/bin/python3", "-X", "utf8", "-m", "demsplit.cli", "run"], True),
        ("-c", ["/usr/bin/python3", "-c", "import demsplit"], False),
        ("/home/u/analysis.py", ["/usr/bin/python3", "/home/u/analysis.py"], False),
        ("-m", ["/usr/bin/python3", "-m", "pytest"], False),
    ],
)
def test_is_command_only_for_the_console_script_and_the_cli_module(monkeypatch, argv0, orig, expected):
    monkeypatch.setattr(sys, "argv", [argv0])
    monkeypatch.setattr(sys, "orig_argv", orig)
    assert command.is_command() is expected


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt and ru_minflt")
def test_the_command_keeps_freed_memory_one_blas_thread_and_rare_collections():
    as_command, as_library = _probe("demsplit"), _probe("analysis.py")
    assert as_command["blas"] == "1" and as_library["blas"] is None
    assert tuple(as_command["gc"]) == command.GC_THRESHOLDS and tuple(as_library["gc"]) != command.GC_THRESHOLDS
    # freed pages reused: a 64 MiB array faults in 16384 small pages or 32 huge ones when it is fresh
    assert as_command["faults"] < 8 <= as_library["faults"]
    assert as_command["kept"] and not as_library["kept"]  # what the first frame's warm-up asks of the process


@pytest.mark.slow
def test_a_blas_thread_count_the_user_set_is_kept():
    assert _probe("demsplit", OPENBLAS_NUM_THREADS="2")["blas"] == "2"


@pytest.mark.slow
def test_the_command_asks_for_no_huge_pages_only_on_a_guest_that_reports_free_memory():
    as_command, as_library = _probe("demsplit"), _probe("analysis.py")
    assert as_command["pages"] == ("0" if command.guest_reports_free_memory() else None)
    assert as_library["pages"] is None
    assert _probe("demsplit", NUMPY_MADVISE_HUGEPAGE="1")["pages"] == "1"  # the user's choice is kept


@pytest.mark.parametrize(("content", "expected"), [("0\n", False), ("913260108\n", True), ("", False), (None, False)])
def test_a_guest_reports_free_memory_when_its_count_is_above_zero(tmp_path, monkeypatch, content, expected):
    path = tmp_path / "reported_kib"
    if content is not None:
        path.write_text(content)
    monkeypatch.setattr(command, "REPORTED_KIB", str(path))
    assert command.guest_reports_free_memory() is expected


EXIT = r"""
import atexit, sys
sys.argv = ["demsplit", "info", sys.argv[1]]

class Teardown:
    def __del__(self):
        print("torn down", flush=True)

keep = Teardown()  # a module global: freed by the interpreter's teardown, which the command skips
atexit.register(lambda: print("atexit ran"))  # block-buffered into a pipe: printed only if flushed
from demsplit.cli import command
command()
"""


@pytest.mark.slow
def test_the_command_ends_without_teardown_but_runs_atexit_and_flushes(tmp_path):
    """The console script's end (cli.command, command.exit_now): its output complete when stdout is a pipe,
    the atexit handlers run, the interpreter's finalization (a module global's __del__) skipped, the
    exit status main's."""
    from conftest import SAMPLES

    script = SAMPLES / "liggghts" / "packing" / "in.packing"
    proc = subprocess.run([sys.executable, "-c", EXIT, str(script)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "atexit ran" in proc.stdout and "torn down" not in proc.stdout
    assert "in.packing" in proc.stdout  # demsplit info's report, all of it before the atexit line
    assert proc.stdout.rstrip().endswith("atexit ran")
    missing = subprocess.run([sys.executable, "-c", EXIT, str(tmp_path / "none.in")], capture_output=True, text=True)
    assert missing.returncode == 2 and "demsplit: error:" in missing.stderr


NUMBA_START = r"""
import json, sys
sys.argv[0] = sys.argv[1]
import numpy as np
from demsplit.readers.fastparse import count_newlines  # a kernel module: imports demsplit.runtime.jit and numba
loaded = "numba.np.arraymath" in sys.modules  # numba's registries, loaded at import by the command only
count_newlines(np.frombuffer(b"a\nb\n", np.uint8), 0, 4)  # a kernel's first call loads them otherwise
from numba.np import arraymath
scipy_linalg_before = "scipy.linalg" in sys.modules
import scipy.linalg  # imports as usual afterwards: the stand-in is gone
print(json.dumps({"loaded_at_import": loaded, "blas": arraymath._HAVE_BLAS,
                  "scipy_linalg": scipy_linalg_before, "dot": float(scipy.linalg.blas.ddot([1.0], [2.0]))}))
"""


@pytest.mark.slow
def test_the_command_loads_numba_without_its_blas_probe_and_scipy_imports_after():
    """demsplit.runtime.jit.load_registries_without_blas_probe: in the command's process numba's registries load
    when demsplit.runtime.jit is imported, without importing scipy.linalg; scipy.linalg still imports and works
    afterwards; a program that imports demsplit keeps numba's own lazy loading and its BLAS probe."""

    def probe(name: str) -> dict:
        proc = subprocess.run([sys.executable, "-c", NUMBA_START, name], capture_output=True, text=True, check=True)
        return json.loads(proc.stdout)

    as_command, as_library = probe("demsplit"), probe("analysis.py")
    assert as_command == {"loaded_at_import": True, "blas": False, "scipy_linalg": False, "dot": 2.0}
    assert as_library == {"loaded_at_import": False, "blas": True, "scipy_linalg": True, "dot": 2.0}
