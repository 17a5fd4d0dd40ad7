"""Checks of the FE model: Hertz at small a/R, mesh convergence, penalty, energy conservation.

1. Hertz limit: a/R1 = 0.01 (sphere on sphere R2 = 2 R1, sphere on an elastic block, sphere on a rigid
   plane), small strain: force, total energy and share against Hertz and the law.
2. Mesh convergence: Feng & Gao's Table 2 case 2 (R1 = 5 mm, R2 = 10 mm, steel, delta = 0.1 mm) and case 5
   (E1 = 70 GPa), both materials, refine 0.5, 1, 2 (and 4, small strain): the size field h_c = a/(12 refine),
   grading 0.35/refine, so every element shrinks by the factor refine.
3. Penalty: kappa = 30, 100, 300 (eps = kappa E*/h_c), case 2, neo-Hookean.
4. Energy conservation: work of the reaction int P d(delta) (Simpson in sqrt(delta)) against the stored
   U1 + U2 + Pi_c, case 2, neo-Hookean, 4, 8 and 16 load steps.
5. nu = 0.49 (near-incompressible), case 2 geometry, refine 1 against 2.
6. Size of the block that stands for a plane: point 49 of the fit sweep (a/R1 = 0.273, E2/E1 = 0.139), both
   materials, block radius and depth L = 20, 200, 2000 R1 (sweep.py uses 2000 R1).

Run::

    nice -n 10 python benchmarks/accuracy_study/convergence.py

Writes results/convergence.json and results/convergence.md.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import fe  # noqa: E402

KEYS = (
    "model",
    "refine",
    "kappa",
    "steps",
    "ndofs",
    "nelements",
    "P_fe",
    "e_P",
    "e_S",
    "U1",
    "U2",
    "Pi_c",
    "ratio_fe",
    "share_fe",
    "share_err",
    "work",
    "e_work",
    "converged",
    "residual",
    "seconds",
)


def run(R1, R2, E1, nu1, E2, nu2, delta, **kw) -> dict:
    s = fe.summary(fe.solve(R1, R2, E1, nu1, E2, nu2, delta, **kw))
    return {k: (float(s[k]) if not isinstance(s[k], str) else s[k]) for k in KEYS}


def table(rows, cols) -> str:
    out = ["| " + " | ".join(cols) + " |", "|" + "|".join(["---"] * len(cols)) + "|"]
    for r in rows:
        cells = []
        for c in cols:
            v = r[c]
            if isinstance(v, str):
                cells.append(v)
            elif c in ("ndofs", "nelements", "steps", "L_over_R1"):
                cells.append(f"{int(v)}")
            elif c.startswith("e_") or c == "share_err":
                cells.append(f"{100 * v:+.4f} %")
            elif c == "seconds":
                cells.append(f"{v:.1f}")
            else:
                cells.append(f"{v:.6g}")
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def main():
    mm, GPa = 1e-3, 1e9
    res = {}
    md = []
    # 1. Hertz limit
    rows = []
    for name, R2, E2 in (
        ("sphere R2 = 2 R1", 10 * mm, 210 * GPa),
        ("elastic block", math.inf, 210 * GPa),
        ("rigid plane", math.inf, math.inf),
    ):
        d = fe.delta_for(0.01, 5 * mm, R2)
        r = run(5 * mm, R2, 210 * GPa, 0.3, E2, 0.3, d, model="small", steps=8)
        r["case"] = name
        rows.append(r)
        print(name, r, flush=True)
    res["hertz"] = rows
    md += [
        "## Hertz limit, a/R1 = 0.01, small strain\n",
        table(rows, ["case", "ndofs", "P_fe", "e_P", "e_S", "share_fe", "share_err", "e_work", "seconds"]),
    ]
    # 2. mesh convergence
    rows = []
    for case, E1 in (("2", 210 * GPa), ("5", 70 * GPa)):
        for model, refines in (("small", (0.5, 1, 2, 4)), ("neohooke", (0.5, 1, 2))):
            for ref in refines:
                r = run(5 * mm, 10 * mm, E1, 0.3, 210 * GPa, 0.3, 0.1 * mm, model=model, refine=ref, steps=2)
                r["case"] = case
                rows.append(r)
                print(case, r, flush=True)
    res["mesh"] = rows
    md += [
        "## Mesh convergence, Feng & Gao Table 2 cases 2 and 5\n",
        table(
            rows,
            ["case", "model", "refine", "ndofs", "P_fe", "U1", "U2", "ratio_fe", "share_fe", "converged", "seconds"],
        ),
    ]
    # 3. penalty
    rows = []
    for kappa in (30, 100, 300):
        r = run(5 * mm, 10 * mm, 210 * GPa, 0.3, 210 * GPa, 0.3, 0.1 * mm, model="neohooke", kappa=kappa, steps=2)
        rows.append(r)
        print(r, flush=True)
    res["penalty"] = rows
    md += [
        "## Penalty, case 2, neo-Hookean\n",
        table(rows, ["kappa", "P_fe", "U1", "U2", "Pi_c", "ratio_fe", "seconds"]),
    ]
    # 4. energy conservation
    rows = []
    for steps in (4, 8, 16):
        r = run(5 * mm, 10 * mm, 210 * GPa, 0.3, 210 * GPa, 0.3, 0.1 * mm, model="neohooke", steps=steps)
        rows.append(r)
        print(r, flush=True)
    res["work"] = rows
    md += [
        "## Energy conservation, case 2, neo-Hookean\n",
        table(rows, ["steps", "work", "U1", "U2", "Pi_c", "e_work", "seconds"]),
    ]
    # 5. nu = 0.49
    rows = []
    for model in ("small", "neohooke"):
        for ref in (1, 2):
            r = run(5 * mm, 10 * mm, 210 * GPa, 0.49, 210 * GPa, 0.3, 0.1 * mm, model=model, refine=ref, steps=2)
            rows.append(r)
            print(r, flush=True)
    res["nu049"] = rows
    md += [
        "## nu1 = 0.49, case 2 geometry\n",
        table(rows, ["model", "refine", "ndofs", "P_fe", "ratio_fe", "share_fe", "seconds"]),
    ]
    # 6. block size
    rows = []
    from sweep import sweep_points

    p = sweep_points(50)[49]
    d = fe.delta_for(p["a_over_R1"], p["R1"], p["R2"])
    for model in ("small", "neohooke"):
        for L in (20, 200, 2000):
            r = run(p["R1"], p["R2"], p["E1"], p["nu1"], p["E2"], p["nu2"], d, model=model, steps=2, block=L * p["R1"])
            r["L_over_R1"] = L
            rows.append(r)
            print(r, flush=True)
    res["block"] = rows
    md += [
        "## Block size (a plane), fit sweep point 49\n",
        table(rows, ["model", "L_over_R1", "ndofs", "P_fe", "U1", "U2", "share_fe", "share_err", "seconds"]),
    ]
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    (out / "convergence.json").write_text(json.dumps(res, indent=1) + "\n")
    (out / "convergence.md").write_text("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
