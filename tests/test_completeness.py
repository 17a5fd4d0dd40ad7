"""A run is analysed whole or refused (docs/design.md, "Energy modes, split rules and completeness").

What the run has but its files lack (a mesh wall whose contacts were not dumped, a history the
law needs cut from the dump's column list) stops ``run`` (exit 2) and is a problem in ``check``
(exit 1), naming the wall or mode and the fix; ``--allow-missing NAME`` goes on and marks those
values "not computed" (``not_computed`` bits, never a silent 0). What LIGGGHTS cannot write at
all (the history of primitive-wall contacts) is marked per contact, per particle and per wall.
"""

from __future__ import annotations

import gzip
import re
import shutil
from pathlib import Path

import demsplit
import numpy as np
import pytest
from demsplit.cli import main
from demsplit.physics.modes import NOT_COMPUTED_BITS, not_computed_modes

PACKING = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts" / "packing"
U_N, U_T = NOT_COMPUTED_BITS["u_n"], NOT_COMPUTED_BITS["u_t"]


@pytest.fixture
def packing(tmp_path) -> Path:
    for f in PACKING.iterdir():
        if f.is_file():
            shutil.copy(f, tmp_path / f.name)
    return tmp_path / "in.packing"


def test_a_deleted_wall_dump_is_refused_with_the_fix(packing, capsys):
    for name in ("wall.txt", "wall_full.txt.gz"):
        (packing.parent / name).unlink()
    assert main(["run", str(packing), "-o", str(packing.parent / "out.h5"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "mesh wall 'floor'" in err and "--allow-missing floor" in err and "wall/gran/local" in err
    assert not (packing.parent / "out.h5").exists()
    assert main(["check", str(packing)]) == 1
    assert "wall 'floor' (mesh)" in capsys.readouterr().out


@pytest.mark.slow
def test_allow_missing_marks_the_wall_not_computed(packing):
    for name in ("wall.txt", "wall_full.txt.gz"):
        (packing.parent / name).unlink()
    out = packing.parent / "out.h5"
    assert main(["run", str(packing), "-o", str(out), "-q", "--allow-missing", "floor"]) == 0
    res = demsplit.load_results(out)
    floor = res.walls[res.walls["wall"] == 0]
    assert len(floor) == len(res.steps) and np.all(floor["not_computed"] == U_N | U_T)
    assert res.provenance["notes"][0].startswith("wall 'floor' NOT COMPUTED")
    assert res.provenance["options"]["allow_missing"] == ["floor"]


def test_primitive_wall_contacts_have_no_history(packing):
    res = demsplit.analyze(packing)
    c = res.contacts
    walls = res.provenance["scene"]["walls"] if "scene" in res.provenance else None
    primitive = c["wall"] >= 1  # wall 0 is the mesh floor, 1.. the primitive planes and post
    if walls is not None:
        assert [w["kind"] for w in walls][0] == "mesh"
    assert primitive.any() and (c["wall"] == 0).any()
    assert np.all(c.loc[primitive, "not_computed"] == U_T)  # u_n is known, u_t is not
    assert np.all(c.loc[~primitive, "not_computed"] == 0)
    assert not_computed_modes(U_T) == ["u_t"]
    # a particle is incomplete exactly when one of its contacts is
    p = res.particles
    touching = set(zip(c.loc[primitive, "step"], c.loc[primitive, "id1"]))
    flagged = set(zip(p.loc[p["not_computed"] != 0, "step"], p.loc[p["not_computed"] != 0, "id"]))
    assert flagged == touching
    w = res.walls
    assert np.all(w.loc[w["wall"] >= 1, "not_computed"] == U_T) and np.all(w.loc[w["wall"] == 0, "not_computed"] == 0)
    per_step = c.groupby("step")["not_computed"].apply(lambda s: int((s != 0).sum()))
    assert res.frames["n_not_computed"].tolist() == per_step.loc[res.frames["step"]].tolist()


def drop_history(script: Path) -> None:
    """The pair dump without its history columns (c_cpgl[34..36]): the script's column list and the file."""
    text = script.read_text()
    cut = " c_cpgl[34] c_cpgl[35] c_cpgl[36]"
    script.write_text(text.replace(cut, ""))
    with gzip.open(script.parent / "pairs_full.txt.gz", "rt") as f:
        lines = f.read().split("\n")
    out, in_rows = [], False
    for line in lines:
        if line.startswith("ITEM: ENTRIES"):
            in_rows = True
            out.append(line.replace(cut, ""))
            continue
        if line.startswith("ITEM:"):
            in_rows = False
        if in_rows and line:
            words = line.split(" ")
            line = " ".join(words[:33] + words[36:])
        out.append(line)
    with gzip.open(script.parent / "pairs_full.txt.gz", "wt") as f:
        f.write("\n".join(out))
    assert re.search(r"c_cpgl\[33\] c_cpgl\[37\]", script.read_text())


@pytest.mark.slow
def test_a_cut_history_is_refused_then_not_computed(packing, capsys):
    drop_history(packing)
    out = packing.parent / "out.h5"
    assert main(["run", str(packing), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "shearx sheary shearz" in err and "--allow-missing u_t" in err
    assert main(["check", str(packing)]) == 1
    assert "NOT COMPUTED: u_t" in capsys.readouterr().out
    assert main(["run", str(packing), "-o", str(out), "-q", "--allow-missing", "u_t"]) == 0
    res = demsplit.load_results(out)
    pairs = res.contacts[res.contacts["wall"] < 0]
    assert np.all(pairs["not_computed"] == U_T) and pairs["u_t"].isna().all()  # unknown: NaN, as every export
    assert (res.raw.contacts.loc[pairs.index, "u_t"] == 0).all()  # stored as 0 with the bit
    assert any(n.startswith("u_t NOT COMPUTED") for n in res.provenance["notes"])


def test_a_mesh_wall_outside_the_last_mesh_fix_is_refused(packing, capsys):
    """LIGGGHTS' wall/gran/local compute holds the last mesh fix wall/gran only: an earlier one is missing."""
    text = packing.read_text()
    wall = "fix wfloor all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor"
    assert wall in text
    packing.write_text(
        text.replace(
            wall,
            "fix floor2 all mesh/surface file floor.stl type 4 move 0 0 -0.01\n"
            "fix wfloor2 all wall/gran model hertz tangential history mesh n_meshes 1 "
            "meshes floor2\n" + wall,
        )
    )
    assert main(["run", str(packing), "-o", str(packing.parent / "out.h5"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "'floor2'" in err and "last mesh 'fix wall/gran'" in err and "--allow-missing floor2" in err


@pytest.mark.slow
def test_the_summary_states_what_was_not_computed_first(packing, capsys):
    for name in ("wall.txt", "wall_full.txt.gz"):
        (packing.parent / name).unlink()
    out = packing.parent / "out.h5"
    assert main(["run", str(packing), "-o", str(out), "-q", "--allow-missing", "floor"]) == 0
    capsys.readouterr()
    assert main(["report", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    at = next(k for k, line in enumerate(lines) if line.startswith("  NOT COMPUTED"))
    assert lines[1].startswith("  Against the material law")  # the headline, then what was not computed
    assert at < next(k for k, line in enumerate(lines) if line.startswith("Energy per particle type"))
    assert "wall 'floor'" in lines[at + 1]
    assert any("primitive-wall contacts are NOT COMPUTED" in line for line in lines[at + 1 : at + 4])


@pytest.mark.slow
def test_not_computed_is_never_a_zero_in_an_export_or_the_report(packing, capsys):
    """--allow-missing floor with primitive walls: the floor's energies and contact count, and the
    primitive-wall tangential energies (per contact, per particle, per wall), are empty CSV cells,
    Parquet nulls, NaN in VTK and the OVITO dump, "not computed" in the report's tables; the store
    keeps 0 with the bits (docs/design.md)."""
    import pandas as pd

    pytest.importorskip("pyarrow")
    meshio = pytest.importorskip("meshio")
    for name in ("wall.txt", "wall_full.txt.gz"):
        (packing.parent / name).unlink()
    d = packing.parent
    out = d / "out.h5"
    assert main(["run", str(packing), "-o", str(out), "-q", "--allow-missing", "floor"]) == 0
    assert (
        main(
            [
                "export",
                str(out),
                "--csv",
                str(d / "csv"),
                "--parquet",
                str(d / "pq"),
                "--vtk",
                str(d / "vtk"),
                "--dump",
                str(d / "p.dump"),
                "-q",
            ]
        )
        == 0
    )
    for table, unknown in (
        ("walls", ["u", "u_t"]),
        ("particles", ["u", "u_t", "u_equal", "u_radius"]),
        ("contacts", ["u_t", "u1", "u2"]),
    ):
        for df in (pd.read_csv(d / "csv" / f"{table}.csv"), pd.read_parquet(d / "pq" / f"{table}.parquet")):
            flagged = (df["not_computed"] & U_T) != 0
            assert flagged.any() and (df.loc[flagged, unknown].isna().all().all())
            assert df.loc[~flagged, unknown].notna().all().all()  # what is known stays a number
    walls = pd.read_csv(d / "csv" / "walls.csv")
    floor = walls[walls["name"] == "floor"]
    assert floor[["u", "u_n", "u_t", "n_contacts"]].isna().all().all()
    assert walls.loc[walls["kind"] == "plane", "u_n"].gt(0).all()  # primitive walls' normal energy is known
    mesh = meshio.read(d / "vtk" / "particles_000000204000.vtu")
    flagged = (mesh.point_data["not_computed"] & U_T) != 0
    assert flagged.any() and np.isnan(mesh.point_data["u_t"][flagged]).all()
    assert not np.isnan(mesh.point_data["u_t"][~flagged]).any()
    assert " nan " in (d / "p.dump").read_text()
    capsys.readouterr()
    assert main(["report", str(out)]) == 0
    text = capsys.readouterr().out
    floor_row = next(line for line in text.splitlines() if line.split()[1:3] == ["floor", "mesh"])
    assert floor_row.count("not computed") == 5  # u u_n u_t n_contacts share
    assert "tangential" in text and "without 104 contact(s) not computed" in text and "n_not_computed" in text
    assert main(["report", str(out), "-o", str(d / "r.html"), "-q"]) == 0
    page = (d / "r.html").read_text()
    assert page.count(">not computed</td>") == 6 * 3 + 2 and "contacts_not_computed" in page  # u u_t share; u_n n
