"""demsplit rebuilds the history of primitive-wall contacts from each wall fix's stored force (``store_force yes``).

Checked on the Debian LIGGGHTS runs of ``sample_dumps/liggghts/walls`` (four contact models, each with a primitive
and with the equivalent mesh floor, 100 spheres sliding and bouncing, five frames of which the first was written at
the setup of the output run):

- the primitive runs: demsplit's energies, from its own laws, against the independent numpy reconstruction of
  ``liggghts_wallforce_reference.py``: the same contacts not computed, for the same rule, and the same values;
- the mesh runs both ways: demsplit from the floor's dumped history, and demsplit from the floor fix's stored force
  (the same dumps read with the floor as the equivalent primitive wall, the same fix id), agree to 1e-9 on every
  contact the force determines; the rest are those the rule leaves out (sliding at the cap in the setup frame);
- negative controls: with the other frame kind's velocities, or a fix that adds a force the balance does not
  model, the contacts are not rebuilt;
- a hysteresis primitive run through ``demsplit run`` and its exports: the totals hold only what is known, and
  pandas, CSV, Parquet and VTK agree cell for cell on which values are known;
- (simulator) ``demsplit prepare`` of the packing sample, run by LIGGGHTS: its primitive walls' tangential energy
  is complete, where the committed dumps leave 104 contacts per frame not computed.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from functools import cache
from pathlib import Path

import demsplit
import numpy as np
import pytest
from demsplit.cli import main
from demsplit.physics.modes import NOT_COMPUTED_BITS
from demsplit.physics.partition import contact_energies
from demsplit.readers import liggghts as liggghts_reader
from demsplit.readers import open_run
from demsplit.readers.liggghts_script import read_script
from demsplit.readers.liggghts_wallforce import REASONS
from test_liggghts_wallforce_facts import MODELS, WALLS, law, rebuilt

AGREEMENT = 1e-9
"""Relative agreement of two reconstructions; a value below 1e-15 of the largest of its frame (a fully unloaded
hysteretic contact: 0 from the force, 1e-41 J from the history) agrees to 1e-15 of that largest."""
REFERENCE_RULES = {
    "capped at a setup step": "capped_at_setup",
    "rolling torque capped at a setup step": "rolling_capped_at_setup",
}
"""The reference's reasons (their start) and demsplit's rule for them."""


def modes_of(model: str) -> list[str]:
    """The modes a floor contact's history gives: u_t, u_r with rolling friction, u_n of hooke/hysteresis."""
    return ["u_t"] + (["u_r"] if law(model).rolling else []) + (["u_n"] if model == "hysteresis" else [])


def agree(mine: np.ndarray, theirs: np.ndarray, largest: float) -> np.ndarray:
    return np.abs(mine - theirs) <= AGREEMENT * np.abs(theirs) + 1e-15 * largest


@cache
def analysed(script: Path) -> list[tuple]:
    """Every frame of a run as demsplit reads it, with its contacts' energies."""
    run = open_run(script)
    return [
        (frame, contact_energies(frame.contacts, run.scene, frame.particles))
        for frame in (run.frame(k) for k in range(len(run)))
    ]


def floor_rows(frame, ids) -> np.ndarray:
    """The contact rows of the floor (wall 0) in the order of the particle ids ``ids``."""
    c = frame.contacts
    rows = np.flatnonzero(c["wall"] == 0)
    at = {int(i): r for r, i in zip(rows, c["id1"][rows])}
    assert sorted(at) == sorted(int(i) for i in ids)  # the same contacts
    return np.array([at[int(i)] for i in ids], dtype=np.int64)


def known(energies, rows: np.ndarray, mode: str) -> np.ndarray:
    return (energies.not_computed[rows] & NOT_COMPUTED_BITS[mode]) == 0


def primitive_copy(scene: str, directory: Path) -> Path:
    """The mesh run ``scene`` read with its floor as the equivalent primitive floor: the same fix id (so the atom
    dump's f_force_wfloor columns are its force), no wall dump; its own dumps."""
    source = WALLS / scene
    text = (source / f"in.{scene}").read_text()
    text = re.sub(r"^fix floor all mesh/surface.*\n", "", text, flags=re.M)
    text = text.replace("mesh n_meshes 1 meshes floor", "primitive type 3 zplane 0.0")
    text = re.sub(r"^(compute dsWall|dump ddsWall|dump_modify ddsWall) .*\n", "", text, flags=re.M)
    assert "primitive type 3 zplane 0.0 store_force yes" in text and "dsWall" not in text
    directory.mkdir(parents=True, exist_ok=True)
    for name in ("ds_atoms.txt.gz", "ds_pairs.txt.gz"):
        shutil.copy(source / name, directory / name)
    (directory / f"in.{scene}").write_text(text)
    return directory / f"in.{scene}"


@pytest.mark.parametrize("model", MODELS)
def test_primitive_run_agrees_with_the_independent_reconstruction(model):
    """Every primitive-floor contact: the modes not computed are the reference's, for its rule (a contact sliding at
    the cap, a rolling torque at its cap, in the setup frame), named in the frame's notes; every other value equals
    the reference's to 1e-9; no particle's balance fails."""
    scene = f"{model}_prim"
    script = WALLS / scene / f"in.{scene}"
    compared = dict.fromkeys(modes_of(model), 0)
    for k, ((frame, energies), (reference, _)) in enumerate(zip(analysed(script), rebuilt(scene))):
        rows = floor_rows(frame, reference.id)
        rules = set()
        for mode in modes_of(model):
            theirs = getattr(reference, mode)
            mine, is_known = getattr(energies, mode)[rows], known(energies, rows, mode)
            assert np.array_equal(is_known, np.isfinite(theirs)), (mode, k)
            assert np.all(agree(mine[is_known], theirs[is_known], np.abs(theirs[is_known]).max(initial=0))), (mode, k)
            assert np.all(mine[~is_known] == 0)  # stored as 0 with its bit, never an estimate
            compared[mode] += int(is_known.sum())
            reasons = getattr(reference, f"reason_{mode[2]}")[~is_known]
            rules |= {rule for start, rule in REFERENCE_RULES.items() for r in reasons if r.startswith(start)}
        assert {n for n in frame.notes if n in REASONS.values()} == {REASONS[r] for r in rules}
        assert bool(rules) == (k == 0)  # only the setup frame leaves contacts out
    assert all(n >= 60 for n in compared.values()), compared


@pytest.mark.parametrize("model", MODELS)
def test_mesh_run_from_its_history_and_from_its_wall_force_agree(model, tmp_path):
    """The mesh floor's energies from its dumped history, and from its fix's stored force (the same dumps read with
    the floor as the equivalent primitive wall), agree to 1e-9 on every contact the force determines; the others are
    the ones the reference leaves out (sliding at the cap at the setup step, which the history confirms:
    tests/test_liggghts_wallforce_facts.py), and only they."""
    scene = f"{model}_mesh"
    history = analysed(WALLS / scene / f"in.{scene}")
    force = analysed(primitive_copy(scene, tmp_path / scene))
    compared = dict.fromkeys(modes_of(model), 0)
    for k, ((hf, he), (ff, fe), (reference, _)) in enumerate(zip(history, force, rebuilt(scene))):
        assert not ff.contacts.get("history_unknown", np.zeros(0)).any() or k == 0
        hrows, frows = floor_rows(hf, reference.id), floor_rows(ff, reference.id)
        assert known(he, hrows, "u_t").all()  # the history is dumped: everything is known
        for mode in modes_of(model):
            theirs, mine = getattr(he, mode)[hrows], getattr(fe, mode)[frows]
            is_known = known(fe, frows, mode)
            assert np.array_equal(is_known, np.isfinite(getattr(reference, mode))), (mode, k)
            assert np.all(agree(mine[is_known], theirs[is_known], np.abs(theirs).max())), (mode, k)
            compared[mode] += int(is_known.sum())
        assert all(
            n in (REASONS["capped_at_setup"], REASONS["rolling_capped_at_setup"])
            for n in ff.notes
            if n in REASONS.values()
        )
    assert all(n >= 60 for n in compared.values()), compared


def test_the_other_frame_kind_does_not_close(monkeypatch):
    """Read with the other frame kind's velocities (the dumped ones mid-run, half-stepped ones at setup), most floor
    contacts of a run in motion fail the balance or the normal model, and stay not computed, with those reasons."""
    real = liggghts_reader.frame_kind
    monkeypatch.setattr(liggghts_reader, "frame_kind", lambda *a: (lambda kind: (not kind[0], kind[1]))(real(*a)))
    for model in ("hertz", "hysteresis"):
        run = open_run(WALLS / f"{model}_prim" / f"in.{model}_prim")
        lost = total = 0
        notes = set()
        for k in range(len(run)):
            frame = run.frame(k)
            e = contact_energies(frame.contacts, run.scene, frame.particles)
            rows = np.flatnonzero(frame.contacts["wall"] == 0)
            lost += int((~known(e, rows, "u_t")).sum())
            total += len(rows)
            notes |= set(frame.notes)
        assert lost > 0.3 * total, (model, lost, total)
        assert notes & {REASONS["open_balance"], REASONS["normal_off_model"]}


def test_an_unmodelled_force_leaves_the_history_unknown_and_says_why(tmp_path):
    """A fix that adds a force the balance does not model (a drag) turns the rebuilding off: every primitive-floor
    contact's u_t is not computed, as without store_force, and the note names the fix."""
    script = primitive_copy("hertz_mesh", tmp_path / "drag")
    script.write_text(
        script.read_text().replace("fix integr all nve/sphere", "fix integr all nve/sphere\nfix drag all viscous 0.001")
    )
    run = open_run(script)
    assert any("fix drag viscous" in note for note in run.join.primitive_note.split("; "))
    frame = run.frame(2)
    e = contact_energies(frame.contacts, run.scene, frame.particles)
    rows = np.flatnonzero(frame.contacts["wall"] == 0)
    assert len(rows) and not known(e, rows, "u_t").any() and known(e, rows, "u_n").all()


def test_a_frame_of_unknown_kind_is_read_the_way_that_closes(tmp_path):
    """After a read_restart the script cannot tell a setup frame from a mid-run one: both readings are made and the
    one whose balances close is kept; in this run in motion it is the right one, so the results are the same."""
    script = primitive_copy("epsd2_mesh", tmp_path / "restart")
    text = script.read_text()
    script.write_text(text.replace("fix integr all nve/sphere", "read_restart none.restart\nfix integr all nve/sphere"))
    assert read_script(script).restart_run == 0
    assert liggghts_reader.frame_kind(read_script(script), None, 40000)[0] is None
    plain = analysed(primitive_copy("epsd2_mesh", tmp_path / "plain"))
    for (_, energies), (_, expected) in zip(analysed(script), plain):
        np.testing.assert_array_equal(energies.not_computed, expected.not_computed)
        np.testing.assert_array_equal(energies.u, expected.u)


def test_which_frames_a_dump_writes_at_the_setup_of_a_run(tmp_path):
    """A dump writes at a run's setup only a step it has not written: its first frame when defined between runs,
    the first step of its first run; the step where one run ends and the next starts was written mid-run."""
    script = tmp_path / "in.kinds"
    script.write_text(
        "units si\ntimestep 1e-6\nrun 1000\ndump a all custom 100 a.txt id type x y z radius\n"
        "run 1000\ntimestep 2e-6\nrun 500\nreset_timestep 0\nrun 300\n"
    )
    s = read_script(script)
    dump = s.dumps[0]
    assert liggghts_reader.frame_kind(s, dump, 1000) == (True, 1e-6)
    assert liggghts_reader.frame_kind(s, dump, 1500) == (False, 1e-6)
    assert liggghts_reader.frame_kind(s, dump, 2000) == (False, 1e-6)  # run 2 ended there: mid-run
    assert liggghts_reader.frame_kind(s, dump, 2400) == (False, 2e-6)
    assert liggghts_reader.frame_kind(s, dump, 0) == (True, 2e-6)  # after reset_timestep 0: a new first step
    assert liggghts_reader.frame_kind(s, None, 0) == (True, 1e-6)


def test_hysteresis_totals_hold_only_what_is_known_in_every_export(tmp_path, capsys):
    """A hooke/hysteresis primitive run through demsplit run: a particle's or the floor's u_t (and u) is NaN exactly
    where one of its contacts' is not computed, and otherwise the sum of its contacts' shares; pandas, CSV, Parquet
    and VTK hold NaN in the same cells; the frames' totals count what is known."""
    import pandas as pd

    pytest.importorskip("pyarrow")
    meshio = pytest.importorskip("meshio")
    out, d = tmp_path / "r.h5", tmp_path
    assert main(["run", str(WALLS / "hysteresis_prim" / "in.hysteresis_prim"), "-o", str(out), "-q"]) == 0
    assert (
        main(["export", str(out), "--csv", str(d / "csv"), "--parquet", str(d / "pq"), "--vtk", str(d / "vtk"), "-q"])
        == 0
    )
    res = demsplit.load_results(out)
    c, p, w = res.contacts, res.particles, res.walls
    unknown = c["u_t"].isna()
    assert unknown.sum() == 10 and (c.loc[unknown, "step"] == 40000).all()  # measured: the setup frame's sliders
    assert not c["u_n"].isna().any()  # the elasto-plastic normal state of every floor contact is rebuilt
    floor = c[c["wall"] == 0]
    assert len(floor) > 100 and floor["u_n"].gt(0).sum() > 100 and floor["u_t"].notna().sum() > 90
    # particles: unknown where a contact is; else the sum of the shares of its contacts
    body1 = c.assign(id=c["id1"], part=c["u_t"] * c["share_t1"])[["step", "id", "part"]]
    pairs = c[c["wall"] < 0]
    body2 = pairs.assign(id=pairs["id2"], part=pairs["u_t"] * (1 - pairs["share_t1"]))[["step", "id", "part"]]
    sums = pd.concat([body1, body2]).groupby(["step", "id"])["part"].agg(lambda s: s.sum(min_count=len(s)))
    merged = p.set_index(["step", "id"])
    merged["expected"] = sums.reindex(merged.index, fill_value=0.0)  # 0: a particle without contacts
    assert merged["u_t"].isna().equals(merged["expected"].isna()) and merged["u_t"].isna().sum() >= 10
    ok = merged["u_t"].notna()
    np.testing.assert_allclose(merged.loc[ok, "u_t"], merged.loc[ok, "expected"], rtol=1e-12, atol=1e-30)
    assert merged["u"].isna().equals(merged["u_t"].isna())
    assert w.loc[w["step"] == 40000, "u_t"].isna().all() and w.loc[w["step"] > 40000, "u_t"].notna().all()
    frames = res.frames.set_index("step")
    assert frames.loc[40000, "n_not_computed"] == 10 and (frames["n_not_computed"].iloc[1:] == 0).all()
    np.testing.assert_allclose(frames["u_t"], c.groupby("step")["u_t"].sum(), rtol=1e-12)  # the known part
    for table, df in (("particles", p), ("contacts", c), ("walls", w)):
        cols = [x for x in df.columns if x not in ("name", "kind")]
        for other in (pd.read_csv(d / "csv" / f"{table}.csv"), pd.read_parquet(d / "pq" / f"{table}.parquet")):
            other = other[cols]
            assert other.isna().to_numpy().tolist() == df[cols].isna().to_numpy().tolist(), table
    for step, frame in p.groupby("step"):
        mesh = meshio.read(d / "vtk" / f"particles_{int(step):012d}.vtu")
        for col in ("u", "u_n", "u_t"):
            assert np.isnan(mesh.point_data[col]).tolist() == frame[col].isna().tolist(), (step, col)


def test_prepare_adds_store_force_and_its_columns(tmp_path):
    """prepare appends store_force yes to every primitive wall fix (before a comment, after a continued line) and
    dumps the torques and the stored forces at full precision; a fix defined after the atom dump or removed by unfix
    gets no column, and a note says so."""
    from demsplit.prepare import prepare_script

    text = (WALLS / "hertz_prim" / "in.hertz_prim").read_text()
    text = re.sub(r"^(dump|dump_modify) .*\n", "", text, flags=re.M).replace(" store_force yes", "")
    text = text.replace(
        "fix wfloor all wall/gran model hertz tangential history primitive type 3 zplane 0.0",
        "fix wfloor all wall/gran model hertz tangential history &\n    primitive type 3 zplane 0.0 "
        "# the floor\nfix wside all wall/gran model hertz tangential history primitive type 3 "
        "xplane -0.01\nunfix wside",
    )
    text += "fix wtop all wall/gran model hertz tangential history primitive type 3 zplane 0.03\nrun 100\n"
    script = tmp_path / "in.user"
    script.write_text(text)
    prepared = prepare_script(script)
    lines = prepared.text.splitlines()
    assert "    primitive type 3 zplane 0.0 store_force yes # the floor" in lines
    assert sum("store_force yes" in line for line in lines) == 3
    dump = next(line for line in lines if line.startswith("dump dsAtoms"))
    assert "tqx tqy tqz f_force_wfloor[1] f_force_wfloor[2] f_force_wfloor[3]" in dump
    assert "wside" not in dump and "wtop" not in dump
    assert any("wside, wtop" in n and "not computed" in n for n in prepared.notes)
    fmt = next(line for line in lines if line.startswith("dump_modify dsAtoms"))
    assert fmt.count("%.17g") == len(dump.split()) - 8  # every column but id and type at full precision


@pytest.mark.simulator
@pytest.mark.slow
def test_packing_prepared_and_rerun_has_its_primitive_walls_complete(liggghts, tmp_path):
    """packing/ (a mesh floor, four primitive planes and a primitive cylinder; hertz): its committed dumps have no
    stored force, so 104 primitive-wall contacts per frame have u_t not computed. prepare adds store_force yes and an
    atom dump beside the script's own (same frames); LIGGGHTS reruns it to the same trajectory, and every contact,
    the cylinder's included, is known; the primitive walls' u_t is 7.79e-9 J per frame."""
    packing = WALLS.parent / "packing"
    before = demsplit.analyze(packing / "in.packing")
    assert before.frames["n_not_computed"].tolist() == [104, 104, 104]
    for name in ("in.packing", "floor.stl"):
        shutil.copy(packing / name, tmp_path / name)
    assert main(["prepare", str(tmp_path / "in.packing"), "-q"]) == 0
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", "in.packing.demsplit", "-echo", "none", "-log", "none"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-2000:]
    import gzip

    with gzip.open(packing / "atoms_full.txt.gz", "rb") as f:
        assert (tmp_path / "atoms_full.txt").read_bytes() == f.read()  # store_force changes nothing
    after = demsplit.analyze(tmp_path / "in.packing.demsplit")
    assert after.frames["n_not_computed"].tolist() == [0, 0, 0]
    c = after.contacts
    primitive = c[c["wall"] >= 1]
    assert primitive["u_t"].notna().all() and (primitive["wall"] == 5).sum() == 3 * 17
    np.testing.assert_allclose(primitive.groupby("step")["u_t"].sum(), 7.786e-9, rtol=1e-3)


def test_a_wall_without_stored_force_leaves_its_particles_unverified(tmp_path):
    """A primitive wall without store_force (here one the run did not have: a plane through the packing) leaves
    its own contacts' history unknown, and that of the floor contacts of the particles touching it (their balance
    misses its force), with that reason; every other floor contact is rebuilt as before."""
    script = tmp_path / "in.hertz_prim"
    for name in ("ds_atoms.txt.gz", "ds_pairs.txt.gz"):
        shutil.copy(WALLS / "hertz_prim" / name, tmp_path / name)
    floor = "fix wfloor all wall/gran model hertz tangential history primitive type 3 zplane 0.0 store_force yes"
    text = (WALLS / "hertz_prim" / "in.hertz_prim").read_text()
    assert floor in text
    script.write_text(
        text.replace(
            floor, floor + "\nfix wcut all wall/gran model hertz tangential history primitive type 3 xplane 0.0"
        )
    )
    plain = analysed(WALLS / "hertz_prim" / "in.hertz_prim")
    assert "wcut" in open_run(script).join.primitive_note
    cut = both = 0
    for (frame, e), (expected, ee) in zip(analysed(script), plain):
        c = frame.contacts
        on_cut = set(c["id1"][c["wall"] == 1].tolist())
        cut += len(on_cut)
        assert not known(e, np.flatnonzero(c["wall"] == 1), "u_t").any()
        rows = np.flatnonzero(c["wall"] == 0)
        touching = np.isin(c["id1"][rows], list(on_cut))
        both += int(touching.sum())
        assert not known(e, rows[touching], "u_t").any()
        before = floor_rows(expected, c["id1"][rows])
        np.testing.assert_array_equal(known(e, rows[~touching], "u_t"), known(ee, before[~touching], "u_t"))
        np.testing.assert_array_equal(e.u_t[rows[~touching]], ee.u_t[before[~touching]])
        assert (REASONS["unstored_wall"] in frame.notes) == bool(touching.any())
    assert cut > 5 and both > 0
