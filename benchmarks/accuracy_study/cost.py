"""Cost against error of each split: 50/50, radius, material (the law), corrected (the fitted model).

Cost: one numpy evaluation of each share function on 1e6 contacts (float64 arrays in memory, one core, best
of 5), in ns per contact. Error: share of body 1 from FE minus the split's share, over the usable points of
the held-out sweep (results/sweep_heldout/, never fitted) and of the fit sweep (results/sweep_fit/); the
corrected split is plugin/physics/accuracy.py's (a plane taken as a half-space).

Run (after sweep.py and fit.py)::

    nice -n 10 python benchmarks/accuracy_study/cost.py

Writes results/cost_vs_error.json and results/cost_vs_error.md.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from fit import load, load_accuracy, stats  # noqa: E402


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


def errors(model: str, name: str) -> dict:
    """Share errors (FE minus split) of each split over the usable points of one sweep (fit or heldout)."""
    acc = load_accuracy()
    rows, _ = load(name, model)
    num = {
        k: np.array([float(r[k]) for r in rows])
        for k in ("a_over_R1", "a_over_R2", "nu1", "nu2", "E1", "E2", "share_fe", "share_law")
    }
    corr = acc.corrected_share(
        num["a_over_R1"], num["a_over_R2"], num["nu1"], num["nu2"], num["E1"], num["E2"], reference=model
    )
    x1, x2 = num["a_over_R1"], num["a_over_R2"]
    rad = np.where(x2 == 0, 1.0, x2 / (x1 + x2))  # r1/(r1 + r2) = (a/R2)/(a/R1 + a/R2); 1 against a plane
    fe_ = num["share_fe"]
    return {
        "50/50": stats(fe_ - 0.5),
        "radius": stats(fe_ - rad),
        "material": stats(fe_ - num["share_law"]),
        "corrected": stats(fe_ - corr),
    }


def main():
    t = timings()
    res = {
        "ns_per_contact": t,
        "errors": {m: {n: errors(m, n) for n in ("heldout", "fit")} for m in ("neohooke", "small")},
    }
    (HERE / "results" / "cost_vs_error.json").write_text(json.dumps(res, indent=1) + "\n")
    lines = [
        "| split | ns per contact | share error vs FE neo-Hookean, held-out sweep: rms / max | vs FE small "
        "strain, held-out sweep: rms / max | vs FE neo-Hookean, fit sweep: rms / max |",
        "|---|---|---|---|---|",
    ]
    for name in ("50/50", "radius", "material", "corrected"):
        e1, e2 = res["errors"]["neohooke"]["heldout"][name], res["errors"]["small"]["heldout"][name]
        e3 = res["errors"]["neohooke"]["fit"][name]
        lines.append(
            f"| {name} | {t[name]:.1f} | {e1['rms']:.4f} / {e1['max_abs']:.4f} | "
            f"{e2['rms']:.4f} / {e2['max_abs']:.4f} | {e3['rms']:.4f} / {e3['max_abs']:.4f} |"
        )
    md = "\n".join(lines) + "\n"
    (HERE / "results" / "cost_vs_error.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
