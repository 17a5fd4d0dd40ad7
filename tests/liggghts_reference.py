"""Independent numpy reconstructions of LIGGGHTS 3.8.0 sphere contact laws (not a test file).

Written from the LIGGGHTS-PUBLIC source (file names below are its ``src/``), not from
demsplit: it reads the dumps and the ``fix property/global`` lines of the runs in
tests/data/liggghts_models/ itself. For a contact it gives

- the elastic normal force LIGGGHTS applies (:func:`normal_force`),
- the elastic normal energy released on the model's own unloading branch (:func:`normal_energy`),
- the tangential stiffness, spring force and energy (:func:`tangential_kt`, ½ k_t |shear|²),
- the rolling stiffness, the rolling torque LIGGGHTS applies at output and the rolling
  spring energy ½ |M_r|²/k_r (:func:`rolling_kr`, :func:`rolling_torque`),
- the sjkr / sjkr2 cohesion force and work (:func:`cohesion_force`, :func:`cohesion_work`).

Every function takes a :class:`Contacts` (plain numpy arrays of one frame: pair and mesh-wall
contacts from the local dumps, with the radii, masses, types, omegas of the atom dump) and a
:class:`Script` (the model words, ``timestep`` and the ``fix property/global`` values of
the run's input script).
"""

from __future__ import annotations

import gzip
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# --------------------------------------------------------------------------
# Reading the runs: the script's properties and the dumps
# --------------------------------------------------------------------------


@dataclass
class Script:
    """What the reconstructions need from a run's input script."""

    path: Path
    words: dict[str, str]  # model / tangential / cohesion / rolling_friction / surface + on/off settings
    props: dict[str, tuple[str, list[float]]]  # property/global NAME -> (style, values)
    dt: float
    mesh_type: int  # atom type of the mesh wall material (fix mesh/surface ... type T)
    primitive_type: int | None
    primitive_z: float | None  # the primitive zplane's height
    dumps: dict[str, str] = field(default_factory=dict)  # dump id -> file name

    # --- property access -------------------------------------------------
    def scalar(self, name: str) -> float:
        style, v = self.props[name]
        assert style == "scalar", (name, style)
        return v[0]

    def per_type(self, name: str) -> np.ndarray:
        """peratomtype values indexed by atom type (index 0 unused)."""
        style, v = self.props[name]
        assert style == "peratomtype", (name, style)
        return np.array([np.nan] + v)

    def pair_table(self, name: str) -> np.ndarray:
        """peratomtypepair values as a matrix indexed [type_i, type_j] (row/column 0 unused)."""
        style, v = self.props[name]
        assert style == "peratomtypepair", (name, style)
        n = int(v[0])
        m = np.full((n + 1, n + 1), np.nan)
        m[1:, 1:] = np.array(v[1:], dtype=float).reshape(n, n)
        return m

    @property
    def normal(self) -> str:
        return self.words["model"]

    @property
    def tangential(self) -> str:
        return self.words.get("tangential", "no_history")

    @property
    def cohesion(self) -> str:
        return self.words.get("cohesion", "off")

    @property
    def rolling(self) -> str:
        return self.words.get("rolling_friction", "off")

    def on(self, setting: str) -> bool:
        return self.words.get(setting, "off") in ("on", "yes")


_MODEL_KEYS = ("model", "tangential", "cohesion", "rolling_friction", "surface")


def read_script(path: str | Path) -> Script:
    """Parse just what the scripts of tests/data/liggghts_models use (one command per line)."""
    path = Path(path)
    words: dict[str, str] = {}
    props: dict[str, tuple[str, list[float]]] = {}
    dt = math.nan
    mesh_type = -1
    prim_type = prim_z = None
    dumps: dict[str, str] = {}
    for raw in path.read_text().splitlines():
        t = raw.split("#")[0].split()
        if not t:
            continue
        if t[0] == "pair_style" and t[1] == "gran":
            for k in range(2, len(t) - 1, 2):
                words[t[k]] = t[k + 1]
        elif t[0] == "timestep":
            dt = float(t[1])
        elif t[0] == "fix" and len(t) > 3 and t[3] == "property/global":
            props[t[4]] = (t[5], [float(x) for x in t[6:]])
        elif t[0] == "fix" and len(t) > 3 and t[3] == "mesh/surface":
            mesh_type = int(t[t.index("type") + 1])
        elif t[0] == "fix" and len(t) > 3 and t[3] == "wall/gran" and "primitive" in t:
            prim_type = int(t[t.index("type") + 1])
            if "zplane" in t:
                prim_z = float(t[t.index("zplane") + 1])
        elif t[0] == "dump":
            dumps[t[1]] = t[5]
    return Script(path, words, props, dt, mesh_type, prim_type, prim_z, dumps)


def _open(path: Path):
    if path.exists():
        return open(path)
    return gzip.open(str(path) + ".gz", "rt")


def read_dump(path: str | Path) -> list[tuple[int, list[str], np.ndarray]]:
    """All frames of a LAMMPS text dump (``path`` or ``path.gz``): (step, column names, rows)."""
    frames = []
    with _open(Path(path)) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines):
        assert lines[i].startswith("ITEM: TIMESTEP"), lines[i]
        step = int(lines[i + 1])
        n = int(lines[i + 3])
        assert lines[i + 4].startswith("ITEM: BOX BOUNDS")
        header = lines[i + 8].split()[2:]
        rows = lines[i + 9:i + 9 + n]
        data = np.array([[float(x) for x in r.split()] for r in rows]).reshape(n, len(header))
        frames.append((step, header, data))
        i += 9 + n
    return frames


# --------------------------------------------------------------------------
# History layout (the order of add_history_value calls, contact_models.h:141-178)
# --------------------------------------------------------------------------

NORMAL_HISTORY = {
    "hertz": [], "hooke": [], "hertz/stiffness": [], "hooke/stiffness": [],
    "hooke/hysteresis": ["deltaMax"],                                       # normal_model_hooke_hysteresis.h:70
    "luding": ["deltaMax", "kc", "fo"],                                     # normal_model_luding.h:69-71
    "thornton_ning": ["tn_virgin_flag", "delta_old", "delta_max", "force_old", "force_max",
                      "adhesion_flag", "detaching_delta", "detaching_flag", "detaching_force",
                      "yielding_flag", "kc", "fo"],                         # normal_model_thornton_ning.h:69-80
    "edinburgh": ["deltaMax", "old_delta", "kc", "fo"],                     # normal_model_edinburgh.h:79-82
    "edinburgh/stiffness": ["deltaMax", "old_delta", "kc", "fo"],
}
TANGENTIAL_HISTORY = {"history": ["shearx", "sheary", "shearz"], "tan_luding": ["shearx", "sheary", "shearz"],
                      "no_history": []}
ROLLING_HISTORY = {"off": [], "cdt": [], "epsd": ["r_torquex_old", "r_torquey_old", "r_torquez_old"],
                   "epsd2": ["r_torquex_old", "r_torquey_old", "r_torquez_old"],
                   "epsd3": ["r_torquex_old", "r_torquey_old", "r_torquez_old"],
                   "luding": ["r_torquex_old", "r_torquey_old", "r_torquez_old",
                              "r_tor_torquex_old", "r_tor_torquey_old", "r_tor_torquey_old"]}
ELASTIC_POTENTIAL = ["elastic_potential_normal", "elastic_force_normal_0", "elastic_force_normal_1",
                     "elastic_force_normal_2", "elastic_torque_normal_i_0", "elastic_torque_normal_i_1",
                     "elastic_torque_normal_i_2", "elastic_torque_normal_j_0", "elastic_torque_normal_j_1",
                     "elastic_torque_normal_j_2"]


def history_layout(script: Script, wall: bool) -> list[str]:
    """Names of the history values in the order LIGGGHTS writes them: the sub-models'
    constructors (surface, normal, cohesion, tangential, rolling), then their postSettings
    (surface_model_default.h:113-118 and normal_model_hertz.h:101-121 for computeElasticPotential)."""
    names = NORMAL_HISTORY[script.normal] + TANGENTIAL_HISTORY[script.tangential] + ROLLING_HISTORY[script.rolling]
    if script.on("computeElasticPotential"):
        if wall:
            names += ["delta_0", "delta_1", "delta_2"]
        names += ELASTIC_POTENTIAL + (["elastic_potential_wall"] if wall else [])
    return names


# --------------------------------------------------------------------------
# One frame's contacts
# --------------------------------------------------------------------------


@dataclass
class Contacts:
    """Pair contacts then mesh-wall contacts of one frame (``wall`` False/True)."""

    step: int
    wall: np.ndarray
    id1: np.ndarray
    id2: np.ndarray        # atom id j; for mesh walls the triangle id
    ti: np.ndarray
    tj: np.ndarray         # mesh walls: the mesh's material type
    ri: np.ndarray
    rj: np.ndarray         # mesh walls: nan
    mi: np.ndarray
    mj: np.ndarray
    xi: np.ndarray         # (n, 3)
    xj: np.ndarray         # (n, 3): mesh walls: the contact point on the wall
    wi: np.ndarray         # omega_i (n, 3)
    wj: np.ndarray         # omega_j (n, 3); 0 for walls
    delta: np.ndarray
    hist: np.ndarray       # (n, H)
    force: np.ndarray      # total contact force on i (n, 3)
    fn: np.ndarray         # force_normal (n, 3)
    ft: np.ndarray         # force_tangential (n, 3)
    torque: np.ndarray     # total contact torque on i (n, 3)
    names: list[str]       # history value names (the same for pairs and walls where it is used)
    wall_names: list[str]

    def __len__(self) -> int:
        return len(self.delta)

    @property
    def reff(self) -> np.ndarray:
        return np.where(self.wall, self.ri, self.ri * self.rj / (self.ri + self.rj))

    @property
    def meff(self) -> np.ndarray:
        return np.where(self.wall, self.mi, self.mi * self.mj / (self.mi + self.mj))

    @property
    def en(self) -> np.ndarray:
        """Unit normal from j (or the wall's contact point) to i, as LIGGGHTS' en."""
        d = self.xi - self.xj
        return d / np.linalg.norm(d, axis=1)[:, None]

    def h(self, name: str, k: int = 1) -> np.ndarray:
        """History value ``name`` (and the k-1 following ones) of every contact."""
        cols = []
        for w in (False, True):
            names = self.wall_names if w else self.names
            i = names.index(name)
            cols.append((w, i))
        out = np.full((len(self), k), np.nan)
        for w, i in cols:
            sel = self.wall == w
            out[sel] = self.hist[sel, i:i + k]
        return out[:, 0] if k == 1 else out


class Run:
    """A run directory of tests/data/liggghts_models: its script and dumps."""

    def __init__(self, directory: str | Path):
        self.dir = Path(directory)
        self.script = read_script(self.dir / "in.run")
        self.atoms = read_dump(self.dir / "atoms.txt")
        self.pairs = read_dump(self.dir / "pairs.txt")
        self.walls = read_dump(self.dir / "wall.txt")
        assert [f[0] for f in self.atoms] == [f[0] for f in self.pairs] == [f[0] for f in self.walls]
        self.pair_names = history_layout(self.script, wall=False)
        self.wall_names = history_layout(self.script, wall=True)

    def __len__(self) -> int:
        return len(self.atoms)

    def history_width(self, wall: bool) -> int:
        """The number of history columns in the dump: its column count minus the 38 others."""
        return self.pairs[0][2].shape[1] - 38 if not wall else self.walls[0][2].shape[1] - 38

    def atom_table(self, k: int) -> dict[str, np.ndarray]:
        step, names, a = self.atoms[k]
        col = {n: a[:, i] for i, n in enumerate(names)}
        ids = col["id"].astype(int)
        index = np.full(ids.max() + 1, -1)
        index[ids] = np.arange(len(ids))
        col["_index"] = index
        return col

    def frame(self, k: int) -> Contacts:
        atoms = self.atom_table(k)
        idx = atoms["_index"]
        pos = np.stack([atoms["x"], atoms["y"], atoms["z"]], 1)
        om = np.stack([atoms["omegax"], atoms["omegay"], atoms["omegaz"]], 1)
        parts = []
        for wall, (_step, _, d) in ((False, self.pairs[k]), (True, self.walls[k])):
            H = d.shape[1] - 38
            if wall:
                i = idx[d[:, 14].astype(int)]
                j = None
                tj = np.full(len(d), self.script.mesh_type)
                rj = mj = np.full(len(d), np.nan)
                xj = d[:, 0:3]
                wj = np.zeros((len(d), 3))
                id2 = d[:, 13].astype(int)
            else:
                i = idx[d[:, 12].astype(int)]
                j = idx[d[:, 13].astype(int)]
                tj = atoms["type"][j].astype(int)
                rj, mj = atoms["radius"][j], atoms["mass"][j]
                xj = pos[j]
                wj = om[j]
                id2 = d[:, 13].astype(int)
            parts.append(dict(
                wall=np.full(len(d), wall), id1=atoms["id"][i].astype(int), id2=id2,
                ti=atoms["type"][i].astype(int), tj=tj, ri=atoms["radius"][i], rj=rj,
                mi=atoms["mass"][i], mj=mj, xi=pos[i], xj=xj, wi=om[i], wj=wj,
                delta=d[:, 34 + H], force=d[:, 15:18], fn=d[:, 18:21], ft=d[:, 21:24],
                torque=d[:, 24:27], hist=d[:, 33:33 + H]))
        Hmax = max(p["hist"].shape[1] for p in parts)
        for p in parts:  # pad so that pairs and walls stack (their layouts may differ)
            h = p["hist"]
            p["hist"] = np.hstack([h, np.full((len(h), Hmax - h.shape[1]), np.nan)])
        merged = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
        return Contacts(step=self.pairs[k][0], names=self.pair_names, wall_names=self.wall_names, **merged)


# --------------------------------------------------------------------------
# Material combinations (global_properties.cpp)
# --------------------------------------------------------------------------


def yeff(s: Script, ti, tj) -> np.ndarray:
    """Y* = 1/((1-nu_i^2)/E_i + (1-nu_j^2)/E_j) (global_properties.cpp:432)."""
    E, nu = s.per_type("youngsModulus"), s.per_type("poissonsRatio")
    return 1. / ((1. - nu[ti] ** 2.) / E[ti] + (1. - nu[tj] ** 2.) / E[tj])


def geff(s: Script, ti, tj) -> np.ndarray:
    """G* = 1/(2(2-nu_i)(1+nu_i)/E_i + 2(2-nu_j)(1+nu_j)/E_j) (global_properties.cpp:463)."""
    E, nu = s.per_type("youngsModulus"), s.per_type("poissonsRatio")
    return 1. / (2. * (2. - nu[ti]) * (1. + nu[ti]) / E[ti] + 2. * (2. - nu[tj]) * (1. + nu[tj]) / E[tj])


def _hooke_kn(s: Script, c: Contacts) -> np.ndarray:
    """normal_model_hooke.h:269: 16/15 sqrt(R*) Y* (15 m* V^2/(16 sqrt(R*) Y*))^(1/5)."""
    Y = yeff(s, c.ti, c.tj)
    sq = np.sqrt(c.reff)
    V = s.scalar("characteristicVelocity")
    return 16. / 15. * sq * Y * np.power(15. * c.meff * V * V / (16. * sq * Y), 0.2)


def normal_kn(s: Script, c: Contacts) -> np.ndarray:
    """The normal model's kn (sidata.kn), used by the tangential and rolling models."""
    m = s.normal
    if m in ("hertz", "thornton_ning"):
        return 4. / 3. * yeff(s, c.ti, c.tj) * np.sqrt(c.reff * c.delta)
    if m in ("hooke", "hooke/hysteresis"):
        return _hooke_kn(s, c)
    if m == "hertz/stiffness":
        return np.sqrt(c.reff * c.delta) * s.pair_table("kn")[c.ti, c.tj]
    if m == "hooke/stiffness":
        return s.pair_table("kn")[c.ti, c.tj]
    if m in ("luding", "edinburgh/stiffness"):
        return s.pair_table("LoadingStiffness")[c.ti, c.tj]
    if m == "edinburgh":
        assert s.scalar("overlapExponent") != 1
        return (4. / 3.) * yeff(s, c.ti, c.tj) * np.sqrt(c.reff)
    raise ValueError(m)


def tangential_kt(s: Script, c: Contacts) -> np.ndarray:
    """The tangential spring stiffness: the normal model's kt (times coeffFrictionStiffness for
    tan_luding, tangential_model_luding_tn.h:113)."""
    m = s.normal
    if m in ("hertz", "thornton_ning", "edinburgh"):
        kt = 8. * geff(s, c.ti, c.tj) * np.sqrt(c.reff * c.delta)      # normal_model_hertz.h:238
    elif m in ("hooke", "hooke/hysteresis"):
        kt = _hooke_kn(s, c)                                             # normal_model_hooke.h:270
    elif m == "hertz/stiffness":
        kt = np.sqrt(c.reff * c.delta) * s.pair_table("kt")[c.ti, c.tj]  # normal_model_hertz_stiffness.h:120
    elif m == "hooke/stiffness":
        kt = s.pair_table("kt")[c.ti, c.tj]
    elif m in ("luding", "edinburgh/stiffness"):
        kt = s.pair_table("LoadingStiffness")[c.ti, c.tj]                # kt = kn
    else:
        raise ValueError(m)
    if s.tangential == "tan_luding":
        kt = kt * s.pair_table("coeffFrictionStiffness")[c.ti, c.tj]
    return kt


# --------------------------------------------------------------------------
# Normal force and energy
# --------------------------------------------------------------------------


def _hysteresis_branch(k1, k2max, kc, phiF, reff, delta, dmax):
    """hooke/hysteresis and luding: (force, k2) from delta and the stored deltaMax
    (normal_model_hooke_hysteresis.h:150-198, normal_model_luding.h:141-177)."""
    dlim = (k2max / (k2max - k1)) * phiF * 2 * reff
    big = dmax >= dlim
    k2 = np.where(big, k2max, k1 + (k2max - k1) * dmax / dlim)
    f_big = k2max * (delta - dlim) + k1 * dlim
    f_small = k2 * (delta - dmax) + k1 * dmax
    f = np.where(big, np.where(f_big >= -kc * delta, f_big, -kc * delta),
                 np.where(f_small >= k1 * delta, k1 * delta,
                          np.where(f_small > -kc * delta, f_small, -kc * delta)))
    return f, k2


def _edinburgh(s: Script, c: Contacts):
    """edinburgh(/stiffness) without adhesion (fixKc off, surfaceEnergy 0): (force, k2, n, dp)
    from delta and the stored plastic overlap deltaMax (normal_model_edinburgh.h:200-312)."""
    n = s.scalar("overlapExponent")
    k1 = normal_kn(s, c)
    k2 = k1 * s.pair_table("UnloadingStiffness")[c.ti, c.tj]
    dp = c.h("deltaMax")
    de = np.power(c.delta, n)
    ftmp = k2 * (de - np.power(dp, n))
    f = np.where(ftmp >= k1 * de, k1 * de, ftmp)
    f = np.where(f < 0.0, 0.0, f)  # limitForce (on by default) with k_adh = 0, f_0 = 0
    return f, k2, n, dp


def normal_force(s: Script, c: Contacts) -> np.ndarray:
    """The elastic normal force (signed, repulsive > 0) LIGGGHTS applies, without cohesion."""
    m = s.normal
    if m in ("hertz", "hooke", "hertz/stiffness", "hooke/stiffness"):
        return normal_kn(s, c) * c.delta
    if m == "hooke/hysteresis":
        k1 = _hooke_kn(s, c)
        f, _ = _hysteresis_branch(k1, k1 * s.pair_table("coefficientMaxElasticStiffness")[c.ti, c.tj],
                                  k1 * s.pair_table("coefficientAdhesionStiffness")[c.ti, c.tj],
                                  s.pair_table("coefficientPlasticityDepth")[c.ti, c.tj], c.reff, c.delta,
                                  c.h("deltaMax"))
        return f
    if m == "luding":
        k1 = s.pair_table("LoadingStiffness")[c.ti, c.tj]
        kc = s.pair_table("coefficientAdhesionStiffness")[c.ti, c.tj] * k1
        f0 = s.pair_table("pullOffForce")[c.ti, c.tj]
        f, _ = _hysteresis_branch(k1, k1 * s.pair_table("UnloadingStiffness")[c.ti, c.tj], kc,
                                  s.pair_table("coefficientPlasticityDepth")[c.ti, c.tj], c.reff, c.delta,
                                  c.h("deltaMax"))
        f = f + f0
        return np.where((f < 0.0) & (kc == 0) & (f0 == 0.0), 0.0, f)  # limitForce, on by default
    if m in ("edinburgh", "edinburgh/stiffness"):
        return _edinburgh(s, c)[0]
    if m == "thornton_ning":
        # incremental: the force is path dependent and stored as force_old (history[3])
        return c.h("force_old")
    raise ValueError(m)


def normal_energy(s: Script, c: Contacts, force: np.ndarray | None = None) -> np.ndarray:
    """Elastic normal energy: the work the contact gives back when unloaded along the model's
    own unloading branch from the current state."""
    m = s.normal
    d = c.delta
    if m in ("hertz", "hertz/stiffness"):
        return 0.4 * normal_kn(s, c) * d * d            # 2/5 F delta
    if m in ("hooke", "hooke/stiffness"):
        return 0.5 * normal_kn(s, c) * d * d
    if m in ("hooke/hysteresis", "luding"):
        f = normal_force(s, c)
        if m == "luding":
            k1 = s.pair_table("LoadingStiffness")[c.ti, c.tj]
            k2max = k1 * s.pair_table("UnloadingStiffness")[c.ti, c.tj]
            phiF = s.pair_table("coefficientPlasticityDepth")[c.ti, c.tj]
        else:
            k1 = _hooke_kn(s, c)
            k2max = k1 * s.pair_table("coefficientMaxElasticStiffness")[c.ti, c.tj]
            phiF = s.pair_table("coefficientPlasticityDepth")[c.ti, c.tj]
        _, k2 = _hysteresis_branch(k1, k2max, 0.0, phiF, c.reff, d, c.h("deltaMax"))
        return np.where(f > 0, f * f / (2 * k2), 0.0)    # released along the current k2 line
    if m in ("edinburgh", "edinburgh/stiffness"):
        f, k2, n, dp = _edinburgh(s, c)
        u = k2 * ((np.power(d, n + 1) - np.power(dp, n + 1)) / (n + 1) - np.power(dp, n) * (d - dp))
        return np.where(f > 0, u, 0.0)
    if m == "thornton_ning":
        # Hertzian unloading (dF = 2 E* a ds, a = sqrt(R* s)) from the current force F:
        # F(s) = F + k (s^1.5 - delta^1.5), k = 4/3 E* sqrt(R*), released down to F = 0 or s = 0
        F = normal_force(s, c) if force is None else force
        k = 4. / 3. * yeff(s, c.ti, c.tj) * np.sqrt(c.reff)
        p15 = np.maximum(d ** 1.5 - F / k, 0.0)
        dp = p15 ** (2. / 3.)
        u = (F - k * d ** 1.5) * (d - dp) + k * (d ** 2.5 - dp ** 2.5) / 2.5
        return np.where(F > 0, u, 0.0)
    raise ValueError(m)


# --------------------------------------------------------------------------
# Tangential
# --------------------------------------------------------------------------


def shear(c: Contacts) -> np.ndarray:
    return c.h("shearx", 3)


def tangential_energy(s: Script, c: Contacts) -> np.ndarray:
    """½ k_t |shear|² (tangential_model_history.h:166-172: F_t = -k_t shear)."""
    sh = shear(c)
    return 0.5 * tangential_kt(s, c) * np.einsum("ij,ij->i", sh, sh)


def tangential_cap(s: Script, c: Contacts, fn: np.ndarray) -> np.ndarray:
    """The Coulomb limit of the spring force: mu |F_n| (history), the static one for tan_luding."""
    mu = s.pair_table("coefficientFriction")[c.ti, c.tj]
    if s.tangential == "tan_luding":
        kc, fo = c.h("kc"), c.h("fo")
        return mu * np.abs(fn + kc * c.delta - fo)
    return mu * np.abs(fn)


# --------------------------------------------------------------------------
# Rolling
# --------------------------------------------------------------------------


def rolling_kr(s: Script, c: Contacts) -> np.ndarray:
    r = s.rolling
    reff = c.reff
    if r in ("epsd", "epsd3"):
        rmu = s.pair_table("coefficientRollingFriction")[c.ti, c.tj]
        factor = 2.25 if r == "epsd" else s.scalar("rollingStiffness")
        return factor * normal_kn(s, c) * rmu * rmu * reff * reff   # rolling_model_epsd.h:299, epsd3.h:213
    if r == "epsd2":
        return tangential_kt(s, c) * reff * reff                      # rolling_model_epsd2.h:193
    if r == "luding":
        return tangential_kt(s, c) * s.pair_table("coeffRollingStiffness")[c.ti, c.tj] * reff * reff
    raise ValueError(r)


def rolling_history(c: Contacts) -> np.ndarray:
    return c.h("r_torquex_old", 3)


def rolling_energy(s: Script, c: Contacts) -> np.ndarray:
    if s.rolling in ("off", "cdt"):
        return np.zeros(len(c))
    m = rolling_history(c)
    return 0.5 * np.einsum("ij,ij->i", m, m) / rolling_kr(s, c)


def relative_rolling_omega(c: Contacts) -> np.ndarray:
    """omega_i - omega_j (pairs); cr omega_i / r for walls, cr = r_i - delta/2, r = r_i - delta
    (surface_model_default.h:176-180, fix_wall_gran_base.h:181-184)."""
    cr = c.ri - 0.5 * c.delta
    wall = (cr * (1.0 / (c.ri - c.delta)))[:, None] * c.wi
    return np.where(c.wall[:, None], wall, c.wi - c.wj)


def _tangential_part(w: np.ndarray, en: np.ndarray) -> np.ndarray:
    return w - en * np.einsum("ij,ij->i", w, en)[:, None]


def rolling_torque(s: Script, c: Contacts, fn: np.ndarray) -> np.ndarray:
    """The rolling torque r_torque LIGGGHTS subtracts from the torque on i when the compute
    re-evaluates the contact at output (no history update there, pair_gran.cpp:699-704).

    epsd/epsd2/epsd3 add the spring increment k_r dt wr_t to the stored torque again and cap
    it at mu_r |F_n| R*; luding stored its own (post-output) value; cdt is mu_r k_n delta R*
    along wr (torsion part removed). The rolling viscous terms are 0 in these runs."""
    r = s.rolling
    en = c.en
    rmu = s.pair_table("coefficientRollingFriction")[c.ti, c.tj]
    wr = relative_rolling_omega(c)
    if r == "cdt":
        mag = np.linalg.norm(wr, axis=1)
        t = (rmu * normal_kn(s, c) * c.delta * c.reff / np.where(mag > 0, mag, 1.0))[:, None] * wr
        return _tangential_part(t, en)
    if r == "luding":
        return rolling_history(c)
    t = rolling_history(c) + (s.dt * rolling_kr(s, c))[:, None] * _tangential_part(wr, en)
    mag = np.linalg.norm(t, axis=1)
    tmax = np.abs(fn) * c.reff * rmu
    factor = np.where(mag > tmax, tmax / np.where(mag > 0, mag, 1.0), 1.0)
    return t * factor[:, None]


def dumped_rolling_torque(c: Contacts) -> np.ndarray:
    """r_torque from the dumped torque on i: torque = -cr_i (en x F_t) - r_torque
    (tangential_model_history.h:229-233, rolling_model_*.h: delta_torque -= r_torque)."""
    cri = c.ri - 0.5 * c.delta
    return -c.torque - cri[:, None] * np.cross(c.en, c.ft)


# --------------------------------------------------------------------------
# Cohesion
# --------------------------------------------------------------------------

_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)


def cohesion_area(s: Script, c: Contacts, delta: np.ndarray | None = None) -> np.ndarray:
    """The area sjkr / sjkr2 multiply by the cohesion energy density (cohesion_model_sjkr.h:93-97,
    cohesion_model_sjkr2.h:93-97), at overlap ``delta`` (default: the contact's)."""
    d = c.delta if delta is None else delta
    ri, rj = c.ri, c.rj
    if s.cohesion == "sjkr":
        r = np.where(c.wall, ri - d, ri + rj - d)
        pair = -np.pi / 4 * ((r - ri - rj) * (r + ri - rj) * (r - ri + rj) * (r + ri + rj)) / (r * r)
        return np.where(c.wall, (ri * ri - r * r) * np.pi, pair)
    if s.cohesion == "sjkr2":
        return np.where(c.wall, np.pi * 2. * ri * d, np.pi * 2. * (2. * ri * rj / (ri + rj)) * d)
    raise ValueError(s.cohesion)


def cohesion_force(s: Script, c: Contacts) -> np.ndarray:
    """F_coh = -k A (signed along en: negative = attractive)."""
    return -s.pair_table("cohesionEnergyDensity")[c.ti, c.tj] * cohesion_area(s, c)


def cohesion_work(s: Script, c: Contacts) -> np.ndarray:
    """-k ∫_0^delta A(s) ds (negative): closed forms for sjkr2 and the sjkr wall
    (-k pi (r_i delta² - delta³/3)); for the sjkr lens area a 16-point Gauss-Legendre rule,
    exact to rounding here (A is smooth on [0, delta], its nearest singularity at s = r_i + r_j)."""
    k = s.pair_table("cohesionEnergyDensity")[c.ti, c.tj]
    d = c.delta
    if s.cohesion == "sjkr2":
        return -k * np.where(c.wall, np.pi * c.ri * d * d, 2. * np.pi * (2. * c.ri * c.rj / (c.ri + c.rj)) * d * d)
    nodes = 0.5 * d[:, None] * (_GL_X[None, :] + 1.0)
    integral = np.zeros(len(c))
    for q in range(len(_GL_X)):
        integral += _GL_W[q] * cohesion_area(s, c, nodes[:, q])
    integral *= 0.5 * d
    wall = np.pi * (c.ri * d * d - d ** 3 / 3.)
    return -k * np.where(c.wall, wall, integral)


# --------------------------------------------------------------------------
# Primitive zplane floor contacts, rebuilt from positions (never dumped)
# --------------------------------------------------------------------------


def primitive_floor_contacts(run: Run, k: int) -> dict[str, np.ndarray]:
    """Atoms touching the primitive zplane: id, type, radius, mass, delta = r - (z - z0)."""
    s = run.script
    a = run.atom_table(k)
    delta = a["radius"] - (a["z"] - s.primitive_z)
    sel = delta > 0
    return dict(id=a["id"][sel].astype(int), type=a["type"][sel].astype(int), radius=a["radius"][sel],
                mass=a["mass"][sel], delta=delta[sel])


def rel_err(a: np.ndarray, b: np.ndarray, scale: np.ndarray | float | None = None) -> np.ndarray:
    """|a - b| / scale (default |b|), elementwise."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    sc = np.abs(b) if scale is None else scale
    return np.abs(a - b) / sc


def floor_contacts(run: Run, k: int) -> Contacts:
    """The primitive-floor contacts of frame ``k`` as :class:`Contacts` (walls, no history,
    no forces: LIGGGHTS never dumps primitive walls); only history-free laws apply to them."""
    p = primitive_floor_contacts(run, k)
    a = run.atom_table(k)
    n = len(p["id"])
    i = a["_index"][p["id"]]
    pos = np.stack([a["x"], a["y"], a["z"]], 1)[i]
    foot = pos.copy()
    foot[:, 2] = run.script.primitive_z
    nan3 = np.full((n, 3), np.nan)
    om = np.stack([a["omegax"], a["omegay"], a["omegaz"]], 1)[i]
    return Contacts(step=run.atoms[k][0], wall=np.ones(n, bool), id1=p["id"], id2=np.full(n, -1),
                    ti=p["type"], tj=np.full(n, run.script.primitive_type), ri=p["radius"], rj=np.full(n, np.nan),
                    mi=p["mass"], mj=np.full(n, np.nan), xi=pos, xj=foot, wi=om, wj=np.zeros((n, 3)),
                    delta=p["delta"], hist=np.zeros((n, 0)), force=nan3, fn=nan3, ft=nan3, torque=nan3,
                    names=[], wall_names=[])
