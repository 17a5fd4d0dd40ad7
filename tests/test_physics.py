"""Physics core: the paper's tables, hard numerical cases, and properties of the law."""

from __future__ import annotations

import tracemalloc

import demsplit as ds
import mpmath
import numpy as np
import pytest
from demsplit.physics.bodies import ContactBodies, FrameContacts
from demsplit.physics.partition import law_energies, split_energies
from hypothesis import given, settings
from hypothesis import strategies as st

GPa = 1e9
mm = 1e-3

# Feng & Gao, Table 2 (sphere-sphere, r1 = 5 mm, E2 = 210 GPa, nu2 = 0.3):
# case: (delta mm, E1 GPa, nu1, r2 mm, P_A N, theoretical S1/S2, S1^N mJ, S2^N mJ, printed S1^N/S2^N)
TABLE2 = {
    1: (0.05, 210, 0.3, 10, 3140.4, 1.0000, 31.83, 32.35, 0.9838),
    2: (0.1, 210, 0.3, 10, 8882.3, 1.0000, 181.16, 185.65, 0.9758),
    3: (0.2, 210, 0.3, 10, 25123.0, 1.0000, 1033.72, 1073.11, 0.9633),
    4: (0.1, 105, 0.3, 10, 5921.5, 2.0000, 161.75, 83.80, 1.9302),
    5: (0.1, 70, 0.3, 10, 4441.2, 3.0000, 136.99, 47.58, 2.8793),
    6: (0.1, 210, 0.2, 10, 8644.8, 1.0549, 180.40, 174.10, 1.0362),
    7: (0.1, 210, 0.1, 10, 8508.3, 1.0879, 179.52, 166.16, 1.0804),
    8: (0.1, 210, 0.0, 10, 8463.8, 1.0989, 178.74, 161.33, 1.1079),
    9: (0.1, 210, 0.3, 7.5, 8426.5, 1.0000, 172.96, 175.70, 0.9844),
    10: (0.1, 210, 0.3, 12.5, 9194.1, 1.0000, 186.75, 192.48, 0.9702),
    11: (0.1, 210, 0.3, 15, 9421.1, 1.0000, 190.83, 197.46, 0.9664),
}
# Tables 3 (sphere-ellipsoid) and 4 (ellipsoid-ellipsoid): body 2 is 210 GPa, nu 0.3.
# case: (E1 GPa, nu1, theoretical S1/S2, S1^N, S2^N, printed S1^N/S2^N)
TABLE3 = {
    1: (210, 0.3, 1.0000, 193.2577, 194.3198, 0.9945),
    2: (105, 0.3, 2.0000, 171.4852, 87.14262, 1.9678),
    3: (70, 0.3, 3.0000, 144.7787, 49.31208, 2.9360),
    4: (210, 0.2, 1.0549, 192.3510, 182.0032, 1.0569),
    5: (210, 0.1, 1.0879, 191.3341, 173.4979, 1.1028),
    6: (210, 0.0, 1.0989, 190.4456, 168.2636, 1.1318),
}
TABLE4 = {
    1: (210, 0.3, 1.0000, 253.4779, 262.9316, 0.9640),
    2: (105, 0.3, 2.0000, 227.4210, 119.0027, 1.9111),
    3: (70, 0.3, 3.0000, 193.0285, 67.6389, 2.8538),
    4: (210, 0.2, 1.0549, 252.7689, 247.0227, 1.0233),
    5: (210, 0.1, 1.0879, 251.8711, 236.8021, 1.0636),
    6: (210, 0.0, 1.0989, 251.1049, 231.4657, 1.0848),
}


def ratio(share1):
    """S1/S2 from the share of body 1."""
    return share1 / (1.0 - share1)


@pytest.mark.parametrize("case", sorted(TABLE2))
def test_table2_theoretical_ratio_and_hertz_force(case):
    delta, E1, nu1, r2, P_A, S_ratio, *_ = TABLE2[case]
    s1 = ds.normal_share(E1 * GPa, nu1, 210 * GPa, 0.3)
    assert round(float(ratio(s1)), 4) == S_ratio
    P = ds.hertz_force(delta * mm, 5 * mm, r2 * mm, E1 * GPa, nu1, 210 * GPa, 0.3)
    assert abs(float(P) - P_A) <= 0.05  # printed to 0.1 N
    # S_e = (2/5) P delta, eq. (13)
    S = ds.hertz_energy(delta * mm, 5 * mm, r2 * mm, E1 * GPa, nu1, 210 * GPa, 0.3)
    assert float(S) == pytest.approx(0.4 * float(P) * delta * mm, rel=1e-14)


@pytest.mark.parametrize("table", [TABLE3, TABLE4], ids=["table3", "table4"])
def test_tables_3_4_theoretical_ratio(table):
    for E1, nu1, S_ratio, *_ in table.values():
        assert round(float(ratio(ds.normal_share(E1 * GPa, nu1, 210 * GPa, 0.3))), 4) == S_ratio


def test_printed_fe_ratios_match_printed_energies_except_known_rounding():
    """The printed FE ratio S1^N/S2^N against the ratio of the printed energies.

    The theoretical column reproduces everywhere (tests above). In the FE
    column three printed ratios differ in the last digit from the ratio of the
    printed energies: Table 2 cases 1 and 5 (0.9838 and 2.8793 against 0.9839
    and 2.8792: the energies are printed to 0.01 mJ, whose rounding moves the
    ratio by up to 3e-4) and Table 3 case 2 (1.9678 against 1.96787, truncated
    rather than rounded)."""
    mismatches = set()
    for name, table, cols in (("T2", TABLE2, (6, 7, 8)), ("T3", TABLE3, (3, 4, 5)), ("T4", TABLE4, (3, 4, 5))):
        for case, row in table.items():
            s1, s2, printed = (row[c] for c in cols)
            if round(s1 / s2, 4) != printed:
                mismatches.add((name, case))
                assert abs(s1 / s2 - printed) < 2e-4
    assert mismatches == {("T2", 1), ("T2", 5), ("T3", 2)}


# --- hard cases ----------------------------------------------------------------------------

STEEL = (210 * GPa, 0.3)
GLASS = (70 * GPa, 0.22)


def mp_hertz_energy(delta, R1, R2, E1, nu1, E2, nu2):
    mpmath.mp.dps = 50
    d, R1, R2, E1, nu1, E2, nu2 = (
        mpmath.mpf(x) if np.isfinite(x) else mpmath.inf for x in (delta, R1, R2, E1, nu1, E2, nu2)
    )
    E = 1 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    R = 1 / (1 / R1 + 1 / R2)
    return mpmath.mpf(8) / 15 * E * mpmath.sqrt(R) * d ** mpmath.mpf(2.5)


def test_zero_overlap():
    assert ds.hertz_energy(0.0, 1e-3, 1e-3, *STEEL, *GLASS) == 0.0
    assert ds.hertz_force(0.0, 1e-3, 1e-3, *STEEL, *GLASS) == 0.0
    assert ds.hooke_energy(0.0, 1e5) == 0.0
    assert 0 < ds.normal_share(*STEEL, *GLASS) < 1  # defined without an overlap


def test_negative_overlap_is_zero_energy_and_flagged():
    d = np.array([-1e-6, -0.0, 1e-6])
    for u in (
        ds.hertz_energy(d, 1e-3, 2e-3, *STEEL, *GLASS),
        ds.hertz_force(d, 1e-3, 2e-3, *STEEL, *GLASS),
        ds.hooke_energy(d, 1e5),
        ds.power_law_energy(d, 1e5, 1.3),
    ):
        assert np.all(np.isfinite(u)) and u[0] == 0 and u[1] == 0 and u[2] > 0
    contacts, particles = two_sphere_frame(delta=d, r1=1e-3, r2=2e-3)
    scene = ds.Scene({1: ds.Material(*STEEL), 2: ds.Material(*GLASS)})
    e = ds.partition(contacts, scene, particles)
    assert e.separated.tolist() == [True, False, False]
    assert np.all(np.isfinite(e.cp)) and e.u_n[0] == 0


@pytest.mark.parametrize("delta_over_R", [1e-300, 1e-12])
def test_tiny_overlap_against_mpmath(delta_over_R):
    R1, R2 = 1e-3, 3e-3
    delta = delta_over_R * R1
    ours = ds.hertz_energy(delta, R1, R2, *STEEL, *GLASS)
    ref = mp_hertz_energy(delta, R1, R2, *STEEL, *GLASS)
    assert np.isfinite(ours)
    if float(ref) == 0.0:  # the true value (~1e-740 J) is below the smallest double: 0 is its rounding
        assert ours == 0.0 and abs(ref) < 1e-300
    else:
        assert abs((ours - ref) / ref) < 1e-12
    s = ds.normal_share(*STEEL, *GLASS)
    d1, d2 = ds.overlap_depths(delta, s)
    assert d1 > 0 and d2 > 0 and d1 + d2 == pytest.approx(delta, rel=1e-15)


@pytest.mark.parametrize("ratio_R", [1e6, 1e-6])
def test_extreme_radius_ratio_against_mpmath(ratio_R):
    R1, delta = 1e-3, 1e-9
    R2 = R1 / ratio_R
    ours = ds.hertz_energy(delta, R1, R2, *STEEL, *GLASS)
    ref = mp_hertz_energy(delta, R1, R2, *STEEL, *GLASS)
    assert abs((ours - ref) / ref) < 1e-12
    # radius plays no role in the split
    assert ds.normal_share(*STEEL, *GLASS) == ds.normal_share(*STEEL, *GLASS)


def test_plane_R2_inf():
    u = ds.hertz_energy(1e-6, 1e-3, np.inf, *STEEL, *GLASS)
    ref = mp_hertz_energy(1e-6, 1e-3, np.inf, *STEEL, *GLASS)
    assert abs((u - ref) / ref) < 1e-13
    assert ds.effective_radius(1e-3, np.inf) == 1e-3


def test_rigid_body_on_one_side():
    assert ds.normal_share(np.inf, 0.3, *GLASS) == 0.0
    assert ds.normal_share(*GLASS, np.inf, 0.3) == 1.0
    assert ds.tangential_share(np.inf, 0.3, *GLASS) == 0.0
    # E* is then the partner's plane-strain modulus
    assert ds.effective_modulus(np.inf, 0.3, *GLASS) == pytest.approx(GLASS[0] / (1 - GLASS[1] ** 2), rel=1e-15)
    u = ds.hertz_energy(1e-6, 1e-3, 1e-3, np.inf, 0.3, *GLASS)
    assert np.isfinite(u) and u > 0


def test_two_rigid_bodies_is_an_error():
    with pytest.raises(ds.ContactError, match="two rigid bodies"):
        ds.normal_share(np.inf, 0.3, np.inf, 0.2)
    with pytest.raises(ds.ContactError, match="two rigid bodies"):
        ds.effective_modulus(np.inf, 0.3, np.inf, 0.2)
    contacts, particles = two_sphere_frame(delta=np.array([1e-6]), r1=1e-3, r2=1e-3)
    scene = ds.Scene({1: ds.Material(np.inf, 0.3), 2: ds.Material(np.inf, 0.2)})
    with pytest.raises(ds.ContactError, match=r"id1=1, id2=2"):
        ds.partition(contacts, scene, particles)


def test_poisson_half():
    # normal: c = 0.75/E, harmless
    assert ds.normal_share(1 * GPa, 0.5, 1 * GPa, 0.5) == 0.5
    assert ds.normal_share(1 * GPa, 0.5, 3 * GPa, 0.5) == pytest.approx(0.75, rel=1e-15)
    # Mindlin: (2 - nu)/G is finite at nu = 0.5
    assert 0 < ds.tangential_share(1 * GPa, 0.5, 2 * GPa, 0.3) < 1
    # paper rule: (1 - 2 nu)/G vanishes; one side 0.5 gets nothing ...
    assert ds.tangential_share(1 * GPa, 0.5, 2 * GPa, 0.3, rule="paper") == 0.0
    # ... both sides 0.5: the limit nu1 = nu2 -> 0.5, share1 = (1/G1)/(1/G1 + 1/G2) = E2/(E1 + E2)
    assert ds.tangential_share(1 * GPa, 0.5, 3 * GPa, 0.5, rule="paper") == pytest.approx(0.75, rel=1e-15)
    # and that limit is what the rule gives just below 0.5
    near = ds.tangential_share(1 * GPa, 0.5 - 1e-9, 3 * GPa, 0.5 - 1e-9, rule="paper")
    assert near == pytest.approx(0.75, rel=1e-8)


@pytest.mark.parametrize("nu", [0.0, -0.9])
def test_zero_and_negative_poisson(nu):
    s = ds.normal_share(1 * GPa, nu, 2 * GPa, 0.25)
    c1, c2 = (1 - nu**2) / 1e9, (1 - 0.25**2) / 2e9
    assert s == pytest.approx(c1 / (c1 + c2), rel=1e-15)
    t = ds.tangential_share(1 * GPa, nu, 2 * GPa, 0.25)
    t1, t2 = 2 * (2 - nu) * (1 + nu) / 1e9, 2 * (2 - 0.25) * 1.25 / 2e9
    assert t == pytest.approx(t1 / (t1 + t2), rel=1e-15)


def test_invalid_materials():
    with pytest.raises(ds.MaterialError, match="Poisson"):
        ds.Material(1e9, 0.6)
    with pytest.raises(ds.MaterialError, match="Poisson"):
        ds.Material(1e9, -1.0)
    with pytest.raises(ds.MaterialError, match="Young"):
        ds.Material(0.0, 0.3)
    with pytest.raises(ds.MaterialError, match="Young"):
        ds.Material(float("nan"), 0.3)


def test_type_without_material():
    contacts, particles = two_sphere_frame(delta=np.array([1e-6]), r1=1e-3, r2=1e-3)
    scene = ds.Scene({1: ds.Material(*STEEL), 3: ds.Material(*GLASS)})
    with pytest.raises(ds.MaterialError, match=r"type\(s\) \[2\] have no material"):
        ds.partition(contacts, scene, particles)


def test_float32_input_is_upcast():
    d32 = np.array([1e-6, 2e-6], dtype=np.float32)
    u = ds.hertz_energy(d32, np.float32(1e-3), np.float32(2e-3), *STEEL, *GLASS)
    assert u.dtype == np.float64
    ref = ds.hertz_energy(d32.astype(np.float64), float(np.float32(1e-3)), float(np.float32(2e-3)), *STEEL, *GLASS)
    assert np.array_equal(u, ref)


def test_other_laws():
    assert ds.hooke_energy(2e-6, 1e5) == pytest.approx(0.5 * 1e5 * 4e-12, rel=1e-15)
    # power law with n = 3/2 and k = (4/3) E* sqrt(R*) is Hertz
    E = ds.effective_modulus(*STEEL, *GLASS)
    R = ds.effective_radius(1e-3, 2e-3)
    k = 4 / 3 * E * np.sqrt(R)
    assert ds.power_law_energy(1e-6, k, 1.5) == pytest.approx(
        ds.hertz_energy(1e-6, 1e-3, 2e-3, *STEEL, *GLASS), rel=1e-13
    )
    ft = np.array([[3.0, 4.0, 0.0]])
    assert ds.tangential_spring_energy(ft, 10.0)[0] == pytest.approx(25 / 20, rel=1e-15)
    assert ds.tangential_spring_energy(ft, 0.0)[0] == 0.0  # separated YADE contact: ks = 0
    assert ds.shear_spring_energy(np.array([[3e-6, 4e-6, 0]]), 1e4)[0] == pytest.approx(0.5 * 1e4 * 25e-12)


@pytest.mark.slow
def test_ten_million_contacts_memory():
    n = 10**7
    rng = np.random.default_rng(1)
    delta = rng.uniform(0, 1e-5, n)
    R1 = rng.uniform(1e-3, 2e-3, n)
    R2 = rng.uniform(1e-3, 2e-3, n)
    E1 = np.full(n, STEEL[0])
    nu1 = np.full(n, STEEL[1])
    E2 = np.full(n, GLASS[0])
    nu2 = np.full(n, GLASS[1])
    inputs = sum(a.nbytes for a in (delta, R1, R2, E1, nu1, E2, nu2))
    tracemalloc.start()
    u = ds.hertz_energy(delta, R1, R2, E1, nu1, E2, nu2)
    s = ds.normal_share(E1, nu1, E2, nu2)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak <= 2 * inputs, f"peak {peak / 1e6:.0f} MB for {inputs / 1e6:.0f} MB of input"
    i = 12345
    assert u[i] == pytest.approx(float(mp_hertz_energy(delta[i], R1[i], R2[i], *STEEL, *GLASS)), rel=1e-13)
    assert np.all((s > 0) & (s < 1))


# --- partition on a frame --------------------------------------------------------------------


def two_sphere_frame(delta, r1, r2, n=None):
    """Particle 1 (type 1) at the origin, particle 2 (type 2) along +x at r1 + r2 - delta."""
    delta = np.atleast_1d(np.asarray(delta, dtype=float))
    k = len(delta)
    particles = {
        "id": np.array([1, 2]),
        "type": np.array([1, 2], dtype=np.int32),
        "x": np.array([0.0, r1 + r2 - delta[-1]]),
        "y": np.zeros(2),
        "z": np.zeros(2),
        "radius": np.array([r1, r2]),
    }
    contacts = {
        "id1": np.ones(k, np.int64),
        "id2": np.full(k, 2, np.int64),
        "wall": np.full(k, -1, np.int64),
        "delta": delta,
        "nx": np.ones(k),
        "ny": np.zeros(k),
        "nz": np.zeros(k),
        "x1": np.zeros(k),
        "y1": np.zeros(k),
        "z1": np.zeros(k),
        "r1": np.full(k, r1),
        "r2": np.full(k, r2),
    }
    return contacts, particles


def random_frame(rng, n_particles=50, n_contacts=200, n_walls=2, with_shear=True):
    ids = rng.permutation(np.arange(1, n_particles + 1))
    particles = {
        "id": ids,
        "type": rng.integers(1, 3, n_particles).astype(np.int32),
        "x": rng.uniform(0, 1, n_particles),
        "y": rng.uniform(0, 1, n_particles),
        "z": rng.uniform(0, 1, n_particles),
        "radius": rng.uniform(1e-3, 3e-3, n_particles),
    }
    i = rng.integers(0, n_particles, n_contacts)
    j = (i + rng.integers(1, n_particles, n_contacts)) % n_particles
    wall = np.where(rng.random(n_contacts) < 0.2, rng.integers(0, n_walls, n_contacts), -1)
    normal = rng.normal(size=(n_contacts, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    r1 = particles["radius"][i]
    r2 = np.where(wall >= 0, np.inf, particles["radius"][j])
    contacts = {
        "id1": ids[i],
        "id2": np.where(wall >= 0, -1, ids[j]),
        "wall": wall,
        "delta": rng.uniform(-1e-6, 1e-5, n_contacts),
        "nx": normal[:, 0],
        "ny": normal[:, 1],
        "nz": normal[:, 2],
        "x1": particles["x"][i],
        "y1": particles["y"][i],
        "z1": particles["z"][i],
        "r1": r1,
        "r2": r2,
    }
    if with_shear:
        for c in ("shearx", "sheary", "shearz"):
            contacts[c] = rng.normal(scale=1e-6, size=n_contacts)
    return contacts, particles


def two_material_scene(n_walls=2, wall_material=(200 * GPa, 0.3)):
    walls = [ds.Wall(f"w{k}", "plane", type=3) for k in range(n_walls)]
    return ds.Scene({1: ds.Material(*STEEL), 2: ds.Material(*GLASS), 3: ds.Material(*wall_material)}, walls=walls)


def test_conservation_per_frame():
    rng = np.random.default_rng(7)
    contacts, particles = random_frame(rng)
    scene = two_material_scene()
    e = ds.partition(contacts, scene, particles)
    pt, wt = ds.per_particle(contacts, e, particles, n_walls=2)
    total = np.sum(e.u_n + e.u_t)
    assert total > 0
    assert abs(pt["u"].sum() + wt["u"].sum() - total) <= 1e-12 * total
    assert abs(pt["u_n"].sum() + wt["u_n"].sum() - e.u_n.sum()) <= 1e-12 * e.u_n.sum()
    assert pt["n_contacts"].sum() + wt["n_contacts"].sum() == 2 * len(e.u_n)  # every contact has two bodies


def test_per_particle_by_hand():
    contacts, particles = two_sphere_frame(delta=np.array([2e-6]), r1=1e-3, r2=2e-3)
    scene = ds.Scene({1: ds.Material(*STEEL), 2: ds.Material(*GLASS)})
    e = ds.partition(contacts, scene, particles)
    pt, _ = ds.per_particle(contacts, e, particles)
    c1, c2 = (1 - 0.09) / 210e9, (1 - 0.22**2) / 70e9
    u = 8 / 15 / (c1 + c2) * np.sqrt(1e-3 * 2e-3 / 3e-3) * (2e-6) ** 2.5
    assert pt["u"][0] == pytest.approx(u * c1 / (c1 + c2), rel=1e-13)
    assert pt["u"][1] == pytest.approx(u * c2 / (c1 + c2), rel=1e-13)
    assert "u_t" in e.missing and "u_t" not in e.skipped  # no shear history in this frame: said, not guessed
    assert np.all(e.not_computed == 2)  # every contact's u_t is unknown


def test_single_material_skips_lookup_and_matches():
    rng = np.random.default_rng(3)
    contacts, particles = random_frame(rng)
    m = ds.Material(*STEEL)
    scene = ds.Scene({1: m, 2: m, 3: m}, walls=[ds.Wall("a", "plane", 3), ds.Wall("b", "plane", 3)])
    assert scene.single_material
    fast = ds.partition(contacts, scene, particles)
    n = len(contacts["delta"])
    looked_up = ContactBodies(None, None, np.full(n, m.E), np.full(n, m.nu), np.full(n, m.E), np.full(n, m.nu), False)
    frame = FrameContacts(contacts, scene, particles)
    frame.bodies = looked_up
    slow = split_energies(frame, law_energies(frame))
    for name in ("u_n", "u_t", "u1", "u2", "depth1", "cp", "share_n1", "share_t1"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name


# --- properties ------------------------------------------------------------------------------

moduli = st.one_of(st.floats(1e5, 1e13), st.just(np.inf))
poisson = st.floats(-0.99, 0.5)


@settings(max_examples=300, deadline=None)
@given(moduli, poisson, moduli, poisson)
def test_swap_and_bounds(E1, nu1, E2, nu2):
    if np.isinf(E1) and np.isinf(E2):
        return
    for fn in (ds.normal_share, ds.tangential_share):
        s12 = fn(E1, nu1, E2, nu2)
        s21 = fn(E2, nu2, E1, nu1)
        assert 0.0 <= s12 <= 1.0
        assert s12 + (1.0 - s12) == 1.0
        assert abs(s12 - (1.0 - s21)) <= 2.0**-53  # swapping the bodies swaps the shares (to one ulp of 1)
    if E1 == E2 and nu1 == nu2:
        assert ds.normal_share(E1, nu1, E2, nu2) == 0.5


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_conservation_property(seed):
    contacts, particles = random_frame(np.random.default_rng(seed), n_particles=20, n_contacts=60)
    e = ds.partition(contacts, two_material_scene(), particles)
    pt, wt = ds.per_particle(contacts, e, particles, n_walls=2)
    total = np.sum(e.u_n + e.u_t)
    assert abs(pt["u"].sum() + wt["u"].sum() - total) <= 1e-12 * max(total, 1e-300)
    assert np.all(e.u1 >= 0) and np.all(e.u2 >= 0)


@settings(max_examples=200, deadline=None)
@given(moduli, poisson, moduli, poisson, st.floats(1e-4, 1e-1), st.floats(1e-4, 1e-1), st.floats(1e-9, 1e-3))
def test_contact_point_in_overlap_lens(E1, nu1, E2, nu2, r1, r2, frac):
    if np.isinf(E1) and np.isinf(E2):
        return
    delta = frac * min(r1, r2)
    x1 = np.array([[0.3, -0.2, 0.1]])
    n = np.array([[2.0, 3.0, 6.0]]) / 7.0
    s = ds.normal_share(E1, nu1, E2, nu2)
    cp = ds.contact_point(x1, n, r1, delta, s)[0]
    along = (cp - x1[0]) @ n[0]
    off_line = np.linalg.norm(cp - x1[0] - along * n[0])
    tol = 8 * np.finfo(float).eps * (np.linalg.norm(x1) + r1)  # rounding of x1 + arm*n and of the projection
    assert off_line <= tol
    assert r1 - delta - tol <= along <= r1 + tol  # inside the lens [r1 - delta, r1] along the line of centres
    if E1 == E2 and nu1 == nu2:
        assert abs(along - (r1 - delta / 2)) <= tol
