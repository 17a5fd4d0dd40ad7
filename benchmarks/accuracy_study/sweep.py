"""The sweep of FE points on which the split's error model is fitted and checked (fit.py does the fitting).

Points (seeded, reproducible; the first n points of a seed do not depend on how many are drawn): body 1 a
sphere of R1 = 5 mm, the smaller body; a/R1 uniform in [0.02, 0.3] (a the Hertz contact radius, delta =
a^2/R*); body 2 a sphere with R2/R1 log-uniform in [1, 8] or (one point in five) a plane (an elastic block of
radius and depth 2000 R1, a half-space to about 1e-5 in share: convergence.py's block-size table); E2/E1
log-uniform in [0.1, 10] or (one point in six) near-rigid, 1000 or 1/1000; nu1, nu2 uniform in [0, 0.49]
(0.5 is out of reach of a displacement formulation: P2 triangles lock). Every point is solved with both
materials of fe.py (``small``: linear elastic, ``neohooke``: compressible neo-Hookean),
mesh refine 1 (docs/accuracy.md's convergence table: share within 1e-5 of refine 2), 2 load steps (4, then 8
if Newton fails, an inverted element or no convergence, or stalls above 1e-6 of the Hertz force; the
solution with the smallest out-of-balance force is kept; stalled.py checks the stalled ones).

Two sweeps, two seeds: the fit sweep (seed 20240611, ``--name fit``) and the held-out sweep (seed 314159,
``--name heldout``), whose points fit.py never fits. Writes results/sweep_<name>/sweep_<model>.csv (every
solved point: inputs, FE energies, shares, convergence indicators) and results/sweep_<name>/sweep.json (the
command, the points that did not solve). A point already in the output CSV with the same inputs is reused,
not solved again (``--fresh`` solves every point).

Run (one FE process at a time: --jobs 1; about 6 s per point for both materials)::

    nice -n 10 python benchmarks/accuracy_study/sweep.py --name fit --points 240
    nice -n 10 python benchmarks/accuracy_study/sweep.py --name heldout --points 160
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
MODELS = ("neohooke", "small")
SEEDS = {"fit": 20240611, "heldout": 314159}
INPUTS = ("a_over_R1", "R1", "R2", "E1", "E2", "nu1", "nu2", "block_L")
STALLED = 1e-6  # a Newton accepted above this out-of-balance force (/ Hertz force) stalled: more load steps
BLOCK = 2000.0  # a plane is an elastic block of radius and depth BLOCK * R1: a half-space to ~1e-5 in share
sys.path.insert(0, str(HERE))


def sweep_points(n: int, seed: int = SEEDS["fit"]) -> list[dict]:
    """The sweep's n points: a/R1, R2, E1, E2, nu1, nu2 (SI), seeded."""
    rng = np.random.default_rng(seed)
    R1 = 5e-3
    pts = []
    for i in range(n):
        aR = rng.uniform(0.02, 0.3)
        R2 = math.inf if rng.uniform() < 0.2 else R1 * math.exp(rng.uniform(0.0, math.log(8.0)))
        u = rng.uniform()
        if u < 1 / 12:
            Er = 1000.0
        elif u < 1 / 6:
            Er = 1e-3
        else:
            Er = math.exp(rng.uniform(math.log(0.1), math.log(10.0)))
        E1 = 100e9
        pts.append(
            dict(
                i=i,
                a_over_R1=aR,
                R1=R1,
                R2=R2,
                E1=E1,
                E2=E1 * Er,
                nu1=rng.uniform(0.0, 0.49),
                nu2=rng.uniform(0.0, 0.49),
                block_L=BLOCK * R1 if math.isinf(R2) else None,
            )
        )
    return pts


def run_point(pt: dict, model: str) -> dict:
    """Solve one sweep point with one material model; the fe.summary dict plus the point's inputs."""
    import fe

    delta = fe.delta_for(pt["a_over_R1"], pt["R1"], pt["R2"])
    best = None
    for steps in (2, 4, 8):  # more load steps when Newton fails (an inverted element, no convergence) or stalls
        try:
            res = fe.solve(
                pt["R1"],
                pt["R2"],
                pt["E1"],
                pt["nu1"],
                pt["E2"],
                pt["nu2"],
                delta,
                model=model,
                refine=1.0,
                steps=steps,
                block=pt["block_L"],
            )
        except (RuntimeError, FloatingPointError) as exc:
            print(f"{model} #{pt['i']} steps={steps}: {exc}", flush=True)
            continue
        if res.converged and (best is None or res.residual < best.residual):
            best = res
        if res.converged and res.residual <= STALLED:
            break
    if best is None:
        return {"i": pt["i"], "model": model, "failed": True}
    s = fe.summary(best)
    s = {
        k: (float(v) if isinstance(v, (np.floating, np.integer, np.bool_, float, int, bool)) else v)
        for k, v in s.items()
    }
    s.update(
        i=pt["i"],
        a_over_R2=(s["a_over_R1"] * pt["R1"] / pt["R2"]),
        E_ratio=pt["E2"] / pt["E1"],
        block_L=pt["block_L"],
        stall_retried=True,
    )
    return s


def _value(v: str):
    """A CSV cell back to a number (or None for an empty cell, the string otherwise)."""
    if v == "":
        return None
    try:
        return float(v)
    except ValueError:
        return v


def read_rows(path: Path) -> list[dict]:
    """Rows of a sweep CSV, numbers as floats, ``i`` as int."""
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        rows = [{k: _value(v) for k, v in r.items()} for r in csv.DictReader(fh)]
    for r in rows:
        r["i"] = int(r["i"])
        r.pop("set", None)  # (rows written before the two-seed sweeps had the fit/held-out label)
        r.setdefault("gap", "current")
        r.setdefault("base", "slide")
    return rows


def same_inputs(row: dict, pt: dict) -> bool:
    """Whether a stored row was solved for this point (the FE inputs equal to 1e-12 relative)."""
    got = {k: row.get(k) for k in INPUTS}  # (block_L: None for a sphere, and in rows written before it was one)
    return all(
        got[k] == pt[k] or (got[k] is not None and pt[k] is not None and abs(got[k] - pt[k]) <= 1e-12 * abs(pt[k]))
        for k in INPUTS
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--name", choices=sorted(SEEDS), default="fit")
    ap.add_argument("--points", type=int, required=True)
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument("--fresh", action="store_true", help="solve every point (do not reuse the output CSV's rows)")
    args = ap.parse_args(argv)
    seed = SEEDS[args.name]
    out = RESULTS / f"sweep_{args.name}"
    out.mkdir(parents=True, exist_ok=True)
    pts = sweep_points(args.points, seed)
    info = {
        "command": f"nice -n 10 python benchmarks/accuracy_study/sweep.py --name {args.name} --points {args.points}",
        "seed": seed,
        "points": args.points,
        "models": {},
    }
    t0 = time.perf_counter()
    for model in args.models.split(","):
        path = out / f"sweep_{model}.csv"
        old = {} if args.fresh else {r["i"]: r for r in read_rows(path)}
        rows, failed, solved = [], [], 0
        for pt in pts:
            r = old.get(pt["i"])
            if r is None or not same_inputs(r, pt) or (r["residual"] > STALLED and not r.get("stall_retried")):
                r = run_point(pt, model)
                solved += 1
                print(
                    f"{model} #{pt['i']} a/R1={pt['a_over_R1']:.3f} "
                    + (
                        "FAILED"
                        if r.get("failed")
                        else f"share err {r['share_err']:+.5f} conv={r['converged']} {r['seconds']:.1f}s"
                    ),
                    flush=True,
                )
            if r.get("failed"):
                failed.append(pt["i"])
            else:
                rows.append(r)
        keys = list(dict.fromkeys(k for r in rows for k in r))
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys)
            w.writeheader()
            w.writerows(rows)
        info["models"][model] = {
            "solved": len(rows),
            "failed": failed,
            "solved_now": solved,
            "not_converged": [r["i"] for r in rows if not r["converged"]],
        }
        print(model, info["models"][model], flush=True)
    info["wall_seconds_this_run"] = time.perf_counter() - t0
    if (out / "sweep.json").exists():  # keep the entries of the models not run now
        old = json.loads((out / "sweep.json").read_text())
        if old.get("points") == args.points:
            info["models"] = {**old.get("models", {}), **info["models"]}
    (out / "sweep.json").write_text(json.dumps(info, indent=1) + "\n")


if __name__ == "__main__":
    main()
