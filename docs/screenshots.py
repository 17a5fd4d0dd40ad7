"""Regenerate the screenshots of docs/visualization.md from the samples.

    python docs/screenshots.py            # from the repository root, in the venv with the test extra

Writes
  docs/ovito-packing.png       the LIGGGHTS packing sample's last frame, spheres coloured by log10 u,
                               rendered off-screen by OVITO's Python module (Tachyon renderer)
  docs/report-example.png      the top of `demsplit report` of the YADE sample mindlin_box, as headless
                               Chromium draws it

Needs: the ``ovito`` module (in the test extra), Debian's ``chromium``, and a Vulkan loader with a
software driver for OVITO off-screen (``apt-get install libvulkan1 mesa-vulkan-drivers``).
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
    pipeline.modifiers.append(ComputePropertyModifier(output_property="log10_u",
                                                      expressions=["u > 0 ? log10(u) : -30"]))
    log_u = np.asarray(pipeline.compute(last).particles["log10_u"])
    log_u = log_u[log_u > -30]
    coding = ColorCodingModifier(property="log10_u", gradient=ColorCodingModifier.Viridis(),
                                 start_value=float(np.quantile(log_u, 0.02)), end_value=float(log_u.max()))
    pipeline.modifiers.append(coding)
    pipeline.add_to_scene()
    viewport = Viewport(type=Viewport.Type.Perspective, camera_dir=(1, 1.6, -0.9))
    viewport.overlays.append(ColorLegendOverlay(
        modifier=coding, title="log10 u (J)", orientation=QtCore.Qt.Orientation.Vertical,
        alignment=QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter,
        legend_size=0.5, font_size=0.07, format_string="%.1f"))
    viewport.zoom_all()
    viewport.render_image(size=(800, 560), filename=str(out), background=(1, 1, 1), frame=last,
                          renderer=TachyonRenderer(ambient_occlusion=False))


def page_picture(page: Path, out: Path, height: int = 2600) -> None:
    """The top ``height`` pixels of ``page`` as headless Chromium draws it, 1100 pixels wide."""
    chromium = shutil.which("chromium") or sys.exit("chromium is not installed (apt-get install chromium)")
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([chromium, "--headless", "--disable-gpu", "--no-sandbox", "--hide-scrollbars",
                        f"--user-data-dir={profile}", f"--window-size=1100,{height}", f"--screenshot={out}",
                        page.as_uri()], check=True, capture_output=True, timeout=300)


def main() -> None:
    os.chdir(REPO)  # the inputs named relative to the repository, as the report's provenance shows them
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        demsplit("run", "sample_dumps/liggghts/packing/in.packing", "-o", tmp / "packing.h5")
        demsplit("export", tmp / "packing.h5", "--dump", tmp / "packing.dump")
        ovito_picture(tmp / "packing.dump", DOCS / "ovito-packing.png")
        demsplit("run", "sample_dumps/yade/mindlin_box.h5", "-o", tmp / "yade.h5")
        demsplit("report", tmp / "yade.h5", "-o", tmp / "report.html")
        page_picture(tmp / "report.html", DOCS / "report-example.png")
    for name in ("ovito-packing.png", "report-example.png"):
        print(f"wrote {DOCS / name} ({(DOCS / name).stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main()
