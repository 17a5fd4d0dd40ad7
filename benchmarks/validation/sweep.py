"""Sweep of the material split's error against FE, the fit of its error model, and a held-out check.

Points (seeded, reproducible): body 1 a sphere of R1 = 5 mm, the smaller body; a/R1 uniform in [0.02, 0.3]
(a the Hertz contact radius, delta = a^2/R*); body 2 a sphere with R2/R1 log-uniform in [1, 8] or (one point
in five) a plane (an elastic block of radius and depth 20 R1); E2/E1 log-uniform in [0.1, 10] or (one point
in six) near-rigid, 1000 or 1/1000; nu1, nu2 uniform in [0, 0.49] (0.5 is out of reach of a displacement
formulation: P2 triangles lock). Every point is solved with both materials of fe.py (``small``: linear elastic,
``neohooke``: compressible neo-Hookean), mesh refine 1 (docs/accuracy.md's convergence table: share within
1e-5 of refine 2).

The fit: y = ln((S1/S2)_FE / (c1/c2)) = k1 - k2, k_i linear in the features of
``plugin/physics/accuracy.py`` (body_terms), least squares over the fit points (two in three); the held-out
points (every third) are predicted with the fitted coefficients. Errors are reported in share of body 1,
(absolute): share_FE - share_model.

Writes results/sweep_<model>.csv (every point), results/fit.json (coefficients, residuals),
results/heldout_predictions.csv (the held-out points, their inputs and the model's predicted share error:
tests/validation/test_fe.py checks plugin/physics/accuracy.py against it).

Run::

    nice -n 10 python benchmarks/validation/sweep.py [--points 48] [--jobs 2]
"""

from __future__ import annotations

import argparse
import csv
import importlib.util
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
REPO = HERE.parent.parent
RESULTS = HERE / "results"
MODELS = ("neohooke", "small")
sys.path.insert(0, str(HERE))


def load_accuracy():
    """plugin/physics/accuracy.py loaded by path (numpy only; no package import needed)."""
    spec = importlib.util.spec_from_file_location("accuracy", REPO / "plugin" / "physics" / "accuracy.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def sweep_points(n: int, seed: int = 20240611) -> list[dict]:
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
        pts.append(dict(i=i, a_over_R1=aR, R1=R1, R2=R2, E1=E1, E2=E1 * Er, nu1=rng.uniform(0.0, 0.49),
                        nu2=rng.uniform(0.0, 0.49)))
    return pts


def run_point(args):
    """Solve one sweep point with one material model; the fe.summary dict plus the point's inputs."""
    pt, model, cache = args
    path = Path(cache) / f"{model}_{pt['i']:03d}.json"
    if path.exists():
        return json.loads(path.read_text())
    import fe

    delta = fe.delta_for(pt["a_over_R1"], pt["R1"], pt["R2"])
    for steps in (2, 4, 8):  # more load steps when Newton fails (an inverted element, no convergence)
        try:
            res = fe.solve(pt["R1"], pt["R2"], pt["E1"], pt["nu1"], pt["E2"], pt["nu2"], delta, model=model,
                           refine=1.0, steps=steps)
        except (RuntimeError, FloatingPointError) as exc:
            print(f"{model} #{pt['i']} steps={steps}: {exc}", flush=True)
            continue
        if res.converged:
            break
    else:
        return {"i": pt["i"], "model": model, "failed": True, "converged": False, "share_err": math.nan,
                "a_over_R1": pt["a_over_R1"], "seconds": math.nan}
    s = fe.summary(res)
    s = {k: (float(v) if isinstance(v, (np.floating, np.integer, np.bool_, float, int, bool)) else v)
         for k, v in s.items()}
    s.update(i=pt["i"], a_over_R2=(s["a_over_R1"] * pt["R1"] / pt["R2"]), E_ratio=pt["E2"] / pt["E1"])
    path.write_text(json.dumps(s))
    return s


def features(acc, rows) -> np.ndarray:
    """Design matrix of k1 - k2 for rows (dicts with a_over_R1, a_over_R2, nu1, nu2, share_law)."""
    x1 = np.array([r["a_over_R1"] for r in rows])
    x2 = np.array([r["a_over_R2"] for r in rows])
    f1 = np.array([r["share_law"] for r in rows])
    nu1 = np.array([r["nu1"] for r in rows])
    nu2 = np.array([r["nu2"] for r in rows])
    y = x1 + x2
    return (acc.body_terms(x1, f1 * y, nu1) - acc.body_terms(x2, (1 - f1) * y, nu2)).T


def radius_share(r) -> float:
    """demsplit's radius split r1/(r1 + r2) (1 against a plane, as plugin/physics/shares.radius_share)."""
    x1, x2 = r["a_over_R1"], r["a_over_R2"]
    return 1.0 if x2 == 0 else x2 / (x1 + x2)


def share_from(f1, d):
    """Share of body 1 from the law's share f1 and the log-ratio correction d = k1 - k2."""
    return f1 / (f1 + (1 - f1) * np.exp(-d))


def stats(err) -> dict:
    err = np.asarray(err)
    return {"n": int(err.size), "rms": float(np.sqrt(np.mean(err**2))), "max_abs": float(np.max(np.abs(err)))}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=48)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cache", default="/tmp/demsplit-validation-sweep")
    ap.add_argument("--models", default=",".join(MODELS))
    args = ap.parse_args(argv)
    Path(args.cache).mkdir(parents=True, exist_ok=True)
    RESULTS.mkdir(exist_ok=True)
    pts = sweep_points(args.points)
    models = args.models.split(",")
    tasks = [(p, m, args.cache) for m in models for p in pts]
    t0 = time.perf_counter()
    if args.jobs > 1:
        from multiprocessing import Pool

        with Pool(args.jobs) as pool:
            out = []
            for k, s in enumerate(pool.imap(run_point, tasks)):
                out.append(s)
                print(f"[{k + 1}/{len(tasks)}] {s['model']} #{s['i']} a/R1={s['a_over_R1']:.3f} "
                      f"share err {s['share_err']:+.5f} conv={s['converged']} {s['seconds']:.1f}s", flush=True)
    else:
        out = [run_point(t) for t in tasks]
    wall = time.perf_counter() - t0
    acc = load_accuracy()
    fit = {"command": "nice -n 10 python benchmarks/validation/sweep.py --points %d --jobs %d" % (args.points,
                                                                                                 args.jobs),
           "wall_seconds": wall, "points": args.points, "models": {}}
    held_rows = []
    for model in models:
        rows = sorted([s for s in out if s["model"] == model], key=lambda s: s["i"])
        failed = [r["i"] for r in rows if r.get("failed")]
        rows = [r for r in rows if not r.get("failed")]
        keys = list(rows[0].keys())
        with open(RESULTS / f"sweep_{model}.csv", "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys + ["set"])
            w.writeheader()
            for r in rows:
                w.writerow({**r, "set": "held-out" if r["i"] % 3 == 2 else "fit"})
        good = [r for r in rows if r["converged"] and r["U2"] > 0]
        fitset = [r for r in good if r["i"] % 3 != 2]
        held = [r for r in good if r["i"] % 3 == 2]
        X = features(acc, fitset)
        y = np.array([math.log(r["ratio_fe"] / r["ratio_law"]) for r in fitset])
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        entry = {"coefficients": [float(c) for c in coef], "failed": failed,
                 "not_converged": [r["i"] for r in rows if not r["converged"]]}
        for name, sub in (("fit", fitset), ("held_out", held)):
            f1 = np.array([r["share_law"] for r in sub])
            sfe = np.array([r["share_fe"] for r in sub])
            pred = share_from(f1, features(acc, sub) @ coef)
            entry[name] = {"model_error": stats(sfe - pred), "law_error": stats(sfe - f1),
                           "radius_error": stats(sfe - np.array([radius_share(r) for r in sub])),
                           "equal_error": stats(sfe - 0.5)}
            if name == "held_out":
                for r, p in zip(sub, pred):
                    held_rows.append({"model": model, "i": r["i"], "a_over_R1": r["a_over_R1"],
                                      "a_over_R2": r["a_over_R2"], "nu1": r["nu1"], "nu2": r["nu2"],
                                      "E1": r["E1"], "E2": r["E2"], "share_law": r["share_law"],
                                      "share_fe": r["share_fe"], "share_model": float(p),
                                      "predicted_error": float(p - r["share_law"])})
        # the law's error and the model's over every converged point (the cost-vs-error table)
        f1 = np.array([r["share_law"] for r in good])
        sfe = np.array([r["share_fe"] for r in good])
        entry["all"] = {"law_error": stats(sfe - f1), "model_error_in_sample": stats(
            sfe - share_from(f1, features(acc, good) @ coef))}
        fit["models"][model] = entry
        print(model, json.dumps(entry, indent=1))
    (RESULTS / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    with open(RESULTS / "heldout_predictions.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(held_rows[0].keys()))
        w.writeheader()
        w.writerows(held_rows)
    print(f"wall {wall:.0f} s")


if __name__ == "__main__":
    main()
