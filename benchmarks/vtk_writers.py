"""Time the VTK writers demsplit could use for its export, on points with arrays like a frame's.

    python benchmarks/vtk_writers.py [--points 500000] [--arrays 10]

meshio (the export's writer, pure Python) against VTK's own XML writer (pip vtk), both binary and
uncompressed, best of 3 each; prints the load average before and after, the file sizes and the
installed size of each package.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np


def best_of(f, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def installed_mb(module) -> float:
    root = Path(module.__file__).parent
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) / 2**20


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=500_000)
    ap.add_argument("--arrays", type=int, default=10)
    a = ap.parse_args()
    import meshio
    import vtkmodules
    from vtkmodules.util import numpy_support as ns
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkPolyData
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    rng = np.random.default_rng(0)
    points = rng.random((a.points, 3))
    data = {f"a{k}": rng.random(a.points) for k in range(a.arrays)}
    out = Path(tempfile.mkdtemp())

    def with_meshio() -> None:
        mesh = meshio.Mesh(points, [("vertex", np.arange(a.points).reshape(-1, 1))], point_data=data)
        meshio.write(out / "m.vtu", mesh, file_format="vtu", binary=True, compression=None)

    def with_vtk() -> None:
        poly, pts = vtkPolyData(), vtkPoints()
        pts.SetData(ns.numpy_to_vtk(points))
        poly.SetPoints(pts)
        for name, values in data.items():
            array = ns.numpy_to_vtk(values)
            array.SetName(name)
            poly.GetPointData().AddArray(array)
        w = vtkXMLPolyDataWriter()
        w.SetFileName(str(out / "v.vtp"))
        w.SetInputData(poly)
        w.SetDataModeToAppended()
        w.SetCompressorTypeToNone()
        w.Write()

    print(f"load average before {os.getloadavg()}; {a.points} points, {a.arrays} float64 arrays")
    for name, f, file, module in (("meshio vtu", with_meshio, "m.vtu", meshio), ("vtk vtp", with_vtk, "v.vtp",
                                                                                  vtkmodules)):
        t = best_of(f)
        print(f"  {name:<11} {t:.3f} s  file {(out / file).stat().st_size / 2**20:.0f} MB  "
              f"package {installed_mb(module):.0f} MB")
    print(f"load average after {os.getloadavg()}")


if __name__ == "__main__":
    main()
