"""Facts about LAMMPS GRANULAR output (Debian's lmp, 29 Sep 2021 - Update 2), checked on the sample runs.

These tests read ``sample_dumps/lammps/`` with plain numpy and rebuild every contact with the independent
reference ``tests/lammps_reference.py`` (never demsplit's code), then hold it against what LAMMPS itself wrote:
the normal force of every pair row and wall contact, the per-atom sums of forces and torques of the step (with
the tangential and rolling springs rebuilt from the dumped ``p1..p7``, the pairs' twisting torques solved by
least squares), the velocities ``single()`` used per pair, and the energies' signs and derivatives. What no dump
holds is flagged by rule and counted here, never dropped. One simulator test reruns a sample with ``lmp``.
"""

from __future__ import annotations

import functools
import math
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from conftest import require_program
from lammps_reference import (
    Frame,
    Run,
    atom_sums,
    jkr_necks,
    normal,
    pair_models,
    parse_granular,
    resolve_intervals,
    solve_twisting,
    torque_unknown_atoms,
)

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps" / "lammps"
TOL = 1e-9  # relative; every figure measured on these samples is below 1e-11 (see sample_dumps/lammps/README.md)

# (folder, input script, dump prefix)
CASES = {
    "hertz_mindlin": ("hertz_mindlin", "in.hertz_mindlin", ""),
    "dmt": ("dmt", "in.dmt", ""),
    "jkr": ("jkr", "in.jkr", ""),
    "hooke_region": ("hooke_region", "in.hooke_region", ""),
    "periodic": ("periodic", "in.periodic", ""),
    "gran_hooke_history": ("legacy", "in.hooke_history", "hooke_history_"),
    "gran_hertz_history": ("legacy", "in.hertz_history", "hertz_history_"),
    "gran_hooke": ("legacy", "in.hooke", "hooke_"),
}


@dataclass
class Checked:
    """One frame rebuilt: the frame, the atom sums after the interval resolution, the resolved contacts, the
    twisting solution and the rule-flagged jkr necks."""

    frame: Frame
    sums: dict
    resolved: list
    twist: dict
    necks: np.ndarray


def check_run(run: Run) -> list[Checked]:
    out = []
    for frame in run.frames():
        sums = atom_sums(frame, run.models)
        resolved = resolve_intervals(frame, sums, TOL)
        out.append(Checked(frame, sums, resolved, solve_twisting(frame, sums), jkr_necks(frame, run.models)))
    return out


@functools.cache
def sample(case: str) -> tuple[Run, list[Checked]]:
    folder, script, prefix = CASES[case]
    run = Run(SAMPLES / folder, script, prefix)
    return run, check_run(run)


def _rel(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> np.ndarray:
    diff = np.abs(a - b) if a.ndim == 1 else np.linalg.norm(a - b, axis=1)
    return diff / np.where(scale > 0, scale, 1)


# ------------------------------------------------------------------------------------------- per contact


def assert_pair_rows(checked: list[Checked]) -> None:
    """Every pair row: the dumped normal force (damping included) is the rebuilt one, fx fy fz = force n; rows that
    single() zeroed (jkr) hold zeros only."""
    for c in checked:
        p = c.frame.pairs
        zeroed = p.extra["why"] == "jkr_zeroed"
        live = ~zeroed
        scale = np.abs(p.Fne) + np.abs(p.Fdamp_s)
        err = _rel(p.Fn_rebuilt[live], p.Fn_dumped[live], scale[live])
        assert err.max(initial=0) < TOL, (c.frame.step, err.max())
        fvec = p.extra["fvec"][live]
        assert _rel(fvec, p.Fn_dumped[live, None] * p.n[live], np.abs(p.Fn_dumped[live])).max(initial=0) < TOL
        for k, column in p.extra["p"].items():
            assert np.all(column[zeroed] == 0), k


@pytest.mark.parametrize("case", CASES)
def test_pair_normal_force_is_lammps_own(case):
    assert_pair_rows(sample(case)[1])


@pytest.mark.parametrize("case", CASES)
def test_wall_contacts_normal_force_and_point(case):
    """The normal part of each wall fix's ``contacts`` force is the rebuilt F_ne - η_n v_n (half-step velocity,
    the wall's own E, ν formulas, tsuji converted once per run); f_ID[5..7] is the centre minus d."""
    run, checked = sample(case)
    n_walls = 0
    for c in checked:
        at = c.frame.atoms
        for w in c.frame.walls:
            scale = np.abs(w.Fne) + np.abs(w.Fdamp_s)
            assert _rel(w.Fn_rebuilt, w.Fn_dumped, scale).max(initial=0) < TOL, (w.kind, c.frame.step)
            fix = w.kind.split(":")[1]
            point = np.stack([at.dump.columns[f"f_{fix}[{k}]"][w.i] for k in (5, 6, 7)], -1)
            d = (at.r[w.i] - w.delta)[:, None] * w.n
            assert np.abs(point - (at.x[w.i] - d)).max(initial=0) < 1e-15
            n_walls += len(w.i)
    assert n_walls > 0


def test_wall_tsuji_is_converted_once_per_run():
    """hertz_mindlin's walls (tsuji, e = 0.3) are defined before its two runs: LAMMPS applied α twice
    (fix_wall_gran.cpp:531-537); with α applied once the rebuilt normal forces miss the dumped ones."""
    run, checked = sample("hertz_mindlin")
    assert run.script.runs_after("floor") == 2
    frame = checked[0].frame
    words = run.script.fix("floor")[5:]
    once = parse_granular(words, wall=True, ninit=1)[0]
    twice = parse_granular(words, wall=True, ninit=2)[0]
    assert not math.isclose(once.damp, twice.damp)
    w = frame.walls[0]
    at = frame.atoms
    nrm = normal(once, w.delta, w.R, at.m[w.i])
    vn = np.einsum("ij,ij->i", at.v_half[w.i], w.n)
    err = _rel(nrm.Fne - nrm.eta_n * vn, w.Fn_dumped, np.abs(w.Fne))
    assert err.max() > 1e-3


@pytest.mark.parametrize("case", CASES)
def test_velocities_single_used(case):
    """single() saw the full-step velocity of atom 1 and the half-step one of a periodic image (a ghost, not
    updated by final_integrate): the dumped force matches that choice and, where the other choice differs, not the
    other. Legacy rows also dump v_n n and v_t (p5-p10), equal to those of that choice."""
    run, checked = sample(case)
    n_ghost = 0
    for c in checked:
        p = c.frame.pairs
        live = p.extra["why"] != "jkr_zeroed"
        scale = np.abs(p.Fne) + np.abs(p.Fdamp_s)
        alt = p.extra["Fn_alt"]
        differs = live & (_rel(alt, p.Fn_rebuilt, scale) > 1e-6)
        assert np.all(_rel(alt, p.Fn_dumped, scale)[differs] > 1e-7)
        n_ghost += int(p.ghost.sum())
        if c.frame.pairs.extra["p"].get(11) is None:  # legacy: p5-p7 = v_n n, p8-p10 = v_t
            q, dv = p.extra["p"], p.extra["dv_s"]
            vn = np.einsum("ij,ij->i", dv, p.n)[:, None] * p.n
            speed = np.linalg.norm(dv, axis=1)
            assert _rel(np.stack([q[5], q[6], q[7]], -1), vn, speed).max() < TOL
            assert _rel(np.stack([q[8], q[9], q[10]], -1), dv - vn, speed).max() < TOL
    periodic = "p" in run.script.first("boundary")[1:4]
    assert (n_ghost > 0) == periodic


@pytest.mark.parametrize("case", CASES)
def test_tangential_force_of_the_step_within_coulomb(case):
    """The step's tangential force, rebuilt from the spring and the half-step velocities (pairs) or dumped
    (walls), never exceeds its Coulomb limit."""
    for c in sample(case)[1]:
        for con in [c.frame.pairs, *c.frame.walls]:
            known = ~np.isnan(con.Ft_step).any(1)
            ft = np.linalg.norm(con.Ft_step[known], axis=1)
            assert np.all(ft <= con.crit_h[known] * (1 + TOL) + 1e-300), con.kind


# ------------------------------------------------------------------------------------------- per atom


@pytest.mark.parametrize("case", CASES)
def test_atom_force_balance(case):
    """Dumped fx fy fz = Σ contact forces of the step + m g for every atom whose contacts are all known; a
    contact capped in single() but not in the step is resolved along single()'s direction with L in its interval."""
    for c in sample(case)[1]:
        at = c.frame.atoms
        err = _rel(c.sums["F"], at.f, c.sums["F_scale"])
        known = ~np.isnan(err)
        assert err[known].max() < TOL, (c.frame.step, err[known].max())
        assert all(r["ok"] for r in c.resolved), c.resolved


@pytest.mark.parametrize("case", CASES)
def test_atom_torque_balance(case):
    """Dumped tqx tqy tqz = Σ contact torques of the step, the pairs' twisting torques τ n solved by least squares
    (no dump holds them); atoms touching a wall with a rolling model left out (its torque is in no dump)."""
    for c in sample(case)[1]:
        t = c.twist
        rel = t["rel"]
        kept = ~np.isnan(rel)
        assert rel[kept].max() < TOL, (c.frame.step, rel[kept].max())
        assert t["unknowns"] < 3 * kept.sum()


@pytest.mark.parametrize("case", ["hertz_mindlin", "jkr"])
def test_solved_twisting_torques_respect_their_limit(case):
    """The twisting torques solved from the torque balance lie within LAMMPS' limit of the step, μ_tw F_ncrit
    (marshall: μ_tw = 2/3 a μ, pair_granular.cpp:622-646), and the pairs single() wrote as capped (p9 != 0) sit on
    it: an independent check of the solution and of everything else in the torque balance."""
    run, checked = sample(case)
    on_limit = 0
    for c in checked:
        p, at = c.frame.pairs, c.frame.atoms
        cols, tau = c.twist["cols"], c.twist["tau"]
        limit = np.zeros(len(cols))
        for k, row in enumerate(cols):
            m = run.models[(at.type[p.i[row]], at.type[p.j[row]])]
            mu_tw = 2 / 3 * math.sqrt(p.R[row] * p.delta[row]) * m.mu if m.twisting == "marshall" else m.twist[2]
            limit[k] = mu_tw * p.crit_h[row] / m.mu
        assert np.all(np.abs(tau) <= limit * (1 + TOL)), np.max(np.abs(tau) / limit)
        capped = p.extra["p9"][cols] != 0
        on_limit += int(np.sum(np.abs(np.abs(tau[capped]) - limit[capped]) <= TOL * limit[capped]))
    assert on_limit > 0 if case == "hertz_mindlin" else on_limit == 0


# ------------------------------------------------------------------------------------------- what no dump holds

# Per frame: jkr pairs that single() zeroed, atoms near a possible jkr neck, region-wall contacts with other
# surfaces touched (their force lost), dmt rows first or capped (the limit undefined), contacts resolved from the
# atom balance (capped in single() only), pairs with a twisting torque, contacts of walls with a rolling model.
UNKNOWN_COUNTS = {
    "hertz_mindlin": [(0, 0, 0, 0, 0, 239, 25), (0, 0, 0, 0, 0, 201, 24), (0, 0, 0, 0, 0, 269, 27)],
    "dmt": [(0, 0, 0, 1, 0, 0, 0), (0, 0, 0, 1, 0, 0, 0), (0, 0, 0, 1, 0, 0, 0)],
    "jkr": [(1, 8, 0, 0, 0, 177, 0), (7, 6, 0, 0, 0, 164, 0), (11, 18, 0, 0, 0, 232, 0)],
    "hooke_region": [(0, 0, 5, 0, 0, 0, 0), (0, 0, 7, 0, 0, 0, 0), (0, 0, 6, 0, 0, 0, 0)],
    "periodic": [(0, 0, 0, 0, 0, 0, 0)] * 3,
    "gran_hooke_history": [(0, 0, 0, 0, 1, 0, 0), (0, 0, 0, 0, 0, 0, 0), (0, 0, 0, 0, 0, 0, 0)],
    "gran_hertz_history": [(0, 0, 0, 0, 0, 0, 0), (0, 0, 0, 0, 0, 0, 0), (0, 0, 0, 0, 1, 0, 0)],
    "gran_hooke": [(0, 0, 0, 0, 0, 0, 0)] * 3,
}


def unknown_counts(c: Checked) -> tuple[int, ...]:
    p, why = c.frame.pairs, c.frame.pairs.extra["why"]
    region = sum(int(w.unknown.sum()) for w in c.frame.walls)
    rolling_walls = sum(
        len(w.i) for w in c.frame.walls if w.extra["model"].rolling != "none" or w.extra["model"].twisting != "none"
    )
    dmt = int(np.isin(why, ["dmt_first_row", "dmt_capped"]).sum())
    return (
        int((why == "jkr_zeroed").sum()),
        len(np.unique(c.necks)),
        region,
        dmt,
        len(c.resolved),
        int(p.twist.sum()),
        rolling_walls,
    )


@pytest.mark.parametrize("case", CASES)
def test_unknowable_contacts_are_flagged_and_counted(case):
    """Each kind of contact no dump can give is found by its rule and counted; its atoms are NaN in the sums (left
    out of the balances, never closed by a zero); every other atom is in both balances."""
    run, checked = sample(case)
    assert [unknown_counts(c) for c in checked] == UNKNOWN_COUNTS[case]
    assert not any((c.frame.pairs.extra["why"] == "no_capped_step").any() for c in checked)
    for c in checked:
        p = c.frame.pairs
        flagged = np.zeros(len(c.frame.atoms.ids), bool)
        flagged[p.i[p.unknown]] = flagged[p.j[p.unknown]] = True
        flagged[c.necks.reshape(-1)] = True
        for w in c.frame.walls:
            flagged[w.i[w.unknown]] = True
        assert np.array_equal(np.isnan(c.sums["F"]).any(1), flagged)
        assert np.array_equal(np.isnan(c.twist["rel"]), flagged | torque_unknown_atoms(c.frame))


def test_linear_nohistory_beside_history_runs_the_history_branch():
    """periodic's 1-2 pairs are linear_nohistory beside mindlin_rescale/force pairs: LAMMPS ran them through the
    history branch with k_t = 0 (a global flag), whose force drops to 0 above the Coulomb limit; the documented
    no-history law (the limit itself) misses the dumped atom forces."""
    run, checked = sample("periodic")
    assert run.models[(1, 2)].tangential == "zero_spring"
    plain = pair_models(run.script, global_history=False)
    frame = next(run.frames(plain))
    sums = atom_sums(frame, plain)
    assert np.nanmax(_rel(sums["F"], frame.atoms.f, sums["F_scale"])) > 1e-3


# ------------------------------------------------------------------------------------------- energies


@pytest.mark.parametrize("case", CASES)
def test_energies_signs_and_unknowns(case):
    """u_n, u_t, u_r >= 0; u_adh <= 0; u_tw is NaN exactly for the pairs with a twisting model, u_t NaN exactly for
    the flagged pairs; every other value finite."""
    for c in sample(case)[1]:
        p = c.frame.pairs
        e = p.energies
        for mode in ("u_n", "u_t", "u_r"):
            assert np.all(e[mode][~np.isnan(e[mode])] >= 0), mode
        assert np.all(e["u_adh"] <= 0)
        assert np.array_equal(np.isnan(e["u_tw"]), p.twist)
        assert np.array_equal(np.isnan(e["u_t"]), p.unknown)
        assert np.all(np.isfinite(e["u_n"])) and np.all(np.isfinite(e["u_adh"]))
        for w in c.frame.walls:
            assert np.all(np.isfinite(w.energies["u_n"])) and np.all(w.energies["u_t"] >= 0)


@pytest.mark.parametrize("case", ["dmt", "jkr"])
def test_adhesive_energy_differentiates_to_the_force(case):
    """d(u_n + u_adh)/dδ = F_ne (the elastic force LAMMPS applies) at every pair's δ, by central differences."""
    run, checked = sample(case)
    for c in checked:
        p, at = c.frame.pairs, c.frame.atoms
        for (a, b), m in run.models.items():
            sel = (at.type[p.i] == a) & (at.type[p.j] == b)
            if not sel.any():
                continue
            d, R, meff = p.delta[sel], p.R[sel], np.ones(sel.sum())
            h = 1e-5 * d
            up, down = normal(m, d + h, R, meff), normal(m, d - h, R, meff)
            slope = (up.u_n + up.u_adh - down.u_n - down.u_adh) / (2 * h)
            assert _rel(slope, p.Fne[sel], np.abs(p.Fne[sel]) + np.abs(normal(m, d, R, meff).u_adh / d)).max() < 1e-7


# ------------------------------------------------------------------------------------------- simulator


@pytest.mark.simulator
def test_rerun_with_lmp(tmp_path):
    """A fresh, smaller run of the hertz_mindlin scene (60 + 60 particles) by Debian's lmp passes the same checks."""
    lmp = require_program("lmp", package="lammps")
    shutil.copy(SAMPLES / "hertz_mindlin" / "in.hertz_mindlin", tmp_path)
    subprocess.run(
        [lmp, "-in", "in.hertz_mindlin", "-var", "npour", "60", "-log", "none", "-echo", "none"],
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=120,
    )
    run = Run(tmp_path, "in.hertz_mindlin", npour="60")
    checked = check_run(run)
    assert len(checked) == 3 and sum(len(c.frame.pairs.i) for c in checked) > 50
    assert_pair_rows(checked)
    for c in checked:
        assert _rel(c.sums["F"], c.frame.atoms.f, c.sums["F_scale"]).max() < TOL
        kept = ~np.isnan(c.twist["rel"])
        assert c.twist["rel"][kept].max() < TOL
        for w in c.frame.walls:
            assert _rel(w.Fn_rebuilt, w.Fn_dumped, np.abs(w.Fne) + np.abs(w.Fdamp_s)).max(initial=0) < TOL
