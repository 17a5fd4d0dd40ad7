"""Write (and run) the wall-force sample scenes: each contact model twice, with a primitive floor and with the
equivalent mesh floor.

    python3 make_scenes.py DIR [SCENE ...]    # writes DIR/SCENE/in.SCENE (+ floor.stl) and runs Debian's liggghts

A scene is MODEL_prim or MODEL_mesh, MODEL one of MODELS. 100 spheres of two materials (types 1, 2) are created
on a lattice with a sideways velocity and fall, under gravity tilted along +x, onto the floor (type 3) of a cell
periodic in x and y: they land, bounce, slide and roll while the frames are written (contacts form and break).
The floor is ``zplane 0`` (``fix wall/gran ... primitive``) or the flat mesh floor.stl at z = 0 spanning the cell
exactly; either way ``store_force yes`` records the wall fix's force on each particle, written by the atom dump as
``f_force_wfloor[1..3]``. The mesh run also dumps its wall contacts with their history the way ``demsplit prepare``
writes them (compute ``dsWall``), so it can be reconstructed both from its history and from its wall force.

Dumps (every OUTPUT_EVERY steps of the last run, all at ``%.17g``): the atom dump first (it must be written before
the wall compute: compute wall/gran/local re-evaluates the wall at output time and zeroes a mesh fix's stored
force, fix_wall_gran.cpp post_force_wall), then the pair dump, then (mesh) the wall dump. The first frame is
written at the setup of the output run (velocities not half-stepped, histories not updated), the others mid-run.
Used by ../regenerate.sh and tests/test_liggghts_wallforce_facts.py.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
HALF_WIDTH = 0.006  # m: the periodic cell and the mesh floor span x, y in [-HALF_WIDTH, HALF_WIDTH]
TIMESTEP = 2.0e-6  # s
GRAVITY = (9.81, (0.15, 0.0, -1.0))  # fix gravity: magnitude (m/s^2) and direction (normalised by LIGGGHTS)
SETTLE = 40000  # steps before the output run
OUTPUT_EVERY, OUTPUT_STEPS = 500, 2000  # frames at SETTLE (setup frame) and 4 more mid-run

# Materials, types 1..3: glass-like spheres, polymer-like spheres, the floor.
YOUNG = (1.0e8, 1.0e7, 5.0e8)
POISSON = (0.25, 0.40, 0.30)
RESTITUTION = ((0.3, 0.3, 0.3), (0.3, 0.3, 0.3), (0.3, 0.3, 0.3))
FRICTION = ((0.5, 0.4, 0.3), (0.4, 0.6, 0.3), (0.3, 0.3, 0.3))
ROLLING_FRICTION = ((0.2, 0.2, 0.2), (0.2, 0.2, 0.2), (0.2, 0.2, 0.2))
CHARACTERISTIC_VELOCITY = 0.5  # m/s, hooke's kn
MAX_ELASTIC_STIFFNESS, PLASTICITY_DEPTH = 2.5, 0.001  # hooke/hysteresis: k2Max/kn, phiF (no adhesion: kc = 0)
DIAMETER = {1: 0.0022, 2: 0.0018}  # m
DENSITY = {1: 2500.0, 2: 1100.0}  # kg/m^3


def _table(values) -> str:
    return " ".join(str(v) for row in values for v in row)


MODELS: dict[str, tuple[str, list[str], list[str]]] = {
    # name: (model words of pair_style gran and fix wall/gran, property/global lines, history columns)
    "hertz": ("model hertz tangential history", [], ["shearx", "sheary", "shearz"]),
    "hooke": (
        "model hooke tangential history",
        [f"characteristicVelocity scalar {CHARACTERISTIC_VELOCITY}"],
        ["shearx", "sheary", "shearz"],
    ),
    "epsd2": (
        "model hertz tangential history rolling_friction epsd2",
        [f"coefficientRollingFriction peratomtypepair 3 {_table(ROLLING_FRICTION)}"],
        ["shearx", "sheary", "shearz", "rolling_torquex", "rolling_torquey", "rolling_torquez"],
    ),
    "hysteresis": (
        "model hooke/hysteresis tangential history",
        [
            f"characteristicVelocity scalar {CHARACTERISTIC_VELOCITY}",
            f"coefficientMaxElasticStiffness peratomtypepair 3 {_table([[MAX_ELASTIC_STIFFNESS] * 3] * 3)}",
            f"coefficientAdhesionStiffness peratomtypepair 3 {_table([[0] * 3] * 3)}",
            f"coefficientPlasticityDepth peratomtypepair 3 {_table([[PLASTICITY_DEPTH] * 3] * 3)}",
        ],
        ["delta_max", "shearx", "sheary", "shearz"],
    ),
}
KEYWORDS = "pos vel id force force_normal force_tangential torque history contactArea delta contactPoint"
"""The keywords of demsplit prepare's contact computes: 32 columns plus the history."""
LOCAL_COLUMNS = (
    "x1 y1 z1 x2 y2 z2 vx1 vy1 vz1 vx2 vy2 vz2 id1 id2 periodic fx fy fz fnx fny fnz ftx fty ftz tqx tqy tqz"
).split()
"""Names of the local dumps' columns before the history; contactArea, delta and contactPoint (3) follow it."""
ATOM_COLUMNS = (
    "id type x y z vx vy vz omegax omegay omegaz fx fy fz tqx tqy tqz radius mass "
    "f_force_wfloor[1] f_force_wfloor[2] f_force_wfloor[3]"
).split()


def local_columns(model: str, wall: bool = False) -> list[str]:
    """Names of the pair (``wall``: the wall) dump's columns for ``model``; a wall row's ids are the mesh index
    within the fix, the triangle id and the particle id."""
    names = LOCAL_COLUMNS + MODELS[model][2] + ["area", "delta", "cpx", "cpy", "cpz"]
    return names[:12] + ["mesh", "triangle", "id"] + names[15:] if wall else names


def write_floor(path: Path, n: int = 4) -> None:
    """The mesh floor: the square [-HALF_WIDTH, HALF_WIDTH]^2 at z = 0 as n x n squares of two triangles."""
    step, lines = 2 * HALF_WIDTH / n, ["solid floor"]
    for i in range(n):
        for j in range(n):
            x0, y0 = -HALF_WIDTH + i * step, -HALF_WIDTH + j * step
            for tri in (
                ((x0, y0), (x0 + step, y0), (x0 + step, y0 + step)),
                ((x0, y0), (x0 + step, y0 + step), (x0, y0 + step)),
            ):
                lines += [
                    "  facet normal 0 0 1",
                    "    outer loop",
                    *(f"      vertex {x:.6f} {y:.6f} 0.000000" for x, y in tri),
                    "    endloop",
                    "  endfacet",
                ]
    path.write_text("\n".join(lines + ["endsolid floor"]) + "\n")


def _local_dump(cid: str, name: str, width: int) -> list[str]:
    return [
        f"dump d{cid} all local {OUTPUT_EVERY} {name} " + " ".join(f"c_{cid}[{k}]" for k in range(1, width + 1)),
        f'dump_modify d{cid} format "{" ".join(["%.17g"] * width)}"',
    ]


def script(scene: str) -> str:
    """The input script of ``scene`` (MODEL_prim or MODEL_mesh)."""
    model, wall = scene.rsplit("_", 1)
    words, props, history = MODELS[model]
    width = len(local_columns(model))
    if wall == "prim":
        floor = [f"fix wfloor all wall/gran {words} primitive type 3 zplane 0.0 store_force yes"]
    else:
        floor = [
            "fix floor all mesh/surface file floor.stl type 3",
            f"fix wfloor all wall/gran {words} mesh n_meshes 1 meshes floor store_force yes",
        ]
    computes = [f"compute dsPair all pair/gran/local {KEYWORDS}"]
    dumps = [
        f"dump dsAtoms all custom {OUTPUT_EVERY} ds_atoms.txt {' '.join(ATOM_COLUMNS)}",
        'dump_modify dsAtoms format "%d %d' + " %.17g" * (len(ATOM_COLUMNS) - 2) + '" sort id',
        *_local_dump("dsPair", "ds_pairs.txt", width),
    ]
    if wall == "mesh":
        computes.append(f"compute dsWall all wall/gran/local {KEYWORDS}")
        dumps += _local_dump("dsWall", "ds_walls.txt", width)
    g, (gx, gy, gz) = GRAVITY
    lines = [
        f"# demsplit sample (sample_dumps/liggghts/walls/make_scenes.py): {words}, {wall} floor with store_force.",
        "units           si",
        "atom_style      granular",
        "atom_modify     map array",
        "boundary        p p f",
        "newton          off",
        "communicate     single vel yes",
        f"region          domain block {-HALF_WIDTH} {HALF_WIDTH} {-HALF_WIDTH} {HALF_WIDTH} -0.002 0.03 units box",
        "create_box      3 domain",
        "neighbor        0.0004 bin",
        "neigh_modify    delay 0",
        f"fix m1 all property/global youngsModulus peratomtype {' '.join(map(str, YOUNG))}",
        f"fix m2 all property/global poissonsRatio peratomtype {' '.join(map(str, POISSON))}",
        f"fix m3 all property/global coefficientRestitution peratomtypepair 3 {_table(RESTITUTION)}",
        f"fix m4 all property/global coefficientFriction peratomtypepair 3 {_table(FRICTION)}",
        *(f"fix p{k} all property/global {p}" for k, p in enumerate(props, 1)),
        f"pair_style      gran {words}",
        "pair_coeff      * *",
        f"timestep        {TIMESTEP}",
        f"fix gravi all gravity {g} vector {gx} {gy} {gz}",
        *floor,
        *computes,
        "region pack block -0.005 0.005 -0.005 0.005 0.0014 0.0098 units box",
        "lattice sc 0.0024",
        "create_atoms 1 region pack",
        "set type 1 type/fraction 2 0.5 32452843",
        "displace_atoms all random 0.00008 0.00008 0.00008 15485863 units box",
        *(f"set type {t} diameter {DIAMETER[t]} density {DENSITY[t]}" for t in (1, 2)),
        "velocity all set 0.2 0.05 0.0 units box",
        "fix integr all nve/sphere",
        "thermo 5000",
        f"run {SETTLE}",
        *dumps,
        f"run {OUTPUT_STEPS}",
    ]
    return "\n".join(lines) + "\n"


def write_scene(scene: str, directory: Path) -> Path:
    """Write ``directory/in.SCENE`` (and floor.stl for a mesh scene); return the script's path."""
    directory.mkdir(parents=True, exist_ok=True)
    if scene.endswith("_mesh"):
        write_floor(directory / "floor.stl")
    path = directory / f"in.{scene}"
    path.write_text(script(scene))
    return path


def run(path: Path, liggghts: str = "liggghts") -> None:
    """Run LIGGGHTS on the script ``path`` in its directory (stdbuf: LIGGGHTS loses error->one messages when
    stdout is a pipe); raise with LIGGGHTS' error lines on failure."""
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", path.name, "-echo", "none", "-log", "none"],
        cwd=path.parent,
        capture_output=True,
        text=True,
        timeout=600,
    )
    if proc.returncode != 0:
        errors = [line for line in (proc.stdout + proc.stderr).splitlines() if "ERROR" in line]
        raise RuntimeError(f"liggghts failed on {path}: {errors or proc.stdout[-2000:]}")


SCENES = [f"{model}_{wall}" for model in MODELS for wall in ("prim", "mesh")]

if __name__ == "__main__":
    out = Path(sys.argv[1])
    for name in sys.argv[2:] or SCENES:
        run(write_scene(name, out / name))
        print(f"{name}: {out / name}")
