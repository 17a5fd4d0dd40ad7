"""Regenerate the pictures of docs/visualization.md from the samples.

    python docs/screenshots.py              # all of them, from the repository root, in the venv with the test extra
    python docs/screenshots.py report vtk   # some of them: report, vtk, ovito

Writes
  docs/report-packing.png      the first screen (1280 x 900) of `demsplit report -o` of the LIGGGHTS packing
                               sample, as headless Chromium draws it
  docs/report-yade.png         the same for the YADE sample mindlin_box
  docs/vtk-packing.png         the packing sample's last frame from `demsplit export --vtk`: the contacts as lines
                               between the bodies coloured by log10 u, the walls coloured by their energy, drawn
                               by VTK off-screen as ParaView draws the same files
  docs/ovito-packing.png       the packing sample's last frame, spheres coloured by log10 u, rendered off-screen
                               by OVITO's Python module (Tachyon renderer)

Needs: Debian's ``chromium`` (report), the ``vtk`` module (in the test extra; vtk), the ``ovito`` module and a
Vulkan loader with a software driver for OVITO off-screen (``apt-get install libvulkan1 mesa-vulkan-drivers``;
ovito).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

DOCS = Path(__file__).resolve().parent
REPO = DOCS.parent
FIRST_SCREEN = (1280, 900)
"""The browser window of the report pictures (pixels): what a reader sees before scrolling."""


def demsplit(*args: str) -> None:
    from demsplit.cli import main

    if main([*map(str, args), "-q"]) != 0:
        sys.exit(f"demsplit {' '.join(map(str, args))} failed")


def ovito_picture(dump: Path, out: Path) -> None:
    """The last frame of ``dump`` (demsplit export --dump), spheres coloured by log10 u."""
    from ovito.io import import_file
    from ovito.modifiers import ColorCodingModifier, ComputePropertyModifier
    from ovito.qt_compat import QtCore
    from ovito.vis import ColorLegendOverlay, TachyonRenderer, Viewport

    pipeline = import_file(str(dump))
    last = pipeline.source.num_frames - 1
    pipeline.modifiers.append(
        ComputePropertyModifier(output_property="log10_u", expressions=["u > 0 ? log10(u) : -30"])
    )
    log_u = np.asarray(pipeline.compute(last).particles["log10_u"])
    log_u = log_u[log_u > -30]
    coding = ColorCodingModifier(
        property="log10_u",
        gradient=ColorCodingModifier.Viridis(),
        start_value=float(np.quantile(log_u, 0.02)),
        end_value=float(log_u.max()),
    )
    pipeline.modifiers.append(coding)
    pipeline.add_to_scene()
    viewport = Viewport(type=Viewport.Type.Perspective, camera_dir=(1, 1.6, -0.9))
    viewport.overlays.append(
        ColorLegendOverlay(
            modifier=coding,
            title="log10 u (J)",
            orientation=QtCore.Qt.Orientation.Vertical,
            alignment=QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter,
            legend_size=0.5,
            font_size=0.07,
            format_string="%.1f",
        )
    )
    viewport.zoom_all()
    viewport.render_image(
        size=(800, 560),
        filename=str(out),
        background=(1, 1, 1),
        frame=last,
        renderer=TachyonRenderer(ambient_occlusion=False),
    )


def page_picture(page: Path, out: Path, size: tuple[int, int] = FIRST_SCREEN) -> None:
    """The top of ``page`` as headless Chromium draws it in a window of ``size`` pixels."""
    chromium = shutil.which("chromium") or sys.exit("chromium is not installed (apt-get install chromium)")
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(
            [
                chromium,
                "--headless",
                "--disable-gpu",
                "--no-sandbox",
                "--hide-scrollbars",
                "--disable-background-networking",
                "--no-first-run",
                f"--user-data-dir={profile}",
                f"--window-size={size[0]},{size[1]}",
                f"--screenshot={out}",
                page.as_uri(),
            ],
            check=True,
            capture_output=True,
            timeout=300,
        )


def vtk_picture(vtk: Path, out: Path) -> None:
    """The last frame of a ``demsplit export --vtk`` directory: contact lines coloured by log10 u (grey: not
    computed, a primitive wall's contact), walls translucent, shaded by their number of contacts."""
    import vtk as v

    files = {name: sorted(vtk.glob(f"{name}_*.vtu"))[-1] for name in ("contacts", "walls")}
    renderer = v.vtkRenderer()
    renderer.SetBackground(1, 1, 1)
    for name, path in files.items():
        reader = v.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(path))
        reader.Update()
        grid = reader.GetOutput()
        if name == "contacts":
            u = grid.GetCellData().GetArray("u")
            log_u = v.vtkDoubleArray()
            log_u.SetName("log10_u")
            values = [u.GetValue(k) for k in range(u.GetNumberOfTuples())]
            for value in values:
                log_u.InsertNextValue(np.log10(value) if value > 0 else np.nan)
            grid.GetCellData().AddArray(log_u)
            known = np.array([x for x in values if x > 0])
            scalar, span = "log10_u", (float(np.log10(np.quantile(known, 0.05))), float(np.log10(known.max())))
        else:
            scalar, span = "n_contacts", (0.0, float(grid.GetCellData().GetArray("n_contacts").GetRange()[1]))
        mapper = v.vtkDataSetMapper()
        mapper.SetInputData(grid)
        mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray(scalar)
        mapper.SetScalarRange(*span)
        lut = v.vtkLookupTable()
        lut.SetHueRange(0.67, 0.0) if name == "contacts" else lut.SetHueRange(0.33, 0.33)
        if name == "walls":
            lut.SetSaturationRange(0.1, 0.6)
        lut.SetNanColor(0.85, 0.85, 0.85, 1.0)
        lut.Build()
        mapper.SetLookupTable(lut)
        actor = v.vtkActor()
        actor.SetMapper(mapper)
        if name == "contacts":
            actor.GetProperty().SetLineWidth(2.5)
            bar = v.vtkScalarBarActor()
            bar.SetLookupTable(lut)
            bar.SetTitle("log10 u (J)")
            bar.SetNumberOfLabels(4)
            bar.SetWidth(0.1)
            bar.SetHeight(0.5)
            bar.GetTitleTextProperty().SetColor(0, 0, 0)
            bar.GetLabelTextProperty().SetColor(0, 0, 0)
            renderer.AddViewProp(bar)
        else:
            actor.GetProperty().SetOpacity(0.25)
        renderer.AddActor(actor)
    window = v.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(900, 700)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(1.0, -1.6, 0.9)
    camera.SetViewUp(0, 0, 1)
    renderer.ResetCamera()
    camera.Zoom(1.05)
    window.Render()
    image = v.vtkWindowToImageFilter()
    image.SetInput(window)
    image.Update()
    writer = v.vtkPNGWriter()
    writer.SetFileName(str(out))
    writer.SetInputConnection(image.GetOutputPort())
    writer.Write()


PICTURES = {
    "report": ("report-packing.png", "report-yade.png"),
    "vtk": ("vtk-packing.png",),
    "ovito": ("ovito-packing.png",),
}


def main(which: list[str]) -> None:
    unknown = set(which) - set(PICTURES)
    if unknown:
        sys.exit(f"unknown pictures {sorted(unknown)}: choose among {sorted(PICTURES)}")
    which = which or list(PICTURES)
    os.chdir(REPO)  # the inputs named relative to the repository, as the report's provenance shows them
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        demsplit("run", "sample_dumps/liggghts/packing/in.packing", "-o", tmp / "packing.h5")
        if "report" in which:
            demsplit("report", tmp / "packing.h5", "-o", tmp / "packing.html")
            page_picture(tmp / "packing.html", DOCS / "report-packing.png")
            demsplit("run", "sample_dumps/yade/mindlin_box.h5", "-o", tmp / "yade.h5")
            demsplit("report", tmp / "yade.h5", "-o", tmp / "yade.html")
            page_picture(tmp / "yade.html", DOCS / "report-yade.png")
        if "vtk" in which:
            demsplit("export", tmp / "packing.h5", "--vtk", tmp / "vtk")
            vtk_picture(tmp / "vtk", DOCS / "vtk-packing.png")
        if "ovito" in which:
            demsplit("export", tmp / "packing.h5", "--dump", tmp / "packing.dump")
            ovito_picture(tmp / "packing.dump", DOCS / "ovito-packing.png")
    for name in (name for key in which for name in PICTURES[key]):
        print(f"wrote {DOCS / name} ({(DOCS / name).stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main(sys.argv[1:])
