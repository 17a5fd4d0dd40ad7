"""How far LIGGGHTS' VTK dumps would put the overlaps and the Hertz energies off, on the committed samples.

Usage (from the repository root): python sample_dumps/liggghts/measure_vtk_precision.py

Seen in Debian's LIGGGHTS 3.8.0 (legacy ASCII ``.vtk``): ``dump custom/vtk`` declares the particle
positions ``POINTS N float`` and prints them with 6 significant digits (``0.00299881``), its other
columns (``radius``, ``mass``) ``double`` with 11 (``0.00028274333882``); ``dump local/gran/vtk``
of ``pair/gran/local`` or ``wall/gran/local`` prints ``delta`` as ``double`` with 11 digits and never
the history (docs/liggghts-output.md, section "VTK dumps"). This script takes the full-precision
(``%.17g``) dumps of each sample, rounds what a VTK dump would round, and compares with the exact
values, per contact (pairs and mesh-floor contacts of every frame):

- ``delta from float32 positions``: r1 + r2 - |x1 - x2| (a wall: r - |x - contact point|) with the
  centres rounded to float32 (radii and wall exact), against the dumped ``delta``, and the Hertz
  energy (8/15) E* sqrt(R*) delta^(5/2) from it (E* cancels in the ratio), per contact and the frame total;
- ``delta from 6-digit positions``: the same with the centres printed as the ASCII file does (``%.6g``);
- ``Hertz u_n, dumped delta (11 digits)``: the ``delta`` of ``local/gran/vtk`` and the radii printed
  with 11 significant digits (what the two VTK dumps give a law without history, at best).

A contact whose float32 overlap is <= 0 is lost (counted, relative error 1). Plain numpy, the dump
parsers of tests/test_liggghts_samples_facts.py; tests/test_liggghts_vtk.py asserts the decision the
numbers support (more than 1e-6 relative in energy: no VTK reader).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from test_liggghts_samples_facts import DELTA, ID1, ID2, full, minimum_image, read_text_dump, row_index  # noqa: E402

SCENES = ("packing", "periodic", "analytic")
WALL_CP = slice(0, 3)  # compute wall/gran/local: contact point on the wall (cols 1-3)
WALL_X = slice(3, 6)  # the particle centre (cols 4-6)
WALL_ID = 14  # the particle id (col 15)


def errors(scene: str) -> dict[str, np.ndarray]:
    """Per-contact relative errors of every variant (module docstring) over all frames of ``scene``,
    and the largest relative error of a frame total (``*_total``), as arrays."""
    out: dict[str, list] = {}
    atoms = read_text_dump(full(scene, "atoms"))
    pairs = read_text_dump(full(scene, "pairs"))
    walls = read_text_dump(full(scene, "wall"))
    for a, p, w in zip(atoms, pairs, walls):
        ids, x, r = a.data[:, 0], a.data[:, 2:5], a.data[:, 14]
        i1, i2 = row_index(ids, p.data[:, ID1]), row_index(ids, p.data[:, ID2])
        iw = row_index(ids, w.data[:, WALL_ID])
        delta = np.concatenate([p.data[:, DELTA], w.data[:, DELTA]])
        rstar = np.concatenate([r[i1] * r[i2] / (r[i1] + r[i2]), r[iw]])
        u = np.sqrt(rstar) * delta**2.5

        def add(key, d, rs=rstar, delta=delta, u=u):
            ue = np.sqrt(rs) * np.clip(d, 0, None) ** 2.5
            out.setdefault("delta_" + key, []).append(np.abs(d / delta - 1))
            out.setdefault("u_n_" + key, []).append(np.abs(ue / u - 1))
            out.setdefault("u_n_" + key + "_total", []).append([abs(ue.sum() / u.sum() - 1)])
            out.setdefault("lost_" + key, []).append([int((d <= 0).sum())])

        for key, xr in (("float32", x.astype(np.float32).astype(np.float64)), ("6digits", printed(x, 6))):
            add(
                key,
                np.concatenate(
                    [
                        r[i1] + r[i2] - np.linalg.norm(minimum_image(xr[i1] - xr[i2], a), axis=1),
                        r[iw] - np.linalg.norm(xr[iw] - w.data[:, WALL_CP], axis=1),
                    ]
                ),
            )
        r11 = printed(r, 11)
        add("vtkdelta", printed(delta, 11), np.concatenate([r11[i1] * r11[i2] / (r11[i1] + r11[i2]), r11[iw]]))
    return {k: np.concatenate(v) for k, v in out.items()}


def printed(values: np.ndarray, digits: int) -> np.ndarray:
    """``values`` as ``%.<digits>g`` prints them, read back."""
    return np.array([float(f"{v:.{digits}g}") for v in np.ravel(values)]).reshape(np.shape(values))


def main() -> None:
    print("relative error against the full-precision dumps (per contact: median, p95, max; frame total: max)")
    for scene in SCENES:
        e = errors(scene)
        print(f"== {scene}: {len(e['delta_float32'])} contacts (pairs and mesh floor, all frames)")
        for name, key in (
            ("float32 positions", "float32"),
            ("6-digit positions", "6digits"),
            ("dumped delta (11 digits)", "vtkdelta"),
        ):
            for what in ("delta", "u_n"):
                v = e[f"{what}_{key}"]
                total = (
                    f"frame total max {e[f'u_n_{key}_total'].max():.2g}"
                    if what == "u_n"
                    else f"lost (delta <= 0) {int(e[f'lost_{key}'].sum())}"
                )
                print(
                    f"  {what:5s} {name:26s} median {np.median(v):8.2g}  p95 {np.percentile(v, 95):8.2g}"
                    f"  max {v.max():8.2g}  | {total}"
                )


if __name__ == "__main__":
    main()
