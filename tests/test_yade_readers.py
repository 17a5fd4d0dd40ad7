"""YADE readers on the committed sample files (no simulator needed).

The samples are made by sample_dumps/yade/regenerate.sh; their counts and
reference energies are in the *.log files printed by YADE.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import demsplit as ds
import numpy as np
import pytest
from demsplit.errors import DemsplitError, InputFormatError, PrecisionError, TruncatedFileError
from demsplit.physics import laws
from demsplit.physics.partition import partition
from demsplit.readers import open_run
from demsplit.readers.yade_export import YadeVtkRun, overlap_error_bound, read_vtk, vtk_frame
from demsplit.readers.yade_snapshot import YadeSnapshotRun, _open_store, open_yade_snapshot
from demsplit.yade import write_snapshot
from reader_contract import ReaderContract

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"

YADE = SAMPLES / "yade"


def _vtk_frame(*args, **kwargs):
    return vtk_frame(*args, **kwargs)[0]


class TestMindlinSnapshotsHdf5(ReaderContract):
    reader = YadeSnapshotRun
    path = YADE / "mindlin_box.h5"


class TestPeriodicSnapshotsNpy(ReaderContract):
    reader = YadeSnapshotRun
    path = YADE / "cundall_periodic.npys"


class TestVtkExport(ReaderContract):
    reader = YadeVtkRun
    path = YADE / "mindlin_box-spheres-00024000.vtk"
    options = {
        "materials": {0: ds.Material(2e7, 0.3), 1: ds.Material(1e8, 0.2)},
        "law": "yade:Law2_ScGeom_MindlinPhys_Mindlin",
        "wall_type": 1,
    }


MINDLIN = ("mindlin_box.h5", "mindlin_box.npys")
CUNDALL = ("cundall_periodic.h5", "cundall_periodic.npys")


def contacts_equal(a: dict, b: dict) -> None:
    assert sorted(a) == sorted(b)
    for c in a:
        np.testing.assert_array_equal(a[c], b[c], err_msg=c)


@pytest.mark.parametrize("name", MINDLIN + CUNDALL)
def test_counts(name):
    run = open_yade_snapshot(YADE / name)
    frames = list(run)
    n_particles = 160 if name.startswith("mindlin") else 192
    assert len(run) == len(frames) == 3
    assert [f.n_particles for f in frames] == [n_particles] * 3
    # the last snapshot is the state YADE printed at the end (log line)
    log = (YADE / (name.split(".")[0] + ".log")).read_text()
    assert f"{frames[-1].n_contacts} real interactions" in log
    for k, f in enumerate(frames):
        meta = run.meta(k)
        assert f.n_contacts == meta["n_interactions_real"]  # no neverErase: every real one overlaps
        assert f.step == meta["iter"]


def test_both_formats_give_the_same_frames():
    for h5, npy in (MINDLIN, CUNDALL):
        for fa, fb in zip(open_yade_snapshot(YADE / h5), open_yade_snapshot(YADE / npy)):
            assert fa.step == fb.step
            contacts_equal(fa.contacts, fb.contacts)
            contacts_equal(fa.particles, fb.particles)


def test_scene_of_the_mindlin_sample():
    scene = open_yade_snapshot(YADE / "mindlin_box.h5").scene
    assert scene.model.law == "yade:Law2_ScGeom_MindlinPhys_Mindlin"
    assert scene.materials[0].E == 2e7 and scene.materials[0].nu == 0.3
    assert scene.materials[1].E == 1e8 and scene.materials[1].nu == 0.2
    assert [w.kind for w in scene.walls] == ["yade_wall"] * 4 + ["facet"] * 2 + ["box"]
    assert [w.type for w in scene.walls] == [1, 1, 0, 0, 1, 1, 0]


def test_id1_is_the_particle_and_normals_point_into_the_wall():
    run = open_yade_snapshot(YADE / "mindlin_box.h5")
    frame = run.frame(2)
    c = frame.contacts
    wall = c["wall"] >= 0
    assert wall.sum() == 67 and (~wall).sum() == 168
    assert np.isin(c["id1"], frame.particles["id"]).all()
    assert (c["id2"][wall] == -1).all() and np.isin(c["id2"][~wall], frame.particles["id"]).all()
    # YADE stores wall contacts as (wall, sphere) with the normal wall -> sphere: the reader swapped them
    _, raw = _open_store(YADE / "mindlin_box.h5").snapshot(2)
    raw_n = np.stack([raw["interactions"][k] for k in ("nx", "ny", "nz")], axis=-1)
    n = np.stack([c["nx"], c["ny"], c["nz"]], axis=-1)
    np.testing.assert_array_equal(n[wall], -raw_n[wall])
    np.testing.assert_array_equal(n[~wall], raw_n[~wall])
    assert (raw["interactions"]["id1"][wall] >= 160).all()  # the bodies after the 160 spheres
    # geometric check: the normal points from the particle towards its wall
    for k, w in enumerate(run.scene.walls):
        rows = c["wall"] == k
        if w.kind == "yade_wall":
            expected = -1.0 if w.position == 0.0 else 1.0
            np.testing.assert_allclose(n[rows, w.axis], expected, err_msg=w.name)
        elif w.kind == "facet":  # the floor: normal points down
            np.testing.assert_allclose(n[rows, 2], -1.0)


def test_energies_of_the_samples_match_yades_own():
    for name in MINDLIN:
        run = open_yade_snapshot(YADE / name)
        for k, frame in enumerate(run):
            e = partition(frame.contacts, run.scene, frame.particles)
            ref = run.meta(k)["law_energies"]["mindlin_normElastEnergy"]
            assert e.u_n.sum() == pytest.approx(ref, rel=1e-10)
    for name in CUNDALL:
        run = open_yade_snapshot(YADE / name)
        for k, frame in enumerate(run):
            e = partition(frame.contacts, run.scene, frame.particles)
            meta = run.meta(k)
            total = (e.u_n + e.u_t).sum()
            assert total == pytest.approx(meta["energy"]["elastPotential"], rel=1e-10)
            assert total == pytest.approx(meta["law_energies"]["cundallstrack_elasticEnergy"], rel=1e-10)


def test_periodic_contacts_use_the_image_of_body_2():
    run = open_yade_snapshot(YADE / "cundall_periodic.h5")
    frame = run.frame(2)
    c, p = frame.contacts, frame.particles
    row = {int(i): k for k, i in enumerate(p["id"])}
    x2 = np.stack([p[a][[row[int(i)] for i in c["id2"]]] for a in "xyz"], axis=-1)
    x1 = np.stack([c["x1"], c["y1"], c["z1"]], axis=-1)
    n = np.stack([c["nx"], c["ny"], c["nz"]], axis=-1)
    image = x1 + (c["r1"] + c["r2"] - c["delta"])[:, None] * n
    crosses = np.abs(image - frame.box.wrap(image)).max(axis=1) > 0
    assert crosses.any()  # some contacts cross the cell boundary
    np.testing.assert_allclose(frame.box.wrap(image), x2, atol=1e-12)


def test_plane_as_plane():
    run = open_yade_snapshot(YADE / "mindlin_box.h5", plane_as_plane=True)
    c = run.frame(2).contacts
    wall = c["wall"] >= 0
    assert np.isinf(c["r2"][wall]).all() and np.isfinite(c["r2"][~wall]).all()
    assert "kno" not in c
    as_built = open_yade_snapshot(YADE / "mindlin_box.h5").frame(2).contacts
    e_plane = partition(c, run.scene).u_n
    e_built = partition(as_built, run.scene).u_n
    np.testing.assert_allclose(e_plane[~wall], e_built[~wall], rtol=1e-12)
    # Wall and Box: R* = R/2 as built, R as a plane: sqrt(2) times the energy
    plane_like = np.isin(c["wall"], [0, 1, 2, 3, 6])
    np.testing.assert_allclose(e_plane[plane_like] / e_built[plane_like], np.sqrt(2.0), rtol=1e-12)
    facet = np.isin(c["wall"], [4, 5])  # R* = 2R/3 as built
    np.testing.assert_allclose(e_plane[facet] / e_built[facet], np.sqrt(1.5), rtol=1e-12)


@pytest.mark.parametrize("name", ["mindlin_box.npys", "mindlin_box.h5"])
def test_truncated_snapshot_file_raises(tmp_path, name):
    src = YADE / name
    cut = tmp_path / name
    if name.endswith(".npys"):
        data = src.read_bytes()
        cut.write_bytes(data[:-1000])  # the last snapshot loses its end
        run = open_yade_snapshot(cut)
        frames = []
        with pytest.raises(TruncatedFileError, match="snapshot 2 .*cut short or damaged") as info:
            for f in run:
                frames.append(f)
        assert len(frames) == 2  # the complete ones are read
        assert "iteration 16000" in str(info.value) and "Fix:" in str(info.value)
        # the writer refuses to append behind a broken record
        meta, tables = _open_store(src).snapshot(0)
        with pytest.raises(TruncatedFileError):
            write_snapshot(cut, meta, tables)
    else:
        h5py = pytest.importorskip("h5py")
        shutil.copy(src, cut)
        with h5py.File(cut, "a") as f:  # as left by a write cut short before its 'complete' mark
            del f["snapshots/000002"].attrs["complete"]
        run = open_yade_snapshot(cut)
        with pytest.raises(TruncatedFileError, match="no 'complete' mark"):
            list(run)
        run.close()
        cut.write_bytes(src.read_bytes()[:100_000])
        with pytest.raises(DemsplitError, match="cut short or damaged"):
            open_yade_snapshot(cut)


@pytest.mark.parametrize("fmt", ["npy", "hdf5"])
def test_writer_round_trip(tmp_path, fmt):
    if fmt == "hdf5":
        pytest.importorskip("h5py")
    store = _open_store(YADE / "cundall_periodic.npys")
    out = tmp_path / "copy.snap"
    for k in range(len(store)):
        assert write_snapshot(out, *store.snapshot(k), format=fmt) == k
    for fa, fb in zip(open_yade_snapshot(YADE / "cundall_periodic.npys"), open_yade_snapshot(out)):
        contacts_equal(fa.contacts, fb.contacts)
    with pytest.raises(InputFormatError, match="cannot append"):
        write_snapshot(out, *store.snapshot(0), format="hdf5" if fmt == "npy" else "npy")


def test_vtk_export_agrees_with_the_snapshot_to_percent_g():
    mindlin = laws.law_class("yade:Law2_ScGeom_MindlinPhys_Mindlin").phys  # the attributes the law reads
    frame = _vtk_frame(
        YADE / "mindlin_box-spheres-00024000.vtk", YADE / "mindlin_box-intrs-00024000.vtk", attributes=mindlin
    )
    ref = open_yade_snapshot(YADE / "mindlin_box.h5").frame(2)
    assert frame.step == ref.step == 24000
    assert frame.n_contacts == ref.n_contacts == 235
    for c in ("id1", "id2", "wall"):
        np.testing.assert_array_equal(frame.contacts[c], ref.contacts[c])
    for c in ("delta", "nx", "ny", "nz", "r1", "r2", "kno", "ftx", "ks"):  # %g: 6 digits
        np.testing.assert_allclose(
            frame.contacts[c], ref.contacts[c], rtol=5e-6, atol=1e-12 * np.abs(ref.contacts[c]).max(), err_msg=c
        )


def test_vtk_without_penetration_depth_is_refused():
    spheres = YADE / "cundall_periodic-spheres-00009000.vtk"
    intrs = YADE / "cundall_periodic-intrs-00009000.vtk"
    with pytest.raises(PrecisionError) as info:
        _vtk_frame(spheres, intrs)
    msg = str(info.value)
    assert "timestep 9000" in msg and "cundall_periodic-intrs-00009000.vtk" in msg
    assert "demsplit.yade.snapshot()" in msg
    frame = _vtk_frame(spheres, intrs, tolerance=np.inf)
    assert frame.n_contacts == 425 and frame.overlap_error.max() > 1e-3


def test_vtk_export_is_a_registered_run_whose_energies_match_the_snapshot():
    """open_run reads VTKExporter files with the scene given as options; the energies (kno, %g) are the
    snapshot's to %g precision."""
    materials = {0: ds.Material(2e7, 0.3), 1: ds.Material(1e8, 0.2)}
    with pytest.raises(InputFormatError, match="do not hold the materials"):
        open_run(YADE / "mindlin_box-spheres-00024000.vtk")
    run = open_run(
        YADE / "mindlin_box-spheres-00024000.vtk",
        materials=materials,
        law="yade:Law2_ScGeom_MindlinPhys_Mindlin",
        wall_type=1,
    )
    assert isinstance(run, YadeVtkRun) and run.steps.tolist() == [24000] and len(run) == 1
    frame = run.frame(0)
    ref_run = open_yade_snapshot(YADE / "mindlin_box.h5")
    ref = ref_run.frame(2)
    e, e_ref = (
        partition(frame.contacts, run.scene, frame.particles),
        partition(ref.contacts, ref_run.scene, ref.particles),
    )
    np.testing.assert_allclose(e.u_n.sum(), e_ref.u_n.sum(), rtol=3e-5)


def test_percent_g_error_bound_by_hand():
    # x = 0.0123456 m: last printed digit h = 1e-7 m; delta = 1e-5 m -> sqrt(3) 1e-7 / 1e-5
    x = np.array([[0.0123456, 0.001, 0.002]])
    bound = overlap_error_bound(x, x + [[0.0, 0.0, 0.001]], np.array([1e-5]))
    assert bound[0] == pytest.approx(np.sqrt(3.0) * 1e-2, rel=1e-12)


VTK_SPHERES = """# vtk DataFile Version 3.0.
comment
ASCII

DATASET POLYDATA
POINTS 2 double
0 0 0
0 0 0.0199

POINT_DATA 2
SCALARS radius double 1
LOOKUP_TABLE default
0.01
0.01
"""


def test_vtk_sphere_file_without_ids(tmp_path):
    path = tmp_path / "s-spheres-00000001.vtk"
    path.write_text(VTK_SPHERES)
    assert read_vtk(path).point_data["radius"].tolist() == [0.01, 0.01]
    with pytest.raises(InputFormatError, match=r"lacks the field\(s\) \['id'\]") as info:
        _vtk_frame(path)
    assert "exportSpheres(what=dict(id='b.id'" in str(info.value)
    path.write_text(VTK_SPHERES + "\nSCALARS id double 1\nLOOKUP_TABLE default\n1.23457e+06\n1.23457e+06\n")
    with pytest.raises(PrecisionError, match="ids above 999999 are destroyed"):
        _vtk_frame(path)
    path.write_text(VTK_SPHERES + "\nSCALARS id double 1\nLOOKUP_TABLE default\n0\n1\n")
    with pytest.raises(DemsplitError, match="no material id field"):
        _vtk_frame(path)
    assert _vtk_frame(path, default_type=0).particles["id"].tolist() == [0, 1]
    path.write_text(VTK_SPHERES[:-10])
    with pytest.raises(InputFormatError, match="expected 2 numbers"):
        read_vtk(path)


VTK_OPTIONS = TestVtkExport.options


def test_vtk_series_of_several_steps_and_a_missing_interactions_file(tmp_path):
    """Every NAME-spheres-N.vtk beside the one given is a frame, by N; a frame whose interactions file is
    missing is refused when it is read (a bad frame), the first frame's when the run is opened."""
    for step in (24000, 25000):
        shutil.copy(YADE / "mindlin_box-spheres-00024000.vtk", tmp_path / f"mindlin_box-spheres-{step:08d}.vtk")
    shutil.copy(YADE / "mindlin_box-intrs-00024000.vtk", tmp_path / "mindlin_box-intrs-00024000.vtk")
    with open_run(tmp_path / "mindlin_box-spheres-00025000.vtk", **VTK_OPTIONS) as run:
        assert run.steps.tolist() == [24000, 25000] and len(run) == 2
        assert [Path(s).name for s in run.sources] == [
            "mindlin_box-spheres-00024000.vtk",
            "mindlin_box-intrs-00024000.vtk",
            "mindlin_box-spheres-00025000.vtk",
        ]
        assert run.frame(0).n_contacts == 235
        with pytest.raises(InputFormatError, match="interactions file of this sphere file is missing") as err:
            run.frame(1)
        assert err.value.step == 25000 and "mindlin_box-intrs-00025000.vtk" in str(err.value)
    (tmp_path / "mindlin_box-intrs-00024000.vtk").unlink()
    with pytest.raises(InputFormatError, match="interactions file of this sphere file is missing"):
        open_run(tmp_path / "mindlin_box-spheres-00025000.vtk", **VTK_OPTIONS)


def test_info_on_vtk_files():
    """info describes a sphere file as the run it starts (with the options a run needs) and an
    interactions file as a part of one."""
    from demsplit.inspection import describe_file

    text = describe_file(YADE / "mindlin_box-spheres-00024000.vtk")
    assert "YADE VTKExporter files" in text and "frames:   1" in text and "160 spheres, 235 contacts" in text
    assert "--material ID:E:NU for the material ids [0, 1]" in text and "--wall-type" in text
    assert "cell fields:  contactPoint, id1, id2" in text
    text = describe_file(YADE / "mindlin_box-intrs-00024000.vtk")
    assert "legacy VTK file" in text and "lines: 235" in text and "not a run of its own" in text
    assert "LIGGGHTS" not in text


@pytest.mark.parametrize("sample", ["laws_box_hertz_linear", "laws_box_deresiewitz"])
def test_plane_as_plane_is_refused_by_a_law_that_reads_yades_kno(sample, capsys, tmp_path):
    """HertzWithLinearShear and MindlinDeresiewitz read the kno YADE stored (the plane as a sphere);
    with --plane-as-plane the run failed on a missing 'kno' column, a message that did not name the
    option. Now one message names it and its fix."""
    from demsplit.cli import main

    rc = main(["run", str(YADE / f"{sample}.h5"), "--plane-as-plane", "-o", str(tmp_path / "out.h5"), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and "--plane-as-plane" in err and "without --plane-as-plane" in err, err
    assert "kno" in err and "missing" not in err and not (tmp_path / "out.h5").exists()


def _joint_frame(smooth_joint: bool):
    """Two JCFpm contacts of spheres r = 1 mm: one on a joint overlapped by 1.5 mm (the spheres slid past each
    other), one bond in tension, and the scene of that law."""
    law = laws.make("yade:Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM", {"smooth_joint": smooth_joint})
    contacts = {
        "id1": np.array([0, 1]),
        "id2": np.array([1, 2]),
        "wall": np.array([-1, -1]),
        "delta": np.array([1.5e-3, -1e-4]),
        "nx": np.ones(2),
        "ny": np.zeros(2),
        "nz": np.zeros(2),
        "x1": np.zeros(2),
        "y1": np.zeros(2),
        "z1": np.zeros(2),
        "r1": np.full(2, 1e-3),
        "r2": np.full(2, 1e-3),
        "on_joint": np.array([1.0, 0.0]),
    }
    particles = {
        "id": np.arange(3),
        "type": np.zeros(3, np.int32),
        "x": np.zeros(3),
        "y": np.zeros(3),
        "z": np.zeros(3),
        "radius": np.full(3, 1e-3),
    }
    scene = ds.Scene({0: ds.Material(1e9, 0.3)}, ds.ContactModel(law.key, {"smooth_joint": smooth_joint}))
    return ds.Frame(step=1, particles=particles, contacts=contacts), scene


def test_a_smooth_joint_may_overlap_beyond_the_smaller_radius():
    """JCFpm declares its plausibility limits: a contact on a smooth joint up to r1 + r2, a bond at any gap; the
    validation applies the law's limit (it refused YADE's own JCFpm example as a broken dump)."""
    from demsplit.errors import ContactError
    from demsplit.validate import overlap_limit, validated_frame

    frame, scene = _joint_frame(smooth_joint=True)
    validated_frame(frame, scene)
    assert overlap_limit(frame.contacts, scene).tolist() == [2e-3, 1e-3]
    assert scene.model.contact_law.separation_limit(1e-3, 1e-3) == np.inf
    frame, scene = _joint_frame(smooth_joint=False)  # without smoothJoint YADE's law acts on delta: a radius at most
    with pytest.raises(ContactError, match="larger than its smaller radius"):
        validated_frame(frame, scene)


def test_several_files_are_one_run_only_for_a_reader_of_several_files():
    """A list of inputs is one run for a reader whose runs are several files (Run.several_files: YADE saved
    states); two snapshot files are two runs."""
    from demsplit.readers.yade_state import YadeStateRun

    assert YadeStateRun.several_files and not YadeSnapshotRun.several_files
    with pytest.raises(InputFormatError, match="a run by itself"):
        open_run([YADE / "mindlin_box.h5", YADE / "cundall_periodic.h5"])


def test_a_format_1_snapshot_is_read_with_what_it_holds(tmp_path):
    """A snapshot of format 1 (before the laws declared their attributes) has no elastic shear force of
    Hertz-Mindlin (shearElastic, fse) and no angular velocities: it is read, with u_t of that law missing
    (refused by run without --allow-missing), the other modes and laws as before."""
    meta, tables = _open_store(YADE / "mindlin_box.npys").snapshot(2)
    for c in ("fsex", "fsey", "fsez"):
        del tables["interactions"][c]
    for c in ("wx", "wy", "wz"):
        del tables["bodies"][c]
    meta["format_version"] = 1
    old = tmp_path / "v1.npys"
    write_snapshot(old, meta, tables, format="npy")
    frame = open_yade_snapshot(old).frame(0)
    new = open_yade_snapshot(YADE / "mindlin_box.npys")
    e, ref = partition(frame.contacts, new.scene, frame.particles), partition(*_frame_and_scene(new))
    assert "u_t" in e.missing and "ftx" not in frame.contacts
    np.testing.assert_array_equal(e.u_n, ref.u_n)


def _frame_and_scene(run):
    frame = run.frame(2)
    return frame.contacts, run.scene, frame.particles


def test_a_wall_without_material_is_refused_not_split_in_half():
    """One particle material and a wall of a type without one: the single-material shortcut (every share 1/2)
    gave that wall half the energy, exit 0; the lookup now names the wall's type."""
    from demsplit.errors import MaterialError

    scene = ds.Scene({0: ds.Material(1e7, 0.3)}, walls=[ds.Wall("w", "yade_wall", type=5)])
    contacts = {
        "id1": np.array([0]),
        "id2": np.array([-1]),
        "wall": np.array([0]),
        "delta": np.array([1e-5]),
        "nx": np.ones(1),
        "ny": np.zeros(1),
        "nz": np.zeros(1),
        "x1": np.zeros(1),
        "y1": np.zeros(1),
        "z1": np.zeros(1),
        "r1": np.full(1, 1e-3),
        "r2": np.full(1, 1e-3),
    }
    particles = {
        "id": np.array([0]),
        "type": np.array([0], np.int32),
        "x": np.zeros(1),
        "y": np.zeros(1),
        "z": np.zeros(1),
        "radius": np.full(1, 1e-3),
    }
    assert not scene.single_material
    with pytest.raises(MaterialError, match=r"wall type\(s\) \[5\] have no material"):
        partition(contacts, scene, particles)
