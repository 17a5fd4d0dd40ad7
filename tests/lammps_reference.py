"""An independent numpy recomputation of the contacts of a LAMMPS GRANULAR run, for the tests.

For Debian's ``lmp`` (LAMMPS 29 Sep 2021 - Update 2, tag ``stable_29Sep2021_update2``); every formula is read from
that tag's source, cited as ``file:line``, never from demsplit's code. From a run's dumps (``compute pair/local`` +
``compute property/local`` rows, a ``%.17g`` atom dump with velocities, forces, torques and the wall fixes'
``contacts`` columns) and its input script, per contact: the elastic normal force, the damping term, the tangential
and rolling springs F_el, the force LAMMPS applied in the step, and the energy of every mode.

Notation: r_i, r_j radii, R = r_i r_j/(r_i + r_j) (a wall: r_i, or r_i r_w/(r_i + r_w) when curved), δ = r_i + r_j - r,
n = (x_i - x_j)/r, m* = m_i m_j/(m_i + m_j) (a wall: m_i), a = sqrt(R δ).

``pair_style granular`` (pair_granular.cpp), per type pair ``kn`` = normal_coeffs[0]:
- kn = k_n (hooke, hertz) or 4/3 E/(2(1 - ν²)) of the line's E, ν (hertz/material, dmt, jkr; coeff() :1006-1016,
  mix_stiffnessE :1780-1784); k_t NULL = 8 G = 2E/((2 - ν)(1 + ν)) (:1021-1024, mix_stiffnessG :1790-1794);
- elastic normal force (compute :328-358, single :1498-1525): hooke kn δ, hertz-like kn a δ, dmt kn a δ - 4πγR;
  jkr: a from LAMMPS' closed form, E = ¾ kn, F = kn a³/R - 2πa² sqrt(4γE/(πa));
- damping (:363-377): η_n = damp (tsuji: α(e) of coeff(), :986-993) times 1 (velocity), m* (mass_velocity),
  a m* (viscoelastic), sqrt(m* kn_fac) (tsuji; kn_fac = kn, or kn a, or kn a with jkr's a); F_n = F_ne - η_n v_n,
  clipped at 0 with limit_damping (:377);
- Coulomb limit (:412-421): F_ncrit = |F_ne + 6πγR| (jkr), |F_n| (others); dmt's |F_ne + 8πγR| reads γ from a
  variable only jkr sets (:416, single :1589): its limit is undefined and a dmt row capped in single() unknown;
- tangential (:423-546): η_t = x_γt η_n, k = k_t (linear_history), k_t a (mindlin*), 0 (linear_nohistory beside
  a history model: ``tangential_history`` is global, :900); the force applied in the step is F_el - η_t v_t with
  F_el the stored spring (-kξ, or the stored force for */force) after the step's Coulomb reset (:510-536);
- rolling sds (:550-616): F_r = F_r,el - γ_r v_r, v_r = R (ω_i - ω_j) × n, limit μ_r F_ncrit, torque R n × F_r;
- twisting (:620-646): torque τ n with τ from a spring that no dump holds (single() writes it only when capped,
  :1694-1716);
- torques (:649-693): -(r_i - δ/2) n × F_t on i, -(r_j - δ/2) n × F_t on j.
The dumped rows come from single() (:1375-1737) after the step, with the velocities then held: full-step for the
owned atom i, half-step for a ghost j (a periodic image on one process: verlet.cpp:254-352 integrates, forwards
ghosts, computes forces, then final_integrate updates owned atoms only before output), and svector (:1724-1735)
p1-p3 the tangential force, p5-p7 the rolling pseudo-force, p9 the capped twisting torque, p10-p12 x_i - x_j.

Legacy ``gran/hooke``, ``gran/hooke/history``, ``gran/hertz/history`` (pair_gran_hooke_history.cpp:244-330,
single :605-757; pair_gran_hertz_history.cpp:183-236; pair_gran_hooke.cpp:160-200): p = 1 or sqrt(R δ) (hertz),
F_n = p (kn δ - m* γn v_n), F_t = -p (kt ξ + m* γt v_t) limited to μ |F_n| (gran/hooke: -min(μ|F_n|, m* γt |v_t|)
t), torque -r n × F_t; kt NULL = 2/7 kn, γt NULL = γn/2, dampflag 0: γt = 0 (:360-380); single() writes p1-p3 F_t,
p5-p7 v_n n, p8-p10 v_t (:746-755).

Walls (fix_wall_gran.cpp): the same laws with m* = m_i, torque -r_i n × F_t (:840, :965, :1097, :1512), and for
``granular`` kn = 4/3 E/(2(1 - ν)) (:160, :171, :183), k_t NULL = E/4 (2 - ν)(1 + ν) (:248), tsuji applied once per
``init()``, i.e. once per ``run`` (:535-540); zcylinder: r_w = -2 R_cyl inside (:662), legacy hertz with the same
r_w (:1020-1021); a region cylinder's side -2 R (region_cylinder.cpp:297). The ``contacts`` array holds the force
of the step (normal + tangential) and the wall point; wall/gran/region keeps the last contact of a particle only
(fix_wall_gran_region.cpp:244-254). A rotating region's wall velocity is ω × (x_c - P), ω = Δθ/dt
(region.cpp:457-517).

Half-step velocities (fix_nve_sphere.cpp:117-135): v_h = v - dt/2 f/m, ω_h = ω - dt/2 τ/(0.4 m r²).

Energies: u_n = ½ kn δ² (hooke), 2/5 kn √R δ^{5/2} (hertz-like, dmt); jkr u_n = 8Ea⁵/(15R²) - 4Ea³Δ/(3R) + EaΔ²,
Δ = a²/R - δ, u_adh = -2πγa²; dmt u_adh = -4πγRδ; u_t = |F_el|²/(2k); u_r = |F_r,el|²/(2 k_r); legacy
u_n = ½ kn δ² or 2/5 kn √R δ^{5/2}, u_t = |F_el|²/(2 p kt).
"""

from __future__ import annotations

import ast
import gzip
import math
import operator
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

# ---------------------------------------------------------------------------------------------------- dumps


@dataclass
class Dump:
    """One frame of a LAMMPS text dump: its step, box bounds (3, 2), periodic flags and columns by name."""

    step: int
    box: np.ndarray
    periodic: np.ndarray
    columns: dict[str, np.ndarray]


def read_dump(path: Path) -> list[Dump]:
    """Every frame of a text dump (atom or local, plain or gzip-compressed)."""
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "rt") as fh:
        lines = fh.read().split("\n")
    frames, k = [], 0
    while k < len(lines) and lines[k].startswith("ITEM: TIMESTEP"):
        n = int(lines[k + 3])
        flags = lines[k + 4].split()[3:]
        box = np.array([[float(v) for v in lines[k + 5 + d].split()[:2]] for d in range(3)])
        names = lines[k + 8].split()[2:]
        values = np.array(" ".join(lines[k + 9 : k + 9 + n]).split(), dtype=float).reshape(n, len(names))
        frames.append(
            Dump(
                int(lines[k + 1]),
                box,
                np.array([f == "pp" for f in flags]),
                {name: values[:, c] for c, name in enumerate(names)},
            )
        )
        k += 9 + n
    return frames


# ---------------------------------------------------------------------------------------------------- script


def _alpha(e: float) -> float:
    """The tsuji damping coefficient of restitution e (pair_granular.cpp:986-993, fix_wall_gran.cpp:535-540)."""
    return 1.2728 - 4.2783 * e + 11.087 * e**2 - 22.348 * e**3 + 27.467 * e**4 - 18.022 * e**5 + 4.8218 * e**6


_OPS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.USub: operator.neg,
    ast.UAdd: operator.pos,
}


# LAMMPS' log() is log10, ln() the natural log (variable.cpp:3394-3413)
_FUNCTIONS = {"sqrt": math.sqrt, "ln": math.log, "log": math.log10}


def _arithmetic(formula: str) -> float:
    """An equal-style formula of numbers, + - * / ^, parentheses, PI, sqrt(), ln() and log() (what the samples and
    the official examples use)."""

    def ev(node: ast.AST) -> float:
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "PI":
            return math.pi
        if isinstance(node, ast.BinOp):
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp):
            return _OPS[type(node.op)](ev(node.operand))
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") in _FUNCTIONS:
            return _FUNCTIONS[node.func.id](ev(node.args[0]))
        raise ValueError(f"the reference does not evaluate {formula!r}")

    return ev(ast.parse(formula.replace("^", "**"), mode="eval").body)


class Script:
    """The commands of an input script, with ``${name}`` substituted as LAMMPS does (an equal-style number printed
    with %.15g, input.cpp substitute()); ``variables`` are the command line's ``-var`` values."""

    def __init__(self, path: Path, **variables: str):
        self.path = Path(path)
        self.vars: dict[str, tuple[str, str]] = {k: ("index", str(v)) for k, v in variables.items()}
        self.commands: list[list[str]] = []
        text = re.sub(r"&[ \t]*\n", " ", self.path.read_text())
        for line in text.split("\n"):
            words = self._substitute(line.split("#")[0]).split()
            if words and words[0] == "variable":
                name, style = words[1], words[2]
                if style in ("index", "string") and name in self.vars and self.vars[name][0] == "index":
                    continue  # an index variable is set once (the command line's value wins)
                self.vars[name] = (style, " ".join(words[3:]))
            elif words:
                self.commands.append(words)

    def _substitute(self, line: str) -> str:
        def value(match: re.Match) -> str:
            style, v = self.vars[match.group(1) or match.group(2)]
            return f"{_arithmetic(v):.15g}" if style == "equal" else v

        return re.sub(r"\$\{(\w+)\}|\$([A-Za-z])", value, line)

    def first(self, name: str) -> list[str]:
        return next(c for c in self.commands if c[0] == name)

    @property
    def ntypes(self) -> int:
        return int(self.first("create_box")[1])

    @property
    def dt(self) -> float:
        return float(self.first("timestep")[1])

    @property
    def newton(self) -> bool:
        return all(c[1] == "on" for c in self.commands if c[0] == "newton")

    def gravity(self) -> np.ndarray:
        """The acceleration of the last ``fix ID group gravity g vector x y z | spherical φ θ | chute angle``
        (fix_gravity.cpp:324-357, 3d)."""
        w = [c for c in self.commands if c[0] == "fix" and c[3] == "gravity"][-1]
        if w[5] == "vector":
            d = np.array([float(v) for v in w[6:9]])
            d /= np.linalg.norm(d)
        else:
            phi, theta = (0.0, 180.0 - float(w[6])) if w[5] == "chute" else (float(w[6]), float(w[7]))
            phi, theta = math.radians(phi), math.radians(theta)
            d = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
        return float(w[4]) * d

    def fix(self, fix_id: str) -> list[str]:
        return next(c for c in self.commands if c[0] == "fix" and c[1] == fix_id)

    def wall_fixes(self) -> list[str]:
        return [c[1] for c in self.commands if c[0] == "fix" and c[3] in ("wall/gran", "wall/gran/region")]

    def region(self, region_id: str) -> list[str]:
        return next(c for c in self.commands if c[0] == "region" and c[1] == region_id)

    def runs_after(self, fix_id: str) -> int:
        """How many ``run`` commands (each an init()) follow the definition of fix ``fix_id``."""
        at = next(k for k, c in enumerate(self.commands) if c[0] == "fix" and c[1] == fix_id)
        return sum(c[0] == "run" for c in self.commands[at:])

    def equal_formula(self, name: str) -> str:
        return self.vars[name][1]


# ---------------------------------------------------------------------------------------------------- models


@dataclass
class Model:
    """One contact model as LAMMPS holds it after parsing: a ``pair_coeff`` line of ``pair_style granular``, the
    ``granular`` words of a wall fix, or a legacy ``gran/*`` style (kind ``legacy/hooke`` etc.)."""

    normal: str
    kn: float = 0.0
    damp: float = 0.0
    cohesion: float = 0.0
    E: float = math.nan
    nu: float = math.nan
    damping: str = "viscoelastic"
    tangential: str = "none"
    kt: float = 0.0
    xgt: float = 0.0
    mu: float = 0.0
    rolling: str = "none"
    roll: tuple[float, float, float] = (0.0, 0.0, 0.0)
    twisting: str = "none"
    twist: tuple[float, float, float] = (0.0, 0.0, 0.0)
    limit_damping: bool = False
    legacy_gt: float = 0.0  # legacy: γt (γn is ``damp``)

    @property
    def legacy(self) -> bool:
        return self.normal.startswith("legacy/")


def parse_granular(words: list[str], wall: bool, ninit: int = 1) -> tuple[Model, list[str]]:
    """The model of ``granular`` words (pair_granular.cpp coeff() :781-980, fix_wall_gran.cpp :113-343) and the
    words left after it (a wall's geometry). ``ninit``: how many times a wall fix's init() converted tsuji."""
    m, k = Model(normal=""), 0
    while k < len(words):
        w = words[k]
        if w in ("hooke", "hertz"):
            m.normal, m.kn, m.damp = w, float(words[k + 1]), float(words[k + 2])
            k += 3
        elif w in ("hertz/material", "dmt", "jkr"):
            m.normal, m.E, m.damp, m.nu = w, float(words[k + 1]), float(words[k + 2]), float(words[k + 3])
            m.kn = 4 / 3 * m.E / (2 * (1 - m.nu)) if wall else 4 / 3 * m.E / (2 * (1 - m.nu**2))
            if w != "hertz/material":
                m.cohesion = float(words[k + 4])
            k += 4 if w == "hertz/material" else 5
        elif w == "damping":
            m.damping, k = words[k + 1], k + 2
        elif w == "tangential":
            m.tangential = words[k + 1]
            if m.tangential == "linear_nohistory":
                m.xgt, m.mu, k = float(words[k + 2]), float(words[k + 3]), k + 4
                continue
            if words[k + 2] == "NULL":
                m.kt = m.E / 4 * (2 - m.nu) * (1 + m.nu) if wall else 2 * m.E / ((2 - m.nu) * (1 + m.nu))
            else:
                m.kt = float(words[k + 2])
            m.xgt, m.mu, k = float(words[k + 3]), float(words[k + 4]), k + 5
        elif w in ("rolling", "twisting"):
            kind = words[k + 1]
            values = tuple(float(v) for v in words[k + 2 : k + 5]) if kind == "sds" else (0.0, 0.0, 0.0)
            if w == "rolling":
                m.rolling, m.roll = kind, values
            else:
                m.twisting, m.twist = kind, values
            k += 5 if kind == "sds" else 2
        elif w == "limit_damping":
            m.limit_damping, k = True, k + 1
        elif w == "cutoff":
            k += 2
        else:
            break
    if m.damping == "tsuji":
        for _ in range(ninit if wall else 1):
            m.damp = _alpha(m.damp)
    return m, words[k:]


def parse_legacy(kind: str, args: list[str]) -> tuple[Model, list[str]]:
    """``gran/<kind> kn kt γn γt μ dampflag [limit_damping]`` (pair_gran_hooke_history.cpp:361-380,
    fix_wall_gran.cpp:96-122; nktv2p = 1 in units si and lj)."""
    kn = float(args[0])
    kt = kn * 2 / 7 if args[1] == "NULL" else float(args[1])
    gn = float(args[2])
    gt = gn / 2 if args[3] == "NULL" else float(args[3])
    if int(args[5]) == 0:
        gt = 0.0
    limit = len(args) > 6 and args[6] == "limit_damping"
    return (
        Model(
            normal=f"legacy/{kind}",
            kn=kn,
            kt=kt,
            damp=gn,
            legacy_gt=gt,
            mu=float(args[4]),
            limit_damping=limit,
            tangential="none" if kind == "hooke" else "legacy",
        ),
        args[6 + limit :],
    )


def pair_models(script: Script, global_history: bool = True) -> dict[tuple[int, int], Model]:
    """The model of every type pair (1-based, both orders); only explicitly set pairs (mixing is refused).
    ``global_history=False`` reads linear_nohistory as its documented law, to show that LAMMPS did not."""
    style = script.first("pair_style")
    n, models = script.ntypes, {}
    if style[1].startswith("gran/"):
        model = parse_legacy(style[1][5:], style[2:])[0]  # gran/<kind>
        return {(i, j): model for i in range(1, n + 1) for j in range(1, n + 1)}
    for c in script.commands:
        if c[0] != "pair_coeff":
            continue
        model = parse_granular(c[3:], wall=False)[0]
        for i in _type_range(c[1], n):
            for j in _type_range(c[2], n):
                if j >= i:
                    models[(i, j)] = models[(j, i)] = model
    # the global flag: a linear_nohistory pair beside a history model runs the history branch with k_t = 0
    history = any(m.tangential not in ("linear_nohistory", "none") for m in models.values())
    if history and global_history:
        models = {
            k: replace(m, tangential="zero_spring") if m.tangential == "linear_nohistory" else m
            for k, m in models.items()
        }
    return models


def _type_range(word: str, n: int) -> range:
    if "*" not in word:
        return range(int(word), int(word) + 1)
    lo, hi = word.split("*")
    return range(int(lo) if lo else 1, (int(hi) if hi else n) + 1)


# ---------------------------------------------------------------------------------------------------- contact laws


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(_dot(a, a))


def jkr_radius(kn: float, coh: float, delta: np.ndarray, R: np.ndarray) -> np.ndarray:
    """LAMMPS' contact radius a(δ) of jkr (pair_granular.cpp:328-354), E = ¾ kn."""
    E = 0.75 * kn
    dR = delta * R
    R2, dR2 = R * R, dR * dR
    t0 = coh * coh * R2 * R2 * E
    t1 = 27 * math.pi**2 * t0
    t2 = 8 * dR * dR2 * E**3
    t3 = 4 * dR2 * E
    t4 = np.cbrt(t1 + t2 + 3 * math.sqrt(3) * math.pi * np.sqrt(np.maximum(0, t0 * (t1 + 2 * t2))))
    t5 = t3 / t4 + t4 / E
    t6 = np.sqrt(np.maximum(0, 2 * dR + t5))
    return (t6 + np.sqrt(np.maximum(0, 4 * dR - t5 + 6 * math.sqrt(6) * coh * math.pi * R2 / (E * t6)))) / math.sqrt(6)


def jkr_pulloff(kn: float, coh: float, R: np.ndarray) -> np.ndarray:
    """δ at pull-off, < 0 (pair_granular.cpp:1810-1820)."""
    E = 0.75 * kn
    a = np.cbrt(9 * math.pi * coh * R * R / (4 * E))
    return a * a / R - 2 * np.sqrt(math.pi * coh * a / E)


@dataclass
class Normal:
    """The normal part of contacts of one model: the elastic force F_ne, the contact radius a (legacy: the factor
    p), the damping coefficient η_n and the energies u_n, u_adh."""

    Fne: np.ndarray
    a: np.ndarray
    eta_n: np.ndarray
    u_n: np.ndarray
    u_adh: np.ndarray


def normal(m: Model, delta: np.ndarray, R: np.ndarray, meff: np.ndarray) -> Normal:
    """pair_granular.cpp:328-377 (fix_wall_gran.cpp:1170-1214) and the legacy styles' p, kn."""
    zero = np.zeros_like(delta)
    if m.legacy:
        p = np.sqrt(R * delta) if m.normal == "legacy/hertz/history" else np.ones_like(delta)
        u_n = 0.4 * m.kn * np.sqrt(R) * delta**2.5 if m.normal == "legacy/hertz/history" else 0.5 * m.kn * delta**2
        return Normal(p * m.kn * delta, p, p * meff * m.damp, u_n, zero)
    if m.normal == "jkr":
        E = 0.75 * m.kn
        a = jkr_radius(m.kn, m.cohesion, delta, R)
        Fne = m.kn * a**3 / R - 2 * math.pi * a * a * np.sqrt(4 * m.cohesion * E / (math.pi * a))
        knfac = m.kn * a
        D = a * a / R - delta
        u_n = 8 * E * a**5 / (15 * R * R) - 4 * E * a**3 * D / (3 * R) + E * a * D * D
        u_adh = -2 * math.pi * m.cohesion * a * a
    else:
        a = np.sqrt(R * delta)
        if m.normal == "hooke":
            Fne, knfac, u_n = m.kn * delta, np.full_like(delta, m.kn), 0.5 * m.kn * delta**2
        else:
            Fne, knfac, u_n = m.kn * a * delta, m.kn * a, 0.4 * m.kn * np.sqrt(R) * delta**2.5
        u_adh = -4 * math.pi * m.cohesion * R * delta if m.normal == "dmt" else zero
        if m.normal == "dmt":
            Fne = Fne - 4 * math.pi * m.cohesion * R
    damp = {
        "velocity": np.ones_like(delta),
        "mass_velocity": meff,
        "viscoelastic": a * meff,
        "tsuji": np.sqrt(meff * knfac),
    }[m.damping]
    return Normal(Fne, a, m.damp * damp, u_n, u_adh)


def normal_force(m: Model, nrm: Normal, vn: np.ndarray) -> np.ndarray:
    """F_n = F_ne - η_n v_n, clipped at 0 with limit_damping (pair_granular.cpp:376-377)."""
    F = nrm.Fne - nrm.eta_n * vn
    return np.maximum(F, 0) if m.limit_damping else F


def coulomb(m: Model, nrm: Normal, Fn: np.ndarray, R: np.ndarray) -> np.ndarray:
    """F_ncrit (pair_granular.cpp:412-421): jkr, dmt from the elastic force, the others from F_n."""
    if m.normal == "jkr":
        return np.abs(nrm.Fne + 6 * math.pi * m.cohesion * R)
    if m.normal == "dmt":
        return np.abs(nrm.Fne + 8 * math.pi * m.cohesion * R)
    return np.abs(Fn)


def spring_stiffness(m: Model, nrm: Normal) -> np.ndarray:
    """The tangential spring k: k_t, k_t a (mindlin*), p kt (legacy), 0 for linear_nohistory beside history."""
    if m.legacy:
        return m.kt * nrm.a
    if m.tangential.startswith("mindlin"):
        return m.kt * nrm.a
    return np.full_like(nrm.a, m.kt if m.tangential == "linear_history" else 0.0)


def tangential_damping(m: Model, nrm: Normal, meff: np.ndarray) -> np.ndarray:
    """η_t: x_γt η_n (pair_granular.cpp:427-428), legacy p m* γt."""
    return nrm.a * meff * m.legacy_gt if m.legacy else m.xgt * nrm.eta_n


def unsliding(
    p: np.ndarray, visc_s: np.ndarray, visc_h: np.ndarray, crit_s: np.ndarray, crit_h: np.ndarray, history: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The spring F_el from single()'s force p = F_el + visc_s limited to crit_s (visc: the damping force), the
    step having applied F_el + visc_h limited to crit_h with the spring reset to the limit (pair_granular.cpp:510-536).

    Not capped in single(): F_el = p - visc_s. Capped (|p| = crit_s): F_el = L w - visc_s, w = p/|p|, L > crit_s,
    and, if the step was capped too, |L w - D| = crit_h, D = visc_s - visc_h: L is that quadratic's larger root.
    A zero limit in the step (F_n clipped by limit_damping) reset the spring to F_el = -visc_h whatever single()
    saw; a zero limit in single() alone leaves p = 0 and the spring unknown. Returns F_el, the capped-in-single flag,
    the flag of a spring that cannot be rebuilt (no consistent capped step) and L. Without history F_el = 0."""
    mag = _norm(p)
    zero = crit_s == 0
    capped = history & (((mag >= crit_s * (1 - 1e-10)) & (mag > 0)) | zero)
    w = p / np.where(mag > 0, mag, 1)[:, None]
    D = visc_s - visc_h
    wD = _dot(w, D)
    disc = wD**2 - _dot(D, D) + crit_h**2
    L = wD + np.sqrt(np.maximum(disc, 0))
    bad = capped & (crit_h > 0) & (zero | (disc < 0) | (L < crit_s * (1 - 1e-10)))
    F_el = np.where(capped[:, None], L[:, None] * w - visc_s, p - visc_s)
    F_el = np.where((crit_h == 0)[:, None], -visc_h, F_el)
    if not history:
        F_el = np.zeros_like(p)
    return F_el, capped, bad, L


# ---------------------------------------------------------------------------------------------------- a frame


@dataclass
class Atoms:
    """The atoms of a frame (rows in id order) with their half-step velocities (fix_nve_sphere.cpp:117-135)."""

    ids: np.ndarray
    type: np.ndarray
    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    f: np.ndarray
    tq: np.ndarray
    r: np.ndarray
    m: np.ndarray
    v_half: np.ndarray
    w_half: np.ndarray
    dump: Dump

    @classmethod
    def of(cls, dump: Dump, dt: float) -> Atoms:
        c = dump.columns
        vec = lambda *names: np.stack([c[k] for k in names], -1)  # noqa: E731
        x, v, w = vec("x", "y", "z"), vec("vx", "vy", "vz"), vec("omegax", "omegay", "omegaz")
        f, tq, r, m = vec("fx", "fy", "fz"), vec("tqx", "tqy", "tqz"), c["radius"], c["mass"]
        return cls(
            c["id"].astype(np.int64),
            c["type"].astype(int),
            x,
            v,
            w,
            f,
            tq,
            r,
            m,
            v - 0.5 * dt * f / m[:, None],
            w - 0.5 * dt * tq / (0.4 * m * r * r)[:, None],
            dump,
        )

    def rows(self, ids: np.ndarray) -> np.ndarray:
        order = np.argsort(self.ids)
        return order[np.searchsorted(self.ids, ids, sorter=order)]


@dataclass
class Contacts:
    """Rebuilt contacts of one kind (pairs, or one wall fix) of a frame; per contact (row): atoms i, j (j = -1 for
    a wall), normal n (from j to i, a wall: from the wall to i), δ, R, the model's quantities and the forces and
    torques of the step, energies, and flags of what could not be rebuilt."""

    kind: str
    i: np.ndarray
    j: np.ndarray
    n: np.ndarray
    delta: np.ndarray
    R: np.ndarray
    Fne: np.ndarray
    Fdamp_s: np.ndarray  # damping term at single()'s (pairs) or the step's (walls) velocities
    Fn_rebuilt: np.ndarray  # the normal force that the dump holds, rebuilt
    Fn_dumped: np.ndarray
    F_step: np.ndarray  # force on i in the step (3)
    tq_i: np.ndarray  # torque on i in the step, twisting left out (3)
    tq_j: np.ndarray
    crit_h: np.ndarray  # the step's Coulomb limit of the tangential force
    Ft_step: np.ndarray
    F_el: np.ndarray
    Fr_el: np.ndarray
    energies: dict[str, np.ndarray]
    ghost: np.ndarray = None  # pairs: j a periodic image (half-step velocities in single())
    capped: np.ndarray = None  # capped in single(): F_el from the step's limit
    unknown: np.ndarray = None  # rule-flagged: the force of the step cannot be rebuilt (see Frame)
    twist: np.ndarray = None  # pairs with a twisting model: torque τ n unknown
    extra: dict = field(default_factory=dict)  # pairs: dumped columns, single()'s limit; walls: model, surfaces


def _tangential_velocity(dv, n, w_sum):
    """v_t - (r_i ω_i + r_j ω_j) × n (pair_granular.cpp:392-403)."""
    vt = dv - _dot(dv, n)[:, None] * n
    return vt - np.cross(w_sum, n)


def minimum_image(atoms: Atoms, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """x_i - x_j of the nearest periodic images."""
    d = atoms.x[i] - atoms.x[j]
    L = atoms.dump.box[:, 1] - atoms.dump.box[:, 0]
    return d - np.where(atoms.dump.periodic, np.round(d / L), 0) * L


def rebuild_pairs(script: Script, atoms: Atoms, local: Dump, models: dict) -> Contacts:
    """The pair rows of ``compute pair/local`` (+ ``property/local patom1 patom2 ptype1 ptype2``), granular or
    legacy, in the column order of the demsplit lines: c_dsL[1..4], c_dsP[1..]."""
    c = local.columns
    key = lambda s, k: c[f"c_ds{s}[{k}]"]  # noqa: E731
    i, j = atoms.rows(key("L", 1).astype(np.int64)), atoms.rows(key("L", 2).astype(np.int64))
    ti, tj = atoms.type[i], atoms.type[j]
    legacy = next(iter(models.values())).legacy
    dist, force = key("P", 1), key("P", 2)
    fvec = np.stack([key("P", k) for k in (3, 4, 5)], -1)
    p = {k: key("P", 5 + k) for k in range(1, 13 if not legacy else 11)}
    if legacy:  # no separation vector: the minimum image of the wrapped positions
        d = minimum_image(atoms, i, j)
    else:
        d = np.stack([p[10], p[11], p[12]], -1)
    ri, rj = atoms.r[i], atoms.r[j]
    R = ri * rj / (ri + rj)
    delta = ri + rj - dist
    # jkr: single() zeroes every value of a pair closer to pull-off than |δ_pulloff| (pair_granular.cpp:1423-1437)
    zeroed = np.zeros(len(i), bool)
    for (a, b), m in models.items():
        if m.normal == "jkr":
            sel = (ti == a) & (tj == b)
            zeroed[sel] = delta[sel] < -jkr_pulloff(m.kn, m.cohesion, R[sel])
    d = np.where(zeroed[:, None], minimum_image(atoms, i, j), d)
    ghost = np.any(d != atoms.x[i] - atoms.x[j], axis=1)
    n = d / dist[:, None]
    meff = atoms.m[i] * atoms.m[j] / (atoms.m[i] + atoms.m[j])
    # single(): i owned (full step), j a ghost (half step) for periodic images; the step: half step for both
    vj_s = np.where(ghost[:, None], atoms.v_half[j], atoms.v[j])
    wj_s = np.where(ghost[:, None], atoms.w_half[j], atoms.w[j])
    dv_s, dv_h = atoms.v[i] - vj_s, atoms.v_half[i] - atoms.v_half[j]
    dv_alt = atoms.v[i] - np.where(ghost[:, None], atoms.v[j], atoms.v_half[j])  # the other choice, to compare
    ws_s = ri[:, None] * atoms.w[i] + rj[:, None] * wj_s
    ws_h = ri[:, None] * atoms.w_half[i] + rj[:, None] * atoms.w_half[j]
    rot_s, rot_h = atoms.w[i] - wj_s, atoms.w_half[i] - atoms.w_half[j]

    N = len(i)
    out = {
        k: np.zeros(N)
        for k in ("Fne", "Fd", "Fn_s", "Fn_alt", "crit_s", "crit_h", "L", "u_n", "u_adh", "u_t", "u_r", "u_tw")
    }
    vecs = {k: np.zeros((N, 3)) for k in ("F_el", "Fr_el", "Ft_h", "Fr_h")}
    Fn_h = np.zeros(N)
    capped, twist = np.zeros(N, bool), np.zeros(N, bool)
    why = np.where(zeroed, "jkr_zeroed", "").astype(object)  # why a contact's step force cannot be rebuilt
    pt = np.stack([p[1], p[2], p[3]], -1)
    pr = np.stack([p[5], p[6], p[7]], -1) if not legacy else np.zeros((N, 3))
    for (a, b), m in models.items():
        sel = np.flatnonzero((ti == a) & (tj == b))
        if len(sel) == 0:
            continue
        s = sel
        nn = n[s]
        nrm = normal(m, delta[s], R[s], meff[s])
        vn_s, vn_h = _dot(dv_s[s], nn), _dot(dv_h[s], nn)
        Fn_s, Fn_hh = normal_force(m, nrm, vn_s), normal_force(m, nrm, vn_h)
        out["Fne"][s], out["Fd"][s], out["Fn_s"][s] = nrm.Fne, Fn_s - nrm.Fne, Fn_s
        out["Fn_alt"][s] = normal_force(m, nrm, _dot(dv_alt[s], nn))
        Fn_h[s] = Fn_hh
        crit_s = m.mu * coulomb(m, nrm, Fn_s, R[s])
        crit_h = m.mu * coulomb(m, nrm, Fn_hh, R[s])
        out["crit_s"][s], out["crit_h"][s] = crit_s, crit_h
        eta_t = tangential_damping(m, nrm, meff[s])
        vt_s = _tangential_velocity(dv_s[s], nn, ws_s[s])
        vt_h = _tangential_velocity(dv_h[s], nn, ws_h[s])
        if m.tangential in ("none", "linear_nohistory"):  # viscous only, limited (pair_gran_hooke.cpp:172-183)
            vmag = _norm(vt_h)
            ft = np.minimum(crit_h, eta_t * vmag) / np.where(vmag > 0, vmag, 1)
            vecs["Ft_h"][s] = -ft[:, None] * vt_h
        else:
            F_el, cap, bad, out["L"][s] = unsliding(
                pt[s],
                -eta_t[:, None] * vt_s,
                -eta_t[:, None] * vt_h,
                crit_s,
                crit_h,
                history=m.tangential != "zero_spring",
            )
            if m.tangential == "zero_spring":  # k_t = 0: -η_t v_t, and 0 once above the limit (:530-535)
                Ft = -eta_t[:, None] * vt_h
                vecs["Ft_h"][s] = np.where((_norm(Ft) > crit_h)[:, None], 0.0, Ft)
            else:
                vecs["F_el"][s], capped[s] = F_el, cap
                why[s[bad]] = "no_capped_step"
                vecs["Ft_h"][s] = F_el - eta_t[:, None] * vt_h
                k = spring_stiffness(m, nrm)
                out["u_t"][s] = _dot(F_el, F_el) / (2 * k)
        if m.rolling == "sds":
            kr, gr, mur = m.roll
            vr_s, vr_h = R[s, None] * np.cross(rot_s[s], nn), R[s, None] * np.cross(rot_h[s], nn)
            Fr_el, cap_r, bad_r, _ = unsliding(
                pr[s], -gr * vr_s, -gr * vr_h, mur * crit_s / m.mu, mur * crit_h / m.mu, history=True
            )
            vecs["Fr_el"][s], vecs["Fr_h"][s] = Fr_el, Fr_el - gr * vr_h
            capped[s] |= cap_r
            why[s[bad_r]] = "no_capped_step"
            out["u_r"][s] = _dot(Fr_el, Fr_el) / (2 * kr)
        if m.normal == "dmt":  # compute() and single() read an unset variable for γ in F_ncrit (:416, :1589): the
            why[s[capped[s]]] = "dmt_capped"  # step's limit is unknown, and so is a capped row's spring; the first
            why[s[s == 0]] = "dmt_first_row"  # row's limit is whatever the stack held (seen 0 and other values)
        twist[s] = m.twisting != "none"
        out["u_n"][s], out["u_adh"][s] = nrm.u_n, nrm.u_adh
        out["u_tw"][s] = np.nan if m.twisting != "none" else 0.0
    unknown = why != ""
    # what cannot be rebuilt is NaN: the step's tangential and rolling forces, their springs and energies
    for k in ("F_el", "Fr_el", "Ft_h", "Fr_h"):
        vecs[k][unknown] = np.nan
    out["u_t"][unknown] = out["u_r"][unknown] = np.nan
    F_step = Fn_h[:, None] * n + vecs["Ft_h"]
    arm_i, arm_j = (ri, rj) if legacy else (ri - delta / 2, rj - delta / 2)
    nxft = np.cross(n, vecs["Ft_h"])
    nxfr = R[:, None] * np.cross(n, vecs["Fr_h"])
    energies = {k: out[k] for k in ("u_n", "u_t", "u_r", "u_tw", "u_adh")}
    return Contacts(
        "pairs",
        i,
        j,
        n,
        delta,
        R,
        out["Fne"],
        out["Fd"],
        out["Fn_s"],
        force,
        F_step,
        -arm_i[:, None] * nxft + nxfr,
        -arm_j[:, None] * nxft - nxfr,
        out["crit_h"],
        vecs["Ft_h"],
        vecs["F_el"],
        vecs["Fr_el"],
        energies,
        ghost=ghost,
        capped=capped,
        unknown=unknown,
        twist=twist,
        extra={
            "fvec": fvec,
            "pt": pt,
            "pr": pr,
            "p9": p.get(9),
            "crit_s": out["crit_s"],
            "L": out["L"],
            "arm_i": arm_i,
            "arm_j": arm_j,
            "Fn_alt": out["Fn_alt"],
            "dv_s": dv_s,
            "p": p,
            "why": why,
        },
    )


def wall_geometry(
    script: Script, fix_id: str, x: np.ndarray, r: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For every atom: d (from the wall point to the centre), its length as LAMMPS computes it, the wall's curvature
    radius r_w (0 flat), the wall's velocity at the contact and the number of the region's surfaces within r
    (fix_wall_gran.cpp:633-671; regions: a cylinder or a plane, static or rotated)."""
    geo = wall_words(script, fix_id)[1]
    N = len(r)
    d, rw, vwall, nsurf = np.zeros((N, 3)), np.zeros(N), np.zeros((N, 3)), np.ones(N, int)
    if geo[0] in ("xplane", "yplane", "zplane"):
        ax = "xyz".index(geo[0][0])
        lo = -1e300 if geo[1] == "NULL" else float(geo[1])
        hi = 1e300 if geo[2] == "NULL" else float(geo[2])
        d1, d2 = x[:, ax] - lo, hi - x[:, ax]
        d[:, ax] = np.where(d1 < d2, d1, -d2)
        rest = geo[3:]
    elif geo[0] == "zcylinder":
        R = float(geo[1])
        rho = np.sqrt(x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1])
        delr = R - rho
        d[:, 0], d[:, 1] = -delr / rho * x[:, 0], -delr / rho * x[:, 1]
        rw = np.where(rho < R, -2 * R, 2 * R)
        rest = geo[2:]
    elif geo[0] == "region":
        reg = script.region(geo[1])
        if reg[2] == "plane":  # region_plane.cpp:80-93: the side the unit normal points to
            point, normal_ = np.array([float(v) for v in reg[3:6]]), np.array([float(v) for v in reg[6:9]])
            normal_ /= np.sqrt(normal_ @ normal_)
            dist = (x - point) @ normal_
            d = dist[:, None] * normal_
        else:
            assert reg[2] == "cylinder" and reg[3] in "xyz", reg
            d, dist, rw, nsurf = _region_cylinder(reg, x, r)
        if "rotate" in reg:
            k = reg.index("rotate")
            point = np.array([float(v) for v in reg[k + 2 : k + 5]])
            axis = np.array([float(v) for v in reg[k + 5 : k + 8]])
            omega = region_angular_velocity(script, reg[k + 1][2:]) * axis / np.linalg.norm(axis)
            vwall = np.cross(omega, (x - d) - point)
        rest = []
    else:
        raise ValueError(f"wall geometry {geo[0]} is not in the reference")
    if "shear" in rest:
        k = rest.index("shear")
        vwall[:, "xyz".index(rest[k + 1])] = float(rest[k + 2])
    if geo[0] != "region":
        dist = np.sqrt(_dot(d, d))  # fix_wall_gran.cpp:671, :1145; a region's distance is its contact's r
    return d, dist, rw, vwall, nsurf


def _region_cylinder(reg: list[str], x: np.ndarray, r: np.ndarray):
    """d, its length, r_w and the number of surfaces touched for a ``side in`` region cylinder: the side, then
    the lo and hi caps, the last touched kept (region_cylinder.cpp:274-420, fix_wall_gran_region.cpp:244-254)."""
    N = len(r)
    ax = "xyz".index(reg[3])
    c1, c2, Rc, lo, hi = (float(v) for v in reg[4:9])
    other = [k for k in range(3) if k != ax]
    e1, e2 = x[:, other[0]] - c1, x[:, other[1]] - c2
    rho = np.sqrt(e1 * e1 + e2 * e2)
    side = np.zeros((N, 3))
    side[:, other[0]], side[:, other[1]] = e1 * (1 - Rc / rho), e2 * (1 - Rc / rho)
    caps = [(x[:, ax] - lo, 1.0), (hi - x[:, ax], -1.0)]
    near = [Rc - rho < r] + [c < r for c, _ in caps]
    d = np.where(near[0][:, None], side, 0.0)
    dist = np.where(near[0], Rc - rho, 0.0)
    rw = np.where(near[0], -2 * Rc, 0.0)
    for (gap, sign), touch in zip(caps, near[1:]):
        cap = np.zeros((N, 3))
        cap[:, ax] = sign * gap
        d = np.where(touch[:, None], cap, d)
        dist = np.where(touch, gap, dist)
        rw = np.where(touch, 0.0, rw)
    return d, dist, rw, sum(k.astype(int) for k in near)


def region_angular_velocity(script: Script, variable: str) -> float:
    """dθ/dt of ``variable NAME equal 2*PI*elapsed/P`` or ``2*PI*(step-S)/P``, θ in steps (the drum's forms;
    region.cpp:473-483 differentiates θ over one step)."""
    formula = script.equal_formula(variable).replace(" ", "")
    match = re.fullmatch(r"2\*PI\*(elapsed|\(step-[0-9]+\))/([0-9.eE+-]+)", formula)
    assert match, f"the reference knows θ = 2*PI*elapsed/P and 2*PI*(step-S)/P only, not {formula}"
    return 2 * math.pi / float(match.group(2)) / script.dt


def wall_words(script: Script, fix_id: str) -> tuple[Model, list[str]]:
    """The model of wall fix ``fix_id`` and the words after it (geometry, ``shear``, ``contacts``)."""
    args = script.fix(fix_id)[4:]
    if args[0] == "granular":
        return parse_granular(args[1:], wall=True, ninit=script.runs_after(fix_id))
    return parse_legacy(args[0], args[1:])


def rebuild_wall(script: Script, atoms: Atoms, fix_id: str) -> Contacts:
    """The contacts of wall fix ``fix_id`` from its ``contacts`` columns f_ID[1..8] (force of the step)."""
    c = atoms.dump.columns
    touching = c[f"f_{fix_id}[1]"] == 1
    i = np.flatnonzero(touching)
    F = np.stack([c[f"f_{fix_id}[{k}]"][i] for k in (2, 3, 4)], -1)
    m = wall_words(script, fix_id)[0]
    d, dist, rw, vwall, nsurf = wall_geometry(script, fix_id, atoms.x[i], atoms.r[i])
    n = d / dist[:, None]
    ri = atoms.r[i]
    R = np.where(rw == 0, ri, ri * rw / (ri + np.where(rw == 0, 1, rw)))
    delta = ri - dist
    meff = atoms.m[i]
    nrm = normal(m, delta, R, meff)  # legacy hertz: polyhertz with the wall's curvature (fix_wall_gran.cpp:1020-1023)
    dv = atoms.v_half[i] - vwall
    vn = _dot(dv, n)
    Fn = normal_force(m, nrm, vn)
    Fn_dumped = _dot(F, n)
    Ft = F - Fn_dumped[:, None] * n
    crit = m.mu * coulomb(m, nrm, Fn, R)
    vt = _tangential_velocity(dv, n, ri[:, None] * atoms.w_half[i])
    eta_t = tangential_damping(m, nrm, meff)
    F_el = Ft + eta_t[:, None] * vt
    u_t = np.zeros(len(i))
    if m.tangential not in ("none", "linear_nohistory"):
        u_t = _dot(F_el, F_el) / (2 * spring_stiffness(m, nrm))
    else:
        F_el = np.zeros_like(F_el)
    unknown_modes = np.nan if (m.rolling != "none" or m.twisting != "none") else 0.0
    energies = {
        "u_n": nrm.u_n,
        "u_t": u_t,
        "u_r": np.full(len(i), unknown_modes if m.rolling != "none" else 0.0),
        "u_tw": np.full(len(i), unknown_modes if m.twisting != "none" else 0.0),
        "u_adh": nrm.u_adh,
    }
    tq = -ri[:, None] * np.cross(n, Ft)
    return Contacts(
        f"wall:{fix_id}",
        i,
        -np.ones(len(i), int),
        n,
        delta,
        R,
        nrm.Fne,
        Fn - nrm.Fne,
        Fn,
        Fn_dumped,
        F,
        tq,
        np.zeros_like(tq),
        crit,
        Ft,
        F_el,
        np.zeros_like(F_el),
        energies,
        unknown=nsurf > 1,
        extra={"model": m, "nsurf": nsurf},
    )


# ---------------------------------------------------------------------------------------------------- a run


@dataclass
class Frame:
    """One frame of a sample: its atoms, rebuilt pairs and walls, and the per-atom sums."""

    step: int
    atoms: Atoms
    pairs: Contacts
    walls: list[Contacts]
    gravity: np.ndarray


class Run:
    """A sample folder: ``in.<name>`` and the dumps ``<prefix>atoms.txt(.gz)`` and ``<prefix>pairs.txt(.gz)``."""

    def __init__(self, folder: Path, script: str, prefix: str = "", **variables: str):
        self.folder = Path(folder)
        self.script = Script(self.folder / script, **variables)
        self.models = pair_models(self.script)
        self.atom_dumps = read_dump(_existing(self.folder / f"{prefix}atoms.txt"))
        self.pair_dumps = read_dump(_existing(self.folder / f"{prefix}pairs.txt"))
        assert [d.step for d in self.atom_dumps] == [d.step for d in self.pair_dumps]

    def frames(self, models: dict | None = None):
        g = self.script.gravity()
        for ad, pd in zip(self.atom_dumps, self.pair_dumps):
            atoms = Atoms.of(ad, self.script.dt)
            walls = [rebuild_wall(self.script, atoms, w) for w in self.script.wall_fixes()]
            yield Frame(ad.step, atoms, rebuild_pairs(self.script, atoms, pd, models or self.models), walls, g)


def _existing(path: Path) -> Path:
    gz = path.with_name(path.name + ".gz")
    return gz if gz.exists() else path


# ---------------------------------------------------------------------------------------------------- balances


def jkr_necks(frame: Frame, models: dict) -> np.ndarray:
    """Pairs (rows i, j) of jkr type pairs apart by less than |δ_pulloff| (δ_pulloff < δ <= 0): each may be a neck
    still attached (the touch flag is in no dump, pair_granular.cpp:266-286) and is absent from ``cutoff radius``
    rows."""
    at = frame.atoms
    jkr = {k: m for k, m in models.items() if m.normal == "jkr"}
    if not jkr:
        return np.zeros((0, 2), int)
    i, j = np.triu_indices(len(at.ids), 1)
    d = _norm(minimum_image(at, i, j))
    radsum = at.r[i] + at.r[j]
    near = np.zeros(len(i), bool)
    for (a, b), m in jkr.items():
        sel = (at.type[i] == a) & (at.type[j] == b)
        R = at.r[i] * at.r[j] / radsum
        near |= sel & (d >= radsum) & (d < radsum - jkr_pulloff(m.kn, m.cohesion, R))
    return np.stack([i[near], j[near]], -1)


def atom_sums(frame: Frame, models: dict) -> dict[str, np.ndarray]:
    """Per atom: the force and torque of every rebuilt contact summed (+ gravity), and the scales Σ|terms|; NaN
    where a contact's force cannot be rebuilt (``Contacts.unknown``) or a jkr neck may act."""
    at = frame.atoms
    N = len(at.ids)
    F, T = np.zeros((N, 3)), np.zeros((N, 3))
    Fs, Ts = np.zeros(N), np.zeros(N)
    for atom in jkr_necks(frame, models).T:
        F[atom] = T[atom] = np.nan
    p = frame.pairs
    for idx, sign, tq in ((p.i, 1.0, p.tq_i), (p.j, -1.0, p.tq_j)):
        np.add.at(F, idx, sign * p.F_step)
        np.add.at(T, idx, tq)
        np.add.at(Fs, idx, _norm(p.F_step))
        np.add.at(Ts, idx, _norm(tq))
    for w in frame.walls:
        np.add.at(F, w.i, w.F_step)
        np.add.at(T, w.i, w.tq_i)
        np.add.at(Fs, w.i, _norm(w.F_step))
        np.add.at(Ts, w.i, _norm(w.tq_i))
        F[w.i[w.unknown]] = T[w.i[w.unknown]] = np.nan  # a region wall's other contacts: not in the dump
    weight = at.m[:, None] * frame.gravity
    F += weight
    Fs += _norm(weight)
    return {"F": F, "T": T, "F_scale": Fs, "T_scale": Ts}


def torque_unknown_atoms(frame: Frame) -> np.ndarray:
    """Atoms whose torque has a term no dump holds beside the pairs' twisting: a wall contact of a wall fix with
    a rolling or twisting model (the ``contacts`` array holds forces only)."""
    out = np.zeros(len(frame.atoms.ids), bool)
    for w in frame.walls:
        m = w.extra["model"]
        if m.rolling != "none" or m.twisting != "none":
            out[w.i] = True
    return out


def solve_twisting(frame: Frame, sums: dict) -> dict:
    """The pairs' twisting torques τ (torque τ n on i, -τ n on j) that close the torque balance of the atoms with
    no other unknown, by sparse least squares: the torque balance holds iff the residual vanishes. Returns τ per
    twisting pair, the atoms' relative residual (NaN for the atoms left out) and the number of unknowns."""
    at, p = frame.atoms, frame.pairs
    N = len(at.ids)
    keep = ~torque_unknown_atoms(frame) & ~np.isnan(sums["T"]).any(1)
    rows = -np.ones(N, int)
    rows[keep] = np.arange(keep.sum())
    cols = np.flatnonzero(p.twist & ~np.isnan(p.n).any(1))
    r, c, v = [], [], []
    for sign, atom in ((1.0, p.i[cols]), (-1.0, p.j[cols])):
        ok = keep[atom]
        for k in range(3):
            r.append(3 * rows[atom[ok]] + k)
            c.append(np.flatnonzero(ok))
            v.append(sign * p.n[cols[ok], k])
    b = (at.tq - sums["T"])[keep].reshape(-1)
    tau = np.zeros(len(cols))
    if len(cols):
        A = scipy.sparse.csr_matrix(
            (np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(len(b), len(cols))
        )
        tau = scipy.sparse.linalg.lsqr(A, b, atol=1e-16, btol=1e-16, iter_lim=20 * len(cols))[0]
        b = b - A @ tau
    scale = sums["T_scale"].copy()
    np.add.at(scale, p.i[cols], np.abs(tau))
    np.add.at(scale, p.j[cols], np.abs(tau))
    rel = np.full(N, np.nan)
    rel[keep] = _norm(b.reshape(-1, 3)) / np.maximum(scale[keep], 1e-300)
    return {"tau": tau, "cols": cols, "rel": rel, "unknowns": len(cols)}


def resolve_intervals(frame: Frame, sums: dict, tol: float) -> list[dict]:
    """Close the force balance of atoms that fail it (relative residual > tol) through the contacts capped in
    single() whose step was not capped (``unsliding``: then L lies in (crit_s, L*], L* the capped-step root): by
    least squares over every such contact of a failing atom, the atoms' residuals are Σ ΔL w (on i; -ΔL w on j),
    w single()'s direction. Updates ``sums`` (forces and torques) and returns per contact with ΔL != 0 its row,
    ΔL, the new L and whether it lies in the interval with the step below its limit."""
    at, p = frame.atoms, frame.pairs
    res = at.f - sums["F"]
    bad = _norm(res) > tol * sums["F_scale"]
    cand = np.flatnonzero(p.capped & ~p.unknown & (bad[p.i] | bad[p.j]))
    if len(cand) == 0:
        return []
    atoms = np.unique(np.concatenate([p.i[cand], p.j[cand]]))
    row = {a: k for k, a in enumerate(atoms)}
    w = p.extra["pt"][cand] / _norm(p.extra["pt"][cand])[:, None]
    A = np.zeros((3 * len(atoms), len(cand)))
    for col, c in enumerate(cand):
        A[3 * row[p.i[c]] : 3 * row[p.i[c]] + 3, col] = w[col]
        A[3 * row[p.j[c]] : 3 * row[p.j[c]] + 3, col] = -w[col]
    dL = np.linalg.lstsq(A, res[atoms].reshape(-1), rcond=None)[0]
    out = []
    for col, c in enumerate(cand):
        dF = dL[col] * w[col]
        sums["F"][p.i[c]] += dF
        sums["F"][p.j[c]] -= dF
        nxd = np.cross(p.n[c], dF)
        sums["T"][p.i[c]] -= p.extra["arm_i"][c] * nxd
        sums["T"][p.j[c]] -= p.extra["arm_j"][c] * nxd
        if abs(dL[col]) > tol * p.crit_h[c]:
            L = p.extra["L"][c] + dL[col]
            below = np.linalg.norm(p.Ft_step[c] + dF) <= p.crit_h[c] * (1 + 1e-9)
            out.append(
                {
                    "row": int(c),
                    "dL": float(dL[col]),
                    "L": float(L),
                    "ok": bool(p.extra["crit_s"][c] * (1 - 1e-9) <= L <= p.extra["L"][c] * (1 + 1e-9) and below),
                }
            )
    return out
