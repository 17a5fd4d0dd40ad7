"""Speed against error: each way of getting a contact's numbers, each split, against the best answer.

Reference: the distribution law (materials, Mindlin tangential factor) on the
full-precision dumps of ``sample_dumps/liggghts/packing`` (``atoms_full``,
``pairs_full``, ``wall_full``: ``%.17g``, overlap from the dumped delta).
Ways of getting the numbers (particle-particle contacts; wall contacts are
left out of every variant and of the reference alike):

``delta %g``
    the default dumps (``%g``), overlap from the dumped ``delta`` column;
``positions %g``
    overlap recomputed from the ``%g`` positions, delta = r1 + r2 - |x2 - x1|
    (what ``--force-positions`` accepts without a delta column);
``positions full``
    overlap from the full-precision positions (delta column dropped);
``(2/5)|Fn| delta``
    normal energy from the dumped normal force and delta (``%g``) with no
    material data for the energy (Hertz: U = (2/5) F delta); no tangential
    energy (it needs kt, i.e. the materials), so its error includes the
    missing tangential part;
``float32``
    the ``delta %g`` arrays stored as float32 (and upcast for the arithmetic).

Splits: ``material`` (the distribution law), ``equal`` (50/50), ``radius``
(radius-weighted). For each pair: throughput (contacts/s of the energy law +
split + per-particle sums on arrays in memory, one core, best of several
repetitions), and the error against the reference:

* per contact: max over the two bodies of |u_b - u_b,ref| / (u_1,ref + u_2,ref);
* per particle: |u - u_ref| / u_ref (particles with u_ref > 0);
* per frame: |sum u - sum u_ref| / sum u_ref (the split does not change it);

as median, 95th percentile and maximum over all frames.

Run::

    python benchmarks/speed_vs_error.py [--sample sample_dumps/liggghts/packing] [--min-time 0.3]

``--big DIR`` adds the throughput (and the errors against ``delta %g``, the
best answer those dumps hold) on a run written by ``benchmarks/generate.py``.
"""

from __future__ import annotations

import argparse
from functools import partial
from pathlib import Path

import harness
import numpy as np
from demsplit.frame import ParticleIndex, take_rows
from demsplit.physics.bodies import FrameContacts
from demsplit.physics.partition import ContactLawEnergy, body_tables, law_energies, split_energies
from demsplit.readers.lammps_dump import open_dump
from demsplit.readers.liggghts import LiggghtsRun

SPLITS = ("material", "equal", "radius")
VARIANTS = ("delta %g", "positions %g", "positions full", "(2/5)|Fn| delta", "float32")


def pair_frames(run: LiggghtsRun) -> list[tuple[dict, dict]]:
    """(particle-particle contacts, particles) of every frame."""
    out = []
    for k in range(len(run)):
        f = run.frame(k)
        out.append((take_rows(f.contacts, f.contacts["wall"] < 0), f.particles))
    return out


def delta_from_positions(contacts: dict, particles: dict) -> dict:
    """The contacts with delta = r1 + r2 - |x2 - x1| from the particles' positions (m)."""
    index = ParticleIndex(particles["id"])
    xyz = np.stack([particles[c] for c in ("x", "y", "z")], axis=-1)
    d = xyz[index.rows(contacts["id2"])] - xyz[index.rows(contacts["id1"])]
    return {**contacts, "delta": contacts["r1"] + contacts["r2"] - np.sqrt(np.einsum("ij,ij->i", d, d))}


def normal_force(run: LiggghtsRun) -> list[np.ndarray]:
    """|Fn| (N) of every pair contact per frame, from the force_normal columns of the pair dump."""
    names = run._pair_names
    tokens = [names[c] for c in ("fnx", "fny", "fnz")]
    return [np.sqrt(sum(f.columns[t] ** 2 for t in tokens)) for f in open_dump(run.pairs.path).frames(tokens)]


def compute(variant: str, contacts: dict, particles: dict, scene, split: str, fn: np.ndarray | None):
    """Per-contact split and per-particle sums of one frame under ``variant``."""
    frame = FrameContacts(contacts, scene, particles)
    if variant == "(2/5)|Fn| delta":
        energies = ContactLawEnergy(np.stack([0.4 * fn * np.maximum(contacts["delta"], 0.0), np.zeros(len(fn))]))
    else:
        energies = law_energies(frame)
    e = split_energies(frame, energies, split=split)
    return e, body_tables(frame, e, n_walls=len(scene.walls))[0]


def timed(f, min_time: float) -> float:
    """Best time of one call of ``f``, repeating for at least ``min_time`` seconds,
    after one untimed call (the first call loads numba's cached kernels)."""
    f()
    return harness.best_of(f, 1, min_time)


def stats(x: np.ndarray) -> tuple[float, float, float]:
    x = np.asarray(x)
    return (float(np.median(x)), float(np.percentile(x, 95)), float(np.max(x))) if x.size else (np.nan,) * 3


def study(frames: dict[str, list], reference: list, scene, fns, min_time: float) -> list[dict]:
    rows = []
    ref_results = [compute("delta %g", c, p, scene, "material", None) for c, p in reference]
    for variant, vframes in frames.items():
        for split in SPLITS:
            per_contact, per_part, per_frame, n_total, t_total = [], [], [], 0, 0.0
            for k, ((c, p), (er, pr)) in enumerate(zip(vframes, ref_results)):
                if not (
                    np.array_equal(c["id1"], reference[k][0]["id1"])
                    and np.array_equal(c["id2"], reference[k][0]["id2"])
                ):
                    raise SystemExit(f"frame {k}: contacts of {variant!r} are not in the reference's order")
                fn = fns[k]
                e, pt = compute(variant, c, p, scene, split, fn)
                total_ref = er.u1 + er.u2
                ok = total_ref > 0
                per_contact.append(np.maximum(np.abs(e.u1 - er.u1), np.abs(e.u2 - er.u2))[ok] / total_ref[ok])
                has = pr["u"] > 0
                per_part.append(np.abs(pt["u"] - pr["u"])[has] / pr["u"][has])
                per_frame.append(abs(pt["u"].sum() - pr["u"].sum()) / pr["u"].sum())
                t_total += timed(partial(compute, variant, c, p, scene, split, fn), min_time)
                n_total += len(c["delta"])
            rows.append(
                {
                    "variant": variant,
                    "split": split,
                    "contacts_per_s": n_total / t_total,
                    "contact": stats(np.concatenate(per_contact)),
                    "particle": stats(np.concatenate(per_part)),
                    "frame": stats(per_frame),
                }
            )
    return rows


def variants(script: Path, default: dict, full: dict | None, min_time: float) -> tuple[dict, list, object, list]:
    """Frames of every variant; the reference frames (full precision, or ``delta %g``)."""
    run = LiggghtsRun(script, **default, force_positions=True)
    g = pair_frames(run)
    frames = {"delta %g": g, "positions %g": [(delta_from_positions(c, p), p) for c, p in g]}
    if full is not None:
        ref = pair_frames(LiggghtsRun(script, **full))
        frames["positions full"] = [(delta_from_positions(c, p), p) for c, p in ref]
    else:
        ref = g
    frames["(2/5)|Fn| delta"] = g
    frames["float32"] = [
        (
            {k: v.astype(np.float32) if v.dtype == np.float64 else v for k, v in c.items()},
            {k: v.astype(np.float32) if v.dtype == np.float64 else v for k, v in p.items()},
        )
        for c, p in g
    ]
    return frames, ref, run.scene, normal_force(run)


def print_table(title: str, rows: list[dict]) -> None:
    print(title)
    print(
        f"{'variant':18s} {'split':9s} {'Mcontacts/s':>11s} | {'per contact: median':>19s} {'p95':>9s} {'max':>9s} | "
        f"{'per particle: median':>20s} {'p95':>9s} {'max':>9s} | {'frame total: max':>16s}"
    )
    for r in rows:
        c, p, f = r["contact"], r["particle"], r["frame"]
        print(
            f"{r['variant']:18s} {r['split']:9s} {r['contacts_per_s'] / 1e6:11.2f} | {c[0]:19.2e} {c[1]:9.2e} "
            f"{c[2]:9.2e} | {p[0]:20.2e} {p[1]:9.2e} {p[2]:9.2e} | {f[2]:16.2e}"
        )
    print()


def main(argv: list[str] | None = None) -> None:
    repo = Path(__file__).resolve().parent.parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sample", type=Path, default=repo / "sample_dumps" / "liggghts" / "packing")
    ap.add_argument("--big", type=Path, help="a directory written by benchmarks/generate.py")
    ap.add_argument("--min-time", type=float, default=0.3, help="seconds of repetitions per timing")
    a = ap.parse_args(argv)
    print("machine:", harness.machine())
    s = a.sample
    frames, ref, scene, fns = variants(
        s / "in.packing",
        {"atoms": s / "atoms.txt", "contacts": s / "pairs.txt", "walls": s / "wall.txt"},
        {"atoms": s / "atoms_full.txt.gz", "contacts": s / "pairs_full.txt.gz", "walls": s / "wall_full.txt.gz"},
        a.min_time,
    )
    n = sum(len(c["delta"]) for c, _ in ref)
    print_table(
        f"{s.name}: {len(ref)} frames, {n} particle-particle contacts; reference: full-precision dumps, "
        "distribution law",
        study(frames, ref, scene, fns, a.min_time),
    )
    if a.big:
        frames, ref, scene, fns = variants(a.big / "in.bench", {}, None, a.min_time)
        n = sum(len(c["delta"]) for c, _ in ref)
        print_table(
            f"{a.big}: {len(ref)} frames, {n} contacts; reference: delta %g, distribution law "
            "(these dumps hold no full precision)",
            study(frames, ref, scene, fns, 0.0),
        )


if __name__ == "__main__":
    main()
