"""A LIGGGHTS run read without its input script: the scene from command-line options."""

from __future__ import annotations

import demsplit
import numpy as np
from conftest import SAMPLES
from demsplit.cli import main
from demsplit.scene import Material

PACKING = SAMPLES / "liggghts" / "packing"
KEYWORDS = (
    "pos vel id force force_normal force_tangential torque torque_normal torque_tangential history "
    "contactArea delta contactPoint"
)
MATERIALS = {1: Material(1.0e8, 0.25), 2: Material(1.0e7, 0.40), 3: Material(5.0e8, 0.30), 4: Material(2.0e8, 0.28)}


def test_pair_and_mesh_contacts_match_the_scripted_run():
    with_script = demsplit.analyze(PACKING / "in.packing")
    without = demsplit.analyze(
        None,
        atoms=PACKING / "atoms_full.txt.gz",
        contacts=PACKING / "pairs_full.txt.gz",
        walls=PACKING / "wall_full.txt.gz",
        materials=MATERIALS,
        scene_options={"columns": KEYWORDS, "wall_columns": KEYWORDS, "wall_type": 4},
    )
    a = with_script.contacts
    b = without.contacts
    pairs_a, pairs_b = a[a.wall < 0].reset_index(drop=True), b[b.wall < 0].reset_index(drop=True)
    for col in ("id1", "id2", "u_n", "u_t", "u1", "u2", "cpx", "cpy", "cpz"):
        np.testing.assert_array_equal(pairs_a[col].to_numpy(), pairs_b[col].to_numpy(), err_msg=col)
    # the mesh floor is wall 0 in both (the scripted run also has five primitive walls, unknown here)
    mesh_a, mesh_b = a[a.wall == 0].reset_index(drop=True), b[b.wall == 0].reset_index(drop=True)
    np.testing.assert_array_equal(mesh_a["u_n"].to_numpy(), mesh_b["u_n"].to_numpy())
    assert (b.wall <= 0).all()
    assert any("no input script" in n for n in without.provenance["notes"])


def test_missing_facts_are_named(tmp_path, capsys):
    code = main(
        [
            "run",
            "--atoms",
            str(PACKING / "atoms.txt"),
            "--contacts",
            str(PACKING / "pairs.txt"),
            "-o",
            str(tmp_path / "o.h5"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert "--material" in err and "--columns" in err and "pairs.txt" in err and "Traceback" not in err


def test_a_type_without_material_is_named(tmp_path, capsys):
    code = main(
        [
            "run",
            "--atoms",
            str(PACKING / "atoms_full.txt.gz"),
            "--contacts",
            str(PACKING / "pairs_full.txt.gz"),
            "--material",
            "2:1e7:0.4",
            "--columns",
            KEYWORDS,
            "-o",
            str(tmp_path / "o.h5"),
        ]
    )
    assert code == 2
    assert "types [1] have no material" in capsys.readouterr().err


def test_cli_scriptless_run(tmp_path):
    out = tmp_path / "o.h5"
    code = main(
        [
            "run",
            "--quiet",
            "--atoms",
            str(PACKING / "atoms_full.txt.gz"),
            "--contacts",
            str(PACKING / "pairs_full.txt.gz"),
            "--material",
            "1:1e8:0.25",
            "--material",
            "2:1e7:0.4",
            "--columns",
            KEYWORDS,
            "-o",
            str(out),
        ]
    )
    assert code == 0
    res = demsplit.load_results(out)
    assert len(res.frames) == 3 and (res.contacts.wall == -1).all() and res.particles.u.sum() > 0
