"""Print demsplit's figures for the primitive walls rebuilt from their stored force (docs/liggghts-output.md).

Usage (from the repository root, in the project's virtual environment):

    python sample_dumps/liggghts/walls/demsplit_figures.py             # the eight walls scenes
    python sample_dumps/liggghts/walls/demsplit_figures.py --packing   # also packing/, prepared and rerun (30 s)

For each primitive scene: the floor contacts whose history modes are not computed when the run is read without its
stored force (the script without ``store_force yes``: what demsplit did before) and with it, the reasons, and the
largest residual of a particle's balance over its tolerance. For each mesh scene: the floor's energies from its
dumped history against those from its stored force (the same dumps read with the floor as the equivalent primitive
wall). The tests that assert these facts: tests/test_liggghts_wallforce.py.
"""

import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np
from demsplit.physics.modes import NOT_COMPUTED_BITS
from demsplit.physics.partition import contact_energies
from demsplit.readers import open_run
from demsplit.readers.liggghts_wallforce import REASONS, WallForce

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests"))
from test_liggghts_wallforce import floor_rows, modes_of, primitive_copy  # noqa: E402
from test_liggghts_wallforce_facts import MODELS, WALLS  # noqa: E402

CLOSURES: list[float] = []
_rebuild = WallForce.rebuild


def _recording(self, *args, **kwargs):
    """WallForce.rebuild, keeping each frame's largest residual over tolerance."""
    out = _rebuild(self, *args, **kwargs)
    CLOSURES.append(out.closure)
    return out


WallForce.rebuild = _recording


def read(script: Path) -> list[tuple]:
    run = open_run(script)
    return [(f, contact_energies(f.contacts, run.scene, f.particles)) for f in (run.frame(k) for k in range(len(run)))]


def not_computed(frames: list[tuple], modes: list[str]) -> dict[str, int]:
    counts = dict.fromkeys(modes, 0)
    for frame, e in frames:
        rows = np.flatnonzero(frame.contacts["wall"] >= 0)
        for m in modes:
            counts[m] += int(((e.not_computed[rows] & NOT_COMPUTED_BITS[m]) != 0).sum())
    return counts


def primitive_scenes(tmp: Path) -> None:
    print("== primitive floors: not computed without / with the stored force")
    names = {text: key for key, text in REASONS.items()}
    for model in MODELS:
        scene = f"{model}_prim"
        script = WALLS / scene / f"in.{scene}"
        bare = tmp / scene / script.name
        bare.parent.mkdir(parents=True)
        for f in ("ds_atoms.txt.gz", "ds_pairs.txt.gz"):
            shutil.copy(WALLS / scene / f, bare.parent / f)
        bare.write_text(script.read_text().replace(" store_force yes", ""))
        CLOSURES.clear()
        frames = read(script)
        reasons = Counter(names[n] for f, _ in frames for n in f.notes if n in names)
        contacts = sum(int((f.contacts["wall"] >= 0).sum()) for f, _ in frames)
        print(
            f"   {scene}: {contacts} floor contacts in {len(frames)} frames; not computed without "
            f"{not_computed(read(bare), modes_of(model))}, with {not_computed(frames, modes_of(model))}; "
            f"frames with each reason {dict(reasons)}; largest residual/tolerance {max(CLOSURES):.2g}"
        )


def mesh_scenes(tmp: Path) -> None:
    print("== mesh floors: energies from the dumped history vs from the stored force (max relative difference)")
    for model in MODELS:
        scene = f"{model}_mesh"
        CLOSURES.clear()
        history, force = read(WALLS / scene / f"in.{scene}"), read(primitive_copy(scene, tmp / scene))
        compared, worst, missing = Counter(), Counter(), Counter()
        for (hf, he), (ff, fe) in zip(history, force):
            ids = hf.contacts["id1"][hf.contacts["wall"] == 0]
            hrows, frows = floor_rows(hf, ids), floor_rows(ff, ids)
            for m in modes_of(model):
                theirs, mine = getattr(he, m)[hrows], getattr(fe, m)[frows]
                known = (fe.not_computed[frows] & NOT_COMPUTED_BITS[m]) == 0
                big = np.abs(theirs) > 1e-15 * np.abs(theirs).max()
                rel = np.abs(mine - theirs)[known & big] / np.abs(theirs)[known & big]
                worst[m] = max(worst[m], float(rel.max(initial=0.0)))
                compared[m] += int(known.sum())
                missing[m] += int((~known).sum())
        print(
            f"   {scene}: compared {dict(compared)}, not computed {dict(missing)}, "
            f"max relative difference {', '.join(f'{m} {v:.2g}' for m, v in worst.items())}; largest residual/"
            f"tolerance {max(CLOSURES):.2g}"
        )


def packing(tmp: Path) -> None:
    source = WALLS.parent / "packing"
    before = read(source / "in.packing")
    print(
        f"== packing: committed dumps (no stored force): u_t not computed per frame "
        f"{[not_computed([f], ['u_t'])['u_t'] for f in before]}"
    )
    for name in ("in.packing", "floor.stl"):
        shutil.copy(source / name, tmp / name)
    subprocess.run(["demsplit", "prepare", "in.packing", "-q"], cwd=tmp, check=True)
    subprocess.run(
        ["stdbuf", "-o0", "-e0", "liggghts", "-in", "in.packing.demsplit", "-echo", "none", "-log", "none"],
        cwd=tmp,
        check=True,
        capture_output=True,
    )
    CLOSURES.clear()
    after = read(tmp / "in.packing.demsplit")
    primitive = [float(e.u_t[f.contacts["wall"] >= 1].sum()) for f, e in after]
    print(
        f"   prepared and rerun: u_t not computed per frame {[not_computed([f], ['u_t'])['u_t'] for f in after]}; "
        f"primitive walls' u_t per frame {', '.join(f'{u:.4g}' for u in primitive)} J; largest residual/tolerance "
        f"{max(CLOSURES):.2g}"
    )


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        primitive_scenes(Path(tmp) / "bare")
        mesh_scenes(Path(tmp) / "mesh")
        if "--packing" in sys.argv[1:]:
            (Path(tmp) / "packing").mkdir()
            packing(Path(tmp) / "packing")
