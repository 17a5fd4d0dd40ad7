"""The LIGGGHTS path end to end, on real LIGGGHTS 3.8.0 output.

What these tests prove, with demsplit's own reader (:func:`demsplit.readers.open_run`)
deciding which contacts exist and the dumps' force columns as the witness:

1. completeness: in the setup frame (the first frame of an output run, where the atom
   force and the contact computes see the same velocities) every particle's dumped
   contact forces plus its weight add up to the atom force, except for the force of
   the primitive walls, which LIGGGHTS does not dump; for every particle with a
   rebuilt primitive-wall contact that missing force is LIGGGHTS' Hertz force on the
   rebuilt contact (normal part exact, tangential part within Coulomb);
2. precision: overlaps recomputed from ``%g`` positions are refused, or, when
   forced, reported with a bound that covers the energy differences against the
   full-precision dumps;
3. the analytic stacks against their closed form (committed dumps, and a fresh
   LIGGGHTS run);
4. periodic contacts: minimum-image normals and overlaps, contact points in the box;
5. bad inputs: the error class, and a message naming file, timestep and line;
6. the ``demsplit`` command on a sample run.

The facts about the files themselves are in ``test_liggghts_samples_facts.py`` and
``docs/liggghts-output.md``.
"""

from __future__ import annotations

import gzip
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import demsplit
import numpy as np
import pytest
from demsplit.cli import main as cli_main
from demsplit.compute import frame_tables
from demsplit.errors import InputFormatError, MaterialError, PrecisionError, TruncatedFileError
from demsplit.frame import Frame, ParticleIndex
from demsplit.pipeline import run_to_store
from demsplit.readers import open_run
from demsplit.readers.lammps_dump import open_dump
from demsplit.readers.liggghts import LiggghtsRun
from demsplit.results.schema import UNBOUNDED
from reader_contract import ReaderContract

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts"


@pytest.mark.slow
class TestPackingSample(ReaderContract):
    reader = LiggghtsRun
    path = SAMPLES / "packing" / "in.packing"


class TestPeriodicSampleWithFullPrecisionDumps(ReaderContract):
    reader = LiggghtsRun
    path = SAMPLES / "periodic" / "in.periodic"
    options = {
        "atoms": SAMPLES / "periodic" / "atoms_full.txt.gz",
        "contacts": SAMPLES / "periodic" / "pairs_full.txt.gz",
        "walls": SAMPLES / "periodic" / "wall_full.txt.gz",
    }


PRIMITIVE = ("plane", "cylinder")

# Force balance of a particle without primitive-wall contacts, relative to the sum of
# the magnitudes of its terms. Measured in the setup frame from the full-precision dumps:
# 1e-16 (packing), 3.1e-13 (periodic: with newton off a periodic pair is evaluated from
# both sides with differently rounded ghost images, and dumped once).
BALANCE_RTOL = 1e-9


def script(scene: str) -> Path:
    return SAMPLES / scene / f"in.{scene}"


@pytest.fixture(scope="module")
def setup_frame():
    """``setup_frame(scene)`` -> (run, frame 0) of a sample run, opened once per module."""
    opened: dict[str, tuple[LiggghtsRun, Frame]] = {}

    def get(scene: str) -> tuple[LiggghtsRun, Frame]:
        if scene not in opened:
            run = open_run(script(scene))
            opened[scene] = (run, run.frame(0))
        return opened[scene]

    yield get
    for run, _ in opened.values():
        run.close()


# --------------------------------------------------------------------------- 1. completeness


def contact_keys(id1: np.ndarray, other: np.ndarray, width: int) -> np.ndarray:
    """One int64 per contact: (id1, other) for ``other`` in [0, width)."""
    return np.asarray(id1, np.int64) * width + np.asarray(other, np.int64)


def unordered_keys(id1: np.ndarray, id2: np.ndarray, width: int) -> np.ndarray:
    return contact_keys(np.minimum(id1, id2), np.maximum(id1, id2), width)


@dataclass
class Balance:
    """Per particle (rows of ``frame.particles``): residual = f - m g - Σ dumped contact
    forces (N, shape (n, 3)), scale = |f| + |m g| + Σ |dumped contact force| (N),
    and the atom dump's velocity (m/s) and mass (kg)."""

    residual: np.ndarray
    scale: np.ndarray
    velocity: np.ndarray
    mass: np.ndarray


def force_balance(run: LiggghtsRun, frame: Frame) -> Balance:
    """Add the dumped pair and mesh-wall forces of the contacts the reader found.

    Asserts first that the reader's pair and mesh-wall contacts are exactly the
    dumped rows (as multisets of (id1, id2) resp. (particle, wall)), each pair once.
    """
    step, particles, contacts = frame.step, frame.particles, frame.contacts
    index = ParticleIndex(particles["id"])
    n = len(particles["id"])
    width = int(particles["id"].max()) + 2

    atoms = run.atoms.frame_at_step(step, columns=["id", "mass", "vx", "vy", "vz", "fx", "fy", "fz"])
    rows = index.rows(atoms.int_column("id"))
    f, v, mass = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n)
    f[rows] = np.stack([atoms.columns[c] for c in ("fx", "fy", "fz")], -1)
    v[rows] = np.stack([atoms.columns[c] for c in ("vx", "vy", "vz")], -1)
    mass[rows] = atoms.columns["mass"]
    weight = mass[:, None] * np.asarray(run.script.gravity)[None, :]

    def per_particle(ids: np.ndarray, force: np.ndarray) -> np.ndarray:
        r = index.rows(ids)
        return np.stack([np.bincount(r, weights=force[:, k], minlength=n) for k in range(3)], -1)

    names = run._pair_names
    pf = run.pairs.frame_at_step(step, columns=[names[c] for c in ("id1", "id2", "fx", "fy", "fz")])
    p1, p2 = pf.int_column(names["id1"]), pf.int_column(names["id2"])
    fp = np.stack([pf.columns[names[c]] for c in ("fx", "fy", "fz")], -1)
    pair = contacts["wall"] < 0
    ours = np.sort(unordered_keys(contacts["id1"][pair], contacts["id2"][pair], width))
    assert len(np.unique(ours)) == len(ours), "a pair contact is listed twice"
    np.testing.assert_array_equal(ours, np.sort(unordered_keys(p1, p2, width)))

    total = f - weight - per_particle(p1, fp) + per_particle(p2, fp)
    scale = (
        np.linalg.norm(f, axis=1)
        + np.linalg.norm(weight, axis=1)
        + per_particle(p1, np.abs(fp)).sum(1)
        + per_particle(p2, np.abs(fp)).sum(1)
    )

    kinds = np.array([w.kind for w in run.scene.walls] + ["pair"])
    mesh = kinds[contacts["wall"]] == "mesh"
    if run.walls is not None:
        wnames = run._wall_names
        wf = run.walls.frame_at_step(step, columns=[wnames[c] for c in ("id1", "mesh_index", "fx", "fy", "fz")])
        wid = wf.int_column(wnames["id1"])
        wall = np.asarray(run.script.dumped_mesh_walls)[wf.int_column(wnames["mesh_index"])]
        fw = np.stack([wf.columns[wnames[c]] for c in ("fx", "fy", "fz")], -1)
        nw = len(run.scene.walls)
        np.testing.assert_array_equal(
            np.sort(contact_keys(contacts["id1"][mesh], contacts["wall"][mesh], nw)),
            np.sort(contact_keys(wid, wall, nw)),
        )
        total -= per_particle(wid, fw)
        scale += per_particle(wid, np.abs(fw)).sum(1)
    else:
        assert not mesh.any()
    return Balance(total, scale, v, mass)


def liggghts_wall_normal_force(
    run: LiggghtsRun, frame: Frame, v: np.ndarray, mass: np.ndarray, picked: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """LIGGGHTS' Hertz normal force Fn (N, along e_n = -n, onto the particle) and the
    friction coefficient of the primitive-wall contacts ``picked`` (``normal_model_hertz.h``):

    Fn = kn δ - γn v_n, kn = 4/3 Y* √(R* δ), Sn = 2 Y* √(R* δ), γn = -2 √(5/6) β √(Sn m*),
    β = ln e / √(ln² e + π²), R* = r, m* = m, v_n = v · e_n (the wall is at rest).
    """
    c = {k: col[picked] for k, col in frame.contacts.items()}
    index = ParticleIndex(frame.particles["id"])
    rows = index.rows(c["id1"])
    t1 = frame.particles["type"][rows] - 1
    t2 = np.array([w.type for w in run.scene.walls])[c["wall"]] - 1
    E, nu = run.script.coefficients["youngsModulus"], run.script.coefficients["poissonsRatio"]
    y_star = 1.0 / ((1 - nu[t1] ** 2) / E[t1] + (1 - nu[t2] ** 2) / E[t2])
    delta, r_star = c["delta"], c["r1"]
    kn = 4.0 / 3.0 * y_star * np.sqrt(r_star * delta)
    sn = 2.0 * y_star * np.sqrt(r_star * delta)
    log_e = np.log(run.script.coefficients["coefficientRestitution"][t1, t2])
    beta = log_e / np.sqrt(log_e**2 + np.pi**2)
    gamma_n = -2.0 * np.sqrt(5.0 / 6.0) * beta * np.sqrt(sn * mass[rows])
    e_n = -np.stack([c["nx"], c["ny"], c["nz"]], -1)
    v_n = np.einsum("ij,ij->i", v[rows], e_n)
    return kn * delta - gamma_n * v_n, run.script.coefficients["coefficientFriction"][t1, t2]


@pytest.mark.parametrize("scene", ["packing", "periodic"])
def test_contacts_without_primitive_walls_balance_the_atom_force(setup_frame, scene):
    run, frame = setup_frame(scene)
    assert run.atoms.path.endswith("atoms_full.txt.gz") and run.pairs.path.endswith("pairs_full.txt.gz")
    b = force_balance(run, frame)
    kinds = np.array([w.kind for w in run.scene.walls] + ["pair"])
    primitive = np.isin(kinds[frame.contacts["wall"]], PRIMITIVE)
    touching = np.isin(frame.particles["id"], frame.contacts["id1"][primitive])
    free = ~touching
    assert free.sum() > 0.5 * len(free)
    rel = np.linalg.norm(b.residual[free], axis=1) / b.scale[free]
    assert rel.max() <= BALANCE_RTOL, f"particle {frame.particles['id'][free][np.argmax(rel)]}: {rel.max():.3g}"


def test_primitive_wall_residual_is_liggghts_hertz_force(setup_frame):
    """The force missing from the dumps is, particle by particle, LIGGGHTS' Hertz force on
    the primitive-wall contacts demsplit rebuilt: no contact missed, none invented."""
    run, frame = setup_frame("packing")
    b = force_balance(run, frame)
    kinds = np.array([w.kind for w in run.scene.walls] + ["pair"])
    primitive = np.flatnonzero(np.isin(kinds[frame.contacts["wall"]], PRIMITIVE))
    fn, mu = liggghts_wall_normal_force(run, frame, b.velocity, b.mass, primitive)
    assert np.all(fn > 0)
    index = ParticleIndex(frame.particles["id"])
    rows = index.rows(frame.contacts["id1"][primitive])
    e_n = -np.stack([frame.contacts[c][primitive] for c in ("nx", "ny", "nz")], -1)
    n_walls = np.bincount(rows, minlength=len(b.mass))

    single = n_walls[rows] == 1
    assert single.sum() >= 50
    r = b.residual[rows[single]]
    observed = np.einsum("ij,ij->i", r, e_n[single])
    # measured: 1e-15 relative; the damping term alone is up to 1.2 % of Fn here
    np.testing.assert_allclose(observed, fn[single], rtol=1e-12)
    tangential = np.linalg.norm(r - observed[:, None] * e_n[single], axis=1)
    np.testing.assert_array_less(tangential, mu[single] * fn[single] + BALANCE_RTOL * b.scale[rows[single]])

    # particles touching two walls (corners, a plane and the post): the residual minus
    # both normal forces is bounded by both Coulomb limits
    many = ~single
    if many.any():
        nrow = len(b.mass)
        normal = np.stack(
            [np.bincount(rows[many], weights=(fn[:, None] * e_n)[many, k], minlength=nrow) for k in range(3)], -1
        )
        limit = np.bincount(rows[many], weights=(mu * fn)[many], minlength=nrow)
        picked = np.unique(rows[many])
        rest = np.linalg.norm(b.residual[picked] - normal[picked], axis=1)
        np.testing.assert_array_less(rest, limit[picked] + BALANCE_RTOL * b.scale[picked])


# --------------------------------------------------------------------------- 2. precision

ROUNDING_G = 5e-6  # largest relative rounding of a value printed with %g (6 significant digits)


def dump_without_column(src: Path, dst: Path, token: str) -> Path:
    """Copy of the text dump ``src`` without column ``token``: the name leaves every
    column header line, the field every data row (trailing spaces kept)."""
    out, rows_left, count, drop = [], 0, 0, None
    lines = src.read_text().split("\n")
    for k, line in enumerate(lines):
        words = line.split(" ")
        if rows_left:
            del words[drop]
            rows_left -= 1
        elif line.startswith("ITEM: NUMBER OF"):
            count = int(lines[k + 1])
        elif line.startswith("ITEM: ") and token in words:
            drop = words.index(token) - 2  # after 'ITEM:' and the label
            del words[drop + 2]
            rows_left = count
        out.append(" ".join(words))
    dst.write_text("\n".join(out))
    return dst


@pytest.fixture(scope="module")
def packing_g(tmp_path_factory) -> dict[str, dict[str, Path]]:
    """Reader options for packing/'s default-precision (%g) dumps: as written, and with
    the pair dump's ``delta`` column (c_cpgl[38]) removed."""
    folder = SAMPLES / "packing"
    base = {"atoms": folder / "atoms.txt", "contacts": folder / "pairs.txt", "walls": folder / "wall.txt"}
    no_delta = dump_without_column(
        folder / "pairs.txt", tmp_path_factory.mktemp("g") / "pairs_no_delta.txt", "c_cpgl[38]"
    )
    return {"dumped delta": base, "no delta": {**base, "contacts": no_delta}}


def refused(options: dict) -> PrecisionError:
    run = open_run(script("packing"), **options)
    try:
        with pytest.raises(PrecisionError) as info:
            run.frame(0)
    finally:
        run.close()
    return info.value


def test_overlaps_from_g_positions_are_refused(packing_g):
    err = refused(packing_g["no delta"])
    text = str(err)
    assert err.file.endswith("atoms.txt") and err.step == 200000
    for words in (
        "pairs: positions, printed precision (6 digits)",
        "6 significant digits",
        "tolerance 0.001",
        "'delta' keyword",
        "%.17g",
        "--force-positions",
    ):
        assert words in text
    # the pair overlaps are among the refused ones: more than with the dumped delta, where
    # only the primitive walls (always rebuilt from positions) exceed the tolerance
    with_delta = refused(packing_g["dumped delta"])
    assert "pairs: dumped delta" in str(with_delta)
    count = [int(str(e).split(" of ")[0].rsplit(" ", 1)[1]) for e in (err, with_delta)]
    assert count[0] > count[1] + 300


def test_forced_g_positions_report_their_bound_in_frame_and_store(packing_g, tmp_path):
    options = {**packing_g["no delta"], "force_positions": True}
    run = open_run(script("packing"), **options)
    bounds = []
    for frame in run:
        assert "pairs: positions, printed precision (6 digits)" in frame.overlap_source
        err, pair = frame.overlap_error, frame.contacts["wall"] < 0
        assert err.shape == (frame.n_contacts,)
        assert np.all(err[pair] > 0) and np.mean(err[pair] > 1e-3) > 0.5
        bounds.append(np.max(err))
    run.close()
    out = tmp_path / "g.h5"
    run_to_store(script("packing"), out, progress=False, **options)
    stored = demsplit.load_results(out).frames
    # no stored number is inf: a bound that is (a contact the printed positions may hide) is stored as UNBOUNDED
    expected = np.where(np.isinf(bounds), UNBOUNDED, bounds)
    np.testing.assert_array_equal(stored["overlap_max_rel_error"].to_numpy(), expected)


def assert_within(error: np.ndarray, bound: np.ndarray) -> None:
    bad = np.flatnonzero(~(error <= bound))
    assert bad.size == 0, (
        f"{bad.size} of {error.size} above the bound, e.g. row {bad[:1]}: {error[bad[:1]]} > {bound[bad[:1]]}"
    )


def contact_key(c: dict, width: int, n_walls: int) -> np.ndarray:
    """(id1, id2, wall) as one int64 per contact (id2 = -1 and wall = -1 allowed)."""
    return (c["id1"] * (width + 1) + c["id2"] + 1) * (n_walls + 1) + c["wall"] + 1


@pytest.mark.parametrize("case", ["dumped delta", "no delta"])
def test_g_energies_match_full_precision_within_the_reported_bound(packing_g, case):
    """U_n ∝ δ^{5/2}: |U_g - U_full| <= U_g ((1 + b)^{5/2} - 1) for the reported bound b;
    U_t = ½ kt |shear|², kt ∝ √δ: <= U_t,g ((1 + b)^{1/2} (1 + ρ)² - 1), ρ = %g rounding
    of the shear. A contact whose printed positions do not show it has b = inf; it must
    then carry no energy, and the full-precision δ must be below √3 h."""
    from demsplit.readers.precision import printed_step

    full = open_run(script("packing"))
    low = open_run(script("packing"), force_positions=True, **packing_g[case])
    n_walls = len(full.scene.walls)
    for k in (0, len(full) - 1):
        ff, fg = full.frame(k), low.frame(k)
        tf, tg = frame_tables(ff, full.scene), frame_tables(fg, low.scene)
        cf, cg = tf["contacts"], tg["contacts"]
        width = int(ff.particles["id"].max()) + 1
        kf, kg = contact_key(cf, width, n_walls), contact_key(cg, width, n_walls)
        assert len(np.unique(kg)) == len(kg)
        common, ig, i_f = np.intersect1d(kg, kf, assume_unique=True, return_indices=True)
        assert len(common) == len(kf), "a contact of the full-precision dumps is missing"
        b = fg.overlap_error[ig]
        u_f = cf["u_n"][i_f] + cf["u_t"][i_f]
        hidden = ~np.isfinite(b)
        extra = np.setdiff1d(np.arange(len(kg)), ig)
        assert np.all(~np.isfinite(fg.overlap_error[extra])) and np.all(cg["u_n"][extra] == 0)
        assert np.all(cg["u_n"][ig][hidden] == 0)
        h = np.max([printed_step(ff.contacts[c][i_f][hidden], 6) for c in ("x1", "y1", "z1")], axis=0)
        assert np.all(ff.contacts["delta"][i_f][hidden] <= np.sqrt(3) * h)

        b = np.where(hidden, 0.0, b)
        tol = (
            cg["u_n"][ig] * ((1 + b) ** 2.5 - 1)
            + cg["u_t"][ig] * ((1 + b) ** 0.5 * (1 + ROUNDING_G) ** 2 - 1)
            + 1e-12 * u_f
        )
        tol = np.where(hidden, u_f, tol)
        assert_within(np.abs(cg["u_n"][ig] - cf["u_n"][i_f]), tol)
        assert_within(np.abs(cg["u_t"][ig] - cf["u_t"][i_f]), tol)
        # the bound is not vacuous: the energies do differ, by up to a good part of it
        assert np.max(np.abs(cg["u_n"][ig] - cf["u_n"][i_f])[~hidden] / tol[~hidden]) > 0.1

        # per particle: each contact gives each body at most its whole energy error
        index = ParticleIndex(ff.particles["id"])
        n = len(ff.particles["id"])
        pair = cf["id2"][i_f] >= 0
        ptol = np.bincount(index.rows(cf["id1"][i_f]), weights=tol, minlength=n) + np.bincount(
            index.rows(cf["id2"][i_f][pair]), weights=tol[pair], minlength=n
        )
        pf, pg = tf["particles"], tg["particles"]
        np.testing.assert_array_equal(pf["id"], pg["id"])
        assert_within(np.abs(pg["u"] - pf["u"]), ptol[index.rows(pf["id"])])
    full.close()
    low.close()


# --------------------------------------------------------------------------- 3. analytic stacks

STACKS = ((1, 2, 3), (4, 5))  # particle ids, bottom to top (sample_dumps/liggghts/README.md)


def check_closed_form(folder: Path) -> None:
    """demsplit.analyze on the analytic stacks against the closed form (README of the
    samples): per contact F = g Σ m above, δ = (3F/(4 Y* √R*))^{2/3}, U = (2/5) F δ;
    shares c1/(c1 + c2), c = (1 - ν²)/E; contact point x1 + (r1 - s1 δ) n."""
    results = demsplit.analyze(folder / "in.analytic")
    run = open_run(folder / "in.analytic")
    frame = run.frame(0)
    run.close()
    p = frame.particles
    row = {int(i): k for k, i in enumerate(p["id"])}
    atoms = open_dump(folder / "atoms_full.txt").frame(0, columns=["id", "mass"])
    mass = dict(zip(atoms.int_column("id").tolist(), atoms.columns["mass"]))
    g = abs(run.script.gravity[2])
    materials = run.scene.materials
    floor_type = run.scene.walls[0].type

    def compliance(t: int) -> float:
        return (1 - materials[t].nu ** 2) / materials[t].E

    c = results.contacts
    assert len(c) == 5 and len(results.particles) == 5
    expected_u = dict.fromkeys(row, 0.0)
    for _, contact in c.iterrows():
        id1, id2, wall = int(contact.id1), int(contact.id2), int(contact.wall)
        stack = next(s for s in STACKS if id1 in s)
        if wall >= 0:
            upper, t2, r_star, nz = id1, floor_type, p["radius"][row[id1]], -1.0
        else:
            assert id2 in stack and abs(stack.index(id1) - stack.index(id2)) == 1
            upper = id1 if stack.index(id1) > stack.index(id2) else id2
            r1, r2 = p["radius"][row[id1]], p["radius"][row[id2]]
            t2, r_star = int(p["type"][row[id2]]), r1 * r2 / (r1 + r2)
            nz = 1.0 if upper == id2 else -1.0
        force = g * sum(mass[i] for i in stack[stack.index(upper) :])
        c1, c2 = compliance(int(p["type"][row[id1]])), compliance(t2)
        delta = (3 * force * (c1 + c2) / (4 * np.sqrt(r_star))) ** (2 / 3)
        u = 0.4 * force * delta
        share = c1 / (c1 + c2)
        np.testing.assert_allclose([contact.delta, contact.u_n], [delta, u], rtol=1e-8)
        assert contact.u_t <= 1e-20 * u  # at rest the shear springs are (numerically) unloaded
        np.testing.assert_allclose(contact.share_n1, share, rtol=1e-12)
        np.testing.assert_allclose([contact.u1, contact.depth1], [share * u, share * delta], rtol=1e-8)
        x1 = np.array([p["x"][row[id1]], p["y"][row[id1]], p["z"][row[id1]]])
        point = x1 + (p["radius"][row[id1]] - share * delta) * np.array([0.0, 0.0, nz])
        np.testing.assert_allclose([contact.cpx, contact.cpy, contact.cpz], point, rtol=1e-8, atol=1e-8 * delta)
        expected_u[id1] += share * u
        if wall < 0:
            expected_u[id2] += (1 - share) * u
    got = dict(zip(results.particles["id"].astype(int), results.particles["u"]))
    np.testing.assert_allclose([got[i] for i in sorted(got)], [expected_u[i] for i in sorted(got)], rtol=1e-8)


def test_analytic_stacks_match_the_closed_form():
    check_closed_form(SAMPLES / "analytic")


@pytest.mark.slow
@pytest.mark.simulator
def test_analytic_stacks_through_liggghts(liggghts, tmp_path):
    """Run LIGGGHTS on the analytic scene (about 3 s) and check the fresh dumps."""
    for name in ("in.analytic", "floor.stl"):
        shutil.copy(SAMPLES / "analytic" / name, tmp_path / name)
    done = subprocess.run(
        [liggghts, "-in", "in.analytic", "-echo", "none", "-log", "none"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    for name in ("atoms_full.txt", "pairs_full.txt", "wall_full.txt"):
        assert (tmp_path / name).is_file()
    check_closed_form(tmp_path)


# --------------------------------------------------------------------------- 4. periodic


def test_periodic_contacts_use_the_minimum_image(setup_frame):
    run, frame = setup_frame("periodic")
    c, p, box = frame.contacts, frame.particles, frame.box
    assert box.periodic == (True, True, False)
    names = run._pair_names
    pf = run.pairs.frame_at_step(frame.step, columns=[names[k] for k in ("id1", "id2", "periodic", "delta")])
    width = int(p["id"].max()) + 1
    pair = np.flatnonzero(c["wall"] < 0)
    ours = contact_keys(c["id1"][pair], c["id2"][pair], width)
    dumped = contact_keys(pf.int_column(names["id1"]), pf.int_column(names["id2"]), width)
    order = np.argsort(dumped)
    at = order[np.searchsorted(dumped, ours, sorter=order)]
    np.testing.assert_array_equal(dumped[at], ours)
    flagged = pair[pf.columns[names["periodic"]][at] == 1]
    assert len(flagged) >= 50

    index = ParticleIndex(p["id"])
    x = np.stack([p["x"], p["y"], p["z"]], -1)
    x1, x2 = x[index.rows(c["id1"][pair])], x[index.rows(c["id2"][pair])]
    n = np.stack([c["nx"], c["ny"], c["nz"]], -1)[pair]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-14)
    r1, r2, delta = c["r1"][pair], c["r2"][pair], c["delta"][pair]
    reach = x1 + (r1 + r2 - delta)[:, None] * n  # the partner's centre, or its periodic image
    # flagged pairs reach the partner through the boundary, a box length from its stored
    # position, exactly at its image
    is_flagged = np.isin(pair, flagged)
    assert np.all(np.max(np.abs(reach - x2)[is_flagged, :2], axis=1) > 0.5 * box.lengths[0])
    np.testing.assert_allclose(box.minimum_image(reach - x2), 0.0, atol=1e-12)
    # the dumped delta is r1 + r2 - |minimum-image distance| (image rounding: 6e-12 relative)
    distance = np.linalg.norm(box.minimum_image(x2 - x1), axis=1)
    np.testing.assert_allclose(pf.columns[names["delta"]][at], r1 + r2 - distance, rtol=1e-10)

    # material-weighted contact points: x1 + (r1 - δ1) n, wrapped back into the box
    tables = frame_tables(frame, run.scene)["contacts"]
    cp = np.stack([tables[k] for k in ("cpx", "cpy", "cpz")], -1)
    assert np.all((cp >= box.lo) & (cp < box.hi))
    unwrapped = x1 + (r1 - tables["depth1"][pair])[:, None] * n
    assert np.any((unwrapped < box.lo) | (unwrapped >= box.hi))  # so the wrap is exercised
    np.testing.assert_allclose(cp[pair], box.wrap(unwrapped), rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- 5. bad inputs


@pytest.fixture(scope="module")
def packing_copy(tmp_path_factory) -> Path:
    """packing/ with full-precision atoms (so overlaps are not refused) and the %g pair
    and wall dumps, as text, in a folder the tests may damage copies in."""
    folder = tmp_path_factory.mktemp("packing")
    for name in ("in.packing", "floor.stl", "pairs.txt", "wall.txt"):
        shutil.copy(SAMPLES / "packing" / name, folder / name)
    with gzip.open(SAMPLES / "packing" / "atoms_full.txt.gz", "rb") as f:
        (folder / "atoms_full.txt").write_bytes(f.read())
    return folder


def frame_starts(text: str) -> list[int]:
    """Character offsets of the frames' 'ITEM: TIMESTEP' lines."""
    out, at = [], text.find("ITEM: TIMESTEP")
    while at >= 0:
        out.append(at)
        at = text.find("ITEM: TIMESTEP", at + 1)
    return out


def row_line(text: str, frame: int, row: int) -> int:
    """1-based line number of data row ``row`` (0-based) of frame ``frame``."""
    return text[: frame_starts(text)[frame]].count("\n") + 1 + 9 + row


def with_token(text: str, line: int, column: int, token: str) -> str:
    """``text`` with field ``column`` (0-based) of 1-based line ``line`` replaced by ``token``."""
    lines = text.split("\n")
    words = lines[line - 1].split(" ")
    words[column] = token
    lines[line - 1] = " ".join(words)
    return "\n".join(lines)


def analyze_error(folder: Path, cls: type, script_name: str = "in.packing", **files: str):
    """The error ``demsplit.analyze`` raises on the damaged files ``files`` (written into
    ``folder``; option name -> (file name, text)), checked to be ``cls``."""
    options = {}
    for option, (name, text) in files.items():
        (folder / name).write_text(text)
        options[option] = folder / name
    with pytest.raises(cls) as info:
        demsplit.analyze(folder / script_name, **options)
    return info.value


def assert_located(err, name: str, step: int | None, line: int | None, *words: str) -> None:
    text = str(err)
    assert err.file is not None and Path(err.file).name == name, text
    assert err.step == step and err.line == line, text
    assert f"{name}:{line}" in text if line is not None else name in text
    if step is not None:
        assert f"timestep {step}" in text
    assert "Fix:" in text
    for w in words:
        assert w in text, f"{w!r} not in {text!r}"


def test_pair_dump_cut_mid_row(packing_copy):
    text = (packing_copy / "pairs.txt").read_text()
    cut = text[:-100]
    err = analyze_error(packing_copy, TruncatedFileError, contacts=("cut_row.txt", cut))
    assert_located(err, "cut_row.txt", 204000, cut.count("\n") + 1, "middle of a row", "rerun")


def test_pair_dump_cut_between_frames(packing_copy):
    text = (packing_copy / "pairs.txt").read_text()
    last = frame_starts(text)[2]
    err = analyze_error(packing_copy, InputFormatError, contacts=("cut_frames.txt", text[:last]))
    assert_located(err, "cut_frames.txt", 204000, None, "no frame at timestep 204000")
    # cut inside the last frame's header: its own line is named
    cut = text[: last + len("ITEM: TIMESTEP\n204000\nITEM: NUM")]
    err = analyze_error(packing_copy, InputFormatError, contacts=("cut_header.txt", cut))
    assert_located(
        err, "cut_header.txt", 204000, None, "damaged header", f"cut_header.txt:{cut.count(chr(10)) + 1}", "expected 9"
    )


def test_header_count_disagrees_with_rows(packing_copy):
    text = (packing_copy / "pairs.txt").read_text()
    second = frame_starts(text)[1]
    bad = text[:second] + text[second:].replace("\n555\n", "\n556\n", 1)
    err = analyze_error(packing_copy, InputFormatError, contacts=("count.txt", bad))
    assert_located(err, "count.txt", 202000, row_line(text, 2, 0) - 9, "says 556 rows but only 555")


@pytest.mark.parametrize(
    "column, token, words",
    [
        (37, "abc", "'abc'; expected a number"),
        (33, "1.2.3", "'1.2.3'; expected a number"),
        (37, "nan", "expected a finite number"),
    ],
)
def test_non_numeric_token(packing_copy, column, token, words):
    text = (packing_copy / "pairs.txt").read_text()
    line = row_line(text, 1, 2)
    err = analyze_error(packing_copy, InputFormatError, contacts=("token.txt", with_token(text, line, column, token)))
    assert_located(err, "token.txt", 202000, line, f"column {column + 1} ('c_cpgl[{column + 1}]')", words)


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("c_cpgl[41]", "c_cpgl[42]", "c_cpgl[42] is beyond the 41 columns compute cpgl writes"),
        ("c_cpgl[1] ", "c_nope[1] ", "reads compute 'nope', which the script does not define"),
    ],
)
def test_local_dump_columns_the_script_does_not_write(packing_copy, old, new, words):
    text = (packing_copy / "pairs.txt").read_text()
    err = analyze_error(packing_copy, InputFormatError, contacts=("columns.txt", text.replace(old, new)))
    assert_located(err, "columns.txt", 200000, 9, words)


def test_wall_type_without_material(packing_copy):
    text = (packing_copy / "in.packing").read_text()
    bad = text.replace("primitive type 3 xplane -0.02", "primitive type 5 xplane -0.02")
    (packing_copy / "in.bad").write_text(bad)
    with pytest.raises(MaterialError) as info:
        open_run(packing_copy / "in.bad")
    line = bad[: bad.index("type 5 xplane")].count("\n") + 1
    assert_located(info.value, "in.bad", None, line, "uses type 5, which has no material", "youngsModulus")


def test_particle_type_without_material(packing_copy):
    text = (packing_copy / "atoms_full.txt").read_text()
    line = row_line(text, 1, 4)
    bad = with_token(text, line, 1, "5")
    err = analyze_error(packing_copy, MaterialError, atoms=("atoms_type5.txt", bad))
    assert_located(err, "atoms_type5.txt", 202000, line, "particle type 5 has no material", "--material")


def test_g_printed_id_above_999999(packing_copy):
    text = (packing_copy / "pairs.txt").read_text()
    line = row_line(text, 1, 2)
    bad = with_token(text, line, 12, "1.23457e+06")  # c_cpgl[13] = id1
    err = analyze_error(packing_copy, PrecisionError, contacts=("ids.txt", bad))
    assert_located(err, "ids.txt", 202000, line, "c_cpgl[13]", "not an exact integer", "%.17g")


# --------------------------------------------------------------------------- 6. the command


def test_cli_run_writes_the_store(setup_frame, tmp_path):
    out = tmp_path / "packing.h5"
    assert cli_main(["run", str(script("packing")), "-o", str(out), "--quiet"]) == 0
    stored = demsplit.load_results(out)
    run, frame = setup_frame("packing")
    np.testing.assert_array_equal(stored.steps, run.steps)
    first = stored.frame(int(run.steps[0])).raw.particles  # as stored: the known part of each particle
    expected = frame_tables(frame, run.scene)["particles"]
    np.testing.assert_array_equal(first["id"].to_numpy(), expected["id"])
    np.testing.assert_allclose(first["u"].to_numpy(), expected["u"], rtol=1e-15)
    assert out.is_file() and not list(tmp_path.glob("*.tmp*"))


def test_cli_run_reports_a_bad_input_in_one_line(packing_copy, tmp_path, capsys):
    text = (packing_copy / "pairs.txt").read_text()
    (packing_copy / "cli_cut.txt").write_text(text[:-100])
    out = tmp_path / "bad.h5"
    code = cli_main(
        [
            "run",
            str(packing_copy / "in.packing"),
            "--contacts",
            str(packing_copy / "cli_cut.txt"),
            "-o",
            str(out),
            "--quiet",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("demsplit: error:") and "cli_cut.txt:" in err and "timestep 204000" in err
    assert "Traceback" not in err and not out.exists()


def test_cli_info(capsys):
    assert cli_main(["info", str(SAMPLES / "packing" / "pairs.txt")]) == 0
    text = capsys.readouterr().out
    for words in ("pairs.txt", "CONTACTS", "200000", "204000", "c_cpgl[38]", "c_cpgl[41]"):
        assert words in text


def test_a_frame_assembled_in_pieces_is_the_frame_in_one(monkeypatch):
    """The join, the printed steps and the overlap check run in pieces of the contacts on the pool's
    threads (threads.map_ranges): the frame is the same, bit for bit."""
    from demsplit.runtime import threads

    script = SAMPLES / "packing" / "in.packing"
    whole = open_run(script).frame(-1)
    monkeypatch.setattr(threads, "MIN_RANGE", 1)
    monkeypatch.setattr(threads, "THREADS", 3)
    monkeypatch.setattr(threads, "_pool", None)
    pieces = open_run(script).frame(-1)
    for table in ("particles", "contacts"):
        a, b = getattr(whole, table), getattr(pieces, table)
        assert list(a) == list(b)
        for c in a:
            assert np.array_equal(np.asarray(a[c]), np.asarray(b[c])), (table, c)
