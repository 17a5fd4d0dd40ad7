"""Print the figures docs/lammps-output.md quotes for demsplit's own reader and laws on the committed samples.

Usage (from the repository root): python sample_dumps/lammps/measure_demsplit.py

Per sample (all frames): the largest relative difference between the normal force demsplit's law rebuilds and the
one LAMMPS dumped (pair rows and wall contacts, scale |F_ne| + |damping|); per atom, between the sum of the rebuilt
contact forces and torques of the step (+ m g; the pairs' twisting torques solved) and the dumped ones; the atoms
whose balance has a term in no dump; per contact, the largest relative difference of u_n, u_t, u_r, u_adh from the
independent reference (tests/lammps_reference.py); per frame and mode, conservation (particles + walls against the
contacts); the contacts with a mode not computed, by reason. The checks themselves are tests/test_lammps_run.py.
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from demsplit.compute import Options, frame_tables  # noqa: E402
from test_lammps_run import CASES, _balances, _modes_of, assembled, reference  # noqa: E402


def energy_error(case: str) -> float:
    """The largest relative difference of a known energy from the reference's, over the rows both write."""
    from test_lammps_run import _keys, _pack, _with_resolution

    run, steps = assembled(case)
    worst = 0.0
    for a, (frame, resolved) in zip(steps, reference(case)[1]):
        mine, c = _modes_of(a, run), a.contacts
        written = ~c["neck"] & ~c["extra_contact"]
        parts = [frame.pairs, *frame.walls]
        keys_ref = np.concatenate([_keys(p.i, p.j, frame.atoms.ids, k) for k, p in enumerate(parts)])
        wall_of = {w.kind.split(":")[1]: k + 1 for k, w in enumerate(frame.walls)}
        kind = np.where(c["wall"] < 0, 0, np.array([wall_of.get(w.name, -1) for w in run.scene.walls] + [0])[c["wall"]])
        keys = _pack(c["id1"], np.where(c["wall"] < 0, c["id2"], -1), kind)
        where = {int(keys[n]): n for n in np.flatnonzero(written)}
        rows = np.array([where[int(k)] for k in keys_ref])
        for mode in ("u_n", "u_t", "u_r", "u_adh"):
            theirs = np.concatenate([p.energies[mode] for p in parts])
            theirs = _with_resolution(theirs, frame, resolved) if mode == "u_t" else theirs
            ours = mine.get(mode, np.zeros(len(keys)))[rows]
            known = ~np.isnan(theirs) & (theirs != 0)
            if known.any():
                worst = max(worst, float(np.max(np.abs(ours[known] - theirs[known]) / np.abs(theirs[known]))))
    return worst


print(
    "case | pair rows, wall contacts (per frame) | F_n per contact | atom force | atom torque | atoms left out "
    "(force, torque) | energies vs reference | conservation | not computed (reason code: contacts)"
)
for case in CASES:
    run, steps = assembled(case)
    fn, force, torque, left, conservation, rows, reasons = 0.0, 0.0, 0.0, [], 0.0, [], {}
    for a in steps:
        r, c = a.rebuilt, a.contacts
        ok = np.isfinite(r.fn_rebuilt) & np.isfinite(c["fn_dumped"])
        fn = max(fn, float(np.max(np.abs(r.fn_rebuilt[ok] - c["fn_dumped"][ok]) / r.fn_scale[ok])))
        rel_f, rel_t, known_f, known_t = _balances(a, run.script.gravity[a.run])
        force, torque = max(force, float(rel_f[known_f].max())), max(torque, float(rel_t[known_t].max()))
        left.append(f"{int((~known_f).sum())}/{int((~known_t).sum())}")
        rows.append(f"{int((c['wall'] < 0).sum() - c['neck'].sum())}+{int((c['wall'] >= 0).sum())}")
        tables = frame_tables(run.to_frame(a), run.scene, Options(allow_missing=("all",)))
        t, p, w = tables["contacts"], tables["particles"], tables["walls"]
        for mode in [m for m in ("u_n", "u_t", "u_r", "u_tw", "u_adh") if m in t]:
            total = t[mode].sum()
            if total:
                conservation = max(conservation, abs(p[mode].sum() + w[mode].sum() - total) / abs(total))
        frame = run.to_frame(a)
        for code in np.unique(frame.contacts["unknown_why"]):
            if code:
                reasons.setdefault(int(code), []).append(int((frame.contacts["unknown_why"] == code).sum()))
    shown = ", ".join(f"{k}: {'/'.join(map(str, v))}" for k, v in sorted(reasons.items())) or "-"
    print(
        f"{case} | {', '.join(rows)} | {fn:.1e} | {force:.1e} | {torque:.1e} | {', '.join(left)} | "
        f"{energy_error(case):.1e} | {conservation:.1e} | {shown}"
    )
