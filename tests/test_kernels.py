"""The compiled per-contact loops (demsplit.kernels) against the plain numpy formulation.

The reference below is the numpy implementation the kernels replaced, written
with the public array API of demsplit.physics (one numpy
pass per operation, np.bincount for the sums). The compiled paths must give the
same numbers: bit for bit where the operations are the same, to 1e-13 relative
where only the order of a sum or of |v|^2 differs.
"""

from __future__ import annotations

from pathlib import Path

import demsplit as ds
import numpy as np
import pytest
from demsplit.compute import Options, frame_tables
from demsplit.frame import ParticleIndex
from demsplit.physics import elastic, formulas, moduli
from demsplit.physics.bodies import FrameContacts
from demsplit.physics.partition import body_tables, law_energies, particle_energy, split_energies
from demsplit.physics.shares import contact_point, normal_share, radius_share, tangential_share
from demsplit.readers import open_run
from hypothesis import given, settings
from hypothesis import strategies as st

kernels = pytest.importorskip("demsplit.kernels")

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts"
GPa = 1e9


# --- the numpy reference ---------------------------------------------------------------------


def reference_rows(particles, ids):
    order = np.argsort(particles["id"], kind="stable")
    pos = np.searchsorted(particles["id"][order], ids)
    return order[pos]


def reference_types(contacts, scene, particles):
    """Material types of both bodies of every contact, by plain numpy gathers."""
    ptype = np.asarray(particles["type"], dtype=np.int64)
    pair = contacts["wall"] < 0
    type1 = ptype[reference_rows(particles, contacts["id1"])]
    type2 = np.empty_like(type1)
    type2[pair] = ptype[reference_rows(particles, contacts["id2"][pair])]
    type2[~pair] = scene.wall_types()[contacts["wall"][~pair]]
    return type1, type2


def reference_constants(contacts, scene, particles):
    """E, nu of both bodies of every contact, by plain numpy gathers."""
    type1, type2 = reference_types(contacts, scene, particles)
    E1, nu1 = scene.lookup(type1)
    E2, nu2 = scene.lookup(type2)
    return E1, nu1, E2, nu2


def reference_hertz(contacts, constants):
    """LIGGGHTS hertz + tangential history energies, numpy."""
    R = moduli.effective_radius(contacts["r1"], contacts["r2"])
    delta = contacts["delta"]
    u_n = elastic.hertz_energy_from_moduli(delta, R, moduli.effective_modulus(*constants))
    kt = formulas.hertz_kt_formula(elastic.overlap(delta), R, moduli.effective_shear_modulus(*constants))
    shear = np.stack([contacts[c] for c in ("shearx", "sheary", "shearz")], axis=-1)
    return u_n, np.where(delta > 0, elastic.shear_spring_energy(shear, kt), 0.0)


def reference_split(contacts, s_n, s_t, u_n, u_t):
    delta = np.asarray(contacts["delta"], dtype=np.float64)
    x1 = np.stack([contacts[c] for c in ("x1", "y1", "z1")], axis=-1)
    normal = np.stack([contacts[c] for c in ("nx", "ny", "nz")], axis=-1)
    return {
        "u1": s_n * u_n + s_t * u_t,
        "u2": (1.0 - s_n) * u_n + (1.0 - s_t) * u_t,
        "depth1": s_n * delta,
        "cp": contact_point(x1, normal, contacts["r1"], delta, s_n),
    }


def reference_sums(contacts, particles, s_n, s_t, u_n, u_t, n_walls):
    n = len(particles["id"])
    pair = contacts["wall"] < 0
    rows1 = reference_rows(particles, contacts["id1"])
    rows2 = reference_rows(particles, contacts["id2"][pair])
    un1, ut1 = s_n * u_n, s_t * u_t
    un2, ut2 = u_n - un1, u_t - ut1

    def body_sum(w1, w2):
        return np.bincount(rows1, weights=w1, minlength=n) + np.bincount(rows2, weights=w2[pair], minlength=n)

    w = contacts["wall"][~pair]
    return (
        {
            "u_n": body_sum(un1, un2),
            "u_t": body_sum(ut1, ut2),
            "n_contacts": np.bincount(rows1, minlength=n) + np.bincount(rows2, minlength=n),
        },
        {
            "u_n": np.bincount(w, weights=un2[~pair], minlength=n_walls),
            "u_t": np.bincount(w, weights=ut2[~pair], minlength=n_walls),
            "n_contacts": np.bincount(w, minlength=n_walls),
        },
    )


def same(a, b, rtol=0.0):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    if rtol == 0.0:
        np.testing.assert_array_equal(a, b)
    else:
        np.testing.assert_allclose(a, b, rtol=rtol, atol=0.0)


def check_against_reference(contacts, scene, particles, n_walls=0):
    """partition + per_particle + the comparison splits vs the numpy reference."""
    frame = FrameContacts(contacts, scene, particles)
    bodies = frame.bodies
    energies = law_energies(frame)
    constants = reference_constants(contacts, scene, particles)
    n = len(contacts["delta"])
    for lo, hi in ((0, n), (n // 3, n // 2)):  # a range's constants, as the accuracy columns take them
        for got, want in zip(bodies.constants(lo, hi), constants):
            same(np.broadcast_to(got, (hi - lo,)), want[lo:hi])
    if scene.model == ds.ContactModel("liggghts:hertz") and "shearx" in contacts:
        own = np.array([w.model is not None and w.model != scene.model for w in scene.walls] + [False])
        pair_law = ~own[contacts["wall"]]  # contacts under the pair model (wall -1: the last entry)
        u_n, u_t = reference_hertz(contacts, constants)
        same(energies.u_n[pair_law], u_n[pair_law])
        same(energies.u_t[pair_law], u_t[pair_law], rtol=1e-13)  # |shear|^2 in order; einsum's may differ
    u_n, u_t = energies.u_n, energies.u_t
    e = split_energies(frame, energies)
    s_n = np.broadcast_to(normal_share(*constants), u_n.shape)
    s_t = np.broadcast_to(tangential_share(*constants), u_n.shape)
    same(e.share_n1, s_n)
    same(e.share_t1, s_t)
    for k, v in reference_split(contacts, s_n, s_t, u_n, u_t).items():
        same(getattr(e, k), v)
    same(e.separated, np.asarray(contacts["delta"]) < 0)
    pt, wt = body_tables(frame, e, n_walls=n_walls)
    ref_p, ref_w = reference_sums(contacts, particles, s_n, s_t, u_n, u_t, len(wt["wall"]))
    for k in ("u_n", "u_t", "n_contacts"):
        same(pt[k], ref_p[k])
        same(wt[k], ref_w[k])
    same(pt["u"], ref_p["u_n"] + ref_p["u_t"])
    total = np.sum(u_n + u_t)
    assert abs(pt["u"].sum() + wt["u"].sum() - total) <= 1e-12 * total
    for split, share in (("equal", 0.5), ("radius", radius_share(contacts["r1"], contacts["r2"]))):
        share = np.broadcast_to(share, u_n.shape)
        u1 = share * u_n + share * u_t
        pair = contacts["wall"] < 0
        rows1 = reference_rows(particles, contacts["id1"])
        rows2 = reference_rows(particles, contacts["id2"][pair])
        n = len(particles["id"])
        expected = np.bincount(rows1, weights=u1, minlength=n) + np.bincount(
            rows2, weights=(u_n + u_t - u1)[pair], minlength=n
        )
        same(particle_energy(frame, energies, split), expected)
    return e


# --- random frames ---------------------------------------------------------------------------


def random_frame(rng, n_particles, n_contacts, n_walls, n_types, dense_ids=True, hard=False):
    ids = (
        rng.permutation(np.arange(1, n_particles + 1))
        if dense_ids
        else rng.choice(10**12, size=n_particles, replace=False)
    )
    particles = {
        "id": ids.astype(np.int64),
        "type": rng.integers(1, n_types + 1, n_particles).astype(np.int32),
        "x": rng.uniform(0, 1, n_particles),
        "y": rng.uniform(0, 1, n_particles),
        "z": rng.uniform(0, 1, n_particles),
        "radius": rng.uniform(1e-3, 3e-3, n_particles),
        "mass": rng.uniform(1e-6, 1e-5, n_particles),
    }
    if n_particles < 2:
        n_contacts = 0
    i = rng.integers(0, max(n_particles, 1), n_contacts)
    j = (i + rng.integers(1, max(n_particles, 2), n_contacts)) % max(n_particles, 1)
    wall = (
        np.where(rng.random(n_contacts) < 0.3, rng.integers(0, max(n_walls, 1), n_contacts), -1)
        if n_walls
        else np.full(n_contacts, -1)
    )
    normal = rng.normal(size=(n_contacts, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    delta = rng.uniform(-1e-6, 1e-5, n_contacts)
    if hard and n_contacts:  # separated, touching, denormal and huge overlaps
        k = rng.integers(0, n_contacts, min(n_contacts, 8))
        delta[k] = rng.choice([-1e-3, 0.0, -0.0, 1e-300, 5e-324, 1e-12, 2e-3], len(k))
    r1 = particles["radius"][i] if n_particles else np.zeros(0)
    r2 = np.where(wall >= 0, np.inf, particles["radius"][j] if n_particles else np.zeros(0))
    contacts = {
        "id1": ids[i] if n_particles else np.zeros(0, np.int64),
        "id2": np.where(wall >= 0, -1, ids[j] if n_particles else 0).astype(np.int64),
        "wall": wall.astype(np.int64),
        "delta": delta,
        "nx": normal[:, 0],
        "ny": normal[:, 1],
        "nz": normal[:, 2],
        "x1": particles["x"][i] if n_particles else np.zeros(0),
        "y1": particles["y"][i] if n_particles else np.zeros(0),
        "z1": particles["z"][i] if n_particles else np.zeros(0),
        "r1": r1,
        "r2": r2,
    }
    for c in ("shearx", "sheary", "shearz"):
        contacts[c] = rng.normal(scale=1e-6, size=n_contacts)
    return contacts, particles


def random_scene(rng, n_types, n_walls, normal, rigid_walls):
    materials = {
        t: ds.Material(float(rng.choice([1e6, 7e7, 2e11])), float(rng.choice([-0.5, 0.0, 0.25, 0.49])))
        for t in range(1, n_types + 1)
    }
    wall_type = n_types + 1
    materials[wall_type] = ds.Material(np.inf if rigid_walls else 2e11, 0.3)
    params = {"characteristic_velocity": 1.0} if normal == "hooke" else {}
    model = ds.ContactModel(f"liggghts:{normal}", {"tangential": "history", **params})
    walls = [ds.Wall(f"w{k}", "plane", type=wall_type) for k in range(n_walls)]
    return ds.Scene(materials, model=model, walls=walls)


def test_a_ranges_constants_from_the_contacts_own_types_and_once_the_frames_arrays_exist():
    """ContactBodies.constants when the contacts carry their types (YADE's contacts do), and after the
    properties built the frame's per-contact arrays: the range of those."""
    rng = np.random.default_rng(5)
    contacts, particles = random_frame(rng, 30, 80, 2, 3, True, hard=True)
    scene = random_scene(rng, 3, 2, "hertz", False)
    t1, t2 = reference_types(contacts, scene, particles)
    bodies = FrameContacts({**contacts, "type1": t1, "type2": t2}, scene, particles).bodies
    want = (*scene.lookup(t1), *scene.lookup(t2))
    n = len(t1)
    for lo, hi in ((0, n), (n // 4, 3 * n // 4)):
        for got, w in zip(bodies.constants(lo, hi), want):
            same(got, w[lo:hi])
    same(bodies.E1, want[0])
    for got, w in zip(bodies.constants(3, 9), want):
        same(got, w[3:9])


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_particles=st.integers(0, 40),
    n_contacts=st.integers(0, 120),
    n_walls=st.integers(0, 3),
    n_types=st.integers(1, 3),
    normal=st.sampled_from(["hertz", "hooke"]),
    dense_ids=st.booleans(),
    rigid_walls=st.booleans(),
)
@pytest.mark.slow
def test_random_frames_match_numpy(seed, n_particles, n_contacts, n_walls, n_types, normal, dense_ids, rigid_walls):
    rng = np.random.default_rng(seed)
    contacts, particles = random_frame(rng, n_particles, n_contacts, n_walls, n_types, dense_ids, hard=True)
    scene = random_scene(rng, n_types, n_walls, normal, rigid_walls)
    check_against_reference(contacts, scene, particles, n_walls=n_walls)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(4))
def test_frames_computed_in_pieces_are_the_frames_in_one(seed, monkeypatch):
    """The per-contact loops and the accuracy columns run in pieces on the pool's threads
    (threads.map_ranges): three pieces give the tables of one, bit for bit."""
    from demsplit import compute
    from demsplit.runtime import threads

    rng = np.random.default_rng(seed)
    contacts, particles = random_frame(rng, 30, 100, 2, 3, dense_ids=bool(seed % 2), hard=False)
    scene = random_scene(rng, 3, 2, "hertz", rigid_walls=bool(seed % 2))
    frame = ds.Frame(step=0, particles=particles, contacts=contacts)
    whole = frame_tables(frame, scene, Options())
    monkeypatch.setattr(threads, "MIN_RANGE", 1)
    monkeypatch.setattr(threads, "THREADS", 3)
    monkeypatch.setattr(threads, "_pool", None)
    monkeypatch.setattr(compute, "ACCURACY_ROWS", 7)
    pieces = frame_tables(frame, scene, Options())
    assert list(whole) == list(pieces)
    for name, table in whole.items():
        assert list(table) == list(pieces[name])
        for c, v in table.items():
            assert np.array_equal(np.asarray(v), np.asarray(pieces[name][c]), equal_nan=True), (name, c)


def test_single_material_and_float32_columns():
    rng = np.random.default_rng(11)
    contacts, particles = random_frame(rng, 30, 100, 2, 1)
    m = ds.Material(7e7, 0.25)
    scene = ds.Scene({1: m, 2: m}, walls=[ds.Wall("a", "plane", 2), ds.Wall("b", "plane", 2)])
    e = check_against_reference(contacts, scene, particles, n_walls=2)
    assert np.all(e.share_n1 == 0.5) and np.all(e.share_t1 == 0.5)
    as32 = {k: (v.astype(np.float32) if v.dtype == np.float64 else v) for k, v in contacts.items()}
    e32 = ds.partition(as32, scene, particles)
    ref = ds.partition(
        {k: v.astype(np.float64) if v.dtype == np.float32 else v for k, v in as32.items()}, scene, particles
    )
    for k in ("u_n", "u_t", "u1", "u2", "depth1", "cp"):
        same(getattr(e32, k), getattr(ref, k))


def test_empty_frame():
    rng = np.random.default_rng(5)
    contacts, particles = random_frame(rng, 10, 0, 2, 2)
    scene = random_scene(rng, 2, 2, "hertz", False)
    e = check_against_reference(contacts, scene, particles, n_walls=2)
    assert e.cp.shape == (0, 3)


def test_unknown_ids_and_walls_are_errors():
    rng = np.random.default_rng(2)
    contacts, particles = random_frame(rng, 20, 50, 2, 2)
    scene = random_scene(rng, 2, 2, "hertz", False)
    bad = dict(contacts, id2=np.where(contacts["wall"] < 0, contacts["id2"], -1))
    bad["id2"][np.flatnonzero(contacts["wall"] < 0)[0]] = 999
    with pytest.raises(ds.ContactError, match="999"):
        ds.partition(bad, scene, particles)
    one_wall = random_scene(rng, 2, 1, "hertz", False)
    wall = contacts["wall"].copy()
    wall[wall >= 0] = 1
    with pytest.raises(ds.ContactError, match="wall"):
        ds.partition(dict(contacts, wall=wall), one_wall, particles)


@pytest.mark.parametrize("dense", [True, False])
def test_contact_rows(dense):
    rng = np.random.default_rng(4)
    contacts, particles = random_frame(rng, 50, 200, 3, 2, dense_ids=dense)
    rows1, rows2 = ParticleIndex(particles["id"]).contact_rows(contacts["id1"], contacts["id2"], contacts["wall"])
    pair = contacts["wall"] < 0
    same(rows1, reference_rows(particles, contacts["id1"]))
    same(rows2[pair], reference_rows(particles, contacts["id2"][pair]))
    same(rows2[~pair], -1 - contacts["wall"][~pair])


# --- the compiled formulas are the numpy ones ------------------------------------------------

HARD = np.array([-1.0, -0.0, 0.0, 5e-324, 1e-300, 1e-12, 1e-3, 0.5, 1e300, np.inf, np.nan])
POSITIVE = np.array([5e-324, 1e-300, 1e-6, 1.0, 7e7, 1e300, np.inf])


def grid(*axes):
    return [a.ravel() for a in np.meshgrid(*axes, indexing="ij")]


def test_compiled_formulas_equal_numpy_bit_for_bit():
    """The scalars the loops compute are the arrays' values: same IEEE operations."""
    d, r1, E = grid(HARD, POSITIVE, POSITIVE)
    with np.errstate(all="ignore"):
        loop_u_n, loop_u_t, _ = kernels.hertz_history_energies(
            d, r1, np.full(len(r1), np.inf), E, E, kernels.NO_CODE, d, r1, E, True
        )
        R = formulas.inverse_curvature_sum(r1, np.inf)  # a particle on a plane: R* = 1/(1/r1)
        same(loop_u_n, elastic.hertz_energy_from_moduli(d, R, E))
        kt = formulas.hertz_kt_formula(elastic.overlap(d), R, E)
        same(loop_u_t, np.where(d > 0, elastic.shear_spring_energy(np.stack([d, r1, E], -1), kt), 0.0))
        r1, r2 = grid(POSITIVE, POSITIVE)
        same(
            np.array([kernels._inverse_curvature_sum(a, b) for a, b in zip(r1, r2)]),
            formulas.inverse_curvature_sum(r1, r2),
        )
        same(np.array([kernels._clamped_overlap(x) for x in HARD]), formulas.clamped_overlap(HARD))
        s_n, u_n, x1, n = grid(np.array([0.0, 0.3, 0.5, 1.0]), HARD, HARD[::2], HARD[1::2])
        loop = kernels.split_contacts(
            np.stack([s_n, s_n[::-1]]),
            kernels.NO_CODE,
            np.stack([u_n, u_n[::-1]]),
            u_n,
            x1,
            x1,
            x1,
            n,
            n,
            n,
            np.abs(x1),
        )
        ref = reference_split(
            {"delta": u_n, "x1": x1, "y1": x1, "z1": x1, "nx": n, "ny": n, "nz": n, "r1": np.abs(x1)},
            s_n,
            s_n[::-1],
            u_n,
            u_n[::-1],
        )
        same(loop[0], np.stack([s_n, s_n[::-1]]))
        for got, k in zip(loop[1:4], ("u1", "u2", "depth1")):
            same(got, ref[k])
        same(loop[4].T, ref["cp"])


def test_hertz_from_codes_equals_per_contact_values():
    rng = np.random.default_rng(9)
    n = 500
    code = rng.integers(0, 4, n).astype(np.int8)
    table = np.array([1e6, 2e9, np.inf, 3e11])
    d, r1, r2, sx, sy, sz = (
        rng.uniform(-1e-5, 1e-4, n),
        rng.uniform(1e-3, 1e-2, n),
        np.full(n, np.inf),
        *rng.normal(size=(3, n)),
    )
    with np.errstate(all="ignore"):
        coded = kernels.hertz_history_energies(d, r1, r2, table, table, code, sx, sy, sz, True)
        flat = kernels.hertz_history_energies(d, r1, r2, table[code], table[code], kernels.NO_CODE, sx, sy, sz, True)
    same(coded[0], flat[0])
    same(coded[1], flat[1])
    bad = kernels.hertz_history_energies(d, -r1, r2, table, table, code, sx, sy, sz, True)[2]
    assert bad == 0


@pytest.mark.slow
@pytest.mark.parametrize("pieces", [1, 3])
def test_the_first_bad_contact_is_found_in_any_piece(pieces, monkeypatch):
    """contact_rows and hertz_history_energies report the first contact naming an unknown id or with
    1/r1 + 1/r2 <= 0, as a contact of the whole list, when the loops run in pieces too."""
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "MIN_RANGE", 1 if pieces > 1 else 1 << 16)
    monkeypatch.setattr(threads, "THREADS", pieces)
    n = 30
    id1, id2, wall = np.arange(n), (np.arange(n) + 1) % n, np.full(n, -1)
    id2[25], id1[27] = 10 * n, -5  # unknown ids, both in the last third
    assert kernels.contact_rows(np.arange(n, dtype=np.int64), id1, id2, wall)[2] == 25
    d, r1, r2 = np.full(n, 1e-5), np.full(n, 1e-3), np.full(n, np.inf)
    r1[[21, 28]] = -1e-3
    E = np.array([1e9])  # one value for all
    assert kernels.hertz_history_energies(d, r1, r2, E, E, kernels.NO_CODE, d, d, d, True)[2] == 21
    assert (
        kernels.hertz_history_energies(d, r1, r2, np.full(n, 1e9), np.full(n, 1e9), kernels.NO_CODE, d, d, d, True)[2]
        == 21
    )


# --- sample runs -----------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["packing", "periodic", "analytic"])
def test_sample_runs_match_numpy(name):
    run = open_run(next((SAMPLES / name).glob("in.*")))
    for k in sorted({0, len(run) - 1}):
        frame = run.frame(k)
        c = frame.contacts
        assert len(c["delta"]) > 0
        check_against_reference(c, run.scene, frame.particles, n_walls=len(run.scene.walls))
        tables = frame_tables(frame, run.scene, Options())
        e = ds.partition(c, run.scene, frame.particles)
        pt, wt = ds.per_particle(c, e, frame.particles, n_walls=len(run.scene.walls))
        for col in ("u", "u_n", "u_t", "n_contacts"):
            same(tables["particles"][col], pt[col])
        cp = frame.box.wrap(e.cp) if frame.box is not None and frame.box.any_periodic else e.cp
        same(np.stack([tables["contacts"][f"cp{a}"] for a in "xyz"], -1), cp)


# --- the LIGGGHTS join -----------------------------------------------------------------------


def reference_repeated_pair(id1, id2):
    """The numpy check the compiled one replaced: one lexsort of the (min, max) pairs."""
    same_ = np.flatnonzero(id1 == id2)
    a, b = np.minimum(id1, id2), np.maximum(id1, id2)
    order = np.lexsort((b, a))
    dup = np.flatnonzero((a[order][1:] == a[order][:-1]) & (b[order][1:] == b[order][:-1]))
    candidates = [(int(same_[0]), int(same_[0]))] if same_.size else []
    if dup.size:
        k = int(np.argmin(order[dup + 1]))
        candidates.append((int(order[dup[k]]), int(order[dup[k] + 1])))
    return min(candidates, key=lambda rows: rows[1]) if candidates else (-1, -1)


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 30), m=st.integers(0, 60), no_self=st.booleans())
def test_repeated_pair_matches_lexsort(seed, n, m, no_self):
    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, n, m), rng.integers(0, n, m)
    if no_self and n > 1:
        b = np.where(a == b, (b + 1) % n, b)
    assert tuple(kernels.repeated_pair(a, b, n)) == reference_repeated_pair(a, b)


@pytest.mark.slow
@pytest.mark.parametrize("pieces", [1, 3])
@pytest.mark.parametrize("periodic", [(False, False, False), (True, True, True), (True, False, True)])
def test_pair_geometry_matches_numpy(periodic, pieces, monkeypatch):
    """One piece, or pieces of the list on the pool's threads (threads.map_ranges): the same numbers."""
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "MIN_RANGE", 1 if pieces > 1 else 1 << 16)
    monkeypatch.setattr(threads, "THREADS", pieces)
    monkeypatch.setattr(threads, "_pool", None)
    rng = np.random.default_rng(8)
    n_particles, n = 40, 300
    box = ds.Box(np.zeros(3), np.array([1.0, 2.0, 0.5]), periodic, np.array([0.1, -0.05, 0.2]))
    x, y, z = (rng.uniform(lo, hi, n_particles) for lo, hi in zip(box.lo, box.hi))
    radius = rng.uniform(0.01, 0.1, n_particles)
    h = rng.choice([0.0, 1e-6, 1e-4], n_particles)
    rows1, rows2 = rng.integers(0, n_particles, n), rng.integers(0, n_particles, n)
    rows2[:5] = rows1[:5]  # dist = 0: the normal is d itself
    xyzr = np.stack([x, y, z, radius], -1)
    got = dict(
        zip(
            ("nx", "ny", "nz", "x1", "y1", "z1", "r1", "r2", "gap", "hmax", "cp"),
            kernels.pair_geometry(rows1, rows2, xyzr, h, box.lengths, box.tilt, box.periodic, True),
        )
    )
    xyz = np.stack([x, y, z], -1)
    d = xyz[rows2] - xyz[rows1]
    if box.any_periodic:
        d = box.minimum_image(d)
    dist = np.sqrt(np.einsum("ij,ij->i", d, d))
    normal = d / np.where(dist > 0, dist, 1.0)[:, None]
    r1, r2 = radius[rows1], radius[rows2]
    for k, v in (("nx", normal[:, 0]), ("ny", normal[:, 1]), ("nz", normal[:, 2]), ("gap", r1 + r2 - dist)):
        same(got[k], v, rtol=1e-12)  # |d|^2 summed in order; einsum's order may differ by one ulp
    for k, v in (
        ("x1", x[rows1]),
        ("y1", y[rows1]),
        ("z1", z[rows1]),
        ("r1", r1),
        ("r2", r2),
        ("hmax", np.maximum(h[rows1], h[rows2])),
    ):
        same(got[k], v)
    same(got["cp"].T, xyz[rows1] + (r1 / (r1 + r2))[:, None] * d)
    no_h_no_cp = kernels.pair_geometry(rows1, rows2, xyzr, h[:0], box.lengths, box.tilt, box.periodic, False)
    assert no_h_no_cp[-2].size == 0 and no_h_no_cp[-1].size == 0
    for a, b in zip(no_h_no_cp[:-2], got.values()):
        same(a, b)


def test_minimum_image_compiled_is_the_box_formula():
    rng = np.random.default_rng(1)
    box = ds.Box(np.zeros(3), np.array([1.0, 2.0, 0.5]), (True, True, True), np.array([0.1, -0.05, 0.2]))
    d = rng.uniform(-3, 3, (200, 3))
    loop = np.array([kernels._minimum_image(*v, box.lengths, box.tilt, box.periodic) for v in d])
    same(loop, box.minimum_image(d))


def test_walls_with_their_own_model():
    """Pairs under hertz (compiled, on a subset of the rows), walls under hooke (numpy)."""
    rng = np.random.default_rng(12)
    contacts, particles = random_frame(rng, 40, 200, 2, 2)
    scene = random_scene(rng, 2, 2, "hertz", False)
    hooke = ds.ContactModel("liggghts:hooke", {"tangential": "history", "characteristic_velocity": 1.0})
    scene = ds.Scene(
        scene.materials,
        model=scene.model,
        walls=[ds.Wall(w.name, w.kind, type=w.type, model=hooke) for w in scene.walls],
    )
    e = check_against_reference(contacts, scene, particles, n_walls=2)
    wall = contacts["wall"] >= 0
    assert wall.sum() > 10
    u_n, _ = reference_hertz(contacts, reference_constants(contacts, scene, particles))
    assert not np.array_equal(e.u_n[wall], u_n[wall])  # the walls' own law, not hertz


@pytest.mark.parametrize("n, threads_, expect", [(10, 4, 1), (1 << 17, 1, 1), (1 << 17, 2, 2), (3 << 16, 8, 3)])
def test_map_ranges_tiles_the_rows_in_order(n, threads_, expect, monkeypatch):
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "THREADS", threads_)
    monkeypatch.setattr(threads, "_pool", None)
    pieces = threads.map_ranges(lambda lo, hi: (lo, hi), n)
    assert len(pieces) == expect and pieces[0][0] == 0 and pieces[-1][1] == n
    assert all(a[1] == b[0] for a, b in zip(pieces, pieces[1:]))


@pytest.mark.parametrize("seed", range(3))
def test_signed_particle_sums_are_the_two_bincounts(seed):
    """The expected error per particle: bit for bit the difference of two bincounts (body 1, body 2 of pairs)."""
    rng = np.random.default_rng(seed)
    n, m = 5000, 300
    rows1 = rng.integers(0, m, n).astype(np.int32)
    rows2 = np.where(rng.random(n) < 0.2, -1 - rng.integers(0, 3, n), rng.integers(0, m, n)).astype(np.int32)
    e, u = rng.normal(scale=0.01, size=n), rng.exponential(size=n)
    du, pair = e * u, rows2 >= 0
    expect = np.bincount(rows1, du, minlength=m) - np.bincount(rows2[pair], du[pair], minlength=m)
    got = kernels.signed_particle_sums(rows1, rows2, e, u, m)
    assert np.array_equal(got, expect)
