"""Cost against error of each split: 50/50, radius, material (the law), corrected (the fitted model).

Cost: one numpy evaluation of each share function on 1e6 contacts (float64 arrays in memory, one core, best
of 5), in ns per contact. Error: share of body 1 from FE minus the split's share, over the converged points
of the sweep (results/sweep_<model>.csv; the corrected split's error on the held-out points and on all points).

Run (after sweep.py)::

    nice -n 10 python benchmarks/validation/cost.py

Writes results/cost_vs_error.json and results/cost_vs_error.md.
"""

from __future__ import annotations

import csv
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from sweep import load_accuracy, radius_share, stats  # noqa: E402


def timings(n: int = 1_000_000, repeat: int = 5) -> dict:
    """ns per contact of each share function on n contacts."""
    from demsplit.physics.shares import normal_share
    from demsplit.physics.shares import radius_share as radius_split

    acc = load_accuracy()
    rng = np.random.default_rng(1)
    r1, r2 = rng.uniform(1e-3, 5e-3, n), rng.uniform(1e-3, 5e-3, n)
    E1, E2 = rng.uniform(1e9, 2e11, n), rng.uniform(1e9, 2e11, n)
    nu1, nu2 = rng.uniform(0.0, 0.49, n), rng.uniform(0.0, 0.49, n)
    delta = rng.uniform(1e-7, 1e-5, n)

    def corrected():
        a = np.sqrt(delta / (1.0 / r1 + 1.0 / r2))  # a = sqrt(R* delta)
        return acc.corrected_share(a / r1, a / r2, nu1, nu2, E1, E2)

    funcs = {
        "50/50": lambda: np.full(n, 0.5),
        "radius": lambda: radius_split(r1, r2),
        "material": lambda: normal_share(E1, nu1, E2, nu2),
        "corrected": corrected,
    }
    out = {}
    for name, f in funcs.items():
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            f()
            best = min(best, time.perf_counter() - t0)
        out[name] = best / n * 1e9
    return out


def errors(model: str) -> dict:
    acc = load_accuracy()
    with open(HERE / "results" / f"sweep_{model}.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["converged"] in ("True", "1.0", "1") and float(r["U2"]) > 0]
    num = {k: np.array([float(r[k]) for r in rows]) for k in ("a_over_R1", "a_over_R2", "nu1", "nu2", "E1", "E2",
                                                              "share_fe", "share_law")}
    held = np.array([r["set"] == "held-out" for r in rows])
    corr = acc.corrected_share(num["a_over_R1"], num["a_over_R2"], num["nu1"], num["nu2"], num["E1"], num["E2"],
                               reference=model)
    rad = np.array([radius_share({k: float(r[k]) for k in ("a_over_R1", "a_over_R2")}) for r in rows])
    fe_ = num["share_fe"]
    return {"50/50": stats(fe_ - 0.5), "radius": stats(fe_ - rad), "material": stats(fe_ - num["share_law"]),
            "corrected": stats(fe_ - corr), "corrected_held_out": stats((fe_ - corr)[held])}


def main():
    t = timings()
    res = {"ns_per_contact": t, "errors": {m: errors(m) for m in ("neohooke", "small")}}
    (HERE / "results" / "cost_vs_error.json").write_text(json.dumps(res, indent=1) + "\n")
    lines = ["| split | ns per contact | share error vs FE neo-Hookean: rms / max | vs FE small strain: rms / max |",
             "|---|---|---|---|"]
    for name in ("50/50", "radius", "material", "corrected"):
        e1, e2 = res["errors"]["neohooke"][name], res["errors"]["small"][name]
        lines.append(f"| {name} | {t[name]:.1f} | {e1['rms']:.4f} / {e1['max_abs']:.4f} | "
                     f"{e2['rms']:.4f} / {e2['max_abs']:.4f} |")
    e1, e2 = res["errors"]["neohooke"]["corrected_held_out"], res["errors"]["small"]["corrected_held_out"]
    lines.append(f"| corrected, held-out points only | | {e1['rms']:.4f} / {e1['max_abs']:.4f} | "
                 f"{e2['rms']:.4f} / {e2['max_abs']:.4f} |")
    md = "\n".join(lines) + "\n"
    (HERE / "results" / "cost_vs_error.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
