"""The sweep points whose Newton stalled: are their shares converged?

fe.solve accepts a stalled Newton (a Gauss point flipping in and out of contact) when the out-of-balance force
is below 1e-4 of the Hertz force (fe.STALL_TOL); converged points are below 1e-8. This script re-solves every
point of the two sweeps (results/sweep_fit/, results/sweep_heldout/) whose final out-of-balance force is above
1e-7 of the Hertz force with 4 and 8 load steps (a different load path, so a different active-set history) and
reports how far body 1's share moves. (sweep.py already tries 4 and 8 steps when a point stalls above 1e-6 and
keeps the solution with the smallest out-of-balance force.)

Run (after sweep.py; one FE process)::

    nice -n 10 python benchmarks/accuracy_study/stalled.py

Writes results/stalled.md and results/stalled.json.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import fe  # noqa: E402
from sweep import SEEDS, read_rows, sweep_points  # noqa: E402

THRESHOLD = 1e-7


def main():
    rows_out = []
    for name in ("fit", "heldout"):
        info = json.loads((HERE / "results" / f"sweep_{name}" / "sweep.json").read_text())
        pts = sweep_points(info["points"], SEEDS[name])
        for model in ("neohooke", "small"):
            for r in read_rows(HERE / "results" / f"sweep_{name}" / f"sweep_{model}.csv"):
                if r["residual"] <= THRESHOLD:
                    continue
                p = pts[r["i"]]
                d = fe.delta_for(p["a_over_R1"], p["R1"], p["R2"])
                row = {"sweep": name, "model": model, "i": r["i"], "residual": r["residual"], "share_fe": r["share_fe"]}
                for steps in (4, 8):
                    s = fe.summary(
                        fe.solve(
                            p["R1"],
                            p["R2"],
                            p["E1"],
                            p["nu1"],
                            p["E2"],
                            p["nu2"],
                            d,
                            model=model,
                            refine=1.0,
                            steps=steps,
                            block=p["block_L"],
                        )
                    )
                    row[f"share_{steps}"] = float(s["share_fe"])
                    row[f"residual_{steps}"] = float(s["residual"])
                    row[f"converged_{steps}"] = bool(s["converged"])
                row["max_change"] = max(abs(row["share_4"] - r["share_fe"]), abs(row["share_8"] - r["share_fe"]))
                rows_out.append(row)
                print(row, flush=True)
    (HERE / "results" / "stalled.json").write_text(json.dumps(rows_out, indent=1) + "\n")
    md = [
        "| sweep | material | point | residual | share | share, 4 steps (residual) | share, 8 steps (residual) | "
        "largest change |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows_out:
        md.append(
            f"| {r['sweep']} | {r['model']} | {r['i']} | {r['residual']:.1e} | {r['share_fe']:.6f} | "
            f"{r['share_4']:.6f} ({r['residual_4']:.0e}) | {r['share_8']:.6f} ({r['residual_8']:.0e}) | "
            f"{r['max_change']:.1e} |"
        )
    worst = max((r["max_change"] for r in rows_out), default=0.0)
    md += ["", "| stalled points | largest change of share |", "|---|---|", f"| {len(rows_out)} | {worst:.1e} |"]
    (HERE / "results" / "stalled.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
