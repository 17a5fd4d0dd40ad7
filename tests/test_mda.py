"""The MDAnalysis bridge: MDAnalysis's LAMMPSDUMP reader against plain parsing,
and energies attached by particle id and usable in selections."""

from __future__ import annotations

import numpy as np
import pytest
from demsplit.errors import InputFormatError
from demsplit.mda import universe_with_energies
from demsplit.results import Results

LO = np.array([-0.02, 0.01, -0.005])
HI = np.array([0.03, 0.06, 0.045])


def write_dump(path, steps, n=40, seed=1, fmt="%.17g"):
    """A LIGGGHTS-like ``dump custom`` (trailing spaces, rows not in id order)
    with a box whose lower corner is not the origin. Returns {step: rows}."""
    rng = np.random.default_rng(seed)
    frames = {}
    with open(path, "w") as f:
        for step in steps:
            ids = rng.permutation(np.arange(1, n + 1) * 7)
            types = 1 + ids % 2
            x = rng.uniform(LO, HI, (n, 3))
            radius = np.where(types == 1, 1e-3, 2e-3)
            f.write(f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{n}\nITEM: BOX BOUNDS ff ff ff\n")
            for lo, hi in zip(LO, HI):
                f.write(f"{lo:g} {hi:g}\n")
            f.write("ITEM: ATOMS id type x y z radius \n")
            for i in range(n):
                f.write(f"{ids[i]} {types[i]} " + " ".join(fmt % v for v in x[i]) + f" {radius[i]:g} \n")
            frames[step] = {"id": ids, "type": types, "x": x, "radius": radius}
    return frames


def plain_parse(path, step):
    """Rows of frame ``step`` parsed with numpy alone: (ids, positions)."""
    lines = open(path).read().splitlines()
    k = next(i for i, line in enumerate(lines) if line == "ITEM: TIMESTEP" and int(lines[i + 1]) == step)
    n = int(lines[k + 3])
    rows = np.loadtxt(lines[k + 9 : k + 9 + n])
    return rows[:, 0].astype(np.int64), rows[:, 2:5]


def results_for(frames):
    tables = []
    for step, fr in frames.items():
        n = len(fr["id"])
        u = (fr["id"] * 1e-7) * (1 + fr["type"])  # distinct, id-dependent energies
        tables.append(
            {
                "particles": {
                    "step": np.full(n, step),
                    "id": fr["id"],
                    "type": fr["type"],
                    "radius": fr["radius"],
                    "u": u,
                    "u_n": 0.8 * u,
                    "u_t": 0.2 * u,
                    "u_equal": 1.1 * u,
                    "u_radius": 0.9 * u,
                    "n_contacts": fr["id"] % 5,
                },
                "frames": {
                    "step": np.array([step]),
                    "time": np.array([np.nan]),
                    "n_particles": np.array([n]),
                    "n_contacts": np.array([0]),
                    "n_wall_contacts": np.array([0]),
                    "u_n": np.array([0.0]),
                    "u_t": np.array([0.0]),
                    "overlap_max_rel_error": np.array([np.nan]),
                },
            }
        )
    return Results.from_frames(tables)


def test_lammpsdump_reader_agrees_with_plain_parsing(tmp_path):
    path = tmp_path / "atoms.dump"
    frames = write_dump(path, [0, 1000])
    res = results_for(frames)
    for step in (1000, 0):
        u = universe_with_energies(path, res, step)
        ids, x = plain_parse(path, step)
        order = np.argsort(ids)
        np.testing.assert_array_equal(u.atoms.ids, ids[order])
        assert u.atoms.positions.dtype == np.float32
        # float32 precision: x -> float32, minus lo, plus lo again: a few ulp of |x|
        tol = 4 * np.finfo(np.float32).eps * np.abs(x[order]).max()
        np.testing.assert_allclose(u.atoms.positions, x[order], rtol=0, atol=tol)
        # without restoring the origin MDAnalysis's positions are shifted by -lo
        raw = universe_with_energies(path, res, step, restore_origin=False)
        np.testing.assert_allclose(raw.atoms.positions, x[order] - LO, rtol=0, atol=tol)


def test_energies_attached_by_id_and_selectable(tmp_path):
    path = tmp_path / "atoms.dump"
    frames = write_dump(path, [0, 500])
    res = results_for(frames)
    u = universe_with_energies(path, res, 500)
    p = res.particles[res.particles["step"] == 500].set_index("id")
    np.testing.assert_array_equal(u.atoms.energies, p.loc[u.atoms.ids, "u"].to_numpy())
    np.testing.assert_array_equal(u.atoms.contact_counts, p.loc[u.atoms.ids, "n_contacts"].to_numpy())
    threshold = float(np.median(p["u"]))
    sel = u.select_atoms(f"type 2 and prop energy > {threshold!r}")
    expected = p.index[(p["type"] == 2) & (p["u"] > threshold)]
    assert len(expected) > 0
    np.testing.assert_array_equal(np.sort(sel.ids), np.sort(expected.to_numpy()))
    sel_n = u.select_atoms(f"prop energy_n <= {0.8 * threshold!r}")
    np.testing.assert_array_equal(np.sort(sel_n.ids), np.sort(p.index[0.8 * p["u"] <= 0.8 * threshold].to_numpy()))


def test_mismatched_ids_are_an_error(tmp_path):
    path = tmp_path / "atoms.dump"
    frames = write_dump(path, [0])
    frames[0]["id"] = frames[0]["id"] + 1  # results of another run
    with pytest.raises(InputFormatError, match="ids must match"):
        universe_with_energies(path, results_for(frames), 0)
    with pytest.raises(InputFormatError, match="no frame with timestep 7"):
        universe_with_energies(path, results_for(frames), 7)


@pytest.mark.parametrize("run", ["packing", "periodic"])
def test_real_liggghts_dump_agrees_with_demsplit_reader(samples, run):
    """MDAnalysis's LAMMPSDUMP reader and demsplit's own atom-dump reader agree on
    ids and positions of real LIGGGHTS 3.8.0 dumps (%g, rows in storage order), every frame.
    MDAnalysis holds float32 positions shifted by the box origin (added back here)."""
    import MDAnalysis as mda
    from demsplit.readers.lammps_dump import open_dump

    path = samples / "liggghts" / run / "atoms.txt"
    dump = open_dump(path)
    u = mda.Universe(str(path), format="LAMMPSDUMP", topology_format="LAMMPSDUMP")
    assert len(u.trajectory) == dump.n_frames
    for k, _ts in enumerate(u.trajectory):
        f = dump.frame(k, columns=["id", "x", "y", "z"])
        order = np.argsort(f.int_column("id"))
        np.testing.assert_array_equal(u.atoms.ids, f.int_column("id")[order])
        x = np.stack([f.columns[c] for c in "xyz"], axis=-1)[order]
        tol = 4 * np.finfo(np.float32).eps * np.abs(x).max()
        np.testing.assert_allclose(u.atoms.positions + f.box.lo, x, rtol=0, atol=tol)


def test_the_compressed_sample_dump_that_run_reads(samples):
    """``atoms_full.txt.gz``, the atom dump ``demsplit run`` reads of the packing sample: MDAnalysis reads it
    decompressed, and the box origin added back comes from the same decompressed text (it was read as raw
    gzip bytes: UnicodeDecodeError). Positions agree with demsplit's reader to float32, energies by id."""
    from demsplit.readers.lammps_dump import open_dump

    path = samples / "liggghts" / "packing" / "atoms_full.txt.gz"
    dump = open_dump(path)
    frames = {}
    for k in range(dump.n_frames):
        f = dump.frame(k, columns=["id", "type", "x", "y", "z", "radius"])
        frames[f.step] = {
            "id": f.int_column("id"),
            "type": f.int_column("type"),
            "radius": f.columns["radius"],
            "x": np.stack([f.columns[c] for c in "xyz"], axis=-1),
        }
    step = max(frames)
    u = universe_with_energies(path, results_for(frames), step)
    fr = frames[step]
    order = np.argsort(fr["id"])
    np.testing.assert_array_equal(u.atoms.ids, fr["id"][order])
    x = fr["x"][order]
    np.testing.assert_allclose(u.atoms.positions, x, rtol=0, atol=4 * np.finfo(np.float32).eps * np.abs(x).max())
    np.testing.assert_array_equal(u.atoms.energies, (fr["id"] * 1e-7 * (1 + fr["type"]))[order])
