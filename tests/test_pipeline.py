"""frame_tables: the per-frame computation the store receives."""

from __future__ import annotations

import demsplit as ds
import numpy as np
import pytest
from demsplit.compute import Options, frame_tables
from demsplit.frame import Box, Frame
from demsplit.results import Results

GPa = 1e9


def chain_frame(clump):
    """Three spheres in a row along x touching pairwise (1-2, 2-3), and sphere 1 on wall 0."""
    r = np.array([1e-3, 2e-3, 1.5e-3])
    delta = np.array([1e-6, 2e-6])
    x = np.array([0.0, r[0] + r[1] - delta[0], 0.0])
    x[2] = x[1] + r[1] + r[2] - delta[1]
    particles = {
        "id": np.array([10, 20, 30]),
        "type": np.array([1, 2, 1], np.int32),
        "x": x,
        "y": np.zeros(3),
        "z": np.full(3, 5e-3),
        "radius": r,
        "clump": np.asarray(clump),
    }
    contacts = {
        "id1": np.array([10, 20, 10]),
        "id2": np.array([20, 30, -1]),
        "wall": np.array([-1, -1, 0]),
        "delta": np.array([1e-6, 2e-6, 3e-6]),
        "nx": np.array([1.0, 1.0, 0.0]),
        "ny": np.zeros(3),
        "nz": np.array([0.0, 0.0, -1.0]),
        "x1": x[[0, 1, 0]],
        "y1": np.zeros(3),
        "z1": np.full(3, 5e-3),
        "r1": r[[0, 1, 0]],
        "r2": np.array([r[1], r[2], np.inf]),
    }
    scene = ds.Scene(
        {1: ds.Material(70 * GPa, 0.22), 2: ds.Material(3 * GPa, 0.35), 3: ds.Material(200 * GPa, 0.3)},
        model=ds.ContactModel("liggghts:hertz", {"tangential": "no_history"}),
        walls=[ds.Wall("floor", "plane", 3)],
    )
    return Frame(step=7, particles=particles, contacts=contacts, box=Box([-1, -1, -1], [1, 1, 1])), scene


def test_frame_tables_totals_and_comparison_splits():
    frame, scene = chain_frame([-1, -1, -1])
    t = frame_tables(frame, scene)
    e = ds.partition(frame.contacts, scene, frame.particles)
    total = e.u_n.sum()
    assert t["frames"]["u_n"][0] == pytest.approx(total, rel=1e-15)
    p = t["particles"]
    u = e.u_n
    # every split conserves the frame's energy; walls keep their part
    assert p["u"].sum() + t["walls"]["u"].sum() == pytest.approx(total, rel=1e-13)
    assert p["u_equal"].sum() == pytest.approx(total - 0.5 * u[2], rel=1e-13)  # the wall keeps half of its contact
    assert p["u_radius"].sum() == pytest.approx(total, rel=1e-13)  # against a plane the particle takes everything
    # 50/50: each particle gets half of each of its contacts' energy
    assert p["u_equal"][0] == pytest.approx(0.5 * u[0] + 0.5 * u[2], rel=1e-14)
    assert p["u_equal"][1] == pytest.approx(0.5 * u[0] + 0.5 * u[1], rel=1e-14)
    # radius split: body 1 takes r1/(r1 + r2)
    r = frame.particles["radius"]
    assert p["u_radius"][0] == pytest.approx(r[0] / (r[0] + r[1]) * u[0] + u[2], rel=1e-14)
    # no tangential spring in this model: said, not guessed
    assert any(note.startswith("u_t is 0: the contact law") for note in frame.notes)
    assert np.all(t["particles"]["u_t"] == 0)


def test_per_clump_sums_members():
    frame, scene = chain_frame([0, 0, -1])  # spheres 10 and 20 form clump 0, 30 is free
    t = frame_tables(frame, scene, Options(compare=False))
    res = Results.from_frames([t])
    clumps = res.per_clump()
    assert list(clumps["clump"]) == [0]
    p = res.particles.set_index("id")
    assert clumps["u"].iloc[0] == pytest.approx(p.loc[10, "u"] + p.loc[20, "u"], rel=1e-15)
    assert clumps["n_members"].iloc[0] == 2


@pytest.mark.parametrize("run", ["liggghts/packing/in.packing", "yade/cundall_periodic.h5"])
def test_particle_table_carries_the_positions_the_reader_gave(run):
    """x y z per particle and frame (m), so every export can be drawn where the particles are."""
    from pathlib import Path

    from demsplit.pipeline import analyze
    from demsplit.readers import open_run

    path = Path(__file__).resolve().parents[1] / "sample_dumps" / run
    res = analyze(path)
    with open_run(path) as r:
        frame = r.frame(len(r) - 1)
    got = res.particles[res.particles["step"] == frame.step]
    for c in ("id", "x", "y", "z"):
        np.testing.assert_array_equal(got[c].to_numpy(), frame.particles[c])
    assert res.particles.attrs["units"]["x"] == "m"
