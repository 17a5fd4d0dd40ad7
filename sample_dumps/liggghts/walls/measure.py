"""Print the figures of the wall-force reconstruction, measured on the walls samples and (--packing) on the packing
sample rerun with ``store_force yes``.

Usage (from the repository root, in the project's virtual environment):

    python sample_dumps/liggghts/walls/measure.py             # the eight walls scenes
    python sample_dumps/liggghts/walls/measure.py --packing   # also rerun packing/ with liggghts (about 20 s)

Uses tests/liggghts_wallforce_reference.py (numpy, no demsplit) and the readers of the tests.
"""

import gzip
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests"))
from liggghts_wallforce_reference import Frame, Law, Wall, from_history, reconstruct  # noqa: E402
from test_liggghts_wallforce_facts import (  # noqa: E402
    FLOOR,
    FLOOR_TYPE,
    SCENES,
    _agree,
    _dump,
    frames,
    law,
    make_scenes,
    rebuilt,
)

PACKING = Path(__file__).resolve().parent.parent / "packing"


def reasons(contacts) -> Counter:
    return Counter(r for mode in "ntr" for r in getattr(contacts, f"reason_{mode}") if r)


def closure_line(closures) -> str:
    closes = sum(int(c.closes.sum()) for c in closures)
    total = sum(len(c.id) for c in closures)
    force = max(float(np.max(c.force_residual / c.force_tolerance)) for c in closures)
    with np.errstate(invalid="ignore"):  # 0/0: an atom touching nothing, with no torque
        torque = max(float(np.nanmax(c.torque_residual / c.torque_tolerance, initial=0.0)) for c in closures)
    return (
        f"balance closes for {closes}/{total} atom-frames (largest residual/tolerance: force {force:.2g}, "
        f"torque {torque:.2g})"
    )


def churn(scene: str, contacts) -> str:
    """Contacts formed and broken between consecutive frames, and the particles' median speed."""
    walls = [set(c.id.tolist()) for c in contacts]
    pairs = [set(zip(f.pairs["id1"].tolist(), f.pairs["id2"].tolist())) for f, _ in frames(scene)]
    pairs = [{tuple(sorted(p)) for p in ps} for ps in pairs]
    formed = sum(len(b - a) for a, b in zip(walls, walls[1:])) + sum(len(b - a) for a, b in zip(pairs, pairs[1:]))
    broken = sum(len(a - b) for a, b in zip(walls, walls[1:])) + sum(len(a - b) for a, b in zip(pairs, pairs[1:]))
    a = frames(scene)[-1][0].atoms
    speed = np.median(np.sqrt(a["vx"] ** 2 + a["vy"] ** 2 + a["vz"] ** 2))
    return f"contacts formed {formed}, broken {broken} between frames; median speed {speed:.2f} m/s"


def velocities(scene: str, model: str) -> str:
    """The floor's normal force against the model's and the balance, with the step's velocities (mid-run: the dumped
    ones less half a step) and with the other frame kind's."""
    right, wrong, fails, touching = 0.0, 0.0, 0, 0
    for (frame, _), (contacts, _) in zip(frames(scene), rebuilt(scene)):
        other = Frame(atoms=frame.atoms, pairs=frame.pairs, setup=not frame.setup, periodic=frame.periodic)
        c, closure = reconstruct(law(model), FLOOR, other)
        scale = np.abs(contacts.fn).max()
        if model != "hysteresis":
            right = max(right, float(np.abs(contacts.fn - contacts.fn_model).max() / scale))
            wrong = max(wrong, float(np.abs(c.fn - c.fn_model).max() / scale))
        busy = np.isin(closure.id, np.concatenate([contacts.id, frame.pairs["id1"], frame.pairs["id2"]]))
        fails += int((~closure.closes[busy]).sum())
        touching += int(busy.sum())
    normal = (
        f"floor normal force vs model, largest / largest force: {right:.1g} with the step's velocities, "
        f"{wrong:.1g} with the other frame kind's; "
        if model != "hysteresis"
        else ""
    )
    return normal + f"with the other frame kind's velocities {fails} of {touching} touching atom-frames do not close"


def walls_scenes() -> None:
    for scene in SCENES:
        model, wall = scene.rsplit("_", 1)
        pairs = [len(f.pairs["id1"]) for f, _ in frames(scene)]
        result = rebuilt(scene)
        contacts = [c for c, _ in result]
        n = sum(len(c.id) for c in contacts)
        capped = sum(int(c.capped.sum()) for c in contacts)
        print(
            f"== {scene}: {len(pairs)} frames, pair contacts {pairs}, floor contacts "
            f"{[len(c.id) for c in contacts]} ({capped} of {n} at the Coulomb cap)"
        )
        print("   " + closure_line([c for _, c in result]) + "; " + churn(scene, contacts))
        modes = ["u_n", "u_t"] + (["u_r"] if "rolling" in make_scenes.MODELS[model][0] else [])
        missing = {m: sum(int(np.isnan(getattr(c, m)).sum()) for c in contacts) for m in modes}
        print(f"   not computed (of {n}): {missing}; reasons {dict(sum((reasons(c) for c in contacts), Counter()))}")
        print("   " + velocities(scene, model))
        if wall == "mesh":
            lw = law(model)
            worst, compared = {}, Counter()
            for (frame, walls), c in zip(frames(scene), contacts):
                history = from_history(lw, frame.atoms, walls, FLOOR_TYPE)
                at = {i: k for k, i in enumerate(history["id"].tolist())}
                rows = np.array([at[i] for i in c.id.tolist()])
                for m in [m for m in ("u_t", "u_r", "u_n") if m in history and (m != "u_n" or model == "hysteresis")]:
                    mine, theirs = getattr(c, m), history[m][rows]
                    ok = np.isfinite(mine)
                    assert _agree(mine[ok], theirs[ok]).all()
                    big = ok & (theirs > 1e-15 * theirs.max())
                    rel = np.abs(mine[big] - theirs[big]) / theirs[big]
                    worst[m] = max(worst.get(m, 0.0), float(rel.max(initial=0.0)))
                    compared[m] += int(ok.sum())
            print(
                f"   from the wall force vs from the history: contacts compared {dict(compared)}, largest relative "
                f"difference { ({m: f'{v:.2g}' for m, v in worst.items()}) }"
            )
            stored_vs_output(scene)


def stored_vs_output(scene: str) -> None:
    """f_force of the mesh floor against the wall compute's output-time force, and that force's tangential part
    rebuilt as the compute evaluates it: the dumped velocities, the history not updated, so uncapped (F_el - gamma_t
    v_tr) wherever k_t |shear| <= mu |F_n(output)|, else F_el rescaled to the cap."""
    model = scene.rsplit("_", 1)[0]
    out, rebuilt_err = [], []
    for frame, walls in frames(scene):
        at = {int(i): k for k, i in enumerate(frame.atoms["id"])}
        rows = np.array([at[int(i)] for i in walls["id"]])
        stored = np.stack([frame.atoms[f"f_force_wfloor[{c}]"][rows] for c in (1, 2, 3)], -1)
        output = np.stack([walls[c] for c in ("fx", "fy", "fz")], -1)
        mu_fn = make_scenes.FRICTION[0][2] * np.abs(output[:, 2])
        ratio = np.hypot(output[:, 0], output[:, 1]) / mu_fn
        out.append(
            f"{'setup ' if frame.setup else ''}{np.abs(stored - output).max() / np.abs(output).max():.1g} "
            f"({(ratio > 1 + 1e-9).sum()} rows beyond mu F_n, up to {ratio.max():.3g}x)"
        )
        if frame.setup:
            continue
        a, delta = frame.atoms, walls["delta"]
        r = a["radius"][rows]
        _, kt, _, gammat = law(model).stiffness(
            a["type"][rows].astype(np.int64), np.full(len(rows), FLOOR_TYPE), r, a["mass"][rows], delta
        )
        en, dist = np.array([0.0, 0.0, 1.0]), r - delta
        omega = np.stack([a[f"omega{c}"][rows] for c in "xyz"], -1)
        vr = np.stack([a[f"v{c}"][rows] for c in "xyz"], -1)
        vt = vr - vr[:, 2:3] * en
        vtr = vt - np.cross((r - 0.5 * delta)[:, None] * omega / dist[:, None], dist[:, None] * en)
        f_el = -kt[:, None] * np.stack([walls[f"shear{c}"] for c in "xyz"], -1)
        mag = np.linalg.norm(f_el, axis=1)
        ft = np.where((mag <= mu_fn)[:, None], f_el - gammat[:, None] * vtr, f_el * (mu_fn / mag)[:, None])
        rebuilt_err.append(np.abs(ft - (output - output[:, 2:3] * en)).max() / np.abs(output).max())
    print("   |stored - output-time force| / largest force per frame: " + "; ".join(out))
    print(
        "   output-time tangential force rebuilt (uncapped unless k_t|shear| > mu F_n(output)), largest error / "
        "largest force per mid-run frame: " + ", ".join(f"{e:.1g}" for e in rebuilt_err)
    )


# packing/: hertz, tangential history; types 1, 2 spheres, 3 primitive walls, 4 mesh floor
PACKING_LAW = Law(
    normal="hertz",
    rolling=None,
    young=(1.0e8, 1.0e7, 5.0e8, 2.0e8),
    poisson=(0.25, 0.40, 0.30, 0.28),
    restitution=((0.3,) * 4,) * 4,
    friction=((0.5, 0.4, 0.3, 0.3), (0.4, 0.6, 0.3, 0.3), (0.3,) * 4, (0.3,) * 4),
    timestep=2e-6,
    gravity=np.array([0.0, 0.0, -9.81]),
)
PACKING_WALLS = [
    Wall("wfloor", 4, "plane", 2, 0.0),
    Wall("wxlo", 3, "plane", 0, -0.02),
    Wall("wxhi", 3, "plane", 0, 0.02),
    Wall("wylo", 3, "plane", 1, -0.02),
    Wall("wyhi", 3, "plane", 1, 0.02),
    Wall("wpost", 3, "cylinder", 2, radius=0.004, center=(0.0, 0.0)),
]
PACKING_PAIR = (
    make_scenes.LOCAL_COLUMNS
    + [f"tq{k}{c}" for k in "nt" for c in "xyz"]
    + ["shearx", "sheary", "shearz", "area", "delta", "cpx", "cpy", "cpz"]
)


def packing() -> None:
    """Rerun packing/ with store_force yes on every wall fix and one more atom dump with the torques and the stored
    forces (before the local dumps); check that the trajectory is the committed one; rebuild every wall contact."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        shutil.copy(PACKING / "floor.stl", tmp)
        text = (PACKING / "in.packing").read_text()
        text = re.sub(r"^(fix w\w+ +all wall/gran .*)$", r"\1 store_force yes", text, flags=re.M)
        columns = "id type x y z vx vy vz omegax omegay omegaz fx fy fz tqx tqy tqz radius mass " + " ".join(
            f"f_force_{w.fix}[{c}]" for w in PACKING_WALLS for c in (1, 2, 3)
        )
        dump = (
            f"dump dforce all custom 2000 atoms_force.txt {columns}\n"
            f'dump_modify dforce format "%d %d{" %.17g" * (len(columns.split()) - 2)}" sort id\n'
        )
        text = text.replace("\ndump dpair ", "\n" + dump + "dump dpair ", 1)
        (tmp / "in.packing").write_text(text)
        subprocess.run(
            ["stdbuf", "-o0", "-e0", "liggghts", "-in", "in.packing", "-echo", "none", "-log", "none"],
            cwd=tmp,
            check=True,
            capture_output=True,
        )
        with gzip.open(PACKING / "atoms_full.txt.gz", "rb") as f:
            same = (tmp / "atoms_full.txt").read_bytes() == f.read()
        print(
            f"== packing rerun with store_force yes: atoms_full.txt {'identical to' if same else 'DIFFERS from'} "
            "the committed one"
        )
        atoms = _dump(tmp, "atoms_force.txt", None)
        pairs = _dump(tmp, "pairs_full.txt", PACKING_PAIR)
        walls = _dump(tmp, "wall_full.txt", PACKING_PAIR[:12] + ["mesh", "triangle", "id"] + PACKING_PAIR[15:])
        closures = []
        for k, ((step, a, periodic), (_, p, _), (_, w, _)) in enumerate(zip(atoms, pairs, walls)):
            frame = Frame(atoms=a, pairs=p, setup=k == 0, periodic=periodic)
            c, closure = reconstruct(PACKING_LAW, PACKING_WALLS, frame)
            closures.append(closure)
            primitive = c.wall > 0
            per_fix = {PACKING_WALLS[i].fix: int((c.wall == i).sum()) for i in range(len(PACKING_WALLS))}
            two = np.bincount(c.id[primitive], minlength=int(a["id"].max()) + 1)
            history = from_history(PACKING_LAW, a, w, 4)
            at = {i: j for j, i in enumerate(history["id"].tolist())}
            floor = np.flatnonzero(~primitive)
            rows = np.array([at[i] for i in c.id[floor].tolist()])
            ok = np.isfinite(c.u_t[floor])
            agree = _agree(c.u_t[floor][ok], history["u_t"][rows][ok])
            print(
                f"   step {step}{' (setup)' if k == 0 else ''}: wall contacts {per_fix}; particles on two primitive "
                f"walls {(two > 1).sum()}; u_t not computed: primitive {int(np.isnan(c.u_t[primitive]).sum())} of "
                f"{int(primitive.sum())}, mesh floor {int((~ok).sum())} of {len(floor)}; reasons "
                f"{dict(reasons(c))}; floor u_t from force = from history (1e-9) for "
                f"{int(agree.sum())}/{len(agree)}; u_t of the primitive walls "
                f"{np.nansum(c.u_t[primitive]):.4g} J (mesh floor {np.nansum(c.u_t[floor]):.4g} J)"
            )
        print("   " + closure_line(closures))


if __name__ == "__main__":
    walls_scenes()
    if "--packing" in sys.argv[1:]:
        packing()
