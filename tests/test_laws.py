"""Every registered contact law, by the same properties (scikit-fem style registry-wide tests).

A new law file is picked up here with no edit: each test loops over
``laws.supported()``. The contacts are random but physical: two materials, a
plane wall, overlaps from touching to 10 % of the smaller radius, and every
column a law declares filled with plausible values.
"""

from __future__ import annotations

import ast
from pathlib import Path

import demsplit as ds
import numpy as np
import pytest
from demsplit.errors import UnsupportedModelError
from demsplit.frame import ParticleIndex
from demsplit.physics import laws
from demsplit.physics.bodies import FrameContacts, LawRows
from demsplit.physics.modes import ADHESION_COLUMN, MODE_COLUMNS
from demsplit.physics.partition import contact_energies
from demsplit.scene import scene_from_dict, scene_to_dict

REPO = Path(__file__).resolve().parents[1]
KEYS = laws.supported()
N = 400


def scene_of(key: str) -> ds.Scene:
    model = ds.ContactModel(key, laws.law_class(key).example_params)
    return ds.Scene(
        {1: ds.Material(7e10, 0.22), 2: ds.Material(3e9, 0.35), 3: ds.Material(2e11, 0.3)},
        model=model,
        walls=[ds.Wall("floor", "plane", 3)],
    )


def frame_of(key: str, seed: int = 0, delta: np.ndarray | None = None) -> tuple[dict, dict]:
    """Particles and contacts (30 % on the wall) with every column the law reads."""
    rng = np.random.default_rng(seed)
    n_p = 60
    particles = {
        "id": np.arange(1, n_p + 1, dtype=np.int64),
        "type": rng.integers(1, 3, n_p).astype(np.int32),
        "x": rng.uniform(0, 1, n_p),
        "y": rng.uniform(0, 1, n_p),
        "z": rng.uniform(0, 1, n_p),
        "radius": rng.uniform(1e-3, 3e-3, n_p),
        "mass": rng.uniform(1e-5, 1e-4, n_p),
    }
    i = rng.integers(0, n_p, N)
    j = (i + rng.integers(1, n_p, N)) % n_p
    wall = np.where(rng.random(N) < 0.3, 0, -1)
    r1 = particles["radius"][i]
    r2 = np.where(wall >= 0, np.inf, particles["radius"][j])
    normal = rng.normal(size=(N, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    if delta is None:
        delta = rng.uniform(0, 0.1, N) * np.minimum(r1, r2)
    contacts = {
        "id1": particles["id"][i],
        "id2": np.where(wall >= 0, -1, particles["id"][j]).astype(np.int64),
        "wall": wall.astype(np.int64),
        "delta": delta,
        "nx": normal[:, 0],
        "ny": normal[:, 1],
        "nz": normal[:, 2],
        "x1": particles["x"][i],
        "y1": particles["y"][i],
        "z1": particles["z"][i],
        "r1": r1,
        "r2": r2,
    }
    for column in laws.make(key, laws.law_class(key).example_params).needs():
        if column.startswith("k"):  # stiffnesses (N/m, N/m^1.5) are positive
            contacts[column] = rng.uniform(1e5, 1e7, N)
        elif column.startswith("shear"):  # spring displacements (m)
            contacts[column] = rng.normal(scale=1e-5, size=N)
        elif column == "delta_p_max":  # a plastic overlap (m), below the current one
            contacts[column] = np.maximum(delta, 0) * rng.uniform(0.0, 0.99, N)
        elif column == "delta_max":  # the largest overlap so far (m): beyond the current one
            contacts[column] = np.maximum(delta, 0) * rng.uniform(1.01, 3.0, N)
        elif column == "tn_delta_old":  # the overlap at the last evaluation (m): the current one
            contacts[column] = delta
        else:  # forces (N)
            contacts[column] = rng.normal(scale=1.0, size=N)
    return particles, contacts


def law_rows(key: str, particles: dict, contacts: dict) -> tuple[laws.ContactLaw, LawRows]:
    scene = scene_of(key)
    return scene.model.contact_law, LawRows(FrameContacts(contacts, scene, particles), slice(None), key)


def test_registry_lists_every_law_file():
    files = {
        p.stem
        for p in (REPO / "plugin" / "physics" / "laws").glob("*.py")
        if not p.stem.startswith("_") and p.stem != "base"
    }
    modules = {laws.law_class(k).__module__.rsplit(".", 1)[1] for k in KEYS}
    assert modules == files
    assert all(":" in k for k in KEYS)  # simulator:name


def test_unknown_law_lists_the_supported_ones():
    with pytest.raises(UnsupportedModelError) as err:
        ds.ContactModel("liggghts:no_such_model")
    assert all(k in str(err.value) for k in KEYS)


@pytest.mark.parametrize("key", KEYS)
def test_declarations(key):
    cls = laws.law_class(key)
    law = laws.make(key, cls.example_params)
    line = law.describe()
    assert key in line and "\n" not in line and cls.summary in line
    assert law.modes and set(law.modes) <= {*MODE_COLUMNS, ADHESION_COLUMN}
    assert set(law.mode_columns) <= set(law.modes)
    for name, (_, meaning) in cls.parameters.items():
        assert meaning, name
    for _, (method, modes) in cls.simulator_energies.items():
        assert method and set(modes) <= set(law.modes)


@pytest.mark.parametrize("key", KEYS)
def test_model_round_trips_through_the_scene_dict(key):
    scene = scene_of(key)
    again = scene_from_dict(scene_to_dict(scene))
    assert again.model == scene.model and again.model.describe() == scene.model.describe()


@pytest.mark.parametrize("key", KEYS)
def test_energy_is_finite_and_not_negative(key):
    law, rows = law_rows(key, *frame_of(key))
    result = law.energies(rows)
    assert set(result.modes) == set(law.modes) and not result.skipped
    for mode, u in result.modes.items():
        assert u.shape == (N,) and np.all(np.isfinite(u)), mode
        assert mode == ADHESION_COLUMN or np.all(u >= 0), mode  # cohesion work is signed
        assert np.any(u != 0), mode


OVERLAP_LAWS = [k for k in KEYS if not laws.law_class(k).normal_from_stored_force]


@pytest.mark.parametrize("key", OVERLAP_LAWS)
def test_no_energy_without_overlap(key):
    particles, contacts = frame_of(key, delta=-np.random.default_rng(3).uniform(0, 1e-4, N))
    contacts["delta"][:5] = 0.0
    law, rows = law_rows(key, particles, contacts)
    for mode, u in law.energies(rows).modes.items():
        assert np.all(u == 0), mode
    assert np.all(law.normal_force(rows) == 0)


@pytest.mark.parametrize("key", OVERLAP_LAWS)
def test_normal_force_is_the_derivative_of_the_normal_energy(key):
    """dU_n/d(delta) by a central difference (step 1e-6 delta) equals the law's elastic normal force."""
    particles, contacts = frame_of(key, seed=5)
    law, rows = law_rows(key, particles, contacts)
    force = law.normal_force(rows)
    h = 1e-6 * contacts["delta"]
    u = {}
    for sign in (1, -1):
        law_s, rows_s = law_rows(key, particles, {**contacts, "delta": contacts["delta"] + sign * h})
        u[sign] = law_s.energies(rows_s).modes["u_n"]
    np.testing.assert_allclose((u[1] - u[-1]) / (2 * h), force, rtol=1e-6)


@pytest.mark.parametrize("key", [k for k in KEYS if laws.law_class(k).compiled])
def test_compiled_equals_numpy(key):
    particles, contacts = frame_of(key, seed=7)
    contacts["delta"][:20] = -contacts["delta"][:20]  # separated contacts too
    law, rows = law_rows(key, particles, contacts)
    compiled, plain = law.energies(rows, compiled=True), law.energies(rows, compiled=False)
    assert compiled.modes.keys() == plain.modes.keys()
    for mode in compiled.modes:
        np.testing.assert_array_equal(compiled.modes[mode], plain.modes[mode])


def swapped(particles: dict, contacts: dict) -> dict:
    """The particle pairs with body 1 and body 2 exchanged (normal reversed, centre of the other body)."""
    pair = contacts["wall"] < 0
    c = {k: v[pair] for k, v in contacts.items()}
    index = ParticleIndex(particles["id"])
    rows2 = index.rows(c["id2"])
    out = dict(
        c,
        id1=c["id2"],
        id2=c["id1"],
        r1=c["r2"],
        r2=c["r1"],
        nx=-c["nx"],
        ny=-c["ny"],
        nz=-c["nz"],
        x1=particles["x"][rows2],
        y1=particles["y"][rows2],
        z1=particles["z"][rows2],
    )
    for k in ("ftx", "fty", "ftz", "shearx", "sheary", "shearz"):
        if k in out:
            out[k] = -c[k]  # a vector quantity seen from the other body
    return out


@pytest.mark.parametrize("key", KEYS)
def test_swapping_the_bodies_swaps_the_shares(key):
    particles, contacts = frame_of(key, seed=11)
    scene = scene_of(key)
    pair = contacts["wall"] < 0
    e = ds.partition({k: v[pair] for k, v in contacts.items()}, scene, particles)
    s = ds.partition(swapped(particles, contacts), scene, particles)
    np.testing.assert_allclose(s.u, e.u, rtol=1e-14)  # the energy of a contact does not depend on the order
    np.testing.assert_allclose(s.shares, 1.0 - e.shares, rtol=0, atol=2.0**-52)  # the complement, to one ulp
    np.testing.assert_allclose(s.u1, e.u2, rtol=1e-12)
    np.testing.assert_allclose(s.u2, e.u1, rtol=1e-12)
    assert np.any(e.shares[0] != 0.5)  # two materials: the test means something


def law_modes(key: str) -> tuple[str, ...]:
    return laws.make(key, laws.law_class(key).example_params).modes


@pytest.mark.parametrize("key", KEYS)
def test_conservation_per_mode(key):
    particles, contacts = frame_of(key, seed=13)
    scene = scene_of(key)
    e = ds.partition(contacts, scene, particles)
    pt, wt = ds.per_particle(contacts, e, particles, n_walls=1)
    assert [m.column for m in e.modes][:2] == ["u_n", "u_t"]
    assert {m.column for m in e.modes} >= set(law_modes(key)) - {ADHESION_COLUMN}
    totals = {m.column: e.u[k].sum() for k, m in enumerate(e.modes)}
    if e.u_adh is not None:
        totals[ADHESION_COLUMN] = e.u_adh.sum()
    assert (e.u_adh is not None) == (ADHESION_COLUMN in law_modes(key))
    for mode, total in totals.items():
        assert abs(pt[mode].sum() + wt[mode].sum() - total) <= 1e-12 * max(abs(total), 1e-300), mode


@pytest.mark.parametrize("key", KEYS)
def test_a_mode_the_law_lacks_is_zero_and_said(key):
    particles, contacts = frame_of(key)
    e = contact_energies(contacts, scene_of(key), particles)
    for k, mode in enumerate(m.column for m in e.modes):
        if mode not in law_modes(key):
            assert np.all(e.u[k] == 0) and mode in e.skipped


@pytest.mark.slow
def test_no_model_name_outside_the_laws_and_the_readers():
    """The core (plugin/ outside physics/laws/) never compares a law's name: a string constant equal to a
    registry key or to a simulator's own word for a law is allowed only in the laws and the readers
    (their word maps) and in the YADE exporter (YADE's class names)."""
    words = set(KEYS) | {k.split(":", 1)[1] for k in KEYS}
    found = []
    for path in (REPO / "plugin").rglob("*.py"):
        rel = path.relative_to(REPO)
        if rel.parts[:3] == ("plugin", "physics", "laws") or rel == Path("plugin/yade.py"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in words:
                found.append(f"{rel}:{node.lineno}: {node.value!r}")
    assert not found, found
