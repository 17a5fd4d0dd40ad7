"""Write and run the small per-model LIGGGHTS runs of tests/data/liggghts_models/.

    python make_runs.py [NAME ...]            # (re)write NAME/in.run, run Debian's liggghts, gzip the dumps
    python make_runs.py --check-width NAME    # also show that one more dump column is refused

Every run is TEMPLATE below with the model words, the properties the model reads and the
dump column lists of the model's compute width (38 + its history columns: HISTORY below,
found from the source's add_history_value calls and confirmed by LIGGGHTS, which refuses a
dump of one more column: --check-width). The scene: 63 spheres of two materials on a
primitive floor (``zplane 0.0``, type 3) inside a square mesh tube (``walls.stl``, type 4),
settled under gravity with ``fix viscous`` (a drag on the atoms, outside the contact law),
compressed by a stronger gravity, partly unloaded, then ``fix viscous`` is removed and two
frames are dumped 500 steps apart. coefficientRestitution 1 makes every normal and
tangential damping coefficient of every model here zero (log e = 0), and the rolling
viscous coefficients are 0, so the dumped forces are the elastic ones.
"""

from __future__ import annotations

import gzip
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
NTYPES = 4


def table(*rows: str) -> str:
    """A symmetric 4x4 peratomtypepair table from its upper triangle rows (row-major)."""
    upper = [r.split() for r in rows]
    m = [[""] * NTYPES for _ in range(NTYPES)]
    for i in range(NTYPES):
        for k, v in enumerate(upper[i]):
            j = i + k
            m[i][j] = m[j][i] = v
    return f"peratomtypepair {NTYPES} " + " ".join(" ".join(r) for r in m)


def same(v: str) -> str:
    return f"peratomtypepair {NTYPES} " + " ".join([v] * NTYPES * NTYPES)


FRICTION = table("0.5 0.4 0.3 0.3", "0.6 0.3 0.3", "0.3 0.3", "0.3")
ROLLFRIC = table("0.08 0.06 0.05 0.05", "0.10 0.05 0.05", "0.05 0.05", "0.05")

# name: (model words for pair_style gran and every fix wall/gran, property/global lines,
#        pair history columns, mesh-wall history columns)
MODELS: dict[str, tuple[str, list[str], int, int]] = {
    "hertz_history": ("model hertz tangential history", [], 3, 3),
    "hertz_stiffness_history": ("model hertz/stiffness tangential history", [
        "kn " + table("9e6 7e6 8e6 8e6", "5e6 6e6 6e6", "9e6 9e6", "9e6"),
        "kt " + table("6e6 5e6 5e6 5e6", "4e6 4e6 4e6", "6e6 6e6", "6e6"),
        "gamman " + same("0"), "gammat " + same("0")], 3, 3),
    "hooke_history": ("model hooke tangential history", [], 3, 3),
    "hooke_stiffness_history": ("model hooke/stiffness tangential history", [
        "kn " + table("4e3 3e3 3.5e3 3.5e3", "2e3 2.5e3 2.5e3", "4e3 4e3", "4e3"),
        "kt " + table("3e3 2e3 2.5e3 2.5e3", "1.5e3 2e3 2e3", "3e3 3e3", "3e3"),
        "gamman " + same("0"), "gammat " + same("0")], 3, 3),
    "hooke_hysteresis_history": ("model hooke/hysteresis tangential history", [
        "coefficientMaxElasticStiffness " + table("2.5 2.0 2.2 2.2", "1.8 2.0 2.0", "2.5 2.5", "2.5"),
        "coefficientAdhesionStiffness " + same("0"),
        "coefficientPlasticityDepth " + table("0.01 0.012 0.01 0.01", "0.015 0.01 0.01", "0.01 0.01", "0.01")],
        4, 4),
    "thornton_ning_history": ("model thornton_ning tangential history", [
        "surfaceEnergy " + same("0"),
        "coefficientYieldRatio peratomtype 0.9 0.9 0.9 0.9"], 15, 15),
    "luding_history": ("model luding tangential history", [
        "LoadingStiffness " + table("4e3 3e3 3.5e3 3.5e3", "2e3 2.5e3 2.5e3", "4e3 4e3", "4e3"),
        "UnloadingStiffness " + table("2.0 1.8 1.9 1.9", "1.6 1.7 1.7", "2.0 2.0", "2.0"),
        "coefficientAdhesionStiffness " + same("0"),
        "coefficientPlasticityDepth " + table("0.01 0.012 0.01 0.01", "0.015 0.01 0.01", "0.01 0.01", "0.01"),
        "pullOffForce " + same("0")], 6, 6),
    "edinburgh_history": ("model edinburgh tangential history", [
        "overlapExponent scalar 1.5", "adhesionExponent scalar 1.5",
        "UnloadingStiffness " + table("5.0 4.0 4.5 4.5", "3.0 3.5 3.5", "5.0 5.0", "5.0"),
        "coefficientAdhesionStiffness " + same("0"), "surfaceEnergy " + same("0"),
        "pullOffForce " + same("0")], 7, 7),
    "edinburgh_stiffness_history": ("model edinburgh/stiffness tangential history", [
        "LoadingStiffness " + table("4e5 3e5 3.5e5 3.5e5", "2e5 2.5e5 2.5e5", "4e5 4e5", "4e5"),
        "overlapExponent scalar 1.5", "adhesionExponent scalar 1.5",
        "UnloadingStiffness " + table("5.0 4.0 4.5 4.5", "3.0 3.5 3.5", "5.0 5.0", "5.0"),
        "coefficientAdhesionStiffness " + same("0"), "surfaceEnergy " + same("0"),
        "pullOffForce " + same("0")], 7, 7),
    # tan_luding reads the normal model's kc/fo history: with hertz (none) it would read outside
    # the contact's history, so it runs with luding.
    "luding_tan_luding": ("model luding tangential tan_luding", [
        "LoadingStiffness " + table("4e3 3e3 3.5e3 3.5e3", "2e3 2.5e3 2.5e3", "4e3 4e3", "4e3"),
        "UnloadingStiffness " + table("2.0 1.8 1.9 1.9", "1.6 1.7 1.7", "2.0 2.0", "2.0"),
        "coefficientAdhesionStiffness " + same("0"),
        "coefficientPlasticityDepth " + table("0.01 0.012 0.01 0.01", "0.015 0.01 0.01", "0.01 0.01", "0.01"),
        "pullOffForce " + same("0"),
        "coeffFrictionStiffness " + table("0.5 0.4 0.45 0.45", "0.3 0.35 0.35", "0.5 0.5", "0.5"),
        "FluidViscosity " + same("0.8"), "FrictionViscosity " + same("1.0")], 6, 6),
    "hertz_rolling_epsd": ("model hertz tangential history rolling_friction epsd", [
        "coefficientRollingFriction " + ROLLFRIC, "coefficientRollingViscousDamping " + same("0")], 6, 6),
    "hertz_rolling_epsd2": ("model hertz tangential history rolling_friction epsd2", [
        "coefficientRollingFriction " + ROLLFRIC], 6, 6),
    "hertz_rolling_epsd3": ("model hertz tangential history rolling_friction epsd3", [
        "coefficientRollingFriction " + ROLLFRIC, "coefficientRollingViscousDamping " + same("0"),
        "rollingStiffness scalar 1.5"], 6, 6),
    # rolling luding reads the normal model's kc/fo history (rolling_model_luding.h:314-315):
    # with hertz it would read outside the history, so it runs with luding.
    "luding_rolling_luding": ("model luding tangential history rolling_friction luding", [
        "LoadingStiffness " + table("4e3 3e3 3.5e3 3.5e3", "2e3 2.5e3 2.5e3", "4e3 4e3", "4e3"),
        "UnloadingStiffness " + table("2.0 1.8 1.9 1.9", "1.6 1.7 1.7", "2.0 2.0", "2.0"),
        "coefficientAdhesionStiffness " + same("0"),
        "coefficientPlasticityDepth " + table("0.01 0.012 0.01 0.01", "0.015 0.01 0.01", "0.01 0.01", "0.01"),
        "pullOffForce " + same("0"),
        "coefficientRollingFriction " + ROLLFRIC, "coefficientRollingViscousDamping " + same("0"),
        "coeffRollingStiffness " + table("0.5 0.4 0.45 0.45", "0.3 0.35 0.35", "0.5 0.5", "0.5")], 12, 12),
    "hertz_rolling_cdt": ("model hertz tangential history rolling_friction cdt", [
        "coefficientRollingFriction " + ROLLFRIC], 3, 3),
    "hertz_cohesion_sjkr": ("model hertz tangential history cohesion sjkr", [
        "cohesionEnergyDensity " + table("2e5 1.5e5 1e5 1e5", "1e5 1e5 1e5", "1e5 1e5", "1e5")], 3, 3),
    "hertz_cohesion_sjkr2": ("model hertz tangential history cohesion sjkr2", [
        "cohesionEnergyDensity " + table("2e5 1.5e5 1e5 1e5", "1e5 1e5 1e5", "1e5 1e5", "1e5")], 3, 3),
    # computeElasticPotential (normal_model_hertz.h:94): pairs get 10 more history values after the
    # shear (potential, elastic force 3, torque on i 3, torque on j 3); walls also the surface
    # model's contact displacement (3, surface_model_default.h:113-118) and a half-step term.
    "hertz_elastic_potential": ("model hertz tangential history computeElasticPotential on", [], 13, 17),
}

TEMPLATE = """\
# demsplit test run {name}: {words}
# Written by tests/data/liggghts_models/make_runs.py (see README.md there). Debian liggghts 3.8.0.
# 63 spheres (types 1, 2) on a primitive floor (zplane 0.0, type 3) inside a square mesh tube
# (walls.stl, type 4). Undamped contacts: coefficientRestitution 1 (log e = 0) zeroes every
# damping coefficient; settling uses fix viscous (a drag on the atoms, not a contact force),
# removed before the dumps.
units           si
atom_style      granular
atom_modify     map array
boundary        f f f
newton          off
communicate     single vel yes
region          domain block -0.008 0.008 -0.008 0.008 -0.002 0.03 units box
create_box      4 domain
neighbor        0.0004 bin
neigh_modify    delay 0
fix m1 all property/global youngsModulus peratomtype 2.0e7 5.0e6 5.0e7 3.0e7
fix m2 all property/global poissonsRatio peratomtype 0.25 0.40 0.30 0.28
fix m3 all property/global coefficientRestitution {restitution}
fix m4 all property/global coefficientFriction {friction}
fix m5 all property/global characteristicVelocity scalar 0.5
{props}
pair_style      gran {words}
pair_coeff      * *
timestep        2.0e-6
fix tube all mesh/surface file walls.stl type 4
fix wtube all wall/gran {wwords} mesh n_meshes 1 meshes tube{wset}
fix wfloor all wall/gran {wwords} primitive type 3 zplane 0.0
compute cpgl all pair/gran/local pos vel id force force_normal force_tangential torque torque_normal torque_tangential history contactArea delta contactPoint
compute cwgl all wall/gran/local pos vel id force force_normal force_tangential torque torque_normal torque_tangential history contactArea delta contactPoint
region pack block -0.0045 0.0045 -0.0045 0.0045 0.0014 0.0185 units box
lattice sc 0.0026
create_atoms 1 region pack
set type 1 type/fraction 2 0.5 32452843
displace_atoms all random 0.0002 0.0002 0.0 15485863 units box
set type 1 diameter 0.0024 density 2500
set type 2 diameter 0.0020 density 1100
fix integr all nve/sphere
fix drag all viscous 0.004
thermo 5000
# settle under gravity, compress (4x gravity), unload part of it (1.5x)
fix grav all gravity 100 vector 0.0 0.0 -1.0
run 20000
unfix grav
fix grav all gravity 400 vector 0.0 0.0 -1.0
run 8000
unfix grav
fix grav all gravity 150 vector 0.0 0.0 -1.0
run 8000
unfix drag
dump datoms all custom 500 atoms.txt id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass
dump_modify datoms format "%d %d {atomfmt}" sort id
dump dpair all local 500 pairs.txt {paircols}
dump_modify dpair format "{pairfmt}"
dump dwall all local 500 wall.txt {wallcols}
dump_modify dwall format "{wallfmt}"
run 500
"""


def write_stl(path: Path, half: float = 0.0055, z0: float = -0.001, z1: float = 0.028) -> None:
    """A square tube |x|, |y| = half, z in [z0, z1]: 4 faces of 2 triangles, normals inward."""
    a = half
    faces = [  # (normal, 4 corners counter-clockwise seen from inside)
        ((1, 0, 0), [(-a, -a, z0), (-a, a, z0), (-a, a, z1), (-a, -a, z1)]),
        ((-1, 0, 0), [(a, -a, z0), (a, -a, z1), (a, a, z1), (a, a, z0)]),
        ((0, 1, 0), [(-a, -a, z0), (-a, -a, z1), (a, -a, z1), (a, -a, z0)]),
        ((0, -1, 0), [(-a, a, z0), (a, a, z0), (a, a, z1), (-a, a, z1)]),
    ]
    out = ["solid tube"]
    for n, (p0, p1, p2, p3) in faces:
        for tri in ((p0, p1, p2), (p0, p2, p3)):
            out.append(f"  facet normal {n[0]} {n[1]} {n[2]}")
            out.append("    outer loop")
            out += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in tri]
            out.append("    endloop")
            out.append("  endfacet")
    out.append("endsolid tube")
    path.write_text("\n".join(out) + "\n")


def script_text(name: str, extra_pair: int = 0, extra_wall: int = 0) -> str:
    words, props, hp, hw = MODELS[name]
    wp, ww = 38 + hp + extra_pair, 38 + hw + extra_wall
    # a fix wall/gran takes its settings (computeElasticPotential on) after the wall's geometry;
    # on a primitive wall computeElasticPotential segfaults LIGGGHTS 3.8.0 (dissipateElasticPotential
    # reads the mesh of a wall that has none), so the primitive floor goes without it
    wwords, _, wset = words.partition(" computeElasticPotential")
    wset = " computeElasticPotential" + wset if wset else ""
    return TEMPLATE.format(
        name=name, words=words, wwords=wwords, wset=wset, restitution=same("1.0"), friction=FRICTION,
        props="\n".join(f"fix p{k} all property/global {p}" for k, p in enumerate(props, 1)),
        atomfmt=" ".join(["%.17g"] * 14),
        paircols=" ".join(f"c_cpgl[{k}]" for k in range(1, wp + 1)),
        wallcols=" ".join(f"c_cwgl[{k}]" for k in range(1, ww + 1)),
        pairfmt=" ".join(["%.17g"] * wp), wallfmt=" ".join(["%.17g"] * ww))


def liggghts(directory: Path, script: str = "in.run", timeout: float = 600) -> subprocess.CompletedProcess:
    # stdbuf: LIGGGHTS loses error->one messages when stdout is a pipe.
    return subprocess.run(["nice", "-n", "10", "stdbuf", "-o0", "-e0", "liggghts", "-in", script,
                           "-echo", "none", "-log", "none"], cwd=directory, capture_output=True, text=True, errors="replace",
                          timeout=timeout)


def make(name: str, root: Path = HERE, gz: bool = True) -> Path:
    d = root / name
    d.mkdir(parents=True, exist_ok=True)
    for f in d.glob("*.txt*"):
        f.unlink()
    write_stl(d / "walls.stl")
    (d / "in.run").write_text(script_text(name))
    proc = liggghts(d)
    if proc.returncode != 0 or "ERROR" in proc.stdout:
        errors = [ln for ln in (proc.stdout + proc.stderr).splitlines() if "ERROR" in ln]
        raise RuntimeError(f"liggghts failed on {name}: {errors or proc.stdout[-2000:]}")
    if gz:
        for f in ("atoms.txt", "pairs.txt", "wall.txt"):
            with open(d / f, "rb") as src, gzip.GzipFile(d / (f + ".gz"), "wb", 9, mtime=0) as dst:
                shutil.copyfileobj(src, dst)
            (d / f).unlink()
    return d / "in.run"


def check_width(name: str, root: Path, extra_pair: int = 1, extra_wall: int = 0) -> str:
    """Run the script with more columns in a local dump: LIGGGHTS must refuse it."""
    d = root / f"_width_{name}"
    d.mkdir(parents=True, exist_ok=True)
    write_stl(d / "walls.stl")
    text = script_text(name, extra_pair, extra_wall)
    (d / "in.run").write_text(text.split("\nrun 20000")[0] + "\nrun 0\n" + "\n".join(
        ln for ln in text.splitlines() if ln.startswith("dump")) + "\nrun 0\n")
    proc = liggghts(d, timeout=120)
    errors = [ln for ln in (proc.stdout + proc.stderr).splitlines() if "ERROR" in ln]
    shutil.rmtree(d)
    return errors[0] if errors else "accepted (no error)"


if __name__ == "__main__":
    args = sys.argv[1:]
    if args and args[0] == "--check-width":
        for name in args[1:] or MODELS:
            print(f"{name}: pair dump with one column more -> {check_width(name, HERE, 1, 0)}")
            print(f"{name}: wall dump with one column more -> {check_width(name, HERE, 0, 1)}")
        sys.exit(0)
    for name in args or MODELS:
        make(name)
        print(f"{name}: {HERE / name / 'in.run'}")
