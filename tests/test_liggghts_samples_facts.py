"""Facts about LIGGGHTS 3.8.0 output, checked on the committed sample runs.

These tests read ``sample_dumps/liggghts/`` with plain numpy (not demsplit's readers) and
pin down what ``docs/liggghts-output.md`` claims: the 41-column layout of
``compute pair/gran/local`` and ``compute wall/gran/local``, force completeness, the
``delta`` column, contact uniqueness, the periodic flag, the binary layout, and the
closed-form Hertz stacks. One simulator test regenerates a tiny packing.
"""

from __future__ import annotations

import gzip
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts"

GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2, `fix gravity 9.81 vector 0 0 -1`
YOUNG = np.array([1.0e8, 1.0e7, 5.0e8, 2.0e8])  # Pa, types 1..4
POISSON = np.array([0.25, 0.40, 0.30, 0.28])
FLOOR_TYPE = 4
ATOM_COLUMNS = "id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass".split()

# 0-based column slices of the 41-column local dumps (all keywords but heatFlux, ms_id).
POS1, POS2 = slice(0, 3), slice(3, 6)
VEL1, VEL2 = slice(6, 9), slice(9, 12)
ID1, ID2, PERIODIC = 12, 13, 14  # wall rows: mesh index, triangle id, particle id
FORCE, FORCE_N, FORCE_T = slice(15, 18), slice(18, 21), slice(21, 24)
TORQUE, TORQUE_N, TORQUE_T = slice(24, 27), slice(27, 30), slice(30, 33)
HISTORY, AREA, DELTA, CONTACT_POINT = slice(33, 36), 36, 37, slice(38, 41)
N_LOCAL_COLUMNS = 41

TIMESTEP = {"packing": 2e-6, "periodic": 2e-6, "analytic": 1e-6}  # s

# Relative rounding of one printed value: %g keeps 6 significant digits (half a unit in
# the 6th digit is <= 5e-6 relative); %.17g round-trips the double.
ROUNDING = {"%g": 5e-6, "full": 1e-15}
# Force balance in the setup frame, relative to Σ|terms| of the particle. Full precision:
# a periodic pair is evaluated twice (newton off), once per side, each time with a ghost
# image whose coordinates carry their own rounding (~1e-18 m against δ ~ 1e-6 m), while
# the dump lists one side only; measured 3.1e-13 in periodic/, 1.4e-15 in packing/.
BALANCE_TOL = {"%g": 10 * ROUNDING["%g"], "full": 1e-11}


@dataclass
class DumpFrame:
    step: int
    label: str  # 'ATOMS', 'ENTRIES', 'CONTACTS', ...
    box_flags: list[str]
    bounds: np.ndarray  # (3, 2)
    columns: list[str]
    data: np.ndarray  # (rows, columns) float64
    header_line: str


def read_text_dump(path: Path) -> list[DumpFrame]:
    """All frames of a LAMMPS text dump (atom or local, optionally gzip-compressed)."""
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "rt") as fh:
        lines = fh.read().split("\n")
    frames, i = [], 0
    while i < len(lines) and lines[i].startswith("ITEM: TIMESTEP"):
        n = int(lines[i + 3])
        columns_line = lines[i + 8]
        label, *columns = columns_line[len("ITEM: ") :].split()
        block = lines[i + 9 : i + 9 + n]
        data = np.loadtxt(block, ndmin=2) if n else np.zeros((0, len(columns)))
        frames.append(
            DumpFrame(
                step=int(lines[i + 1]),
                label=label,
                box_flags=lines[i + 4].split()[3:],
                bounds=np.loadtxt(lines[i + 5 : i + 8]),
                columns=columns,
                data=data,
                header_line=columns_line,
            )
        )
        i += 9 + n
    return frames


def read_binary_dump(path: Path) -> list[dict]:
    """Frames of a LAMMPS binary ``dump custom`` (native little-endian on this machine)."""
    raw = path.read_bytes()
    frames, off = [], 0

    def take(dtype, count):
        nonlocal off
        out = np.frombuffer(raw, dtype, count, off)
        off += out.nbytes
        return out

    while off < len(raw):
        step, natoms = take(np.int64, 2)
        triclinic = int(take(np.int32, 1)[0])
        boundary = take(np.int32, 6)
        box = take(np.float64, 9 if triclinic else 6)
        ncols, nchunks = take(np.int32, 2)
        chunks = [take(np.float64, int(take(np.int32, 1)[0])) for _ in range(nchunks)]
        data = np.concatenate(chunks).reshape(-1, ncols)
        frames.append(
            dict(step=int(step), natoms=int(natoms), triclinic=triclinic, boundary=boundary, box=box, data=data)
        )
    return frames


def full(scene: str, name: str) -> Path:
    """Full-precision dump of a scene: gzip-compressed in packing/ and periodic/."""
    plain = SAMPLES / scene / f"{name}_full.txt"
    return plain if plain.exists() else plain.with_name(plain.name + ".gz")


def dump_path(scene: str, name: str, precision: str) -> Path:
    return full(scene, name) if precision == "full" else SAMPLES / scene / f"{name}.txt"


def row_index(atom_ids: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """Rows of the atom table holding particles ``ids`` (ids written as doubles)."""
    assert np.all(ids == np.round(ids)), "ids must be integers"
    lookup = np.full(int(atom_ids.max()) + 1, -1)
    lookup[atom_ids.astype(int)] = np.arange(len(atom_ids))
    rows = lookup[ids.astype(int)]
    assert np.all(rows >= 0), "contact names a particle missing from the atom dump"
    return rows


def minimum_image(dx: np.ndarray, frame: DumpFrame) -> np.ndarray:
    """Shortest periodic image of separation vectors ``dx`` (rows) in the frame's box."""
    length = frame.bounds[:, 1] - frame.bounds[:, 0]
    periodic = np.array([flag == "pp" for flag in frame.box_flags])
    return dx - periodic * length * np.round(dx / length)


def touches_primitive_wall(x: np.ndarray, r: np.ndarray, scene: str) -> np.ndarray:
    """Particles within reach of packing/'s primitive walls (never in any dump).

    The reach is padded by 1e-6 m, ten times the %g rounding step of the positions, so
    that a particle barely touching a wall is excluded also when read from the %g dump.
    """
    if scene != "packing":
        return np.zeros(len(r), bool)
    r = r + 1e-6
    planes = (np.abs(np.abs(x[:, 0]) - 0.02) < r) | (np.abs(np.abs(x[:, 1]) - 0.02) < r)
    post = np.abs(np.hypot(x[:, 0], x[:, 1]) - 0.004) < r
    return planes | post


def plane_strain_modulus_pair(t1: np.ndarray, t2: np.ndarray) -> np.ndarray:
    """Y* = 1/[(1-nu1^2)/E1 + (1-nu2^2)/E2] (Pa) for 1-based types."""
    c = (1 - POISSON**2) / YOUNG
    return 1 / (c[t1 - 1] + c[t2 - 1])


SCENES = ["packing", "periodic"]


# ---------------------------------------------------------------------------- headers


@pytest.mark.parametrize("scene", SCENES)
def test_headers_labels_and_trailing_spaces(scene):
    atoms = read_text_dump(SAMPLES / scene / "atoms.txt")
    pairs = read_text_dump(SAMPLES / scene / "pairs.txt")
    walls = read_text_dump(SAMPLES / scene / "wall.txt")
    assert atoms[0].label == "ATOMS" and atoms[0].columns == ATOM_COLUMNS
    # dump_modify label CONTACTS renames both "NUMBER OF ..." and the column item.
    text = (SAMPLES / scene / "pairs.txt").read_text()
    assert "ITEM: NUMBER OF CONTACTS\n" in text and "ENTRIES" not in text
    assert pairs[0].label == "CONTACTS"
    assert walls[0].label == "ENTRIES"
    assert pairs[0].columns == [f"c_cpgl[{k}]" for k in range(1, N_LOCAL_COLUMNS + 1)]
    assert walls[0].columns == [f"c_cwgl[{k}]" for k in range(1, N_LOCAL_COLUMNS + 1)]
    for path in ("atoms.txt", "pairs.txt", "wall.txt"):
        lines = (SAMPLES / scene / path).read_text().split("\n")
        item_columns = [ln for ln in lines if ln.startswith(("ITEM: ATOMS", "ITEM: CONTACTS", "ITEM: ENTRIES"))]
        data_lines = lines[9:12]
        assert all(ln.endswith(" ") for ln in item_columns + data_lines)
        assert not lines[0].endswith(" ")  # "ITEM: TIMESTEP" has none
    expected_flags = ["pp", "pp", "ff"] if scene == "periodic" else ["ff", "ff", "ff"]
    assert all(f.box_flags == expected_flags for f in atoms + pairs + walls)


@pytest.mark.parametrize("scene", SCENES)
def test_full_precision_dumps_hold_the_same_values(scene):
    """%g and %.17g dumps of one quantity agree to 6 significant digits, row by row."""
    for name in ("atoms", "pairs", "wall"):
        coarse = read_text_dump(SAMPLES / scene / f"{name}.txt")
        fine = read_text_dump(full(scene, name))
        assert [f.step for f in coarse] == [f.step for f in fine]
        for c, f in zip(coarse, fine):
            assert c.data.shape == f.data.shape
            np.testing.assert_allclose(c.data, f.data, rtol=ROUNDING["%g"], atol=1e-300)
            assert not np.array_equal(c.data, f.data)  # the full dump really has more digits


@pytest.mark.parametrize("scene", SCENES)
def test_binary_dump_layout_and_values(scene):
    """The .bin atom dump parses with the documented layout and equals the %.17g text."""
    binary = read_binary_dump(SAMPLES / scene / "atoms.bin")
    text = read_text_dump(full(scene, "atoms"))
    assert [b["step"] for b in binary] == [t.step for t in text]
    periodic = scene == "periodic"
    for b, t in zip(binary, text):
        assert b["triclinic"] == 0
        # boundary codes per axis (lo, hi): 0 = p, 1 = f
        assert b["boundary"].tolist() == ([0, 0, 0, 0, 1, 1] if periodic else [1] * 6)
        assert b["box"].tolist() == t.bounds.ravel().tolist()
        assert b["natoms"] == len(t.data)
        assert np.array_equal(b["data"], t.data)


# ---------------------------------------------------------------- completeness (a)


def force_balance(scene: str, precision: str):
    """Per frame: (atom f, Σ dumped forces + m g, Σ |terms|, excluded) for every particle."""
    atoms = read_text_dump(dump_path(scene, "atoms", precision))
    pairs = read_text_dump(dump_path(scene, "pairs", precision))
    walls = read_text_dump(dump_path(scene, "wall", precision))
    for a, p, w in zip(atoms, pairs, walls, strict=True):
        assert a.step == p.step == w.step
        ids, x, f = a.data[:, 0], a.data[:, 2:5], a.data[:, 8:11]
        r, m = a.data[:, 14], a.data[:, 15]
        n = len(ids)
        i1, i2 = row_index(ids, p.data[:, ID1]), row_index(ids, p.data[:, ID2])
        iw = row_index(ids, w.data[:, ID2 + 1])
        total = m[:, None] * GRAVITY
        for k in range(3):
            total[:, k] += (
                np.bincount(i1, p.data[:, FORCE][:, k], n)
                - np.bincount(i2, p.data[:, FORCE][:, k], n)
                + np.bincount(iw, w.data[:, FORCE][:, k], n)
            )
        pair_mag = np.linalg.norm(p.data[:, FORCE], axis=1)
        scale = (
            m * 9.81
            + np.linalg.norm(f, axis=1)
            + np.bincount(i1, pair_mag, n)
            + np.bincount(i2, pair_mag, n)
            + np.bincount(iw, np.linalg.norm(w.data[:, FORCE], axis=1), n)
        )
        yield a.step, f, total, scale, touches_primitive_wall(x, r, scene)


@pytest.mark.parametrize("precision", ["%g", "full"])
@pytest.mark.parametrize("scene", SCENES)
def test_contact_forces_add_up_to_atom_force(scene, precision):
    """Σ pair forces (+ on id1, − on id2) + mesh-wall forces + m g = atom f.

    Exact (to the printed precision) in the first frame, written at the setup of the
    output run, where LIGGGHTS has just recomputed the forces from the dumped x and v.
    Frames written mid-run differ by the damping term only: the atom f was computed
    with the half-step velocity, the compute re-evaluates it with the end-of-step v
    (with coefficientRestitution 1 the mismatch drops to 1e-14 N, docs/liggghts-output.md).
    """
    frames = list(force_balance(scene, precision))
    assert len(frames) == 3
    for k, (step, f, total, scale, excluded) in enumerate(frames):
        err = np.abs(total - f).max(axis=1) / scale
        assert (~excluded).sum() > 0.5 * len(f)
        if k == 0:
            assert err[~excluded].max() < BALANCE_TOL[precision], step
        else:
            assert err[~excluded].max() < 0.05, step
        if excluded.any():  # primitive-wall forces are missing from the dumps
            assert err[excluded].max() > 0.1


def test_analytic_forces_balance_exactly():
    ((_, f, total, scale, _),) = force_balance("analytic", "full")
    assert np.abs(f).max() < 1e-15  # at rest the net force vanishes (to rounding)
    assert (np.abs(total - f).max(axis=1) / scale).max() < 1e-13


# ------------------------------------------------------------ pair layout, (b), (c)


@pytest.mark.parametrize("scene", SCENES + ["analytic"])
def test_pair_columns_follow_the_documented_layout(scene):
    atoms = read_text_dump(full(scene, "atoms"))
    pairs = read_text_dump(full(scene, "pairs"))
    for a, p in zip(atoms, pairs, strict=True):
        ids, x, v, r = a.data[:, 0], a.data[:, 2:5], a.data[:, 5:8], a.data[:, 14]
        d = p.data
        i1, i2 = row_index(ids, d[:, ID1]), row_index(ids, d[:, ID2])
        # pos / vel: both particles, positions wrapped into the box as in the atom dump
        np.testing.assert_array_equal(d[:, POS1], x[i1])
        np.testing.assert_allclose(d[:, POS2], x[i2], rtol=0, atol=1e-17)
        np.testing.assert_array_equal(d[:, VEL1], v[i1])
        ghost = d[:, PERIODIC] == 1
        np.testing.assert_array_equal(d[~ghost, VEL2], v[i2[~ghost]])
        # A periodic ghost keeps the velocity communicated before the step's force call:
        # the half-step v − (dt/2) f/m in frames written mid-run; v in the setup frame.
        half_step = v - TIMESTEP[scene] / 2 * a.data[:, 8:11] / a.data[:, 15:16]
        expected = v if a.step == atoms[0].step else half_step
        np.testing.assert_allclose(d[ghost, VEL2], expected[i2[ghost]], rtol=1e-12, atol=1e-20)
        # (b) delta = r1 + r2 − |x1 − x2| with the minimum image, to full precision
        sep = minimum_image(x[i1] - x[i2], a)
        dist = np.linalg.norm(sep, axis=1)
        delta = r[i1] + r[i2] - dist
        assert np.all(d[:, DELTA] > 0)  # only touching pairs are listed
        np.testing.assert_allclose(d[:, DELTA], delta, rtol=1e-10, atol=1e-18)
        # contactPoint: radius-weighted, with the unwrapped image of particle 2
        x2_image = x[i1] - sep
        cp = (x[i1] * r[i2, None] + x2_image * r[i1, None]) / (r[i1] + r[i2])[:, None]
        np.testing.assert_allclose(d[:, CONTACT_POINT], cp, rtol=0, atol=1e-17)
        # force = force_normal + force_tangential; force_normal along e_n, repulsive on id1
        e_n = sep / dist[:, None]  # from particle 2 to particle 1
        np.testing.assert_allclose(d[:, FORCE], d[:, FORCE_N] + d[:, FORCE_T], rtol=0, atol=1e-18)
        fn = np.einsum("ij,ij->i", d[:, FORCE_N], e_n)
        assert np.all(fn > 0)
        np.testing.assert_allclose(d[:, FORCE_N], fn[:, None] * e_n, rtol=0, atol=1e-12 * np.abs(d[:, FORCE_N]).max())
        # torque on id1 = −(r1 − δ/2) e_n × F_t, not divided by a radius
        torque = -(r[i1] - d[:, DELTA] / 2)[:, None] * np.cross(e_n, d[:, FORCE_T])
        np.testing.assert_allclose(d[:, TORQUE], torque, rtol=0, atol=1e-12 * max(np.abs(torque).max(), 1e-300))
        np.testing.assert_allclose(d[:, TORQUE_N] + d[:, TORQUE_T], d[:, TORQUE], rtol=0, atol=1e-30)
        # history = shear displacement, perpendicular to e_n
        shear = d[:, HISTORY]
        assert np.abs(np.einsum("ij,ij->i", shear, e_n)).max() <= 1e-12 * max(np.abs(shear).max(), 1e-300)
        # contactArea = lens area πa² (≈ 2π R* δ, twice the Hertz area πR*δ)
        lens = (
            -np.pi
            / 4
            * ((dist - r[i1] - r[i2]) * (dist + r[i1] - r[i2]) * (dist - r[i1] + r[i2]) * (dist + r[i1] + r[i2]))
            / dist**2
        )
        np.testing.assert_allclose(d[:, AREA], lens, rtol=1e-9)


@pytest.mark.parametrize("scene", SCENES + ["analytic"])
def test_each_contact_listed_once(scene):
    """(c) one row per contact; periodic-image rows (flag 1) have id1 > id2."""
    for p in read_text_dump(full(scene, "pairs")):
        ids = p.data[:, [ID1, ID2]]
        unordered = np.sort(ids, axis=1)
        assert len(np.unique(unordered, axis=0)) == len(ids)
        assert np.all(ids[:, 0] != ids[:, 1])
        flagged = p.data[:, PERIODIC] == 1
        assert set(np.unique(p.data[:, PERIODIC])) <= {0.0, 1.0}
        assert np.all(ids[flagged, 0] > ids[flagged, 1])
        if scene == "periodic":
            assert flagged.sum() > 10
            # on those rows the naive difference of the (wrapped) pos columns is a box length off
            naive = np.linalg.norm(p.data[flagged, POS1] - p.data[flagged, POS2], axis=1)
            assert np.all(naive > 0.012)
        else:
            assert not flagged.any()
        for w in read_text_dump(full(scene, "wall")):
            assert len(np.unique(w.data[:, ID2 + 1])) == len(w.data)  # one row per particle here


def test_g_format_loses_the_overlap_but_not_the_delta_column():
    """%g positions give δ to ~1 % only; the %g delta column keeps 6 digits."""
    atoms = read_text_dump(SAMPLES / "packing" / "atoms.txt")[0]
    pairs = read_text_dump(SAMPLES / "packing" / "pairs.txt")[0]
    exact = read_text_dump(full("packing", "pairs"))[0].data[:, DELTA]
    ids, x, r = atoms.data[:, 0], atoms.data[:, 2:5], atoms.data[:, 14]
    i1, i2 = row_index(ids, pairs.data[:, ID1]), row_index(ids, pairs.data[:, ID2])
    from_positions = r[i1] + r[i2] - np.linalg.norm(x[i1] - x[i2], axis=1)
    rel_positions = np.abs(from_positions - exact) / exact
    rel_column = np.abs(pairs.data[:, DELTA] - exact) / exact
    assert rel_column.max() <= ROUNDING["%g"]
    assert np.median(rel_positions) > 1e-3 and rel_positions.max() > 0.1


# ---------------------------------------------------------------------- wall layout


@pytest.mark.parametrize("scene", SCENES + ["analytic"])
def test_wall_columns_follow_the_documented_layout(scene):
    """Mesh-wall rows of compute wall/gran/local against the atoms and the flat STL floor."""
    half, grid = {"packing": (0.022, 4), "periodic": (0.012, 4), "analytic": (0.009, 3)}[scene]
    atoms = read_text_dump(full(scene, "atoms"))
    walls = read_text_dump(full(scene, "wall"))
    for a, w in zip(atoms, walls, strict=True):
        ids, x, v, r = a.data[:, 0], a.data[:, 2:5], a.data[:, 5:8], a.data[:, 14]
        d = w.data
        assert len(d) > 0
        iw = row_index(ids, d[:, ID2 + 1])
        xp = x[iw]
        # pos: contact point on the wall (the centre projected on z = 0), then the centre
        np.testing.assert_array_equal(d[:, 0:2], xp[:, 0:2])
        assert np.all(d[:, 2] == 0.0)
        np.testing.assert_array_equal(d[:, POS2], xp)
        # vel: wall velocity (0, fixed mesh), then particle velocity
        assert np.all(d[:, VEL1] == 0.0)
        np.testing.assert_array_equal(d[:, VEL2], v[iw])
        # id: mesh index in `meshes` (0-based), triangle id (0-based, STL order), particle id
        assert np.all(d[:, ID1] == 0)
        step = 2 * half / grid
        col = np.floor((xp[:, 0] + half) / step)
        row = np.floor((xp[:, 1] + half) / step)
        upper = (xp[:, 1] + half - row * step) > (xp[:, 0] + half - col * step)
        np.testing.assert_array_equal(d[:, ID2], 2 * (grid * col + row) + upper)
        # delta = r − d and contactArea = π(r² − d²), d = distance from the centre to the wall
        np.testing.assert_allclose(d[:, DELTA], r[iw] - xp[:, 2], rtol=0, atol=1e-19)
        np.testing.assert_allclose(d[:, AREA], np.pi * (r[iw] ** 2 - xp[:, 2] ** 2), rtol=1e-12)
        # force_normal along the wall normal (z); contactPoint is not written (zeros)
        assert np.all(d[:, FORCE_N][:, :2] == 0) and np.all(d[:, FORCE_N][:, 2] > 0)
        np.testing.assert_allclose(d[:, FORCE], d[:, FORCE_N] + d[:, FORCE_T], rtol=0, atol=1e-18)
        assert np.all(d[:, CONTACT_POINT] == 0.0)


# ------------------------------------------------------------------- closed form


def test_analytic_closed_form():
    """At rest each contact carries the weight above it: δ = (3F/(4 Y* √R*))^(2/3)."""
    (atoms,) = read_text_dump(SAMPLES / "analytic" / "atoms_full.txt")
    (pairs,) = read_text_dump(SAMPLES / "analytic" / "pairs_full.txt")
    (walls,) = read_text_dump(SAMPLES / "analytic" / "wall_full.txt")
    ids, types = atoms.data[:, 0].astype(int), atoms.data[:, 1].astype(int)
    r, m = atoms.data[:, 14], atoms.data[:, 15]
    assert ids.tolist() == [1, 2, 3, 4, 5]  # dump_modify sort id
    above = {1: [1, 2, 3], 2: [2, 3], 3: [3], 4: [4, 5], 5: [5]}  # id -> itself and the spheres it carries
    weight = {i: 9.81 * m[np.array(above[i]) - 1].sum() for i in above}
    support = {2: 1, 3: 2, 5: 4}  # id -> the sphere it rests on

    rows = {tuple(sorted(map(int, row[[ID1, ID2]]))): row for row in pairs.data}
    assert set(rows) == {(1, 2), (2, 3), (4, 5)}
    for upper, lower in support.items():
        row = rows[(lower, upper)]
        force = weight[upper]
        r_eff = r[upper - 1] * r[lower - 1] / (r[upper - 1] + r[lower - 1])
        y_eff = plane_strain_modulus_pair(types[upper - 1], types[lower - 1])
        delta = (3 * force / (4 * y_eff * np.sqrt(r_eff))) ** (2 / 3)
        np.testing.assert_allclose(row[DELTA], delta, rtol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(row[FORCE_N]), force, rtol=1e-12)
    for row in walls.data:
        pid = int(row[ID2 + 1])
        assert pid in (1, 4)
        force = weight[pid]
        y_eff = plane_strain_modulus_pair(types[pid - 1], FLOOR_TYPE)
        delta = (3 * force / (4 * y_eff * np.sqrt(r[pid - 1]))) ** (2 / 3)  # wall: R* = r
        np.testing.assert_allclose(row[DELTA], delta, rtol=1e-9)
        np.testing.assert_allclose(row[FORCE][2], force, rtol=1e-12)


# --------------------------------------------------------------------- simulator


@pytest.mark.slow
@pytest.mark.simulator
def test_tiny_packing_writes_the_expected_dumps(liggghts, tmp_path):
    """Run in.packing with 60 particles and a short settle; check every dump's headers."""
    for name in ("in.packing", "floor.stl"):
        shutil.copy(SAMPLES / "packing" / name, tmp_path / name)
    result = subprocess.run(
        [
            "stdbuf",
            "-o0",
            "-e0",
            liggghts,
            "-in",
            "in.packing",
            "-echo",
            "none",
            "-log",
            "none",
            "-var",
            "nparticles",
            "60",
            "-var",
            "nsettle",
            "40000",
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stdout[-2000:]
    steps = [42000, 44000]  # every 2000 after a settle of 40000 steps (40000 is written too)
    atoms = read_text_dump(tmp_path / "atoms.txt")
    assert [f.step for f in atoms] == [40000] + steps
    assert all(f.columns == ATOM_COLUMNS and len(f.data) == 60 for f in atoms)
    pairs = read_text_dump(tmp_path / "pairs.txt")
    assert [f.label for f in pairs] == ["CONTACTS"] * 3
    assert all(f.columns == [f"c_cpgl[{k}]" for k in range(1, 42)] for f in pairs)
    assert all(f.data.shape[1] == N_LOCAL_COLUMNS for f in pairs if len(f.data))
    assert sum(len(f.data) for f in pairs) > 0
    walls = read_text_dump(tmp_path / "wall.txt")
    assert [f.label for f in walls] == ["ENTRIES"] * 3
    assert all(f.columns == [f"c_cwgl[{k}]" for k in range(1, 42)] for f in walls)
    full_atoms = read_text_dump(tmp_path / "atoms_full.txt")
    binary = read_binary_dump(tmp_path / "atoms.bin")
    for t, b in zip(full_atoms, binary, strict=True):
        assert np.array_equal(t.data, b["data"])
    full_pairs = read_text_dump(tmp_path / "pairs_full.txt")
    for coarse, fine in zip(pairs, full_pairs, strict=True):
        np.testing.assert_allclose(coarse.data, fine.data, rtol=ROUNDING["%g"], atol=1e-300)
