"""Synthetic per-frame result tables, shaped like the pipeline's, for the
store, aggregate and report tests.

The tables are internally consistent: each contact's energy is split between
its two bodies by its shares, particle and wall energies are the sums of their
contacts' shares, so every frame conserves energy (to rounding), and the 50/50
and radius splits follow their definitions.
"""

from __future__ import annotations

import numpy as np


def synthetic_frame(
    step: int,
    *,
    n_particles: int = 60,
    n_pairs: int = 150,
    n_wall_contacts: int = 10,
    n_walls: int = 2,
    seed: int = 0,
    simulator_point: bool = True,
) -> dict[str, dict[str, np.ndarray]]:
    """One frame of tables as the pipeline hands them to ResultWriter.append."""
    rng = np.random.default_rng(seed * 1_000_003 + step)
    ids = np.arange(1, n_particles + 1, dtype=np.int64) * 10
    types = rng.integers(1, 3, n_particles).astype(np.int32)
    radius = np.where(types == 1, 1e-3, 2e-3) * rng.uniform(0.9, 1.1, n_particles)
    i1 = rng.integers(0, n_particles, n_pairs + n_wall_contacts)
    i2 = (i1 + rng.integers(1, n_particles, len(i1))) % n_particles
    is_wall = np.arange(len(i1)) >= n_pairs
    wall = np.where(is_wall, rng.integers(0, n_walls, len(i1)), -1).astype(np.int64)
    r1, r2 = radius[i1], np.where(is_wall, radius[i1], radius[i2])
    delta = rng.uniform(1e-7, 1e-5, len(i1))
    u_n = rng.lognormal(-14, 1.0, len(i1))
    u_t = rng.lognormal(-16, 1.0, len(i1))
    share_n1 = np.where(types[i1] == np.where(is_wall, 0, types[i2]), 0.5, rng.uniform(0.2, 0.8, len(i1)))
    share_t1 = share_n1 * 0.9 + 0.05
    u1 = share_n1 * u_n + share_t1 * u_t
    u2 = (1 - share_n1) * u_n + (1 - share_t1) * u_t
    depth1 = share_n1 * delta
    n = rng.normal(size=(len(i1), 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    x1 = rng.uniform(0, 0.05, (len(i1), 3))
    cp = x1 + (r1 - depth1)[:, None] * n
    contacts = {
        "step": np.full(len(i1), step, np.int64),
        "id1": ids[i1],
        "id2": np.where(is_wall, -1, ids[i2]),
        "wall": wall,
        "delta": delta,
        "u_n": u_n,
        "u_t": u_t,
        "share_n1": share_n1,
        "share_t1": share_t1,
        "u1": u1,
        "u2": u2,
        "depth1": depth1,
        "cpx": cp[:, 0],
        "cpy": cp[:, 1],
        "cpz": cp[:, 2],
    }
    if simulator_point:
        cp_sim = x1 + (r1 - delta * r2 / (r1 + r2))[:, None] * n  # radius-weighted point
        contacts.update(cpx_sim=cp_sim[:, 0], cpy_sim=cp_sim[:, 1], cpz_sim=cp_sim[:, 2])
    total = u_n + u_t
    pair = ~is_wall
    share_r = r1 / (r1 + r2)  # radius split: body 1 takes r1/(r1 + r2)
    u = np.bincount(i1, u1, n_particles) + np.bincount(i2[pair], u2[pair], n_particles)
    particles = {
        "step": np.full(n_particles, step, np.int64),
        "id": ids,
        "type": types,
        "radius": radius,
        "u": u,
        "u_n": np.bincount(i1, share_n1 * u_n, n_particles)
        + np.bincount(i2[pair], ((1 - share_n1) * u_n)[pair], n_particles),
        "u_t": np.bincount(i1, share_t1 * u_t, n_particles)
        + np.bincount(i2[pair], ((1 - share_t1) * u_t)[pair], n_particles),
        "u_equal": np.bincount(i1, 0.5 * total, n_particles) + np.bincount(i2[pair], 0.5 * total[pair], n_particles),
        "u_radius": np.bincount(i1, share_r * total, n_particles)
        + np.bincount(i2[pair], ((1 - share_r) * total)[pair], n_particles),
        "n_contacts": (np.bincount(i1, minlength=n_particles) + np.bincount(i2[pair], minlength=n_particles)),
    }
    w = wall[is_wall]
    walls = {
        "step": np.full(n_walls, step, np.int64),
        "wall": np.arange(n_walls, dtype=np.int64),
        "u": np.bincount(w, u2[is_wall], n_walls),
        "u_n": np.bincount(w, ((1 - share_n1) * u_n)[is_wall], n_walls),
        "u_t": np.bincount(w, ((1 - share_t1) * u_t)[is_wall], n_walls),
        "n_contacts": np.bincount(w, minlength=n_walls).astype(np.int64),
    }
    frames = {
        "step": np.array([step], np.int64),
        "time": np.array([step * 1e-6]),
        "n_particles": np.array([n_particles], np.int64),
        "n_contacts": np.array([n_pairs + n_wall_contacts], np.int64),
        "n_wall_contacts": np.array([n_wall_contacts], np.int64),
        "u_n": np.array([u_n.sum()]),
        "u_t": np.array([u_t.sum()]),
        "overlap_max_rel_error": np.array([-1.0]),
    }
    return {"particles": particles, "contacts": contacts, "walls": walls, "frames": frames}


WALLS_META = [
    {"wall": 0, "name": "floor", "kind": "plane", "type": 3},
    {"wall": 1, "name": "drum", "kind": "cylinder", "type": 3},
]

PROVENANCE = {
    "inputs": [{"path": "/data/run.dump", "size": 123, "blake3": "ab" * 32}],
    "options": {"tangential_rule": "mindlin", "split": "material"},
    "scene": {"materials": {"1": {"E": 1e7, "nu": 0.3}, "2": {"E": 5e7, "nu": 0.25}}},
    "model": {"law": "liggghts:hertz", "params": {"tangential": "history"}},
    "demsplit_version": "test",
}
