"""Write (and run) one small undamped LIGGGHTS run per contact model, from template.in.

    python make_run.py DIR [NAME ...]     # writes DIR/NAME/in.run and runs Debian's liggghts there

Each run is template.in with the model's words, the properties it needs and the
dump column list of its compute width (38 columns plus the model's history,
measured: the runs fail to write a longer list); with a liquid-bridge cohesion
model the atom dump also writes the liquid content f_surfaceLiquidContent (the
fix the model creates at the first run, before the dump is defined). Used by
regenerate.sh and by tests/test_liggghts_laws_vs_liggghts.py.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _table(value: str) -> str:
    return " ".join([value] * 16)  # 4 atom types, every pair alike


# the liquid bridges: 1 % of each particle's volume in liquid, a contact angle per type (LIGGGHTS 3.8.0 takes
# half their product), fluidViscosity 0 (no viscous force: undamped like the other runs)
_BRIDGE = [
    "surfaceLiquidContentInitial scalar 0.01",
    "surfaceTension scalar 0.072",
    "contactAngle peratomtype 20 35 10 25",
    "minSeparationDistanceRatio scalar 1.01",
    "maxSeparationDistanceRatio scalar 1.1",
    "fluidViscosity scalar 0",
]
LIQUID_CONTENT = "f_surfaceLiquidContent"


MODELS: dict[str, tuple[str, list[str], int]] = {
    # name: (pair_style gran words, property/global lines, compute width = 38 + history)
    "hertz": ("model hertz tangential history", [], 41),
    "hooke": ("model hooke tangential history", [], 41),
    "no_history": ("model hertz tangential no_history", [], 38),  # no shear spring: no history
    "rolling_cdt": (
        "model hertz tangential history rolling_friction cdt",  # a constant torque: no spring
        [f"coefficientRollingFriction peratomtypepair 4 {_table('0.2')}"],
        41,
    ),
    "hertz_stiffness": (
        "model hertz/stiffness tangential history",
        [
            f"kn peratomtypepair 4 {_table('2e9')}",
            f"kt peratomtypepair 4 {_table('1e9')}",
            f"gamman peratomtypepair 4 {_table('0')}",
            f"gammat peratomtypepair 4 {_table('0')}",
        ],
        41,
    ),
    "hooke_stiffness": (
        "model hooke/stiffness tangential history",
        [
            f"kn peratomtypepair 4 {_table('2e3')}",
            f"kt peratomtypepair 4 {_table('1e3')}",
            f"gamman peratomtypepair 4 {_table('0')}",
            f"gammat peratomtypepair 4 {_table('0')}",
        ],
        41,
    ),
    "hooke_hysteresis": (
        "model hooke/hysteresis tangential history",
        [
            f"coefficientMaxElasticStiffness peratomtypepair 4 {_table('2.5')}",
            f"coefficientAdhesionStiffness peratomtypepair 4 {_table('0')}",
            f"coefficientPlasticityDepth peratomtypepair 4 {_table('0.05')}",
        ],
        42,
    ),
    "luding": (
        "model luding tangential history",
        [
            f"LoadingStiffness peratomtypepair 4 {_table('2e3')}",
            f"UnloadingStiffness peratomtypepair 4 {_table('2.0')}",
            f"coefficientAdhesionStiffness peratomtypepair 4 {_table('0')}",
            f"coefficientPlasticityDepth peratomtypepair 4 {_table('0.05')}",
            f"pullOffForce peratomtypepair 4 {_table('0')}",
        ],
        44,
    ),
    "edinburgh": (
        "model edinburgh tangential history",
        [
            "overlapExponent scalar 1.5",
            "adhesionExponent scalar 1.5",
            f"UnloadingStiffness peratomtypepair 4 {_table('5.0')}",
            f"coefficientAdhesionStiffness peratomtypepair 4 {_table('0')}",
            f"surfaceEnergy peratomtypepair 4 {_table('0')}",
            f"pullOffForce peratomtypepair 4 {_table('0')}",
        ],
        45,
    ),
    "rolling_epsd": (
        "model hertz tangential history rolling_friction epsd",
        [
            f"coefficientRollingFriction peratomtypepair 4 {_table('0.2')}",
            f"coefficientRollingViscousDamping peratomtypepair 4 {_table('0')}",
        ],
        44,
    ),
    "rolling_epsd2": (
        "model hertz tangential history rolling_friction epsd2",
        [f"coefficientRollingFriction peratomtypepair 4 {_table('0.2')}"],
        44,
    ),
    "rolling_epsd3": (
        "model hertz tangential history rolling_friction epsd3",
        [
            f"coefficientRollingFriction peratomtypepair 4 {_table('0.2')}",
            f"coefficientRollingViscousDamping peratomtypepair 4 {_table('0')}",
            "rollingStiffness scalar 1.5",
        ],
        44,
    ),
    "cohesion_sjkr": (
        "model hertz tangential history cohesion sjkr",
        [f"cohesionEnergyDensity peratomtypepair 4 {_table('2e4')}"],
        41,
    ),
    "cohesion_sjkr2": (
        "model hertz tangential history cohesion sjkr2",
        [f"cohesionEnergyDensity peratomtypepair 4 {_table('2e4')}"],
        41,
    ),
    "cohesion_easo": ("model hertz tangential history cohesion easo/capillary/viscous", _BRIDGE, 42),
    "cohesion_washino": ("model hertz tangential history cohesion washino/capillary/viscous", _BRIDGE, 42),
    "thornton_ning": (
        "model thornton_ning tangential history",
        [f"surfaceEnergy peratomtypepair 4 {_table('0')}", "coefficientYieldRatio peratomtype 0.02 0.02 0.02 0.02"],
        53,
    ),  # nearly all yielded
    "thornton_ning_mixed": (
        "model thornton_ning tangential history",
        [f"surfaceEnergy peratomtypepair 4 {_table('0')}", "coefficientYieldRatio peratomtype 0.1 0.1 0.1 0.1"],
        53,
    ),  # most elastic
    "edinburgh_stiffness": (
        "model edinburgh/stiffness tangential history",
        [
            "overlapExponent scalar 1.0",
            "adhesionExponent scalar 1.0",
            f"LoadingStiffness peratomtypepair 4 {_table('2e3')}",
            f"UnloadingStiffness peratomtypepair 4 {_table('5.0')}",
            f"coefficientAdhesionStiffness peratomtypepair 4 {_table('0')}",
            f"surfaceEnergy peratomtypepair 4 {_table('0')}",
            f"pullOffForce peratomtypepair 4 {_table('0')}",
        ],
        45,
    ),
    "tan_luding": (
        "model luding tangential tan_luding",
        [
            f"LoadingStiffness peratomtypepair 4 {_table('2e3')}",
            f"UnloadingStiffness peratomtypepair 4 {_table('2.0')}",
            f"coefficientAdhesionStiffness peratomtypepair 4 {_table('0')}",
            f"coefficientPlasticityDepth peratomtypepair 4 {_table('0.05')}",
            f"pullOffForce peratomtypepair 4 {_table('0')}",
            f"coeffFrictionStiffness peratomtypepair 4 {_table('0.5')}",
            f"FluidViscosity peratomtypepair 4 {_table('0.8')}",
            f"FrictionViscosity peratomtypepair 4 {_table('1.0')}",
        ],
        44,
    ),
    "rolling_luding": (
        "model luding tangential history rolling_friction luding",
        [
            f"LoadingStiffness peratomtypepair 4 {_table('2e3')}",
            f"UnloadingStiffness peratomtypepair 4 {_table('2.0')}",
            f"coefficientAdhesionStiffness peratomtypepair 4 {_table('0')}",
            f"coefficientPlasticityDepth peratomtypepair 4 {_table('0.05')}",
            f"pullOffForce peratomtypepair 4 {_table('0')}",
            f"coefficientRollingFriction peratomtypepair 4 {_table('0.2')}",
            f"coefficientRollingViscousDamping peratomtypepair 4 {_table('0')}",
            f"coeffRollingStiffness peratomtypepair 4 {_table('0.5')}",
        ],
        50,
    ),
}


def write_run(name: str, directory: Path) -> Path:
    """Write ``directory/in.run`` (and the floor mesh) for model ``name``; return the script's path."""
    words, props, width = MODELS[name]
    directory.mkdir(parents=True, exist_ok=True)
    shutil.copy(HERE / "floor.stl", directory / "floor.stl")
    lines = "\n".join(f"fix p{k} all property/global {p}" for k, p in enumerate(props, 1))
    columns = {cid: " ".join(f"c_{cid}[{k}]" for k in range(1, width + 1)) for cid in ("cpgl", "cwgl")}
    text = (HERE / "template.in").read_text().replace("MODEL", words).replace("EXTRA_PROPS", lines)
    text = text.replace("HISTORY", "history" if width > 38 else "")  # LIGGGHTS refuses it without a history
    text = text.replace("PAIRCOLS", columns["cpgl"]).replace("WALLCOLS", columns["cwgl"])
    text = text.replace("PAIRFMT", " ".join(["%.17g"] * width)).replace("WALLFMT", " ".join(["%.17g"] * width))
    liquid = "/capillary/" in words  # a liquid-bridge cohesion model
    text = text.replace("ATOMCOLS", f" {LIQUID_CONTENT}" if liquid else "")
    text = text.replace("ATOMFMT", " %.17g" if liquid else "")
    (directory / "in.run").write_text(text)
    return directory / "in.run"


def run(script: Path, liggghts: str = "liggghts") -> None:
    """Run LIGGGHTS on ``script`` in its directory; raise with LIGGGHTS' error line on failure."""
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", script.name],
        cwd=script.parent,
        capture_output=True,
        text=True,
        timeout=600,
    )
    if proc.returncode != 0:
        errors = [line for line in (proc.stdout + proc.stderr).splitlines() if "ERROR" in line]
        raise RuntimeError(f"liggghts failed on {script}: {errors or proc.stdout[-2000:]}")


if __name__ == "__main__":
    out = Path(sys.argv[1])
    for name in sys.argv[2:] or MODELS:
        run(write_run(name, out / name))
        print(f"{name}: {out / name / 'in.run'}")
