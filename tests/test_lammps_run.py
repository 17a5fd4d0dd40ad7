"""demsplit's LAMMPS reader and laws against LAMMPS itself, on the sample runs (``sample_dumps/lammps/``).

Through demsplit's own reader (:class:`demsplit.readers.lammps.LammpsRun`) and laws (``lammps:*``): per contact,
the normal force rebuilt from demsplit's law equals the one LAMMPS dumped; per atom, the sum of the rebuilt
contact forces and torques of the step (plus gravity; the pairs' twisting torques, in no dump, solved by least
squares) equals LAMMPS' dumped ``fx fy fz`` and ``tqx tqy tqz``: this checks the springs the energies rest on.
Per contact, demsplit's energies equal those of the independent reference ``tests/lammps_reference.py`` and it
marks unknown exactly what the reference finds unknowable; ``demsplit run`` on every sample conserves every mode.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from demsplit import Material
from demsplit.cli import main
from demsplit.compute import Options, frame_tables
from demsplit.errors import InputFormatError
from demsplit.physics.modes import NOT_COMPUTED_BITS
from demsplit.readers import open_run, reader_for
from demsplit.readers.lammps import LammpsRun
from demsplit.readers.lammps_balance import twisting_torques
from demsplit.readers.liggghts import LiggghtsRun
from demsplit.results import load_results
from lammps_reference import Run as Reference
from lammps_reference import atom_sums, resolve_intervals
from reader_contract import ReaderContract

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps" / "lammps"
TOL = 1e-9
MATERIALS = {1: Material(1e7, 0.25), 2: Material(2e6, 0.4)}
WALL = Material(5e7, 0.3)

# case -> (folder, script, dump prefix, the options demsplit needs, the modes no dump holds)
CASES = {
    "hertz_mindlin": ("hertz_mindlin", "in.hertz_mindlin", "", {}, ("u_tw", "u_r")),
    "dmt": ("dmt", "in.dmt", "", {}, ("u_t", "u_r")),
    "jkr": ("jkr", "in.jkr", "", {}, ("u_tw", "u_t", "u_r", "u_n", "u_adh")),
    "hooke_region": (
        "hooke_region",
        "in.hooke_region",
        "",
        {"materials": MATERIALS, "wall_materials": {"shell": WALL}},
        ("u_t",),
    ),
    "periodic": ("periodic", "in.periodic", "", {"materials": {2: MATERIALS[2]}}, ()),
    "gran_hooke_history": (
        "legacy",
        "in.hooke_history",
        "hooke_history_",
        {"materials": MATERIALS, "wall_materials": {"floor": WALL}},
        (),
    ),
    "gran_hertz_history": (
        "legacy",
        "in.hertz_history",
        "hertz_history_",
        {"materials": MATERIALS, "wall_materials": {"floor": WALL, "cyl": WALL}},
        (),
    ),
    "gran_hooke": (
        "legacy",
        "in.hooke",
        "hooke_",
        {"materials": MATERIALS, "wall_materials": {"floor": WALL, "sides": WALL}},
        (),
    ),
}


def script_of(case: str) -> Path:
    folder, script, *_ = CASES[case]
    return SAMPLES / folder / script


@functools.cache
def assembled(case: str) -> tuple[LammpsRun, list]:
    """Every frame of a sample as demsplit's reader assembles it (contacts, springs, step forces)."""
    run = open_run(script_of(case), **CASES[case][3])
    out = []
    for k in range(len(run)):
        af = run.atoms.frame(k, columns=run._atom_columns())
        out.append(run.assemble(af, run._local_at(int(run.steps[k]))))
    return run, out


@functools.cache
def reference(case: str) -> tuple[Reference, list]:
    folder, script, prefix, *_ = CASES[case]
    ref = Reference(SAMPLES / folder, script, prefix)
    frames = []
    for frame in ref.frames():
        sums = atom_sums(frame, ref.models)
        frames.append((frame, resolve_intervals(frame, sums, TOL)))
    return ref, frames


def _rel(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> np.ndarray:
    diff = np.abs(a - b) if a.ndim == 1 else np.linalg.norm(a - b, axis=1)
    return diff / np.where(scale > 0, scale, 1.0)


# ------------------------------------------------------------------------------------------- the reader's contract


class TestHertzMindlinSample(ReaderContract):
    reader = LammpsRun
    path = SAMPLES / "hertz_mindlin" / "in.hertz_mindlin"


class TestLegacyHookeHistorySample(ReaderContract):
    reader = LammpsRun
    path = SAMPLES / "legacy" / "in.hooke_history"
    options = CASES["gran_hooke_history"][3]


def test_a_lammps_script_is_told_from_a_liggghts_one():
    """The scripts' own words decide; --simulator decides where they cannot."""
    assert reader_for(script_of("hertz_mindlin")) is LammpsRun
    assert reader_for(script_of("gran_hooke")) is LammpsRun
    liggghts = SAMPLES.parent / "liggghts" / "packing" / "in.packing"
    assert reader_for(liggghts) is LiggghtsRun
    assert reader_for(liggghts, "lammps") is LammpsRun
    assert reader_for(script_of("dmt"), "liggghts") is LiggghtsRun


# ------------------------------------------------------------------------------------------- per contact


@pytest.mark.parametrize("case", CASES)
def test_rebuilt_normal_force_is_the_dumped_one(case):
    """Every pair row and wall contact LAMMPS wrote: the normal force demsplit's law gives (damping at the
    velocities LAMMPS used) is the dumped one, to 1e-9 of |F_ne| + |damping|; the rows it cannot compare are the
    jkr rows single() zeroed, and every other row was compared."""
    ref, frames = reference(case)
    for a, (frame, _) in zip(assembled(case)[1], frames):
        r, c = a.rebuilt, a.contacts
        written = ~c["neck"] & ~c["extra_contact"]
        compared = written & np.isfinite(r.fn_rebuilt)
        assert compared.sum() == len(frame.pairs.i) + sum(len(w.i) for w in frame.walls) - int(
            (frame.pairs.extra["why"] == "jkr_zeroed").sum()
        )
        err = _rel(r.fn_rebuilt[compared], c["fn_dumped"][compared], r.fn_scale[compared])
        assert err.max() < TOL, (a.step, err.max())


def test_a_wrong_coefficient_is_an_error_naming_the_line(tmp_path):
    """A script whose model differs from the run's (k_n of hooke_region's 1-1 pairs) is refused by the first row
    whose dumped normal force it does not give."""
    text = script_of("hooke_region").read_text().replace("1 1 hooke 800.0", "1 1 hooke 801.0")
    copy = _copy_sample("hooke_region", tmp_path, text)
    run = open_run(copy, **CASES["hooke_region"][3])
    with pytest.raises(InputFormatError) as err:
        run.frame(0)
    message = str(err.value)
    assert "pairs.txt.gz:" in message and "timestep 51000" in message and "lammps:hooke" in message
    assert err.value.line > 9  # a row of the frame, after its header


# ------------------------------------------------------------------------------------------- per atom


def _balances(a, gravity) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per atom: the relative force and torque residuals of demsplit's rebuilt step (NaN where a term is in no
    dump), gravity from the script, the twisting torques solved."""
    r, atoms = a.rebuilt, a.atoms
    n = len(atoms["r"])
    pair = a.rows2 >= 0

    def total(on1, on2):
        out, scale = np.zeros((n, 3)), np.zeros(n)
        np.add.at(out, a.rows1, on1)
        np.add.at(out, a.rows2[pair], on2[pair])
        np.add.at(scale, a.rows1, np.linalg.norm(on1, axis=1))
        np.add.at(scale, a.rows2[pair], np.linalg.norm(on2[pair], axis=1))
        return out, scale

    g = np.asarray(gravity)
    F, Fs = total(r.force, -r.force)
    weight = atoms["m"][:, None] * g
    rel_f = np.linalg.norm(atoms["f"] - weight - F, axis=1) / (Fs + np.linalg.norm(weight, axis=1))
    T, Ts = total(r.torque1, r.torque2)
    known = np.isfinite(T).all(1)
    res = np.where(known[:, None], atoms["tq"] - np.nan_to_num(T), 0.0)
    n_L = -np.stack([a.contacts[c] for c in ("nx", "ny", "nz")], -1)
    twist = np.flatnonzero(r.twisting & pair & np.isfinite(r.torque1).all(1))
    tau = twisting_torques(res, a.rows1[twist], a.rows2[twist], n_L[twist], known)
    for rows, sign in ((a.rows1[twist], 1.0), (a.rows2[twist], -1.0)):
        np.add.at(res, rows, -sign * tau[:, None] * n_L[twist])
        np.add.at(Ts, rows, np.abs(tau))
    rel_t = np.where(known, np.linalg.norm(res, axis=1) / np.where(Ts > 0, Ts, 1.0), np.nan)
    return rel_f, rel_t, np.isfinite(F).all(1), known


@pytest.mark.parametrize("case", CASES)
def test_atom_force_and_torque_balance(case):
    """Σ rebuilt contact forces + m g = the dumped fx fy fz, Σ rebuilt torques + the solved twisting torques = the
    dumped tqx tqy tqz, to 1e-9, for every atom whose terms are all in the dumps; the atoms left out are those the
    reference leaves out (its rule-flagged contacts and necks, and for the torque the walls with a rolling model)."""
    ref, frames = reference(case)
    run, steps = assembled(case)
    for a, (frame, _) in zip(steps, frames):
        rel_f, rel_t, known_f, known_t = _balances(a, run.script.gravity[a.run])
        assert rel_f[known_f].max() < TOL, (a.step, rel_f[known_f].max())
        assert rel_t[known_t].max() < TOL, (a.step, np.nanmax(rel_t[known_t]))
        sums = atom_sums(frame, ref.models)
        ref_known = ~np.isnan(sums["F"]).any(1)
        order = np.argsort(a.atoms["id"])
        assert np.array_equal(known_f[order], ref_known[np.argsort(frame.atoms.ids)])
        assert known_f.sum() > 0.8 * len(known_f)


# ------------------------------------------------------------------------------------------- energies


def _modes_of(a, run: LammpsRun) -> dict[str, np.ndarray]:
    """demsplit's energies of every contact of an assembled step (NaN where not computed)."""
    from demsplit.physics.partition import contact_energies

    frame = run.to_frame(a)
    e = contact_energies(frame.contacts, run.scene, frame.particles)
    out = {m.column: e.u[k].copy() for k, m in enumerate(e.modes)}
    if e.u_adh is not None:
        out["u_adh"] = e.u_adh.copy()
    for mode, values in out.items():
        values[(e.not_computed & NOT_COMPUTED_BITS[mode]) != 0] = np.nan
    return out


@pytest.mark.parametrize("case", CASES)
def test_energies_equal_the_reference_per_contact(case):
    """Per pair row and wall contact: u_n, u_t, u_r, u_adh equal the reference's to 1e-9 (a spring the atoms'
    balance moved: the reference's resolution), and a value is not computed exactly where the reference has none."""
    run, steps = assembled(case)
    ref, frames = reference(case)
    for a, (frame, resolved) in zip(steps, frames):
        mine = _modes_of(a, run)
        c = a.contacts
        written = ~c["neck"] & ~c["extra_contact"]
        parts = [frame.pairs, *frame.walls]
        keys_ref = np.concatenate([_keys(p.i, p.j, frame.atoms.ids, k) for k, p in enumerate(parts)])
        wall_of = {w.kind.split(":")[1]: k + 1 for k, w in enumerate(frame.walls)}
        fix_ids = [w.name for w in run.scene.walls]
        kind = np.where(c["wall"] < 0, 0, np.array([wall_of.get(f, -1) for f in fix_ids] + [0])[c["wall"]])
        ids2 = np.where(c["wall"] < 0, c["id2"], -1)
        keys_mine = _pack(c["id1"], ids2, kind)
        assert np.array_equal(np.sort(keys_mine[written]), np.sort(keys_ref))
        where = {int(keys_mine[n]): n for n in np.flatnonzero(written)}
        rows = np.array([where[int(k)] for k in keys_ref])
        for mode in ("u_n", "u_t", "u_r", "u_adh"):
            theirs = np.concatenate([p.energies[mode] for p in parts])
            if mode == "u_t":
                theirs = _with_resolution(theirs, frame, resolved)
            ours = mine.get(mode, np.zeros(len(keys_mine)))[rows]
            assert np.array_equal(np.isnan(ours), np.isnan(theirs)), mode
            known = ~np.isnan(theirs)
            scale = np.maximum(np.abs(theirs[known]), 1e-300)
            assert (np.abs(ours[known] - theirs[known]) <= TOL * scale).all(), (mode, a.step)
        twist = np.concatenate([p.twist if p.twist is not None else np.zeros(len(p.i), bool) for p in parts])
        if twist.any():
            assert np.all(np.isnan(mine["u_tw"][rows][twist]))


def _pack(i: np.ndarray, j: np.ndarray, kind: np.ndarray) -> np.ndarray:
    return (np.asarray(i, np.int64) * 1_000_003 + (np.asarray(j, np.int64) + 1)) * 16 + np.asarray(kind, np.int64)


def _keys(i: np.ndarray, j: np.ndarray, ids: np.ndarray, kind: int) -> np.ndarray:
    return _pack(ids[i], np.where(j >= 0, ids[np.maximum(j, 0)], -1), np.full(len(i), kind))


def _with_resolution(u_t: np.ndarray, frame, resolved: list) -> np.ndarray:
    """The reference's pair u_t with the springs its force balance moved: u scales with |F_el|^2."""
    u_t = u_t.copy()
    p = frame.pairs
    for r in resolved:
        c = r["row"]
        w = p.extra["pt"][c] / np.linalg.norm(p.extra["pt"][c])
        moved = p.F_el[c] + r["dL"] * w
        u_t[c] *= (moved @ moved) / (p.F_el[c] @ p.F_el[c])
    return u_t


# ------------------------------------------------------------------------------------------- demsplit run


def _cli(case: str, out: Path, allow: bool) -> list[str]:
    """``demsplit run`` of a sample with the material options its models need (and ``--allow-missing`` for
    what no dump holds)."""
    options = CASES[case][3]
    args = ["run", str(script_of(case)), "-o", str(out), "-q"]
    for t, m in options.get("materials", {}).items():
        args += ["--material", f"{t}:{m.E!r}:{m.nu!r}"]
    for fid, m in options.get("wall_materials", {}).items():
        args += ["--wall-material", f"{fid}:{m.E!r}:{m.nu!r}"]
    for mode in CASES[case][4] if allow else ():
        args += ["--allow-missing", mode]
    return args


@pytest.mark.parametrize("case", CASES)
def test_demsplit_run_succeeds_and_conserves_every_mode(case, tmp_path):
    """``demsplit run`` on the sample succeeds; per frame and mode the particles and walls hold the contacts'
    energy (the stored values: a contact not computed holds 0 with its bit, the bodies its known part); the
    stored contacts' not-computed bits are those of the reader's rebuild."""
    assert main(_cli(case, tmp_path / "out.h5", allow=True)) == 0
    run, steps = assembled(case)
    options = Options(allow_missing=CASES[case][4])
    stored = load_results(tmp_path / "out.h5").contacts
    for a in steps:
        tables = frame_tables(run.to_frame(a), run.scene, options)
        c, p, w = tables["contacts"], tables["particles"], tables["walls"]
        for mode in [m for m in ("u_n", "u_t", "u_r", "u_tw", "u_adh") if m in c]:
            total = c[mode].sum()
            assert abs(p[mode].sum() + w[mode].sum() - total) <= 1e-12 * max(abs(total), 1e-300), mode
        mine = stored[stored["step"] == a.step]
        assert np.array_equal(mine["not_computed"].to_numpy(), c["not_computed"])
        assert len(mine) == len(a.contacts["delta"])


@pytest.mark.parametrize("case", [c for c in CASES if CASES[c][4]])
def test_what_no_dump_holds_is_refused_without_allow_missing(case, tmp_path, capsys):
    """Each mode no dump holds refuses the run, naming it and the option; with it the run goes on."""
    assert main(_cli(case, tmp_path / "out.h5", allow=False)) == 2
    err = capsys.readouterr().err
    assert "--allow-missing" in err and any(f"--allow-missing {m}" in err for m in CASES[case][4])


def _copy_sample(case: str, tmp_path: Path, text: str) -> Path:
    """The sample's dumps linked into tmp_path beside a script of ``text``."""
    folder = SAMPLES / CASES[case][0]
    for f in folder.glob("*.gz"):
        (tmp_path / f.name).symlink_to(f)
    path = tmp_path / CASES[case][1]
    path.write_text(text)
    return path


# ------------------------------------------------------------------------------------------- refusals


def _refused(case: str, tmp_path: Path, old: str, new: str, *extra: str) -> str:
    """``demsplit run`` of the sample whose script has ``old`` replaced by ``new``: its exit status must be 2 and
    its one message is returned."""
    text = script_of(case).read_text()
    assert old in text
    path = _copy_sample(case, tmp_path, text.replace(old, new))
    args = _cli(case, tmp_path / "out.h5", allow=True)
    args[1] = str(path)
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "demsplit.cli", *args, *extra], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    return proc.stderr


def test_g_atom_dump_is_refused_with_the_fix(tmp_path):
    err = _refused("dmt", tmp_path, "dump_modify     dsAtoms format float %.17g sort id", "dump_modify dsAtoms sort id")
    assert "dump dsAtoms" in err and "%g" in err and "dump_modify dsAtoms format float %.17g" in err


def test_g_pair_dump_is_refused_with_the_fix(tmp_path):
    err = _refused("dmt", tmp_path, "dump_modify     dsPairs format float %.17g", "dump_modify dsPairs format float %g")
    assert "dump dsPairs" in err and "overlap" in err and "dump_modify dsPairs format float %.17g" in err


def test_cutoff_type_is_refused_with_the_fix(tmp_path):
    err = _refused("dmt", tmp_path, "p10 p11 p12 cutoff radius", "p10 p11 p12")
    assert "compute dsP" in err and "cutoff type" in err and "in.dmt:" in err and "cutoff radius" in err


def test_a_pair_quantity_missing_is_refused(tmp_path):
    err = _refused("dmt", tmp_path, "c_dsP[16] c_dsP[17]", "c_dsP[16]")
    assert "p12" in err and "dump dsPairs" in err


def test_a_wall_column_missing_is_refused(tmp_path):
    """The script's wall fix 'cyl' renamed: the atom dump has no f_cyl2 columns."""
    text = script_of("jkr").read_text().replace("fix             cyl all", "fix             cyl2 all")
    path = _copy_sample("jkr", tmp_path, text)
    with pytest.raises(InputFormatError) as err:
        open_run(path)
    assert "f_cyl2[1]" in str(err.value) and "atoms.txt.gz" in str(err.value)


def test_a_cross_pair_left_to_mixing_is_refused_where_it_touches(tmp_path):
    old = (
        "pair_coeff      1 2 dmt 3892944.0389294405 4.0e6 0.0 0.06 &\n"
        "                tangential mindlin_rescale 2987861.811391223 1.0 0.55 rolling sds 15.0 0.002 0.12\n"
    )
    err = _refused("dmt", tmp_path, old, "")
    assert "pair_coeff 1 2" in err and "mix" in err


def test_a_jkr_wall_is_refused(tmp_path):
    err = _refused(
        "jkr",
        tmp_path,
        "fix             floor all wall/gran granular hertz/material 5.0e7 4.0e6 0.3",
        "fix             floor all wall/gran granular jkr 5.0e7 4.0e6 0.3 0.02",
    )
    assert "jkr wall" in err and "in.jkr:" in err


def test_types_without_e_and_nu_are_refused_naming_the_option(tmp_path, capsys):
    assert main(["run", str(script_of("hooke_region")), "-o", str(tmp_path / "out.h5"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "--material 1:" in err and "lammps:hooke" in err


def test_a_wall_model_without_e_and_nu_is_refused_naming_the_option(tmp_path, capsys):
    args = [
        "run",
        str(script_of("hooke_region")),
        "-o",
        str(tmp_path / "out.h5"),
        "-q",
        "--material",
        "1:1e7:0.25",
        "--material",
        "2:2e6:0.4",
    ]
    assert main(args) == 2
    assert "--wall-material shell:E:NU" in capsys.readouterr().err


def test_a_wall_without_contacts_is_refused_unless_allowed(tmp_path):
    old = "tangential mindlin NULL 1.0 0.4 zplane 0.0 NULL contacts"
    err = _refused("hertz_mindlin", tmp_path, old, "tangential mindlin NULL 1.0 0.4 zplane 0.0 NULL")
    assert "floor" in err and "contacts" in err and "--allow-missing floor" in err


def test_simulator_option_picks_the_reader(tmp_path, capsys):
    """--simulator liggghts reads a LAMMPS script as LIGGGHTS would: it has no 'pair_style gran model ...'."""
    args = _cli("dmt", tmp_path / "out.h5", allow=True) + ["--simulator", "liggghts"]
    assert main(args) == 2
    assert "pair_style 'granular' is not supported" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------- prepare and lmp


def _without_demsplit_lines(case: str) -> str:
    """The sample's script as a user would have written it: no demsplit computes and dumps, no 'contacts'."""
    text = script_of(case).read_text()
    head, _, tail = text.partition("# demsplit:")
    return head.replace(" contacts", "") + "run             " + tail.rsplit("run", 1)[1].split()[0] + "\n"


def test_prepare_adds_what_demsplit_reads(tmp_path, capsys):
    path = tmp_path / "in.hertz_mindlin"
    path.write_text(_without_demsplit_lines("hertz_mindlin"))
    assert main(["prepare", str(path), "-o", str(tmp_path / "in.prepared")]) == 0
    out = capsys.readouterr().out
    text = (tmp_path / "in.prepared").read_text()
    assert text.count(" contacts") == 2 and "lmp -in in.prepared" in out
    assert "pair/local dist force fx fy fz p1 p2 p3 p4 p5 p6 p7 p8 p9 p10 p11 p12 cutoff radius" in text
    assert "property/local patom1 patom2 ptype1 ptype2 cutoff radius" in text
    assert text.count("format float %.17g") == 2 and "f_cyl[8]" in text and "f_floor[8]" in text
    assert text.index("dump dsAtoms") < text.index("run             ${nfall}")
    assert main(["prepare", str(tmp_path / "in.prepared"), "-o", str(tmp_path / "again")]) == 0
    assert "nothing to add" in capsys.readouterr().out


@pytest.mark.simulator
def test_a_prepared_script_run_by_lmp_is_read_and_checked(tmp_path):
    """The hertz_mindlin scene without demsplit's lines, with a trajectory dump of its own, prepared and run by
    Debian's lmp (60 + 60 particles): the trajectory is byte for byte the unprepared run's; demsplit reads the run
    (every dumped normal force checked), its atoms' balances close, and demsplit run succeeds."""
    from conftest import require_program

    lmp = require_program("lmp", package="lammps")
    import subprocess

    head, run_line, tail = _without_demsplit_lines("hertz_mindlin").rpartition("run             ")
    user = (
        head + "dump t all custom 500 t.txt id x y z vx vy vz omegax omegay omegaz fx fy fz\n"
        "dump_modify t format float %.17g sort id\n" + run_line + tail
    )
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "in.user").write_text(user)
    (tmp_path / "in.user").write_text(user)
    assert main(["prepare", str(tmp_path / "in.user"), "-o", str(tmp_path / "in.ds"), "-q"]) == 0
    for where, script in ((tmp_path / "plain", "in.user"), (tmp_path, "in.ds")):
        subprocess.run(
            [lmp, "-in", script, "-var", "npour", "60", "-log", "none", "-echo", "none"],
            cwd=where,
            check=True,
            capture_output=True,
            timeout=300,
        )
    assert (tmp_path / "t.txt").read_bytes() == (tmp_path / "plain" / "t.txt").read_bytes()
    run = open_run(tmp_path / "in.ds", variables={"npour": "60"})
    frames = 0
    for k in range(len(run)):
        a = run.assemble(run.atoms.frame(k, columns=run._atom_columns()), run._local_at(int(run.steps[k])))
        if a.rebuilt is None or not len(a.contacts["delta"]):
            continue
        rel_f, rel_t, known_f, known_t = _balances(a, run.script.gravity[a.run])
        assert rel_f[known_f].max(initial=0) < TOL and rel_t[known_t].max(initial=0) < TOL, a.step
        frames += 1
    assert frames >= 10
    out = tmp_path / "out.h5"
    assert (
        main(
            [
                "run",
                str(tmp_path / "in.ds"),
                "--var",
                "npour",
                "60",
                "-o",
                str(out),
                "-q",
                "--allow-missing",
                "u_tw",
                "--allow-missing",
                "u_r",
            ]
        )
        == 0
    )


OFFICIAL = Path("/usr/share/lammps/examples")


@pytest.mark.simulator
@pytest.mark.slow
@pytest.mark.parametrize(
    "example, options",
    [
        ("pour/in.pour", ["--material", "1:1e5:0.3", "--wall-material", "zlower:1e5:0.3"]),
        ("granular/in.pour.drum", ["--allow-missing", "all"]),
    ],
)
def test_official_examples_prepared_and_run_unedited(example, options, tmp_path):
    """LAMMPS' own examples (Debian's copies), prepared and run by lmp as they are: demsplit reads every frame
    (each dumped normal force checked, the capped springs checked against the atoms' balance; in.pour changes its
    gravity between its two runs, the drum rotates its region walls and writes its first frame at a run's setup)."""
    from conftest import require_program

    lmp = require_program("lmp", package="lammps")
    import shutil
    import subprocess

    source = OFFICIAL / example
    if not source.is_file():
        pytest.fail(f"{source} is missing: Debian's lammps package installs the examples")
    shutil.copy(source, tmp_path / source.name)
    # every 1000 steps: the drum's own output (thermo 100) would give 51 frames to check, which takes minutes
    assert main(["prepare", str(tmp_path / source.name), "-o", str(tmp_path / "in.ds"), "-q", "--every", "1000"]) == 0
    subprocess.run(
        [lmp, "-in", "in.ds", "-log", "none", "-echo", "none"],
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=600,
    )
    assert main(["run", str(tmp_path / "in.ds"), "-o", str(tmp_path / "out.h5"), "-q", *options]) == 0
    frames = load_results(tmp_path / "out.h5").frames
    assert len(frames) == (51 if source.name == "in.pour" else 4) and (frames["n_contacts"] > 0).sum() >= 3


@pytest.mark.simulator
def test_a_run_on_two_processes_is_read_and_checked(tmp_path):
    """The hertz_mindlin scene (60 + 60 particles) run by lmp on two processes split along x: single() read the
    half-step velocities of the pairs' atoms 2 that were ghosts of the other process, which no dump says; demsplit
    finds them by their dumped normal force, and the atoms' balances close."""
    from conftest import require_program

    lmp = require_program("lmp", package="lammps")
    mpirun = require_program("mpirun", package="openmpi-bin")
    import subprocess

    text = script_of("hertz_mindlin").read_text().replace("boundary        f f f", "boundary f f f\nprocessors 2 1 1")
    (tmp_path / "in.mpi").write_text(text)
    subprocess.run(
        [
            mpirun,
            "--allow-run-as-root",
            "--oversubscribe",
            "-np",
            "2",
            lmp,
            "-in",
            "in.mpi",
            "-var",
            "npour",
            "60",
            "-log",
            "none",
            "-echo",
            "none",
        ],
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=300,
    )
    run = open_run(tmp_path / "in.mpi", variables={"npour": "60"})
    found = 0
    for k in range(len(run)):
        a = run.assemble(run.atoms.frame(k, columns=run._atom_columns()), run._local_at(int(run.steps[k])))
        rel_f, rel_t, known_f, known_t = _balances(a, run.script.gravity[a.run])
        assert rel_f[known_f].max() < TOL and rel_t[known_t].max() < TOL
        found += any("another process" in note for note in a.notes)
    assert found >= 1


def test_pair_coeff_ranges_and_the_global_history_flag(tmp_path):
    """``pair_coeff 1 * ...`` sets 1-1 and 1-2, a later line overrides an earlier one, and linear_nohistory beside
    a history model runs LAMMPS' history branch (k_t = 0); E and nu of a type come from its own i i line only."""
    from demsplit.readers.lammps_script import read_lammps_script

    path = tmp_path / "in.ranges"
    path.write_text(
        "units si\natom_style sphere\nregion b block 0 1 0 1 0 1\ncreate_box 3 b\npair_style granular\n"
        "pair_coeff * * hooke 1e5 0.5 tangential linear_nohistory 1.0 0.5\n"
        "pair_coeff 1 * hertz/material 1e7 0.5 0.25 tangential mindlin NULL 1.0 0.5\n"
        "pair_coeff 3 3 dmt 2e6 0.5 0.4 0.05 tangential linear_history 1e4 1.0 0.5\n"
        "pair_coeff 2 3 hooke 2e5 0.5 tangential linear_nohistory 1.0 0.5\nrun 10\n"
    )
    script = read_lammps_script(path)
    laws = {pair: m.law for pair, m in script.pair_models.items()}
    assert laws == {
        (1, 1): "lammps:hertz/material",
        (1, 2): "lammps:hertz/material",
        (1, 3): "lammps:hertz/material",
        (2, 2): "lammps:hooke",
        (2, 3): "lammps:hooke",
        (3, 3): "lammps:dmt",
    }
    assert script.pair_models[(2, 3)].params["kn"] == 2e5
    assert script.pair_models[(2, 2)].contact_law.history_branch
    assert set(script.line_materials) == {1, 3} and script.line_materials[3] == Material(2e6, 0.4)
