"""LIGGGHTS' VTK dumps, written by Debian's LIGGGHTS: ``demsplit info`` says what each holds and lacks,
and a run whose script writes only VTK dumps is refused naming them and ``demsplit prepare``."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from conftest import SAMPLES, require_program
from demsplit.cli import main

ANALYTIC = SAMPLES / "liggghts" / "analytic"


@pytest.mark.simulator
def test_vtk_dumps_are_described_and_a_vtk_only_run_is_refused_with_the_fix(tmp_path, capsys):
    liggghts = require_program("liggghts")
    shutil.copy(ANALYTIC / "floor.stl", tmp_path / "floor.stl")
    lines = (ANALYTIC / "in.analytic").read_text().split("\n")
    kept = [line for line in lines if not line.startswith(("dump", "compute cwgl"))]
    text = "\n".join(kept).replace("run             300000", "run 1000")
    text = text.replace(
        "run             0",
        "dump dv all custom/vtk 1000 atoms*.vtk id type x y z radius\n"
        "dump dx all custom/vtk 1000 atoms*.vtu id type x y z radius\n"
        "dump dl all local/gran/vtk 1000 pairs*.vtk cpgl\nrun 1000",
    )
    script = tmp_path / "in.vtk"
    script.write_text(text)
    proc = subprocess.run([liggghts, "-in", script.name], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:]
    assert main(["info", str(tmp_path / "pairs2000.vtk")]) == 0
    out = capsys.readouterr().out
    assert "dump local/gran/vtk" in out and "delta (double)" in out and "no history and no contactPoint" in out
    assert "id1 (double)" in out and "demsplit prepare" in out
    for atoms in ("atoms2000.vtk", "atoms2000.vtu"):
        assert main(["info", str(tmp_path / atoms)]) == 0
        out = capsys.readouterr().out
        assert "dump custom/vtk" in out and "single precision" in out and "radius" in out
    assert main(["run", str(script), "-o", str(tmp_path / "r.h5"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "dump dv (custom/vtk)" in err and "dump dl (local/gran/vtk)" in err and "demsplit prepare" in err
    assert not (tmp_path / "r.h5").exists()


def test_the_vtk_precision_numbers_of_the_docs():
    """docs/liggghts-output.md "VTK dumps": overlaps from a VTK dump's positions (float32, printed with 6
    digits) put the Hertz energy off by far more than 1e-6 on the samples, the dumped 11-digit delta
    by less than 1e-9: the decision written there (no overlap from VTK positions) rests on these."""
    import sys

    sys.path.insert(0, str(SAMPLES / "liggghts"))
    from measure_vtk_precision import errors

    for scene in ("packing", "periodic"):
        e = errors(scene)
        assert e["u_n_float32"].max() > 1e-3 and np.median(e["u_n_float32"]) > 1e-4
        assert e["u_n_6digits"].max() > 1e-1
        assert e["u_n_vtkdelta"].max() < 1e-9 and e["delta_vtkdelta"].max() < 1e-10
