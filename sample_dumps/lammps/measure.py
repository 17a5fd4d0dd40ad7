"""Print the figures quoted in sample_dumps/lammps/README.md, measured on the committed samples.

Usage (from the repository root): python sample_dumps/lammps/measure.py

Uses the independent reference of tests/lammps_reference.py through the checks of
tests/test_lammps_samples_facts.py (no demsplit).
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from test_lammps_samples_facts import CASES, _rel, sample, unknown_counts  # noqa: E402


def worst(values) -> str:
    values = np.concatenate([np.ravel(v) for v in values])
    values = values[~np.isnan(values)]
    return f"{values.max():.1e}" if len(values) else "-"


print(
    "case | atoms | pair rows/frame (images) | wall contacts/frame | capped in single() | pair F_n | wall F_n"
    " | atom force | atom torque | atoms left out | unknown counts per frame"
)
for case in CASES:
    run, checked = sample(case)
    pair_err, wall_err, force_err, torque_err = [], [], [], []
    for c in checked:
        p = c.frame.pairs
        live = p.extra["why"] != "jkr_zeroed"
        pair_err.append(_rel(p.Fn_rebuilt[live], p.Fn_dumped[live], (np.abs(p.Fne) + np.abs(p.Fdamp_s))[live]))
        for w in c.frame.walls:
            wall_err.append(_rel(w.Fn_rebuilt, w.Fn_dumped, np.abs(w.Fne) + np.abs(w.Fdamp_s)))
        force_err.append(_rel(c.sums["F"], c.frame.atoms.f, c.sums["F_scale"]))
        torque_err.append(c.twist["rel"])
    print(
        f"{case} | {len(checked[0].frame.atoms.ids)}"
        f" | {', '.join(f'{len(c.frame.pairs.i)} ({int(c.frame.pairs.ghost.sum())})' for c in checked)}"
        f" | {', '.join(str(sum(len(w.i) for w in c.frame.walls)) for c in checked)}"
        f" | {', '.join(str(int(c.frame.pairs.capped.sum())) for c in checked)}"
        f" | {worst(pair_err)} | {worst(wall_err)} | {worst(force_err)} | {worst(torque_err)}"
        f" | {', '.join(str(int(np.isnan(c.twist['rel']).sum())) for c in checked)}"
        f" | {[unknown_counts(c) for c in checked]}"
    )

print("\nelastic energy of the last frame (J): pairs u_n u_t u_r u_adh | walls u_n u_t; pairs with u_tw unknown")
for case in CASES:
    c = sample(case)[1][-1]
    e = c.frame.pairs.energies
    walls = [np.nansum(np.concatenate([w.energies[m] for w in c.frame.walls] or [np.zeros(0)])) for m in ("u_n", "u_t")]
    print(
        f"{case}: {np.nansum(e['u_n']):.2e} {np.nansum(e['u_t']):.2e} {np.nansum(e['u_r']):.2e}"
        f" {np.nansum(e['u_adh']):.2e} | {walls[0]:.2e} {walls[1]:.2e}; {int(np.isnan(e['u_tw']).sum())}"
    )
