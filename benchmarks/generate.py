"""Generate a large, realistic LIGGGHTS run for benchmarks: dumps plus input script.

Writes into ``DIR`` (default: a new temporary directory; never the repository)

* ``atoms.txt``: ``dump custom`` of ``id type x y z vx vy vz fx fy fz omegax
  omegay omegaz radius mass`` (``%d`` ids/types, ``%g`` reals, trailing space,
  as LIGGGHTS prints it),
* ``pairs.txt``: ``dump local`` of the 41 columns of ``compute pair/gran/local
  pos vel id force force_normal force_tangential torque torque_normal
  torque_tangential history contactArea delta contactPoint`` (label
  ``ENTRIES``, ``%g`` except the two id columns, written with ``%.10g`` by
  the script's ``dump_modify format``: with ``%g`` every id above 999999 would
  be destroyed and demsplit would rightly refuse the dump),
* ``in.bench``: an input script with the materials, contact model, computes
  and dumps of ``sample_dumps/liggghts/packing/in.packing`` (no walls), so that
  ``demsplit run DIR/in.bench -o out.h5`` finds the dumps.

Geometry (consistent, so energies mean something): particles on a jittered
cubic lattice of spacing ``a`` = 4 mm, types 1 and 2 alternating, radii
a/2 (1 + 1e-3 u) with u uniform in [0.2, 1], positions jittered by 1e-5 a per
frame. Contacts are bonds between x and y lattice neighbours (z layers are
1.01 a apart, so they do not touch; z bonds are added only when more
contacts are asked for than x/y bonds exist), a random subset when fewer are
asked for, in id1 order. Per contact, computed in float64 before printing:
delta = r1 + r2 - |x1 - x2|, the Hertz normal force on body 1
(4/3) E* sqrt(R*) delta^1.5 along x1 - x2, a small random shear history
perpendicular to the normal (|shear| <= 0.1 delta) and the tangential force
-kt shear with kt = 8 G* sqrt(R* delta), contact area pi R* delta, contact
point x1 + (r1 - delta/2) n. Velocities and torques are small random numbers.

Formatting is vectorised (:func:`format_g`: printf ``%g`` digit for digit,
without a Python loop per value). Run::

    python benchmarks/generate.py [DIR] [--particles 1000000] [--contacts 2000000] [--frames 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from demsplit.physics.elastic import hertz_force
from demsplit.physics.moduli import effective_radius, effective_shear_modulus

ATOM_COLUMNS = (
    "id",
    "type",
    "x",
    "y",
    "z",
    "vx",
    "vy",
    "vz",
    "fx",
    "fy",
    "fz",
    "omegax",
    "omegay",
    "omegaz",
    "radius",
    "mass",
)
N_LOCAL = 41
ID_COLUMNS = (12, 13)  # 0-based columns of id1, id2 in the pair/gran/local layout
SPACING = 0.004  # lattice spacing a (m)
DENSITY = {1: 2500.0, 2: 1100.0}
MATERIALS = {1: (1.0e8, 0.25), 2: (1.0e7, 0.40)}  # type: (E Pa, nu), as in.packing
ROWS_PER_CHUNK = 50_000
STEP0, EVERY = 200_000, 2000

_EXP_CHARS = 3  # exponent digits reserved (%g prints at least 2, up to 3)


def format_g(values: np.ndarray, precision: int = 6) -> np.ndarray:
    """printf ``%.{precision}g`` of every value, vectorised.

    Returns a uint8 array of shape ``values.shape + (W,)`` holding each value's
    characters, 0 where a slot is unused (remove them with ``a[a != 0]``).
    Exact for finite values (up to ties at the last digit, where the float
    product x 10^k may round the other way than C's exact decimal conversion).
    """
    x = np.asarray(values, dtype=np.float64)
    P = precision
    neg = np.signbit(x)
    ax = np.abs(x)
    zero = ax == 0
    safe = np.where(zero, 1.0, ax)
    e = np.floor(np.log10(safe)).astype(np.int64)
    m = np.rint(safe * 10.0 ** (P - 1 - e))
    for _ in range(2):  # log10/product rounding: bring m back into [10^(P-1), 10^P)
        up = m >= 10.0**P
        e = np.where(up, e + 1, e)
        down = m < 10.0 ** (P - 1)
        e = np.where(down, e - 1, e)
        m = np.where(up | down, np.rint(safe * 10.0 ** (P - 1 - e)), m)
    m = np.where(zero, 0, m).astype(np.uint32 if P <= 9 else np.uint64)
    e = np.where(zero, 0, e)
    # the P digits of m (characters), most significant first
    digits = np.empty(x.shape + (P,), dtype=np.uint8)
    rest = m
    for i in range(P - 1, -1, -1):
        rest, d = np.divmod(rest, 10)
        digits[..., i] = d
    # %g strips trailing zeros: ndig = position of the last nonzero digit + 1
    nonzero = digits != 0
    ndig = np.where(nonzero.any(axis=-1), P - np.argmax(nonzero[..., ::-1], axis=-1), 1).astype(np.int64)
    ndig = np.where(zero, 1, ndig)
    fixed = (e >= -4) & (e < P)
    # digit sequence: position q shows digit j = q + shift of m (0 where j < 0), point after q == point
    shift = np.where(fixed, np.minimum(e, 0), 0)
    point = np.where(fixed, np.maximum(e, 0), 0)
    length = np.where(fixed, np.maximum(ndig - shift, point + 1), ndig)
    n_q = P + 4
    out = np.zeros(x.shape + (1 + 2 * n_q + 2 + _EXP_CHARS,), dtype=np.uint8)
    out[..., 0] = np.where(neg, ord("-"), 0)
    # the P digits of m as characters, padded with 4 zeros on both sides so that j = q + shift indexes them
    chars = np.full(x.shape + (P + 8,), 48, dtype=np.uint8)
    chars[..., 4 : 4 + P] += digits
    q = np.arange(n_q)
    picked = np.take_along_axis(chars, (q + shift[..., None] + 4), axis=-1)
    out[..., 1 : 1 + 2 * n_q : 2] = np.where(q < length[..., None], picked, 0)
    out[..., 2 : 2 + 2 * n_q : 2] = np.where((q == point[..., None]) & (length[..., None] > q + 1), ord("."), 0)
    k = 1 + 2 * n_q
    sci = ~fixed
    out[..., k] = np.where(sci, ord("e"), 0)
    out[..., k + 1] = np.where(sci, np.where(e < 0, ord("-"), ord("+")), 0)
    ae = np.abs(e)
    out[..., k + 2] = np.where(sci & (ae >= 100), 48 + ae // 100, 0)
    out[..., k + 3] = np.where(sci, 48 + (ae // 10) % 10, 0)
    out[..., k + 4] = np.where(sci, 48 + ae % 10, 0)
    return out


def format_rows(columns: list[np.ndarray], precisions: list[int]) -> bytes:
    """Rows of the given columns, each value followed by a space, one row per line
    (LAMMPS's layout, trailing space included)."""
    parts = [format_g(c, p) for c, p in zip(columns, precisions)]
    n = len(columns[0])
    sep = np.full((n, 1), ord(" "), dtype=np.uint8)
    row = np.concatenate([x for part in parts for x in (part, sep)] + [np.full((n, 1), 10, np.uint8)], axis=1)
    return row[row != 0].tobytes()


def _header(step: int, n: int, label: str, names: list[str], lo: np.ndarray, hi: np.ndarray) -> bytes:
    bounds = "".join(f"{a:g} {b:g}\n" for a, b in zip(lo, hi))
    return (
        f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF {label}\n{n}\nITEM: BOX BOUNDS ff ff ff\n{bounds}"
        f"ITEM: {label} {' '.join(names)} \n"
    ).encode()


def _write_rows(f, columns: list[np.ndarray], precisions: list[int]) -> None:
    n = len(columns[0])
    for start in range(0, n, ROWS_PER_CHUNK):
        f.write(format_rows([c[start : start + ROWS_PER_CHUNK] for c in columns], precisions))


def lattice(n_particles: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Particle ids, types, lattice positions (m), radii (m) and masses (kg)."""
    side = int(np.ceil(n_particles ** (1 / 3)))
    k = np.arange(n_particles)
    ijk = np.stack([k % side, (k // side) % side, k // (side * side)], axis=1)
    types = (ijk.sum(axis=1) % 2 + 1).astype(np.int64)
    radius = SPACING / 2 * (1 + 1e-3 * rng.uniform(0.2, 1.0, n_particles))
    density = np.where(types == 1, DENSITY[1], DENSITY[2])
    return {
        "id": k + 1,
        "type": types,
        "ijk": ijk,
        "side": np.int64(side),
        "radius": radius,
        "mass": 4 / 3 * np.pi * radius**3 * density,
    }


def bonds(p: dict[str, np.ndarray], n_contacts: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, float]:
    """Row pairs (i < j) of touching lattice neighbours, and the z spacing factor."""
    n, side = len(p["id"]), int(p["side"])
    k = np.arange(n)
    pairs = []
    for axis, stride in ((0, 1), (1, side), (2, side * side)):
        ok = (p["ijk"][:, axis] < side - 1) & (k + stride < n)
        pairs.append((k[ok], k[ok] + stride))
        if axis == 1 and sum(len(a) for a, _ in pairs) >= n_contacts:
            break
    z_factor = 1.0 if len(pairs) == 3 else 1.01
    i = np.concatenate([a for a, _ in pairs])
    j = np.concatenate([b for _, b in pairs])
    if n_contacts < len(i):
        keep = np.sort(rng.choice(len(i), n_contacts, replace=False))
        i, j = i[keep], j[keep]
    order = np.lexsort((j, i))
    return i[order], j[order], z_factor


def frame_arrays(p: dict, i: np.ndarray, j: np.ndarray, z_factor: float, rng: np.random.Generator) -> tuple[list, list]:
    """Columns of the atom dump and of the pair dump for one frame."""
    n, m = len(p["id"]), len(i)
    xyz = p["ijk"] * (SPACING * np.array([1.0, 1.0, z_factor])) + rng.uniform(-1e-5, 1e-5, (n, 3)) * SPACING
    small = lambda scale, shape: rng.normal(0.0, scale, shape)  # noqa: E731
    v, f, w = small(1e-4, (n, 3)), small(1e-6, (n, 3)), small(1e-2, (n, 3))
    atoms = [p["id"], p["type"], *xyz.T, *v.T, *f.T, *w.T, p["radius"], p["mass"]]

    r1, r2 = p["radius"][i], p["radius"][j]
    d = xyz[j] - xyz[i]
    dist = np.sqrt(np.einsum("ij,ij->i", d, d))
    n12 = d / dist[:, None]
    delta = r1 + r2 - dist
    if np.any(delta <= 0):
        raise RuntimeError("generator bug: a lattice bond does not overlap")
    t1, t2 = p["type"][i] - 1, p["type"][j] - 1
    E = np.array([MATERIALS[1][0], MATERIALS[2][0]])
    nu = np.array([MATERIALS[1][1], MATERIALS[2][1]])
    fn = hertz_force(delta, r1, r2, E[t1], nu[t1], E[t2], nu[t2])
    fnv = -fn[:, None] * n12  # on body 1, away from body 2
    R = effective_radius(r1, r2)
    G = effective_shear_modulus(E[t1], nu[t1], E[t2], nu[t2])
    kt = 8.0 * G * np.sqrt(R * delta)
    s = rng.normal(0.0, 1.0, (m, 3))
    s -= np.einsum("ij,ij->i", s, n12)[:, None] * n12
    s *= (0.1 * delta * rng.uniform(0, 1, m) / np.maximum(np.linalg.norm(s, axis=1), 1e-300))[:, None]
    ftv = -kt[:, None] * s
    tq = small(1e-7, (m, 3))
    cp = xyz[i] + (r1 - delta / 2)[:, None] * n12
    pairs = [
        *xyz[i].T,
        *xyz[j].T,
        *v[i].T,
        *v[j].T,
        p["id"][i],
        p["id"][j],
        np.zeros(m),
        *(fnv + ftv).T,
        *fnv.T,
        *ftv.T,
        *tq.T,
        *(0.5 * tq).T,
        *(0.5 * tq).T,
        *s.T,
        np.pi * R * delta,
        delta,
        *cp.T,
    ]
    assert len(pairs) == N_LOCAL
    return atoms, pairs


def script_text(atoms: str, pairs: str) -> str:
    local = " ".join(f"c_cpgl[{k}]" for k in range(1, N_LOCAL + 1))
    fmt = " ".join("%.10g" if k in ID_COLUMNS else "%g" for k in range(N_LOCAL))
    return f"""# demsplit benchmark run written by benchmarks/generate.py (materials, model, computes and
# dumps of sample_dumps/liggghts/packing/in.packing; no walls).
units           si
atom_style      granular
atom_modify     map array
boundary        f f f
newton          off
communicate     single vel yes
region          domain block -0.01 10 -0.01 10 -0.01 10 units box
create_box      2 domain

fix m1 all property/global youngsModulus peratomtype {MATERIALS[1][0]:g} {MATERIALS[2][0]:g}
fix m2 all property/global poissonsRatio peratomtype {MATERIALS[1][1]:g} {MATERIALS[2][1]:g}
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.3 0.3 0.3 0.3
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.4 0.4 0.6

pair_style      gran model hertz tangential history
pair_coeff      * *
timestep        2.0e-6

compute cpgl all pair/gran/local pos vel id force force_normal force_tangential &
    torque torque_normal torque_tangential history contactArea delta contactPoint

dump datoms all custom {EVERY} {atoms} {" ".join(ATOM_COLUMNS)}
dump dpair  all local {EVERY} {pairs} {local}
dump_modify dpair format "{fmt}"

run             {EVERY * 2}
"""


def generate(out: Path, n_particles: int, n_contacts: int, n_frames: int, seed: int = 1) -> dict:
    """Write the dumps and ``in.bench`` into ``out``; return sizes and timings."""
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    p = lattice(n_particles, rng)
    i, j, zf = bonds(p, n_contacts, rng)
    lo = np.array([-SPACING] * 3)
    hi = (p["ijk"].max(axis=0) + 1) * SPACING * np.array([1.0, 1.0, zf])
    atom_prec = [10, 10] + [6] * (len(ATOM_COLUMNS) - 2)
    pair_prec = [10 if k in ID_COLUMNS else 6 for k in range(N_LOCAL)]
    t_compute = t_write = 0.0
    with open(out / "atoms.txt", "wb") as fa, open(out / "pairs.txt", "wb") as fp:
        for k in range(n_frames):
            t0 = time.perf_counter()
            atoms, pairs = frame_arrays(p, i, j, zf, rng)
            t1 = time.perf_counter()
            step = STEP0 + k * EVERY
            fa.write(_header(step, n_particles, "ATOMS", list(ATOM_COLUMNS), lo, hi))
            _write_rows(fa, atoms, atom_prec)
            fp.write(_header(step, len(i), "ENTRIES", [f"c_cpgl[{c}]" for c in range(1, N_LOCAL + 1)], lo, hi))
            _write_rows(fp, pairs, pair_prec)
            t_compute += t1 - t0
            t_write += time.perf_counter() - t1
    (out / "in.bench").write_text(script_text("atoms.txt", "pairs.txt"))
    return {
        "dir": str(out),
        "particles": n_particles,
        "contacts": len(i),
        "frames": n_frames,
        "bytes": {f: (out / f).stat().st_size for f in ("atoms.txt", "pairs.txt")},
        "seconds_compute": round(t_compute, 2),
        "seconds_format_write": round(t_write, 2),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", nargs="?", help="output directory (default: a new temporary directory)")
    ap.add_argument("--particles", type=int, default=1_000_000)
    ap.add_argument("--contacts", type=int, default=2_000_000)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)
    out = Path(a.dir) if a.dir else Path(tempfile.mkdtemp(prefix="demsplit-bench-"))
    if (Path(__file__).resolve().parent.parent / ".git").exists() and Path(
        __file__
    ).resolve().parent.parent in out.resolve().parents:
        ap.error("refusing to write the benchmark dumps into the repository; give a directory outside it")
    info = generate(out, a.particles, a.contacts, a.frames, a.seed)
    print(info)


if __name__ == "__main__":
    main()
