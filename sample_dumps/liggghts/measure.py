"""Print the numbers quoted in docs/liggghts-output.md, measured on the committed samples.

Usage (from the repository root): python sample_dumps/liggghts/measure.py

Uses the plain-numpy dump parsers of tests/test_liggghts_samples_facts.py (no demsplit).
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from test_liggghts_samples_facts import (  # noqa: E402
    AREA,
    CONTACT_POINT,
    DELTA,
    FORCE_N,
    FORCE_T,
    HISTORY,
    ID1,
    ID2,
    PERIODIC,
    POISSON,
    SAMPLES,
    YOUNG,
    force_balance,
    full,
    minimum_image,
    plane_strain_modulus_pair,
    read_text_dump,
    row_index,
)


def shear_modulus_pair(t1, t2):
    """G* = 1/[2(2-nu1)(1+nu1)/E1 + 2(2-nu2)(1+nu2)/E2] (Pa) for 1-based types."""
    c = 2 * (2 - POISSON) * (1 + POISSON) / YOUNG
    return 1 / (c[t1 - 1] + c[t2 - 1])


def stats(a):
    return f"median {np.median(a):.2g}, p95 {np.percentile(a, 95):.2g}, max {a.max():.2g}"


for scene in ("packing", "periodic", "analytic"):
    print(f"== {scene}")
    atoms_full = read_text_dump(full(scene, "atoms"))
    pairs_full = read_text_dump(full(scene, "pairs"))
    walls_full = read_text_dump(full(scene, "wall"))
    for _k, (a, p, w) in enumerate(zip(atoms_full, pairs_full, walls_full)):
        ids, x, r, t = a.data[:, 0], a.data[:, 2:5], a.data[:, 14], a.data[:, 1].astype(int)
        d = p.data
        i1, i2 = row_index(ids, d[:, ID1]), row_index(ids, d[:, ID2])
        sep = minimum_image(x[i1] - x[i2], a)
        box = a.bounds
        cp_out = ((d[:, CONTACT_POINT] < box[:, 0]) | (d[:, CONTACT_POINT] > box[:, 1])).any(axis=1)
        print(
            f"step {a.step}: {len(ids)} particles, {len(d)} pair contacts "
            f"({int(d[:, PERIODIC].sum())} periodic-flagged, {cp_out.sum()} contactPoints outside the box), "
            f"{len(w.data)} mesh-wall contacts; delta {d[:, DELTA].min():.3g}..{d[:, DELTA].max():.3g} m"
        )
        # Hertz elastic force vs the dumped normal force (damping included in the dump)
        r_eff = r[i1] * r[i2] / (r[i1] + r[i2])
        f_el = 4 / 3 * plane_strain_modulus_pair(t[i1], t[i2]) * np.sqrt(r_eff) * d[:, DELTA] ** 1.5
        rel_fn = np.abs(np.linalg.norm(d[:, FORCE_N], axis=1) - f_el) / f_el
        kt = 8 * shear_modulus_pair(t[i1], t[i2]) * np.sqrt(r_eff * d[:, DELTA])
        ft = np.linalg.norm(d[:, FORCE_T], axis=1)
        print(f"  pairs: | |force_normal| - Hertz F_el | / F_el: {stats(rel_fn)}")
        sheared = ft > 0  # the analytic stacks carry no tangential force
        if sheared.any():
            rel_ft = np.linalg.norm(-kt[:, None] * d[:, HISTORY] - d[:, FORCE_T], axis=1)[sheared] / ft[sheared]
            print(f"  pairs: | -kt*history - force_tangential | / |force_tangential|: {stats(rel_ft)}")
        print(f"  pairs: contactArea / (pi R* delta): {stats(d[:, AREA] / (np.pi * r_eff * d[:, DELTA]))}")
        iw = row_index(ids, w.data[:, ID2 + 1])
        f_wall = 4 / 3 * plane_strain_modulus_pair(t[iw], 4) * np.sqrt(r[iw]) * w.data[:, DELTA] ** 1.5
        rel_w = np.abs(np.linalg.norm(w.data[:, FORCE_N], axis=1) - f_wall) / f_wall
        print(f"  mesh wall: | |force_normal| - Hertz F_el(R* = r) | / F_el: {stats(rel_w)}")
        kt_wall = 8 * shear_modulus_pair(t[iw], 4) * np.sqrt(r[iw] * w.data[:, DELTA])
        ft_wall = np.linalg.norm(w.data[:, FORCE_T], axis=1)
        if (ft_wall > 0).all():
            rel_tw = np.linalg.norm(-kt_wall[:, None] * w.data[:, HISTORY] - w.data[:, FORCE_T], axis=1) / ft_wall
            print(f"  mesh wall: | -kt*history - force_tangential | / |force_tangential|: {stats(rel_tw)}")
        print(
            f"  atom rows sorted by id: {bool(np.all(np.diff(ids) > 0))}; "
            f"same order as the first frame: {np.array_equal(ids, atoms_full[0].data[:, 0])}"
        )
    for precision in ("%g", "full") if scene != "analytic" else ("full",):
        for step, f, total, scale, excluded in force_balance(scene, precision):
            err = np.abs(total - f).max(axis=1) / scale
            print(
                f"  force balance {precision:4s} step {step}: max |sum - f| / sum|terms| = "
                f"{err[~excluded].max():.2g} over {(~excluded).sum()} particles "
                f"({excluded.sum()} touching primitive walls excluded)"
            )
    if scene == "analytic":
        continue
    for a6, p6, pf in zip(
        read_text_dump(SAMPLES / scene / "atoms.txt"), read_text_dump(SAMPLES / scene / "pairs.txt"), pairs_full
    ):
        ids, x, r = a6.data[:, 0], a6.data[:, 2:5], a6.data[:, 14]
        i1, i2 = row_index(ids, pf.data[:, ID1]), row_index(ids, pf.data[:, ID2])
        delta_g = r[i1] + r[i2] - np.linalg.norm(minimum_image(x[i1] - x[i2], a6), axis=1)
        exact = pf.data[:, DELTA]
        rel = np.abs(delta_g - exact) / exact
        energy = np.clip(delta_g, 0, None) ** 2.5
        print(
            f"  %g step {a6.step}: delta from %g positions: {stats(rel)}, {(delta_g <= 0).sum()} <= 0; "
            f"frame sum of delta^2.5 off by {abs(energy.sum() / (exact**2.5).sum() - 1):.2g}; "
            f"%g delta column max rel error {(np.abs(p6.data[:, DELTA] - exact) / exact).max():.2g}"
        )
