"""The atoms' force and torque balance of a LAMMPS step, which pins the springs single() found at their limit.

A spring single() wrote at its Coulomb limit was rebuilt assuming the step capped it too
(:func:`demsplit.physics.laws._lammps.unsliding`); had the step not capped it, its force L lies below that root,
anywhere in (crit_s, L*]. No row says which: the atoms' balance does. Each atom's dumped force f satisfies
f = m g + sum of its contacts' step forces (verlet.cpp: pair, walls, gravity), and its torque the same with the
contacts' torques, the pairs' twisting torques tau n being unknowns (no dump holds them). :func:`close_balances`

1. verifies the force balance of every atom whose terms are all known (not a row the rebuild could not give, nor a
   possible jkr neck; a script with other forces than gravity and the granular walls verifies none);
2. solves, by least squares over the failing atoms, the force L of the capped rows on them (the step below its
   limit), and keeps a solution that closes every such atom with L in its interval; a capped row that no
   verifiable atom pins, or whose solution does not close, is unknown;
3. solves the pairs' twisting torques by least squares (conjugate gradients on the normal equations) over the
   atoms whose torque terms are known and verifies their torque balance; a rolling spring capped in single() on an
   atom that fails it, or on no verifiable atom, is unknown;
4. a verifiable atom whose force (torque) balance still does not close has a term that is not what the dumps and
   the script say (an MPI run's dmt rows, whose limit reads an unset variable on each process): the tangential and
   rolling (the rolling) springs of its pair contacts are unknown.

Every check is relative to the sum of the magnitudes of the atom's terms, within :data:`TOLERANCE`.
"""

from __future__ import annotations

import numpy as np

from ..physics.laws._lammps import R_BIT, T_BIT, Rebuilt, norm

TOLERANCE = 1e-9
"""Largest relative residual of an atom's balance (scale: the sum of the magnitudes of its terms)."""
CG_ITERATIONS = 2000
"""Most conjugate-gradient iterations of the twisting torques' least squares."""


def _sums(
    n_atoms: int, rows1: np.ndarray, rows2: np.ndarray, on1: np.ndarray, on2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per atom, the sum of the contacts' vectors (``on1`` on body 1, ``on2`` on body 2; a wall has no body 2) and
    the sum of their magnitudes; NaN where a term is unknown."""
    total, scale = np.zeros((n_atoms, 3)), np.zeros(n_atoms)
    pair = rows2 >= 0
    np.add.at(total, rows1, on1)
    np.add.at(total, rows2[pair], on2[pair])
    np.add.at(scale, rows1, norm(on1))
    np.add.at(scale, rows2[pair], norm(on2[pair]))
    return total, scale


def _bad_atoms(n_atoms: int, rows1: np.ndarray, rows2: np.ndarray, unknown: np.ndarray) -> np.ndarray:
    """Atoms with a term in an ``unknown`` contact."""
    bad = np.zeros(n_atoms, dtype=bool)
    bad[rows1[unknown]] = True
    bad[rows2[unknown & (rows2 >= 0)]] = True
    return bad


def _mark(r: Rebuilt, rows: np.ndarray, bit: int) -> None:
    """The springs ``bit`` of ``rows`` are unknown: single() capped them and no balance pinned them."""
    r.unknown[rows] |= bit
    r.why[rows] = np.where(r.why[rows] == 0, 3, r.why[rows])
    r.force[rows] = np.nan
    r.torque1[rows] = np.nan
    r.torque2[rows] = np.nan


def close_balances(a, gravity: tuple[float, float, float] | None) -> None:
    """Check the capped springs of an assembled step (:class:`.lammps_join.Assembled`) against its atoms' force
    and torque balance (module docstring), updating its rebuild in place; ``gravity`` None: the balance cannot be
    written (no gravity read, or other forces act), so every capped spring is unknown."""
    r, atoms = a.rebuilt, a.atoms
    if gravity is None:
        _mark(r, np.flatnonzero(r.interval_t), T_BIT)
        _mark(r, np.flatnonzero(r.interval_r), R_BIT)
        return
    n_L = -np.stack([a.contacts[c] for c in ("nx", "ny", "nz")], axis=-1)
    weight = atoms["m"][:, None] * np.asarray(gravity)[None, :]
    resolved = _close_forces(a, r, n_L, weight)
    open_forces = _unclosed(a, r, *_force_residuals(a, r, weight), T_BIT | R_BIT)
    open_torques = _close_torques(a, r, n_L)
    notes = []
    if resolved:
        notes.append(
            "springs that single() wrote at their limit but the step had not capped were pinned by the atoms' "
            "force balance"
        )
    if open_forces or open_torques:
        notes.append(
            "atoms whose force or torque balance does not close (a term of the step is not what the dumps "
            "and the script say): the springs of their pair contacts are not computed"
        )
    a.notes += notes


def _force_residuals(a, r: Rebuilt, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per atom: f - m g - the sum of its contacts' step forces, the sum of the terms' magnitudes, and whether
    every term is known."""
    n_atoms = len(a.atoms["r"])
    F, scale = _sums(n_atoms, a.rows1, a.rows2, r.force, -r.force)
    known = ~_bad_atoms(n_atoms, a.rows1, a.rows2, ~np.all(np.isfinite(r.force), axis=1))
    return a.atoms["f"] - weight - np.nan_to_num(F), scale + norm(weight), known


def _unclosed(a, r: Rebuilt, res: np.ndarray, scale: np.ndarray, known: np.ndarray, bits: int) -> int:
    """Step 4 of the module docstring: the springs ``bits`` of the pair contacts of every verifiable atom whose
    balance does not close are unknown (code 6); returns how many such atoms."""
    fails = known & (norm(res) > TOLERANCE * scale)
    if not fails.any():
        return 0
    pair = a.rows2 >= 0
    rows = np.flatnonzero(pair & (fails[a.rows1] | fails[np.maximum(a.rows2, 0)]))
    r.unknown[rows] |= bits
    r.why[rows] = np.where(r.why[rows] == 0, 6, r.why[rows])
    return int(fails.sum())


def _close_forces(a, r: Rebuilt, n_L: np.ndarray, weight: np.ndarray) -> int:
    """Step 1 and 2 of the module docstring; returns how many capped springs the balance moved."""
    rows1, rows2 = a.rows1, a.rows2
    res, scale, known = _force_residuals(a, r, weight)
    fails = known & (norm(res) > TOLERANCE * scale)
    capped = np.flatnonzero(r.interval_t)
    on_known = known[rows1[capped]] | ((rows2[capped] >= 0) & known[np.maximum(rows2[capped], 0)])
    _mark(r, capped[~on_known], T_BIT)
    capped = capped[on_known]
    candidates = capped[fails[rows1[capped]] | ((rows2[capped] >= 0) & fails[np.maximum(rows2[capped], 0)])]
    if not len(candidates):
        return 0
    involved = np.unique(np.concatenate([rows1[candidates], rows2[candidates][rows2[candidates] >= 0]]))
    involved = involved[known[involved]]
    where = {int(atom): k for k, atom in enumerate(involved)}
    A = np.zeros((3 * len(involved), len(candidates)))
    w = r.direction_t[candidates]
    for col, c in enumerate(candidates):
        for atom, sign in ((rows1[c], 1.0), (rows2[c], -1.0)):
            if atom >= 0 and int(atom) in where:
                A[3 * where[int(atom)] : 3 * where[int(atom)] + 3, col] = sign * w[col]
    dL = np.linalg.lstsq(A, res[involved].reshape(-1), rcond=None)[0]
    after = res[involved] - (A @ dL).reshape(-1, 3)
    L = r.spring_limit_t[candidates] + dL
    inside = (L >= r.limit_t[candidates] * (1.0 - 1e-9)) & (dL <= TOLERANCE * np.maximum(r.limit_t[candidates], 1e-300))
    closed = np.all(norm(after) <= TOLERANCE * scale[involved])
    if not (closed and inside.all()):
        _mark(r, candidates, T_BIT)
        return 0
    dF = dL[:, None] * w
    r.spring_t[candidates] += dF
    r.force[candidates] += dF
    nxd = np.cross(n_L[candidates], dF)
    r.torque1[candidates] -= r.arm1[candidates, None] * nxd
    r.torque2[candidates] -= r.arm2[candidates, None] * nxd
    return int(np.count_nonzero(np.abs(dL) > TOLERANCE * r.limit_t[candidates]))


def _close_torques(a, r: Rebuilt, n_L: np.ndarray) -> int:
    """Step 3 of the module docstring, then step 4 for the torques (the rolling springs); returns how many atoms'
    torque balance does not close."""
    atoms, rows1, rows2 = a.atoms, a.rows1, a.rows2
    n_atoms = len(atoms["r"])
    capped = np.flatnonzero(r.interval_r)
    T, scale = _sums(n_atoms, rows1, rows2, r.torque1, r.torque2)
    unknown = ~np.all(np.isfinite(r.torque1), axis=1)
    known = ~_bad_atoms(n_atoms, rows1, rows2, unknown)
    res = np.where(known[:, None], atoms["tq"] - np.nan_to_num(T), 0.0)
    twist = np.flatnonzero(r.twisting & ~unknown & (rows2 >= 0))
    tau = twisting_torques(res, rows1[twist], rows2[twist], n_L[twist], known)
    for atom, sign in ((rows1[twist], 1.0), (rows2[twist], -1.0)):
        np.add.at(res, atom, -sign * tau[:, None] * n_L[twist])
        np.add.at(scale, atom, np.abs(tau))
    fails = known & (norm(res) > TOLERANCE * scale)
    on_known = known[rows1[capped]] | ((rows2[capped] >= 0) & known[np.maximum(rows2[capped], 0)])
    on_fail = fails[rows1[capped]] | ((rows2[capped] >= 0) & fails[np.maximum(rows2[capped], 0)])
    _mark(r, capped[~on_known | on_fail], R_BIT)
    return _unclosed(a, r, res, scale, known, R_BIT)


def twisting_torques(res: np.ndarray, i: np.ndarray, j: np.ndarray, n: np.ndarray, known: np.ndarray) -> np.ndarray:
    """The twisting torques tau (tau n on atom i, -tau n on atom j) that best explain the torque residuals ``res``
    of the ``known`` atoms, by conjugate gradients on the normal equations (CGLS)."""
    if not len(i):
        return np.zeros(0)
    wi, wj = known[i].astype(float), known[j].astype(float)

    def apply(tau: np.ndarray) -> np.ndarray:
        out = np.zeros_like(res)
        np.add.at(out, i, (wi * tau)[:, None] * n)
        np.add.at(out, j, -(wj * tau)[:, None] * n)
        return out

    def adjoint(y: np.ndarray) -> np.ndarray:
        return wi * np.einsum("ij,ij->i", y[i], n) - wj * np.einsum("ij,ij->i", y[j], n)

    tau = np.zeros(len(i))
    rr = res.copy()
    s = adjoint(rr)
    p, gamma = s.copy(), s @ s
    floor = 1e-32 * max(gamma, 1e-300)
    best, best_norm, since = tau.copy(), np.sum(rr * rr), 0
    for _ in range(CG_ITERATIONS):  # rounding stalls the iteration near the solution: keep the best iterate
        if gamma <= floor or since > 50:
            break
        q = apply(p)
        alpha = gamma / max(np.sum(q * q), 1e-300)
        tau += alpha * p
        rr -= alpha * q
        s = adjoint(rr)
        gamma, old = s @ s, gamma
        p = s + (gamma / old) * p
        size = np.sum(rr * rr)
        if size < best_norm:
            best, best_norm, since = tau.copy(), size, 0
        else:
            since += 1
    return best
