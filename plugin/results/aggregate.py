"""Statistics of per-particle energies: pure functions of the result DataFrames.

Every function takes the tidy tables of :class:`demsplit.results.Results` and
returns a new tidy DataFrame (one row per group). With ``by_frame=True`` (the
default) each frame is summarised on its own (groups include ``step``); with
``by_frame=False`` all rows of all frames are pooled into one distribution
per group (energies are then particle-frame observations).

Distribution statistics of a sample x_1..x_n (:func:`distribution_stats`):

- ``count`` n, ``total`` = sum x_i, ``mean`` = total/n,
- ``std`` = sqrt(sum (x_i - mean)^2 / n) (population spread, ddof = 0: the
  particles present, not an estimate of a larger population),
- ``p05 p25 p50 p75 p95``: quantiles by linear interpolation between order
  statistics (numpy's default, Hyndman & Fan type 7),
- ``top1_share``, ``top10_share``: the fraction of the total held by the
  ceil(0.01 n) and ceil(0.10 n) largest values (at least one value),
- ``gini`` = sum_i (2i - n - 1) x_(i) / (n sum x), x_(i) sorted ascending,
  i = 1..n: 0 when every particle holds the same energy, (n-1)/n when one
  particle holds all of it.

Empty groups and groups with zero total give NaN for the ratios.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from ..errors import DemsplitError
from ..physics.modes import ADHESION_COLUMN, MODE_COLUMNS

QUANTILES = {"p05": 0.05, "p25": 0.25, "p50": 0.50, "p75": 0.75, "p95": 0.95}
TOP_FRACTIONS = {"top1_share": 0.01, "top10_share": 0.10}
STAT_COLUMNS = ("count", "total", "mean", "std", *QUANTILES, *TOP_FRACTIONS, "gini")

SPLITS = {"material": "u", "equal": "u_equal", "radius": "u_radius", "springs": "u_springs"}
"""The distribution rules compared by :func:`split_comparison`: the material
(Feng & Gao) law, the 50/50 split (LAMMPS pe/atom, Kratos), the
radius-weighted split (Aspherix) and, for YADE's linear law only, the
series-spring split its own stiffness implies (reported when the column is present)."""

DEFAULT_SIZE_BINS = 8
"""Number of log-spaced radius classes between the smallest and the largest
radius when :func:`per_size` is given no bins."""


def gini(x: np.ndarray) -> float:
    """Gini coefficient G = sum_i (2i - n - 1) x_(i) / (n sum x) of values
    ``x`` >= 0 (x_(i) ascending, i = 1..n); NaN if n = 0 or sum x = 0."""
    x = np.sort(np.asarray(x, dtype=np.float64))
    n = len(x)
    total = x.sum()
    if n == 0 or total == 0:
        return math.nan
    i = np.arange(1, n + 1)
    return float(np.sum((2 * i - n - 1) * x) / (n * total))


def top_share(x: np.ndarray, fraction: float) -> float:
    """Fraction of sum x held by the ceil(fraction * n) largest values (at least one)."""
    x = np.asarray(x, dtype=np.float64)
    n = len(x)
    total = x.sum()
    if n == 0 or total == 0:
        return math.nan
    k = max(1, math.ceil(fraction * n))
    return float(np.sort(x)[n - k :].sum() / total)


def distribution_stats(x: np.ndarray) -> dict[str, float]:
    """The statistics of the module docstring for one sample ``x``."""
    x = np.asarray(x, dtype=np.float64)
    n = len(x)
    out: dict[str, float] = {"count": n, "total": float(x.sum())}
    if n == 0:
        out.update({name: math.nan for name in STAT_COLUMNS[2:]})
        return out
    out["mean"] = out["total"] / n
    out["std"] = float(x.std())
    qs = np.quantile(x, list(QUANTILES.values()))
    out.update({name: float(q) for name, q in zip(QUANTILES, qs)})
    out.update({name: top_share(x, f) for name, f in TOP_FRACTIONS.items()})
    out["gini"] = gini(x)
    return out


def grouped_stats(df: pd.DataFrame, keys: Sequence[str], value: str) -> pd.DataFrame:
    """:func:`distribution_stats` of column ``value`` for each group of ``keys``
    (sorted by the keys); one row per group, columns ``keys`` + STAT_COLUMNS."""
    _require(df, [*keys, value], "particles")
    keys = list(keys)
    rows = []
    if not keys:
        rows.append(distribution_stats(df[value].to_numpy()))
    else:
        for key, sub in df.groupby(keys, sort=True)[value]:
            rows.append({**dict(zip(keys, key)), **distribution_stats(sub.to_numpy())})
    out = pd.DataFrame(rows, columns=[*keys, *STAT_COLUMNS])
    out["count"] = out["count"].astype(np.int64)
    for k in keys:
        out[k] = out[k].astype(df[k].dtype)
    return out


def per_type(particles: pd.DataFrame, value: str = "u", *, by_frame: bool = True) -> pd.DataFrame:
    """Statistics of ``value`` (J) per particle type, plus ``share_of_total``:
    the type's total over the total of all types (of that frame if by_frame), ``n_not_computed`` (the
    particles of the type with a value not computed: the statistics hold their known part; with the
    particles' ``not_computed`` column), and, when the particles
    carry ``u_n_error``, ``expected_error``: the type's expected normal-energy error over its total
    (the energy-weighted expected error of the split, from the finite-element model, docs/accuracy.md)."""
    keys = ["step", "type"] if by_frame else ["type"]
    out = grouped_stats(particles, keys, value)
    whole = out.groupby("step")["total"].transform("sum") if by_frame else out["total"].sum()
    with np.errstate(invalid="ignore", divide="ignore"):
        out["share_of_total"] = out["total"] / whole
    if "not_computed" in particles:
        unknown = particles.assign(n_not_computed=particles["not_computed"] != 0)
        counts = unknown.groupby(keys, sort=True)["n_not_computed"].sum().reset_index()
        out = out.merge(counts, on=keys, how="left")
        out["n_not_computed"] = out["n_not_computed"].astype(np.int64)
    if "u_n_error" in particles and value == "u":
        err = particles.groupby(keys, sort=True)["u_n_error"].sum().rename("err").reset_index()
        err = out[keys].merge(err, on=keys, how="left")["err"].to_numpy()
        with np.errstate(invalid="ignore", divide="ignore"):
            out["expected_error"] = err / out["total"].to_numpy()
    return out


def size_bins(radius: np.ndarray, bins=None) -> np.ndarray:
    """Edges (m, ascending) of the radius classes.

    ``bins``: ``None`` (DEFAULT_SIZE_BINS log-spaced classes), an int N or
    ``"log:N"`` (N classes, edges geomspace(r_min, r_max, N+1)),
    ``"linear:N"`` (linspace), ``"quantile:N"`` (edges at the quantiles
    k/N of the radii; repeated edges, as with a few discrete sizes, are merged,
    so there may be fewer classes), or an explicit sequence of edges.
    """
    r = np.asarray(radius, dtype=np.float64)
    if isinstance(bins, (list, tuple, np.ndarray)):
        edges = np.asarray(bins, dtype=np.float64)
        if edges.ndim != 1 or len(edges) < 2 or np.any(np.diff(edges) <= 0):
            raise DemsplitError(
                f"size bin edges must be an increasing sequence of at least 2 radii, got {bins!r}.",
                fix="pass ascending edges in metres, e.g. [0.001, 0.002, 0.004].",
            )
        return edges
    if len(r) == 0:
        return np.array([0.0, 0.0])
    kind, n = "log", DEFAULT_SIZE_BINS
    if isinstance(bins, (int, np.integer)):
        n = int(bins)
    elif isinstance(bins, str):
        kind, _, count = bins.partition(":")
        try:
            n = int(count) if count else DEFAULT_SIZE_BINS
        except ValueError:
            n = 0
    elif bins is not None:
        raise DemsplitError(
            f"cannot use {bins!r} as size bins.",
            fix="pass an int, 'log:N', 'linear:N', 'quantile:N' or a sequence of edges.",
        )
    if n < 1 or kind not in ("log", "linear", "quantile"):
        raise DemsplitError(
            f"cannot use {bins!r} as size bins.",
            fix="pass an int >= 1, 'log:N', 'linear:N', 'quantile:N' or a sequence of edges.",
        )
    lo, hi = r.min(), r.max()
    if kind == "quantile":
        return np.unique(np.quantile(r, np.linspace(0.0, 1.0, n + 1)))
    if kind == "log":
        if lo <= 0:
            raise DemsplitError(
                f"log-spaced size bins need radii > 0, found a radius of {lo!r} m.",
                fix="pass bins='linear:N' or explicit edges.",
            )
        return np.geomspace(lo, hi, n + 1) if hi > lo else np.array([lo, hi])
    return np.linspace(lo, hi, n + 1) if hi > lo else np.array([lo, hi])


def size_class(radius: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Index k of the class [edges[k], edges[k+1]) of each radius (the last class
    includes its upper edge). A radius outside the edges is an error."""
    r = np.asarray(radius, dtype=np.float64)
    k = np.searchsorted(edges, r, side="right") - 1
    n = max(len(edges) - 1, 1)
    k[r == edges[-1]] = n - 1
    outside = (r < edges[0]) | (r > edges[-1])
    if outside.any():
        raise DemsplitError(
            f"{int(outside.sum())} particle(s) have radii outside the size bins "
            f"[{edges[0]:.6g}, {edges[-1]:.6g}] m (e.g. {r[outside][0]:.6g} m).",
            fix="widen the bin edges to cover every radius, or let demsplit choose them.",
        )
    return k


def elastic_columns(table: pd.DataFrame) -> list[str]:
    """The elastic mode columns ``table`` has (``u_n u_t``, and ``u_r u_tw`` where the laws have them),
    in mode order: their sum is the elastic total."""
    return [c for c in MODE_COLUMNS if c in table]


def energy_columns(table: pd.DataFrame) -> list[str]:
    """The elastic mode columns of ``table`` and, when present, the cohesion work ``u_adh``."""
    return elastic_columns(table) + ([ADHESION_COLUMN] if ADHESION_COLUMN in table else [])


def per_clump(particles: pd.DataFrame) -> pd.DataFrame:
    """Energy of each rigid clump per frame (YADE): the sums of ``u``, every mode
    column (J) and ``n_contacts`` over the clump's member spheres (``clump``
    column, -1 for free particles, which are left out), with ``n_members``."""
    _require(particles, ["clump", "u", "u_n", "u_t", "n_contacts"], "particles")
    members = particles[particles["clump"] >= 0]
    sums = {c: (c, "sum") for c in ["u", *energy_columns(particles)]}
    out = (
        members.groupby(["step", "clump"], sort=True)
        .agg(n_members=("id", "size"), **sums, n_contacts=("n_contacts", "sum"))
        .reset_index()
    )
    return out


def per_size(particles: pd.DataFrame, bins=None, value: str = "u", *, by_frame: bool = True) -> pd.DataFrame:
    """Statistics of ``value`` per radius class (classes from :func:`size_bins`
    over the radii of all frames, so every frame uses the same classes).
    Columns: [``step``], ``size_class``, ``r_lo``, ``r_hi`` (m), STAT_COLUMNS."""
    _require(particles, ["radius", value], "particles")
    edges = size_bins(particles["radius"].to_numpy(), bins)
    df = particles.assign(size_class=size_class(particles["radius"].to_numpy(), edges))
    keys = ["step", "size_class"] if by_frame else ["size_class"]
    out = grouped_stats(df, keys, value)
    k = out["size_class"].to_numpy()
    out.insert(len(keys), "r_lo", edges[k])
    out.insert(len(keys) + 1, "r_hi", edges[np.minimum(k + 1, len(edges) - 1)])
    return out


def per_frame(particles: pd.DataFrame, walls: pd.DataFrame, frames: pd.DataFrame) -> pd.DataFrame:
    """One row per frame: the frame table, plus
    ``u_contacts`` = the sum of the elastic modes (u_n + u_t [+ u_r + u_tw]) over contacts (J),
    ``u_particles`` = sum of particle ``u``, ``u_walls`` = sum of wall ``u`` (J;
    as the frames table has them when the pipeline recorded them, so that the
    balance of every frame needs only the frames table; else summed here),
    ``balance_rel_error`` = |u_particles + u_walls - u_contacts| / u_contacts
    (energy conservation of the split; ~1e-15 when correct),
    and the distribution statistics of particle ``u`` (``mean`` ... ``gini``;
    NaN for frames whose particles are not in ``particles``)."""
    out = frames.copy()
    out["u_contacts"] = out[elastic_columns(out)].sum(axis=1)
    for col, table in (("u_particles", particles), ("u_walls", walls)):
        if col not in out:
            sums = table.groupby("step")["u"].sum() if len(table) else pd.Series(dtype=float)
            out[col] = out["step"].map(sums).fillna(0.0).to_numpy(dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["balance_rel_error"] = (out["u_particles"] + out["u_walls"] - out["u_contacts"]).abs() / out["u_contacts"]
    stats = grouped_stats(particles, ["step"], "u").drop(columns=["count", "total"])
    out = out.merge(stats, on="step", how="left")
    out.attrs["units"] = {
        **frames.attrs.get("units", {}),
        "u_contacts": "J",
        "u_particles": "J",
        "u_walls": "J",
        "balance_rel_error": "1",
    }
    return out


def wall_energy(walls: pd.DataFrame, walls_meta: list[dict], frames: pd.DataFrame | None = None) -> pd.DataFrame:
    """Energy per wall and frame (``walls`` table) with each wall's ``name``,
    ``kind`` and material ``type`` from ``walls_meta``, and ``share`` = wall u /
    total elastic contact energy of the frame (every elastic mode over all contacts)."""
    meta = pd.DataFrame(walls_meta, columns=["wall", "name", "kind", "type"])
    if len(meta):
        meta["wall"] = meta["wall"].astype(np.int64)
    out = walls.merge(meta, on="wall", how="left")
    if frames is not None and len(frames):
        total = frames[elastic_columns(frames)].sum(axis=1).to_numpy()
        with np.errstate(invalid="ignore", divide="ignore"):
            out["share"] = out["u"].to_numpy() / pd.Series(total, index=frames["step"]).reindex(out["step"]).to_numpy()
    return out.sort_values(["step", "wall"], kind="stable").reset_index(drop=True)


SPLIT_STATS = ("total", "mean", "std", "p50", "p95", "top10_share", "gini")


def split_comparison(particles: pd.DataFrame, *, by_frame: bool = True) -> pd.DataFrame:
    """Per-type statistics under the distribution rules of SPLITS present in
    ``particles``, side by side: columns ``<stat>_<rule>`` for each stat in SPLIT_STATS, and the
    misattribution of each simpler rule in percent,
    ``misattribution_equal_pct`` = (sum_type u_equal - sum_type u)/sum_type u * 100,
    ``misattribution_radius_pct`` likewise with u_radius (NaN if sum_type u = 0)."""
    _require(particles, ["u", "u_equal", "u_radius"], "particles")
    rules = {rule: column for rule, column in SPLITS.items() if column in particles}
    keys = ["step", "type"] if by_frame else ["type"]
    out = None
    for rule, column in rules.items():
        stats = grouped_stats(particles, keys, column)
        stats = stats[[*keys, *SPLIT_STATS] if out is not None else [*keys, "count", *SPLIT_STATS]]
        stats = stats.rename(columns={s: f"{s}_{rule}" for s in SPLIT_STATS})
        out = stats if out is None else out.merge(stats, on=keys)
    with np.errstate(invalid="ignore", divide="ignore"):
        for rule in list(rules)[1:]:
            out[f"misattribution_{rule}_pct"] = (
                (out[f"total_{rule}"] - out["total_material"]) / out["total_material"] * 100.0
            )
    return out


def contact_point_shift(contacts: pd.DataFrame, *, by_frame: bool = True) -> pd.DataFrame:
    """Distance between demsplit's material-weighted contact point and the
    simulator's own, in units of the overlap: d = |cp - cp_sim| / delta.

    One row per [step and] kind (``pair`` or ``wall``): ``count`` (contacts with
    both points and delta > 0), ``n_missing`` (contacts without a simulator point:
    cp_sim NaN), ``median``, ``p95``, ``max`` of d, and ``print_bound_median``: the
    median over contacts of the bound that printing puts on d, half a unit in the
    last printed digit of each coordinate of cp_sim (counted from the values: a
    coordinate that a ``%g`` dump printed rounds to itself at 6 significant digits),
    over delta. Where it is not far below ``median``, the shift measures the dump's
    precision, not the two contact points.
    """
    needed = ["cpx", "cpy", "cpz", "cpx_sim", "cpy_sim", "cpz_sim", "delta", "wall"]
    if not {"cpx_sim", "cpy_sim", "cpz_sim"} <= set(contacts.columns):
        raise DemsplitError(
            "the results hold no simulator contact point (columns cpx_sim cpy_sim cpz_sim).",
            fix="dump the simulator's contact point (LIGGGHTS: compute pair/gran/local contactPoint; "
            "YADE: i.geom.contactPoint in the export) and rerun demsplit.",
        )
    _require(contacts, needed, "contacts")
    cp = contacts[["cpx", "cpy", "cpz"]].to_numpy()
    sim = contacts[["cpx_sim", "cpy_sim", "cpz_sim"]].to_numpy()
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.linalg.norm(cp - sim, axis=1) / contacts["delta"].to_numpy()
    bound = np.zeros(len(d))
    pair = contacts["wall"].to_numpy() < 0
    for rows in (pair, ~pair):  # pair and wall points may come from dumps of different precision
        with np.errstate(invalid="ignore", divide="ignore"):
            bound[rows] = np.linalg.norm(printed_half_unit(sim[rows]), axis=1) / contacts["delta"].to_numpy()[rows]
    df = pd.DataFrame(
        {
            "step": contacts["step"].to_numpy(),
            "kind": np.where(contacts["wall"].to_numpy() < 0, "pair", "wall"),
            "d": d,
            "bound": bound,
            "missing": np.isnan(sim).any(axis=1),
        }
    )
    keys = ["step", "kind"] if by_frame else ["kind"]
    rows = []
    for key, sub in df.groupby(keys, sort=True):
        ok = sub["d"].to_numpy()[~sub["missing"].to_numpy() & np.isfinite(sub["d"].to_numpy())]
        row = dict(zip(keys, key))
        row.update(count=len(ok), n_missing=int(sub["missing"].sum()))
        if len(ok):
            bounds = sub["bound"].to_numpy()[~sub["missing"].to_numpy() & np.isfinite(sub["d"].to_numpy())]
            row.update(
                median=float(np.median(ok)),
                p95=float(np.quantile(ok, 0.95)),
                max=float(ok.max()),
                print_bound_median=float(np.median(bounds)),
            )
        else:
            row.update(median=math.nan, p95=math.nan, max=math.nan, print_bound_median=math.nan)
        rows.append(row)
    return pd.DataFrame(rows, columns=[*keys, "count", "n_missing", "median", "p95", "max", "print_bound_median"])


def printed_half_unit(values: np.ndarray, sample: int = 2000) -> np.ndarray:
    """Half a unit in the last printed digit of every value (m for coordinates): a dump prints all its
    values with one format, so the significant digits d are the fewest (1..15) with which every value of
    a sample of ``sample`` finite nonzero ones rounds to itself, and the bound is 0.5 10^(floor(log10 |v|)
    - d + 1); 0 everywhere for values printed at full precision (more than 15 digits)."""
    v = np.asarray(values, dtype=np.float64)
    finite = v[np.isfinite(v) & (v != 0)]
    if not len(finite):
        return np.zeros(v.shape)
    picked = finite[:: max(1, len(finite) // sample)]
    digits = next((d for d in range(1, 16) if all(float(f"{x:.{d}g}") == x for x in picked)), None)
    if digits is None:
        return np.zeros(v.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        exponent = np.floor(np.log10(np.abs(v)))
    return np.where(np.isfinite(exponent), 0.5 * 10.0 ** (exponent - digits + 1), 0.0)


def _require(df: pd.DataFrame, columns: Sequence[str], table: str) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise DemsplitError(
            f"the {table} table has no column(s) {missing} (it has {list(df.columns)}).",
            fix="rerun demsplit with a version that writes these columns.",
        )
