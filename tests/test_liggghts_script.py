"""The LIGGGHTS input-script parser and the column layouts of the granular local
computes: hand-written scripts for every parsing rule, and runs of Debian's
``liggghts`` that prove the code-order layout on the real program."""

from __future__ import annotations

import itertools
import subprocess
import textwrap
from pathlib import Path

import numpy as np
import pytest
from demsplit.errors import MaterialError, ScriptError, UnsupportedModelError
from demsplit.readers.liggghts_script import CODE_ORDER, DEFAULT_KEYWORDS, local_layout, read_script

HEADER = """\
units si
atom_style granular
boundary p p f
create_box 2 reg
fix m1 all property/global youngsModulus peratomtype 5.e6 7.e6
fix m2 all property/global poissonsRatio peratomtype 0.45 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.3 0.4 0.4 0.5
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.6 0.6 0.7
fix m5 all property/global characteristicVelocity scalar 2.5
"""


def write(tmp_path: Path, body: str, name: str = "in.script") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return path


def script(tmp_path: Path, body: str, **kw):
    return read_script(write(tmp_path, HEADER + textwrap.dedent(body)), **kw)


# ---------------------------------------------------------------- layouts


def test_default_layout_is_the_documented_block_order():
    cols = local_layout("pair", [])
    assert len(cols) == 6 + 6 + 3 + 3 + 3 + 3 + 1
    assert cols[:6] == ["x1", "y1", "z1", "x2", "y2", "z2"]
    assert cols[12:15] == ["id1", "id2", "periodic"]
    assert cols[21:24] == ["shearx", "sheary", "shearz"]
    assert cols[-1] == "area"
    assert local_layout("pair", DEFAULT_KEYWORDS) == cols


def test_every_keyword_order_gives_the_code_order():
    keywords = ["delta", "history", "pos", "force_normal", "id", "contactPoint"]
    expected = local_layout("pair", keywords)
    assert (
        expected.index("x1")
        < expected.index("id1")
        < expected.index("fnx")
        < expected.index("shearx")
        < expected.index("delta")
        < expected.index("cpx")
    )
    for perm in itertools.permutations(keywords):
        assert local_layout("pair", list(perm)) == expected


def test_all_keywords_width_and_heat_flux_last():
    every = list(CODE_ORDER)
    assert len(local_layout("pair", every)) == 41
    with_heat = local_layout("pair", ["heatFlux"] + every)
    assert with_heat[-1] == "heat_flux" and with_heat[:-1] == local_layout("pair", every)


def test_wall_layout_names_cannot_be_confused_with_pair_names():
    cols = local_layout("wall", ["id", "pos", "vel", "contactPoint"])
    assert cols[:6] == ["wall_cpx", "wall_cpy", "wall_cpz", "x1", "y1", "z1"]
    assert cols[6:12] == ["wall_vx", "wall_vy", "wall_vz", "vx1", "vy1", "vz1"]
    assert cols[12:15] == ["mesh_index", "tri_id", "id1"]
    assert cols[15:] == ["unwritten_cpx", "unwritten_cpy", "unwritten_cpz"]
    assert "id2" not in cols and "x2" not in cols


def test_history_width_and_names():
    assert local_layout("pair", ["history"], 0 + 3) == ["shearx", "sheary", "shearz"]
    assert local_layout("pair", ["history"], 5) == [f"history{k}" for k in range(1, 6)]
    with pytest.raises(ScriptError, match="no_history"):
        local_layout("pair", ["history"], 0)


def test_bad_keywords():
    with pytest.raises(ScriptError, match="unknown keyword"):
        local_layout("pair", ["pos", "positions"])
    with pytest.raises(UnsupportedModelError, match="multisphere"):
        local_layout("wall", ["ms_id"])


# ---------------------------------------------------------------- scene


def test_materials_model_coefficients_gravity(tmp_path):
    s = script(
        tmp_path,
        """
        pair_style gran model hooke tangential history ktToKnUser on limitForce on
        fix g all gravity 9.81 vector 0 3 -4
        timestep 1e-5
        run 100
    """,
    )
    assert s.scene.materials[1].E == 5e6 and s.scene.materials[2].nu == 0.3
    assert s.scene.model.law == "liggghts:hooke"
    assert s.scene.model.params == {
        "tangential": "history",
        "characteristic_velocity": 2.5,
        "kt_to_kn": 2 / 7,
        "rolling": "off",
        "cohesion": "off",
        "rolling_friction": None,
        "rolling_stiffness": None,
        "cohesion_energy_density": None,
        "friction_stiffness": None,
        "rolling_stiffness_ratio": None,
        "torsion": "off",
        "surface_tension": None,
        "contact_angle": None,
        "max_separation_ratio": None,
        "min_separation_ratio": None,
        "fluid_viscosity": None,
        "liquid_content_initial": None,
        "bridge_volume_fraction": None,
        "limit_liquid_content": "off",
        "contact_distance_factor": None,
    }
    np.testing.assert_array_equal(s.coefficients["coefficientFriction"], [[0.5, 0.6], [0.6, 0.7]])
    assert s.coefficients["characteristicVelocity"] == 2.5
    np.testing.assert_allclose(s.gravity, [0, 9.81 * 0.6, -9.81 * 0.8])
    assert s.periodic == (True, True, False)
    assert s.timestep == 1e-5 and s.run_steps == [100]


def test_hertz_no_history_is_the_default_tangential(tmp_path):
    s = script(tmp_path, "pair_style gran model hertz\n")
    assert s.scene.model.law == "liggghts:hertz" and s.scene.model.params["tangential"] == "no_history"


def test_walls_primitive_and_mesh(tmp_path):
    s = script(
        tmp_path,
        """
        pair_style gran model hertz tangential history
        fix floor all wall/gran model hertz tangential history primitive type 2 zplane -0.01
        fix drum all wall/gran model hooke tangential no_history primitive type 2 ycylinder 0.05 0.1 0.2
        fix cad all mesh/surface file lid.stl type 2 scale 0.001 move 0 0 0.1 rotate axis 1 0 0 angle 90 scale 2
        fix lid all wall/gran model hertz tangential history mesh n_meshes 1 meshes cad
    """,
    )
    floor, drum, lid = s.scene.walls
    assert (floor.kind, floor.axis, floor.position, floor.type, floor.model) == ("plane", 2, -0.01, 2, None)
    assert (drum.kind, drum.axis, drum.radius, drum.center) == ("cylinder", 1, 0.05, (0.1, 0.2))
    assert drum.model.law == "liggghts:hooke" and drum.model.params["tangential"] == "no_history"
    assert lid.kind == "mesh" and lid.file == str(tmp_path / "lid.stl")
    assert lid.transforms == (
        ("scale", (0.001,)),
        ("move", (0.0, 0.0, 0.1)),
        ("rotate", (1.0, 0.0, 0.0, 90.0)),
        ("scale", (2.0,)),
    )
    assert s.dumped_mesh_walls == [2]


@pytest.mark.parametrize(
    "pair, cls, match",
    [
        ("model thornton_ning tangential history rolling_friction epsd", UnsupportedModelError, "no normal stiffness"),
        ("model hertz tangential history rolling_friction luding torsion on", UnsupportedModelError, "torsion on"),
        ("model hertz tangential tan_luding", UnsupportedModelError, "friction_stiffness"),
        ("model hertz/stiffness tangential history", ScriptError, "property/global kn"),
        ("model hertz tangential history cohesion easo/capillary/viscous", UnsupportedModelError, "surface_tension"),
        ("model hertz tangential history cohesion capillary", UnsupportedModelError, "easo/capillary/viscous"),
        ("model hertz tangential history cohesion sjkr", UnsupportedModelError, "cohesion_energy_density"),
        ("model hertz tangential history rolling_friction epsd", UnsupportedModelError, "rolling_friction"),
        ("model hertz tangential history_mdm", UnsupportedModelError, "history_mdm"),
        ("model hertz tangential history surface superquadric", UnsupportedModelError, "superquadric"),
        ("tangential history", ScriptError, "no 'model'"),
    ],
)
def test_unsupported_models(tmp_path, pair, cls, match):
    with pytest.raises(cls, match=match) as err:
        script(tmp_path, f"pair_style gran {pair}\n")
    assert err.value.line == HEADER.count("\n") + 1 and err.value.fix


BRIDGE_PROPERTIES = """
    fix b1 all property/global surfaceLiquidContentInitial scalar 0.02
    fix b2 all property/global surfaceTension scalar 0.072
    fix b3 all property/global contactAngle peratomtype 20 35
    fix b4 all property/global minSeparationDistanceRatio scalar 1.01
    fix b5 all property/global maxSeparationDistanceRatio scalar 1.1
    fix b6 all property/global fluidViscosity scalar 0.001
    fix b7 all property/global lbVolumeFraction scalar 0.1
"""


@pytest.mark.parametrize(
    "model, lb",
    [
        ("easo/capillary/viscous", ""),
        ("washino/capillary/viscous", ""),
        ("washino/capillary/viscous", "modifyLbVolume on"),
    ],
)
def test_liquid_bridges_map_their_properties_and_history(tmp_path, model, lb):
    """The liquid-bridge models take their properties, washino its bridge volume fraction (lbVolumeFraction only with
    modifyLbVolume on, else 0.05) and the contact distance factor of neigh_modify; their history holds the bridge
    flag (LIGGGHTS' contflag) between the normal model's and the shear; the law reads the liquid content."""
    s = script(
        tmp_path,
        BRIDGE_PROPERTIES
        + f"""
        neigh_modify delay 0 contact_distance_factor 1.5
        pair_style gran model hertz tangential history cohesion {model} {lb}
        compute cp all pair/gran/local id history delta
    """,
    )
    law = s.scene.model.contact_law
    p = law.params
    assert (
        p["surface_tension"],
        p["contact_angle"],
        p["max_separation_ratio"],
        p["min_separation_ratio"],
        p["fluid_viscosity"],
        p["liquid_content_initial"],
    ) == (0.072, (20.0, 35.0), 1.1, 1.01, 0.001, 0.02)
    assert p["bridge_volume_fraction"] == (0.1 if lb else None) and law.contact_distance_factor() == 1.5
    assert law.particle_columns == ("f_surfaceLiquidContent",) and "u_adh" in law.modes
    assert s.local_computes["cp"].columns == [
        "id1",
        "id2",
        "periodic",
        "liquid_bridge",
        "shearx",
        "sheary",
        "shearz",
        "delta",
    ]


def test_liquid_bridge_refusals(tmp_path):
    with pytest.raises(UnsupportedModelError, match="limitLiquidContent on"):
        script(
            tmp_path,
            BRIDGE_PROPERTIES + "pair_style gran model hertz tangential history cohesion "
            "washino/capillary/viscous limitLiquidContent on\n",
        )
    with pytest.raises(ScriptError, match="lbVolumeFraction"):
        script(
            tmp_path,
            BRIDGE_PROPERTIES.replace("lbVolumeFraction", "otherProperty") + "pair_style gran model hertz "
            "tangential history cohesion washino/capillary/viscous modifyLbVolume on\n",
        )
    with pytest.raises(UnsupportedModelError, match="holds liquid"):
        script(tmp_path, "fix wet all mesh/surface/liquidtransfer file floor.stl type 2\n")


def test_rolling_friction_is_a_mode_and_widens_history(tmp_path):
    s = script(
        tmp_path,
        """
        fix m6 all property/global coefficientRollingFriction peratomtypepair 2 0.1 0.2 0.2 0.3
        pair_style gran model hertz tangential history rolling_friction epsd computeElasticPotential on
        compute cp all pair/gran/local history
    """,
    )
    assert not any("rolling" in w for w in s.warnings)
    law = s.scene.model.contact_law
    assert law.modes == ("u_n", "u_t", "u_r")
    assert law.params["rolling_friction"] == ((0.1, 0.2), (0.2, 0.3))
    cols = s.local_computes["cp"].columns
    assert cols[:6] == ["shearx", "sheary", "shearz", "rolling_torquex", "rolling_torquey", "rolling_torquez"]
    assert len(cols) == 3 + 3 + 10 and cols[6] == "elastic_potential"


@pytest.mark.parametrize(
    "model, props, law, history",
    [
        (
            "hertz/stiffness",
            "kn peratomtypepair 2 1e9 2e9 2e9 3e9\nfix p2 all property/global kt peratomtypepair 2 1e9 1e9 1e9 1e9",
            "liggghts:hertz/stiffness",
            ["shearx", "sheary", "shearz"],
        ),
        (
            "hooke/hysteresis",
            "coefficientMaxElasticStiffness peratomtypepair 2 2 2 2 2\nfix p2 all property/global "
            "coefficientAdhesionStiffness peratomtypepair 2 0 0 0 0\nfix p3 all property/global "
            "coefficientPlasticityDepth peratomtypepair 2 0.1 0.1 0.1 0.1",
            "liggghts:hooke/hysteresis",
            ["delta_max", "shearx", "sheary", "shearz"],
        ),
    ],
)
def test_more_normal_models_and_their_history(tmp_path, model, props, law, history):
    s = script(
        tmp_path,
        f"""
        fix p1 all property/global {props}
        pair_style gran model {model} tangential history
        compute cp all pair/gran/local id history
    """,
    )
    assert s.scene.model.law == law
    assert s.local_computes["cp"].columns == ["id1", "id2", "periodic"] + history


LUDING = (
    "LoadingStiffness peratomtypepair 2 2e3 2e3 2e3 2e3\nfix p2 all property/global UnloadingStiffness "
    "peratomtypepair 2 2 2 2 2\nfix p3 all property/global coefficientAdhesionStiffness peratomtypepair 2 0 0 0 "
    "0\nfix p4 all property/global coefficientPlasticityDepth peratomtypepair 2 0.1 0.1 0.1 0.1\nfix p5 all "
    "property/global pullOffForce peratomtypepair 2 0 0 0 0"
)


@pytest.mark.parametrize(
    "words, props, law, params, history",
    [
        (
            "thornton_ning tangential history",
            "surfaceEnergy peratomtypepair 2 0 0 0 0",
            "liggghts:thornton_ning",
            {},
            [
                "tn_virgin_flag",
                "tn_delta_old",
                "tn_delta_max",
                "tn_force_old",
                "tn_force_max",
                "tn_adhesion_flag",
                "tn_detaching_delta",
                "tn_detaching_flag",
                "tn_detaching_force",
                "tn_yielding_flag",
                "tn_kc",
                "tn_fo",
                "shearx",
                "sheary",
                "shearz",
            ],
        ),
        (
            "edinburgh/stiffness tangential history",
            LUDING + "\nfix p6 all property/global overlapExponent scalar 1",
            "liggghts:edinburgh/stiffness",
            {"loading_stiffness": ((2e3, 2e3), (2e3, 2e3))},
            ["delta_p_max", "edinburgh_old_delta", "edinburgh_kc", "edinburgh_fo", "shearx", "sheary", "shearz"],
        ),
        (
            "luding tangential tan_luding rolling_friction luding torsion off",
            LUDING + "\nfix p6 all property/global "
            "coeffFrictionStiffness peratomtypepair 2 0.5 0.5 0.5 0.5\nfix p7 all property/global "
            "coeffRollingStiffness "
            "peratomtypepair 2 0.3 0.3 0.3 0.4",
            "liggghts:luding",
            {
                "friction_stiffness": ((0.5, 0.5), (0.5, 0.5)),
                "rolling_stiffness_ratio": ((0.3, 0.3), (0.3, 0.4)),
                "torsion": "off",
            },
            [
                "delta_max",
                "luding_kc",
                "luding_fo",
                "shearx",
                "sheary",
                "shearz",
                "rolling_torquex",
                "rolling_torquey",
                "rolling_torquez",
                "torsion_torquex",
                "torsion_torquey",
                "torsion_torquez",
            ],
        ),
    ],
)
def test_models_from_the_liggghts_source_and_their_history(tmp_path, words, props, law, params, history):
    """thornton_ning, edinburgh/stiffness, tan_luding and rolling_friction luding: the law, the parameters from
    the properties and the history block (widths measured in tests/test_liggghts_laws_vs_liggghts.py)."""
    s = script(
        tmp_path,
        f"""
        fix p1 all property/global {props}
        pair_style gran model {words}
        compute cp all pair/gran/local id history
    """,
    )
    assert s.scene.model.law == law
    assert {k: s.scene.model.params[k] for k in params} == params
    assert s.local_computes["cp"].columns == ["id1", "id2", "periodic"] + history


def test_thornton_ning_surface_energy_is_refused(tmp_path):
    with pytest.raises(UnsupportedModelError, match="surfaceEnergy > 0") as err:
        script(
            tmp_path,
            """
            fix p1 all property/global surfaceEnergy peratomtypepair 2 0 0.1 0.1 0
            pair_style gran model thornton_ning tangential history
        """,
        )
    assert err.value.fix


def test_cohesion_sjkr_is_the_cohesion_mode(tmp_path):
    s = script(
        tmp_path,
        """
        fix m6 all property/global cohesionEnergyDensity peratomtypepair 2 0 1e5 1e5 2e5
        pair_style gran model hertz tangential history cohesion sjkr2
    """,
    )
    law = s.scene.model.contact_law
    assert law.modes == ("u_n", "u_t", "u_adh") and law.params["cohesion"] == "sjkr2"
    assert law.params["cohesion_energy_density"] == ((0.0, 1e5), (1e5, 2e5))


def test_units_other_than_si_are_refused(tmp_path):
    with pytest.raises(UnsupportedModelError, match="units 'cgs'") as err:
        read_script(write(tmp_path, "atom_style granular\nunits cgs\n"))
    assert err.value.line == 2


@pytest.mark.parametrize(
    "line, match",
    [
        ("fix m1 all property/global youngsModulus peratomtype 5.e6", "expected 2 values"),
        ("fix m1 all property/global youngsModulus peratomtype 5.e6 0", "type 2 is 0.0"),
        ("fix m1 all property/global youngsModulus peratomtype -1 5.e6", "type 1 is -1.0"),
        ("fix m2 all property/global poissonsRatio peratomtype 0.3 0.5000001", "0 <= nu <= 0.5"),
        ("fix m2 all property/global poissonsRatio peratomtype -0.1 0.3", "0 <= nu <= 0.5"),
        ("fix m3 all property/global coefficientRestitution peratomtypepair 2 0.3 0.4 0.4", "expected 2x2"),
    ],
)
def test_bad_materials(tmp_path, line, match):
    with pytest.raises(MaterialError, match=match) as err:
        script(tmp_path, line + "\npair_style gran model hertz tangential history\n")
    assert err.value.line == HEADER.count("\n") + 1
    assert str(tmp_path / "in.script") in str(err.value)


def test_nu_one_half_is_accepted(tmp_path):
    s = script(
        tmp_path,
        "fix m2 all property/global poissonsRatio peratomtype 0.5 0.0\n"
        "pair_style gran model hertz tangential history\n",
    )
    assert s.scene.materials[1].nu == 0.5 and s.scene.materials[2].nu == 0.0


@pytest.mark.parametrize(
    "line",
    [
        "fix w all wall/gran model hertz tangential history primitive type 3 zplane 0",
        "fix ins all particletemplate/sphere 15485863 atom_type 3 density constant 2500 radius constant 0.01",
        "fix cad all mesh/surface file a.stl type 3",
    ],
)
def test_type_without_material(tmp_path, line):
    with pytest.raises(MaterialError, match="type 3") as err:
        script(tmp_path, "pair_style gran model hertz tangential history\n" + line + "\n")
    assert err.value.line == HEADER.count("\n") + 2


def test_hooke_needs_characteristic_velocity(tmp_path):
    path = write(
        tmp_path,
        HEADER.replace("characteristicVelocity", "somethingElse") + "pair_style gran model hooke tangential history\n",
    )
    with pytest.raises(ScriptError, match="characteristicVelocity"):
        read_script(path)


# ---------------------------------------------------------------- lines and variables


def test_variables_continuation_comments_quotes_include(tmp_path):
    write(
        tmp_path,
        """\
        variable nu2 string 0.3   # included files see the includer's variables
        fix m2 all property/global poissonsRatio peratomtype &
            ${nuOne} ${nu2}
    """,
        name="materials.in",
    )
    s = script(
        tmp_path,
        """\
        variable nuOne index 0.25
        variable nuOne index 0.4          # an index variable keeps its first value
        variable E equal 2*v_half^2+sqrt(4)*1e6   # uses v_half, defined below
        variable half equal 2.5e3
        variable d index dumps
        variable n equal (3+1)*250
        include materials.in
        fix m1 all property/global youngsModulus peratomtype &
          ${E} $(v_E*1.5)   # comment with $undefined and 'quote
        pair_style gran model hertz tangential history
        compute cp all pair/gran/local pos
        dump d1 all local ${n} ${d}/pairs_*.txt c_cp[1] c_cp[4]
        dump_modify d1 label "C # not a comment ${d}"
    """,
    )
    E1 = 2 * 2.5e3**2 + 2e6
    assert s.scene.materials[1].E == pytest.approx(E1, rel=1e-15)
    assert s.scene.materials[2].E == pytest.approx(1.5 * E1, rel=1e-15)
    assert s.scene.materials[1].nu == 0.25 and s.scene.materials[2].nu == 0.3
    (d1,) = s.dumps
    assert d1.every == 1000 and d1.file == str(tmp_path / "dumps" / "pairs_*.txt")
    assert d1.label == "C # not a comment ${d}"  # no substitution inside quotes
    assert d1.layout.columns == ["x1", "x2"] and d1.compute == "cp"


def test_command_line_variables_win(tmp_path):
    body = (
        "variable r index 0.2\nvariable r string 0.3\n"
        "fix m2 all property/global poissonsRatio peratomtype ${r} $r\n"
        "pair_style gran model hertz tangential history\n"
    )
    assert script(tmp_path, body).scene.materials[1].nu == 0.3
    assert script(tmp_path, body, variables={"r": "0.45"}).scene.materials[2].nu == 0.45


def test_fixes_that_could_matter_are_listed(tmp_path):
    s = script(tmp_path, "fix push all addforce 0 0 1\nfix integr all nve/sphere\njump SELF loop\n")
    assert any("addforce" in w for w in s.warnings) and not any("nve/sphere" in w for w in s.warnings)
    assert any("'jump' is not followed" in w for w in s.warnings)


def test_runtime_only_variables(tmp_path):
    s = script(tmp_path, "variable n equal count(all)\nprint ${n}\n")
    assert any("count" in w for w in s.warnings)
    with pytest.raises(ScriptError, match="only known while LIGGGHTS runs"):
        script(tmp_path, "variable n equal step\nrun ${n}\n")


def test_include_cycle(tmp_path):
    write(tmp_path, "include b.in\n", name="a.in")
    write(tmp_path, "include a.in\n", name="b.in")
    with pytest.raises(ScriptError, match="includes itself"):
        read_script(tmp_path / "a.in")


# ---------------------------------------------------------------- dumps


def test_dump_modify_accumulates_and_precision(tmp_path):
    s = script(
        tmp_path,
        """
        pair_style gran model hertz tangential history
        compute cp all pair/gran/local delta id
        dump a all custom 100 atoms.txt id type x y z radius
        dump_modify a sort id
        dump_modify a format "%d %d %.17g %.17g %.17g %.16e"
        dump_modify a label ATOMS
        dump b all custom 100 atoms.bin id type x y z
        dump c all local 100 pairs.txt c_cp[4] c_cp[1] c_cp[2]
        dump_modify c format "%.15g %.14g %.15g" label CONTACTS
        dump e all local 100 pairs2.txt c_cp[4] c_cp[1] c_cp[2]
        dump_modify e format "%.17g %d %d"
    """,
    )
    a, b, c, e = s.dumps
    assert (a.sort, a.label, a.full_precision) == ("id", "ATOMS", True)
    assert a.keywords == ["id", "type", "x", "y", "z", "radius"] and a.layout is None
    assert b.full_precision and b.format is None
    assert c.layout.columns == ["delta", "id1", "id2"] and c.label == "CONTACTS"
    assert not c.full_precision  # %.14g keeps 14 digits only
    assert not e.full_precision and any("dump e" in w and "garbage" in w for w in s.warnings)


def test_dump_local_out_of_range_and_mixed(tmp_path):
    with pytest.raises(ScriptError, match="out of range"):
        script(
            tmp_path,
            "pair_style gran model hertz tangential history\n"
            "compute cp all pair/gran/local pos id\ndump c all local 1 p.txt c_cp[10]\n",
        )


# ---------------------------------------------------------------- the real program

SIM_HEADER = """\
atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
region reg block -0.06 0.06 -0.06 0.06 -0.06 0.06 units box
create_box 2 reg
neighbor 0.002 bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype 5.e6 7.e6
fix m2 all property/global poissonsRatio peratomtype 0.45 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.3 0.3 0.3 0.3
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5
pair_style gran model hertz tangential history {pair_options}
pair_coeff * *
timestep 0.00001
"""

# id: (type, x, y, z, diameter); 1-2, 1-3 and 3-4 overlap
ATOMS = {
    1: (1, 0.0, 0.0, 0.0, 0.010),
    2: (2, 0.0093, 0.0011, 0.0004, 0.009),
    3: (1, -0.0005, 0.0097, 0.0002, 0.010),
    4: (2, -0.0012, 0.0185, -0.0006, 0.008),
}


def atoms_block(atoms=ATOMS, z_shift=0.0) -> str:
    lines = [f"create_atoms {t} single {x} {y} {z + z_shift} units box" for t, x, y, z, _ in atoms.values()]
    lines += [f"set atom {i} diameter {d} density 2500" for i, (*_, d) in atoms.items()]
    lines += [
        "velocity all set 0.01 0.02 0.0 units box",
        "group three id 3",
        "velocity three set 0.03 -0.01 0.02 units box",
        "fix integr all nve/sphere",
    ]
    return "\n".join(lines) + "\n"


def run_liggghts(liggghts: str, path: Path) -> None:
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", path.name, "-log", "none"],
        cwd=path.parent,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0 and "ERROR" not in proc.stdout, proc.stdout[-2000:] + proc.stderr[-2000:]


def last_frame(path: Path) -> np.ndarray:
    """Rows of the last frame of a dump local file, as floats."""
    lines = path.read_text().splitlines()
    start = max(i for i, line in enumerate(lines) if line.startswith("ITEM: ENTRIES")) + 1
    return np.array([[float(v) for v in line.split()] for line in lines[start:]])


def full_format(n: int) -> str:
    return '"' + " ".join(["%.17g"] * n) + '"'


@pytest.mark.simulator
def test_pair_layout_matches_the_real_program(liggghts, tmp_path):
    keywords = "delta force_normal history id pos"  # permuted and partial
    compute = f"compute cp all pair/gran/local {keywords}\n"
    probe = read_script(write(tmp_path, SIM_HEADER.format(pair_options="") + compute))
    n = len(probe.local_computes["cp"].columns)
    order = list(range(n, 0, -1))  # dump the columns backwards
    body = (
        SIM_HEADER.format(pair_options="")
        + atoms_block()
        + compute
        + "dump d all local 5 pairs.txt "
        + " ".join(f"c_cp[{k}]" for k in order)
        + "\n"
        + f"dump_modify d format {full_format(n)}\nrun 20\n"
    )
    path = write(tmp_path, body)
    run_liggghts(liggghts, path)

    s = read_script(path)
    (dump,) = s.dumps
    assert dump.full_precision and dump.compute == "cp"
    cols = dump.layout.columns
    assert cols == s.local_computes["cp"].columns[::-1]
    rows = last_frame(Path(dump.file))
    assert rows.shape == (3, len(cols))
    c = {name: rows[:, k] for k, name in enumerate(cols)}
    radius = {i: d / 2 for i, (*_, d) in ATOMS.items()}
    r1 = np.array([radius[int(i)] for i in c["id1"]])
    r2 = np.array([radius[int(i)] for i in c["id2"]])
    d = np.stack([c["x1"] - c["x2"], c["y1"] - c["y2"], c["z1"] - c["z2"]], axis=1)
    np.testing.assert_allclose(c["delta"], r1 + r2 - np.linalg.norm(d, axis=1), rtol=1e-12)
    assert np.all(c["delta"] > 0) and np.all(c["periodic"] == 0)
    assert {frozenset((int(a), int(b))) for a, b in zip(c["id1"], c["id2"])} == {
        frozenset(p) for p in [(1, 2), (1, 3), (3, 4)]
    }
    fn = np.stack([c["fnx"], c["fny"], c["fnz"]], axis=1)  # along the line of centres
    np.testing.assert_allclose(np.cross(fn, d), 0, atol=1e-12 * np.abs(fn).max() * np.abs(d).max())
    shear = np.stack([c["shearx"], c["sheary"], c["shearz"]], axis=1)  # perpendicular to it
    np.testing.assert_allclose(np.einsum("ij,ij->i", shear, d), 0, atol=1e-9 * np.abs(shear).max() * np.abs(d).max())


STL = """\
solid square
 facet normal 0 0 1
  outer loop
   vertex -60 -60 0
   vertex 60 -60 0
   vertex 60 60 0
  endloop
 endfacet
 facet normal 0 0 1
  outer loop
   vertex -60 -60 0
   vertex 60 60 0
   vertex -60 60 0
  endloop
 endfacet
endsolid square
"""


@pytest.mark.simulator
@pytest.mark.parametrize("wall_options, history_width", [("", 3), ("computeElasticPotential on", 17)])
def test_wall_layout_matches_the_real_program(liggghts, tmp_path, wall_options, history_width):
    (tmp_path / "square.stl").write_text(STL)
    # a floor 2 mm above the origin: scale first (mm -> m), then move
    wall = (
        "fix cad all mesh/surface file square.stl type 2 scale 0.001 move 0 0 0.002\n"
        f"fix floor all wall/gran model hertz tangential history mesh n_meshes 1 meshes cad {wall_options}\n"
    )
    compute = "compute cw all wall/gran/local history delta id pos force\n"
    head = SIM_HEADER.format(pair_options="") + wall
    probe = read_script(write(tmp_path, head + compute))
    cols = probe.local_computes["cw"].columns
    assert len(cols) == 6 + 3 + 3 + history_width + 1
    atoms = {1: (1, 0.0, 0.0, 0.0048, 0.010), 2: (2, 0.03, 0.01, 0.0039, 0.005)}
    body = (
        head
        + atoms_block(atoms)
        + compute
        + "dump d all local 5 walls.txt "
        + " ".join(f"c_cw[{k}]" for k in range(1, len(cols) + 1))
        + f"\ndump_modify d format {full_format(len(cols))}\nrun 20\n"
    )
    path = write(tmp_path, body)
    run_liggghts(liggghts, path)

    s = read_script(path)
    (floor,) = s.scene.walls
    assert s.dumped_mesh_walls == [0] and floor.kind == "mesh" and floor.type == 2
    z_floor = 0.0
    for op, values in floor.transforms:  # in the order LIGGGHTS applies them
        z_floor = z_floor * values[0] if op == "scale" else z_floor + values[2]
    assert z_floor == pytest.approx(0.002)
    rows = last_frame(tmp_path / "walls.txt")
    assert rows.shape == (2, len(cols))
    c = {name: rows[:, k] for k, name in enumerate(s.dumps[0].layout.columns)}
    radius = np.array([atoms[int(i)][4] / 2 for i in c["id1"]])
    np.testing.assert_allclose(c["delta"], radius - (c["z1"] - z_floor), rtol=1e-12)
    np.testing.assert_allclose(c["wall_cpz"], z_floor, rtol=1e-12)
    np.testing.assert_allclose(c["wall_cpx"], c["x1"], atol=1e-15)
    assert set(c["mesh_index"]) == {0} and set(c["tri_id"]) <= {0, 1}
    assert sorted(c["id1"]) == [1, 2]


def test_an_included_foreign_text_file_is_refused_with_a_bounded_excerpt(tmp_path):
    (tmp_path / "shadow").write_text("root:$6$" + "x" * 200 + ":19000:0:99999:7:::\nuser:*:19000\n")
    with pytest.raises(ScriptError, match="not start with a LIGGGHTS command name") as err:
        script(tmp_path, "include shadow\n")
    message = str(err.value)
    assert str(err.value.file) == str(tmp_path / "shadow") and err.value.line == 1
    assert "included from" in message and "$6$" not in message  # named, not quoted


@pytest.mark.parametrize("line", ['PRETTY_NAME="Debian"', "Root:x", "# only a comment\n9lives 1"])
def test_words_that_are_no_command_name_are_refused(tmp_path, line):
    with pytest.raises(ScriptError, match="not start with a LIGGGHTS command name"):
        script(tmp_path, line + "\n")
