"""Wall contacts rebuilt from the wall fix's force (``store_force yes``), checked on Debian LIGGGHTS runs.

``sample_dumps/liggghts/walls`` holds four contact models (hertz, hooke, hertz with rolling epsd2, hooke/hysteresis;
tangential history), each run twice: with a primitive floor and with the equivalent mesh floor, whose contact history
is dumped too (``make_scenes.py``). 100 spheres of two materials slide and bounce over the floor while five frames are
written (the first at the setup of the output run). ``liggghts_wallforce_reference.py`` rebuilds every floor contact
from the floor fix's stored force, the atom dump and the pair dump's history. Checked here:

- every particle's dumped force and torque equal m g plus its contacts as LIGGGHTS applied them in the step, within
  the tolerance of the printed precision, in every frame of every run: with the step's velocities (mid-run: the
  dumped ones less half a step of the dumped force and torque; at the setup frame: the dumped ones), and not with the
  others;
- the mesh runs, rebuilt from their wall force, give the energies their dumped history gives: u_t, u_r (epsd2) and
  hooke/hysteresis's u_n agree to 1e-9 on every contact the force determines; the others are those the rule leaves
  out (capped at the setup step), and the history shows they were capped;
- the primitive runs are complete: every floor contact of every mid-run frame gets its u_t (u_r, u_n), and only the
  setup frame's contacts capped at that step are not computed;
- what ``store_force`` holds: the compute's output-time force equals it (to rounding) only in the setup frame; mid-run
  the compute re-evaluates sliding contacts without the cap, far beyond the Coulomb limit;
- (simulator) one scene rerun by ``liggghts`` reproduces the committed dumps, and a dump written after the wall
  compute's dump reads the mesh fix's stored force as 0.
"""

from __future__ import annotations

import gzip
import importlib.util
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from liggghts_wallforce_reference import Frame, Law, Wall, from_history, reconstruct, tolerance
from test_liggghts_samples_facts import read_text_dump

WALLS = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts" / "walls"
_spec = importlib.util.spec_from_file_location("make_scenes", WALLS / "make_scenes.py")
make_scenes = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_scenes)

MODELS = list(make_scenes.MODELS)
FLOOR = [Wall(fix="wfloor", type=3, kind="plane", axis=2, position=0.0)]
FLOOR_TYPE = 3
AGREEMENT = 1e-9
"""Relative agreement of the two reconstructions of a mesh run; a contact whose energy is 0 (a fully unloaded
hysteretic contact) agrees to 1e-15 of the frame's largest value."""


def law(model: str) -> Law:
    """The scene's contact law, from make_scenes' tables."""
    words = make_scenes.MODELS[model][0].split()
    magnitude, direction = make_scenes.GRAVITY
    direction = np.asarray(direction, dtype=np.float64)
    return Law(
        normal=words[1],
        rolling=words[words.index("rolling_friction") + 1] if "rolling_friction" in words else None,
        young=make_scenes.YOUNG,
        poisson=make_scenes.POISSON,
        restitution=make_scenes.RESTITUTION,
        friction=make_scenes.FRICTION,
        timestep=make_scenes.TIMESTEP,
        gravity=magnitude * (direction / np.sqrt(direction @ direction)),
        rolling_friction=make_scenes.ROLLING_FRICTION,
        characteristic_velocity=make_scenes.CHARACTERISTIC_VELOCITY,
        max_elastic_stiffness=make_scenes.MAX_ELASTIC_STIFFNESS,
        plasticity_depth=make_scenes.PLASTICITY_DEPTH,
    )


def _dump(directory: Path, name: str, columns: list[str] | None) -> list[tuple[int, dict, np.ndarray]]:
    """(step, columns by name, periodic box lengths) of every frame of a dump (plain or .gz)."""
    path = directory / name
    out = []
    for f in read_text_dump(path if path.exists() else path.with_name(name + ".gz")):
        names = f.columns if columns is None else columns
        periodic = np.where([flag == "pp" for flag in f.box_flags], f.bounds[:, 1] - f.bounds[:, 0], 0.0)
        out.append((f.step, {c: f.data[:, k] for k, c in enumerate(names)}, periodic))
    return out


@cache
def frames(scene: str, directory: Path = WALLS) -> list[tuple[Frame, dict | None]]:
    """Every frame of a scene run (the first written at the output run's setup) and, for a mesh scene, its wall
    dump's columns."""
    model, wall = scene.rsplit("_", 1)
    atoms = _dump(directory / scene, "ds_atoms.txt", None)
    pairs = _dump(directory / scene, "ds_pairs.txt", make_scenes.local_columns(model))
    walls = (
        _dump(directory / scene, "ds_walls.txt", make_scenes.local_columns(model, wall=True))
        if wall == "mesh"
        else [None] * len(atoms)
    )
    assert (
        [s for s, _, _ in atoms]
        == [s for s, _, _ in pairs]
        == list(range(make_scenes.SETTLE, make_scenes.SETTLE + make_scenes.OUTPUT_STEPS + 1, make_scenes.OUTPUT_EVERY))
    )
    return [
        (Frame(atoms=a, pairs=p, setup=step == make_scenes.SETTLE, periodic=periodic), w and w[1])
        for (step, a, periodic), (_, p, _), w in zip(atoms, pairs, walls)
    ]


@cache
def rebuilt(scene: str):
    """The reference's wall contacts and balance of every frame of a scene."""
    model = scene.rsplit("_", 1)[0]
    return [reconstruct(law(model), FLOOR, frame) for frame, _ in frames(scene)]


SCENES = make_scenes.SCENES


@pytest.mark.parametrize("scene", SCENES)
def test_every_balance_closes_in_a_scene_in_motion(scene):
    """Every particle of every frame closes; the floor contacts include capped (sliding) and uncapped ones, and
    contacts form and break between frames. (With rolling friction the floor contacts slide mid-run: epsd2's
    uncapped ones are in its setup frame.)"""
    seen_wall, seen_pair, churn, capped, uncapped = set(), set(), 0, 0, 0
    for (frame, _), (contacts, closure) in zip(frames(scene), rebuilt(scene)):
        assert closure.closes.all(), (scene, closure.id[~closure.closes])
        assert len(contacts.id) >= 15 and len(frame.pairs["id1"]) >= 15
        wall, pair = set(contacts.id.tolist()), set(zip(frame.pairs["id1"].tolist(), frame.pairs["id2"].tolist()))
        if seen_wall:
            churn += len(wall ^ seen_wall) + len(pair ^ seen_pair)
        seen_wall, seen_pair = wall, pair
        capped += contacts.capped.sum()
        uncapped += (~contacts.capped).sum()
    assert churn > 50 and capped > 20 and uncapped > 3, (churn, capped, uncapped)


@pytest.mark.parametrize("scene", SCENES)
def test_the_force_was_evaluated_with_the_half_step_velocities(scene):
    """With the other frame kind's velocities (the dumped ones mid-run, half-stepped ones at setup) the balance of
    most particles touching anything fails: the closure tells the velocities LIGGGHTS used. With the right ones the
    floor's normal force is the model's (hertz, hooke) to the tolerance."""
    model = scene.rsplit("_", 1)[0]
    for (frame, _), (contacts, _) in zip(frames(scene), rebuilt(scene)):
        wrong = Frame(atoms=frame.atoms, pairs=frame.pairs, setup=not frame.setup, periodic=frame.periodic)
        _, closure = reconstruct(law(model), FLOOR, wrong)
        touching = np.isin(closure.id, np.concatenate([contacts.id, frame.pairs["id1"], frame.pairs["id2"]]))
        assert (~closure.closes[touching]).mean() > 0.5, (scene, frame.setup)
        if model in ("hertz", "hooke", "epsd2"):
            scale = np.abs(contacts.fn).max()
            assert np.all(np.abs(contacts.fn - contacts.fn_model) <= 1e-14 * scale)


def _agree(mine: np.ndarray, theirs: np.ndarray) -> np.ndarray:
    return np.abs(mine - theirs) <= AGREEMENT * np.abs(theirs) + 1e-15 * np.abs(theirs).max()


@pytest.mark.parametrize("model", MODELS)
def test_mesh_run_rebuilt_from_its_wall_force_agrees_with_its_history(model):
    """u_t, u_r and hooke/hysteresis's u_n of the mesh floor's contacts, rebuilt from the floor fix's force, are those
    of the dumped history to 1e-9 wherever the force determines them; where it does not, the contact sat at the cap
    at the setup step (the history shows it: k_t |shear| or |M + k_r w_t dt| beyond the cap)."""
    scene = f"{model}_mesh"
    modes = ["u_t"] + (["u_r"] if law(model).rolling else []) + (["u_n"] if model == "hysteresis" else [])
    compared = dict.fromkeys(modes, 0)
    for (frame, walls), (contacts, closure) in zip(frames(scene), rebuilt(scene)):
        history = from_history(law(model), frame.atoms, walls, FLOOR_TYPE)
        assert len(set(history["id"].tolist())) == len(history["id"])  # one floor contact per particle
        at = {i: k for k, i in enumerate(history["id"].tolist())}
        assert sorted(at) == sorted(contacts.id.tolist())  # the same contacts as the dump's
        rows = np.array([at[i] for i in contacts.id.tolist()])
        assert closure.closes.all()
        for mode in modes:
            mine, theirs = getattr(contacts, mode), history[mode][rows]
            known = np.isfinite(mine)
            assert np.all(_agree(mine[known], theirs[known])), (mode, frame.setup)
            compared[mode] += known.sum()
            reasons = getattr(contacts, f"reason_{mode[2]}")[~known]
            assert all(r.startswith(("capped at a setup step", "rolling torque capped")) for r in reasons)
            assert frame.setup or not len(reasons)
        if frame.setup:  # the force cannot tell the spring of a contact that was capped without the rescale
            assert np.isnan(contacts.u_t).sum() >= 3
            shear = np.stack([walls[f"shear{c}"] for c in "xyz"], -1)[rows]
            cap = make_scenes.FRICTION[0][2] * np.abs(contacts.fn)
            spring = contacts.kt * np.sqrt(np.einsum("ij,ij->i", shear, shear))
            assert np.all(spring[np.isnan(contacts.u_t)] > cap[np.isnan(contacts.u_t)])
        else:
            assert all(np.isfinite(getattr(contacts, mode)).all() for mode in modes)
    assert all(n >= 60 for n in compared.values()), compared


@pytest.mark.parametrize("model", MODELS)
def test_primitive_run_is_complete(model):
    """Every primitive-floor contact of every mid-run frame gets its u_t (and u_r, u_n) and every particle closes;
    in the setup frame the contacts left out are exactly those capped at the setup step. A capped contact's spring
    sits at the cap mu |F_n| (the rescaled history); an uncapped one's is within it."""
    scene = f"{model}_prim"
    lw = law(model)
    for frame, _ in frames(scene):
        contacts, closure = reconstruct(lw, FLOOR, frame)
        assert closure.closes.all()
        spring = np.sqrt(np.einsum("ij,ij->i", contacts.spring, contacts.spring))
        cap = make_scenes.FRICTION[0][2] * np.abs(contacts.fn)
        assert np.all(spring <= cap * (1 + 1e-9))
        assert np.all(np.isfinite(contacts.u_n))
        missing = np.isnan(contacts.u_t)
        if frame.setup:
            assert np.array_equal(missing, contacts.capped) and missing.any()
        else:
            assert not missing.any() and np.allclose(spring[contacts.capped], cap[contacts.capped], rtol=1e-9)
            if lw.rolling:
                assert np.isfinite(contacts.u_r).all() and contacts.u_r.sum() > 0
        assert np.all(contacts.u_t[~missing] >= 0) and contacts.u_t[~missing].sum() > 0


@pytest.mark.parametrize("model", MODELS)
def test_stored_force_and_output_time_force(model):
    """The mesh floor's ``f_force_wfloor`` (the force applied in the step) equals the wall compute's ``force`` (its
    re-evaluation at output) to rounding only in the setup frame. Mid-run the compute re-evaluates with the dumped
    velocities and no history update: a contact capped in the step whose normal force came out no smaller is not
    capped again, and gets the full viscous force of its slip velocity, beyond mu |F_n| (the cap bounds the
    spring only: the setup step, which does not update the history either, applies such forces too)."""
    for frame, walls in frames(f"{model}_mesh"):
        at = {int(i): k for k, i in enumerate(frame.atoms["id"])}
        rows = np.array([at[int(i)] for i in walls["id"]])
        stored = np.stack([frame.atoms[f"f_force_wfloor[{c}]"][rows] for c in (1, 2, 3)], -1)
        output = np.stack([walls[c] for c in ("fx", "fy", "fz")], -1)
        scale = np.abs(output).max()
        tangential = np.hypot(output[:, 0], output[:, 1])
        beyond = tangential / (make_scenes.FRICTION[0][2] * np.abs(output[:, 2]))
        if frame.setup:
            assert np.abs(stored - output).max() <= 4 * np.finfo(float).eps * scale
        else:
            assert np.abs(stored - output).max() > 1e-3 * scale and beyond.max() > 10


def test_the_tolerance_follows_the_printed_precision():
    """%.17g round-trips (only arithmetic rounding is allowed); %g's 6 digits add 4 x 5e-6 of each term."""
    scale = np.array([1.0])
    assert tolerance(scale, 0.0)[0] < 1e-13 and tolerance(scale, 5e-6)[0] == pytest.approx(2e-5, rel=1e-6)


@pytest.mark.simulator
def test_rerun_reproduces_the_scene_and_a_late_dump_reads_a_zeroed_stored_force(liggghts, tmp_path):
    """Rerun epsd2_mesh with one more atom dump defined after the wall compute's dump: the run's dumps are the
    committed ones byte for byte (the extra dump changes nothing), the reference closes on them, and the late dump
    reads f_force_wfloor as 0 for every particle (the compute's output-time evaluation zeroed it) while the atom
    dump written before it holds the floor's force."""
    scene = "epsd2_mesh"
    path = make_scenes.write_scene(scene, tmp_path / scene)
    text = path.read_text().rsplit("run ", 1)
    late = (
        f"dump late all custom {make_scenes.OUTPUT_EVERY} late.txt id f_force_wfloor[1] f_force_wfloor[2] "
        f"f_force_wfloor[3]\ndump_modify late sort id\n"
    )
    path.write_text(text[0] + late + "run " + text[1])
    make_scenes.run(path, liggghts)
    for name in ("ds_atoms.txt", "ds_pairs.txt", "ds_walls.txt"):
        with gzip.open(WALLS / scene / f"{name}.gz", "rb") as f:
            assert (tmp_path / scene / name).read_bytes() == f.read(), name
    fresh = frames(scene, tmp_path)
    for frame, _ in fresh:
        _, closure = reconstruct(law("epsd2"), FLOOR, frame)
        assert closure.closes.all()
    stored = np.concatenate(
        [[a[f"f_force_wfloor[{c}]"] for c in (1, 2, 3)] for _, a, _ in _dump(tmp_path / scene, "ds_atoms.txt", None)]
    )
    zeroed = np.concatenate(
        [[a[f"f_force_wfloor[{c}]"] for c in (1, 2, 3)] for _, a, _ in _dump(tmp_path / scene, "late.txt", None)]
    )
    assert np.count_nonzero(stored) > 100 and not zeroed.any()
