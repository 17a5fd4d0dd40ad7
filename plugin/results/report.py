"""What a user reads: a terminal summary and a self-contained HTML report.

:func:`text_summary` prints what was not computed, the per-type table of one frame (the last by
default), the split comparison, the walls and the per-frame energy balance.
:func:`write_html` writes one HTML page of one frame and the per-frame series, every figure embedded
as a base64 PNG (matplotlib, Agg backend), no file outside the page referenced. From the top: what was
not computed (the store's provenance: ``not_computed``, ``skipped``, the NOT COMPUTED notes, walls
marked missing, the frame's contacts with not-computed modes), the energy per mode, per material type
(histogram), the normalised distribution P(u/<u>) and its CCDF, where the energy sits (against height,
a slice and a projection coloured by u), per size class (bars over the real class bounds), the split
comparison with the per-particle misattribution of the 50/50 and radius splits, the per-frame series on
a log axis, the walls, the contact point, and the provenance folded away.

Energy columns are found generically (:func:`energy_modes`: every ``u_*`` column that is an energy
mode), so a mode added later (rolling ``u_r``, twisting ``u_tw``, the signed cohesion work ``u_adh``,
kept apart from the elastic total) shows up without a change here. Material names:
:meth:`Results.type_names`, then ``demsplit report --type-name T=NAME``.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import StoreError
from ..outputs import REPORT, REPORT_GENERATOR, check_output_path, write_output
from .aggregate import elastic_columns
from .schema import UNBOUNDED, UNITS, known
from .tables import NOT_COMPUTED_TEXT, Results, not_computed_mask

MODE_NAMES = {
    "u_n": "normal",
    "u_t": "tangential",
    "u_r": "rolling",
    "u_tw": "twisting",
    "u_adh": "cohesion work (signed, apart from the elastic total)",
}

NOT_MODES = frozenset({"u_equal", "u_radius", "u_springs", "u_particles", "u_walls", "u_contacts"})
"""``u_*`` columns that are not energy modes: the other splits' per-particle totals and the frame sums."""

SCATTER_MAX_POINTS = 100_000
"""Scatter plots and projections draw at most this many particles (a seeded
random subset, stated in the caption)."""

HEIGHT_BINS = 20
"""Slabs of the energy-against-height profile."""


def energy_modes(df: pd.DataFrame) -> list[str]:
    """The energy mode columns of ``df``: every ``u_*`` column but the other splits, the frame sums
    and the ``*_error`` columns; the known modes (normal, tangential, rolling, twisting, cohesion) first."""
    cols = [c for c in df.columns if c.startswith("u_") and c not in NOT_MODES and not c.endswith("_error")]
    order = list(MODE_NAMES)
    return sorted(cols, key=lambda c: (order.index(c) if c in order else len(order), c))


def mode_label(column: str) -> str:
    return f"{MODE_NAMES.get(column, column)} ({column})"


def _type_label(t, names: Mapping[int, str]) -> str:
    return f"{names[int(t)]} (type {t})" if int(t) in names else f"type {t}"


def _with_names(df: pd.DataFrame, names: Mapping[int, str], column: str = "type") -> pd.DataFrame:
    """``df`` with a ``material`` column after ``column`` when any type is named."""
    if not names or column not in df:
        return df
    out = df.copy()
    out.insert(
        list(out.columns).index(column) + 1,
        "material",
        [names.get(int(t), "") if pd.notna(t) else "" for t in out[column]],
    )
    return out


def _pick_step(results: Results, step: int | None) -> int:
    steps = results.steps
    if len(steps) == 0:
        raise StoreError("the results hold no frames.", fix="run demsplit on a run with at least one frame.")
    if step is None:
        return int(steps.max())
    results.frame(step)  # raises with the available steps if absent
    return int(step)


UNDEFINED_TEXT = "-"
"""What a table shows for a ratio without a value (a share or an inequality of no energy, 0/0)."""


def _fmt(df: pd.DataFrame, unknown: Mapping[str, np.ndarray] | None = None) -> pd.DataFrame:
    """Floats with 4 significant digits for display (NaN, a ratio of nothing: :data:`UNDEFINED_TEXT`); the
    cells of ``unknown`` (column -> rows, as :func:`~demsplit.results.tables.not_computed_mask` gives them for
    the same rows) read "not computed"."""
    out = df.map(lambda v: (UNDEFINED_TEXT if math.isnan(v) else f"{v:.4g}") if isinstance(v, float) else v)
    for column, rows in (unknown or {}).items():
        if column in out:
            out[column] = np.where(rows, NOT_COMPUTED_TEXT, out[column].astype(object))
    return out


def _mode_total(frame: pd.Series, contacts: pd.DataFrame, mode: str) -> str:
    """A frame's total of ``mode`` for display (J), followed by how many contacts it leaves out as not
    computed (their ``not_computed`` bit of that mode); "not computed" when that is every contact."""
    from ..physics.modes import NOT_COMPUTED_BITS

    text = f"{frame[mode]:.6g} J"
    if "not_computed" in contacts and mode in NOT_COMPUTED_BITS:
        n = int(((contacts["not_computed"].to_numpy(dtype=np.int64) & NOT_COMPUTED_BITS[mode]) != 0).sum())
        if n and n == len(contacts):
            return f"not computed (in all {n} contacts)"
        if n:
            text += f" without {n} contact(s) not computed"
    return text


def not_computed(results: Results, frame: pd.Series | None = None) -> list[str]:
    """What the results do not hold, one sentence each: ``provenance["not_computed"]`` (name -> reason),
    the NOT COMPUTED notes, ``provenance["skipped"]`` (mode -> why a law has no such energy), walls the
    scene marks missing, and the count of this frame's contacts with not-computed modes."""
    prov = results.provenance or {}
    items = []
    for name, reason in dict(prov.get("not_computed") or {}).items():
        why = reason if isinstance(reason, str) else json.dumps(reason, sort_keys=True, default=str)
        items.append(f"{name}: {why}")
    items += [n for n in prov.get("notes", []) if "NOT COMPUTED" in n]
    items += [f"{k} (not computed by the law): {v}" for k, v in dict(prov.get("skipped") or {}).items()]
    told = " ".join(items)
    for w in (prov.get("scene", {}) or {}).get("walls", []):
        if isinstance(w, Mapping) and w.get("missing") and f"'{w.get('name')}'" not in told:
            items.append(f"wall '{w.get('name')}': {w['missing']}")
    if frame is not None and frame.get("n_not_computed", 0):
        items.append(
            f"{int(frame['n_not_computed'])} contact(s) of this frame have modes not computed (column not_computed)"
        )
    return items


def simulator_energies(results: Results, step: int, frame: pd.Series) -> list[str]:
    """The simulator's own elastic energies of frame ``step`` beside demsplit's sum of the same modes, one
    sentence each: the reader's ``yade_energies`` in the provenance (YADE's law energy functions recorded by a
    snapshot, the ``O.energy`` entries the law fills when the run tracks energies)."""
    run = (results.provenance or {}).get("run") or {}
    lines = []
    for e in run.get("yade_energies", []):  # checked when the store is read (results.store)
        if e["step"] != step:
            continue
        modes = [m for m in e["modes"] if m in frame]
        ours, theirs = float(sum(frame[m] for m in modes)), float(e["value"])
        line = f"YADE's own {e['name']} = {theirs:.10g} J, demsplit's {' + '.join(modes)} = {ours:.10g} J" + (
            f" (relative difference {abs(ours - theirs) / abs(theirs):.2g})" if theirs else ""
        )
        if theirs == 0 and ours > 0 and e["name"].startswith("O.energy"):
            line += (
                "; YADE's ForceResetter zeroes it at the start of each step, so a state saved before the "
                "InteractionLoop holds 0"
            )
        lines.append(line)
    return lines


SPLIT_NAMES = {"equal": "50/50", "radius": "radius"}
"""The simpler splits the headline measures, by their particle column ``u_<rule>``."""


def split_headline(one: Results, names: Mapping[int, str]) -> tuple[pd.DataFrame, list[str]]:
    """The tool's headline for the frame of ``one``: per material type, the elastic energy its particles hold
    under the material law (J) and how far the 50/50 and the radius splits put it off,
    (u_split - u)/u in percent, with the part of that error the wall contacts alone make (percentage points:
    the rest comes from the particle pairs, computed contact by contact from the stored shares and radii), and
    the material law's expected error (finite-element model). Then sentences that explain the numbers: with
    one particle material the material law gives each particle of a pair half (it is the 50/50 split there);
    against a wall (r = inf) the radius split r1/(r1 + r2) gives the particle the whole contact. Values not
    computed are left out of the sums (the raw tables' 0), as in every total of the report."""
    p = one.raw.particles
    rules = [rule for rule in SPLIT_NAMES if f"u_{rule}" in p]
    per_type = p.groupby("type")
    table = pd.DataFrame({"type": list(per_type.groups), "particles": per_type.size().to_numpy()})
    if names:
        table.insert(1, "material", [names.get(int(t), "") for t in table["type"]])
    u = per_type["u"].sum().to_numpy()
    total = u.sum()
    table["material_law"] = u
    table["share_pct"] = u / total * 100 if total > 0 else np.nan
    walls_part = _wall_parts(one, rules, table["type"].to_numpy()) if rules else {}
    for rule in rules:
        other = per_type[f"u_{rule}"].sum().to_numpy()
        table[rule] = other
        with np.errstate(invalid="ignore", divide="ignore"):
            table[f"{rule}_off_pct"] = (other - u) / u * 100
            if rule in walls_part:
                table[f"{rule}_off_walls_pct"] = walls_part[rule] / u * 100
    errors = one.per_type()
    if "expected_error" in errors:
        table["expected_error_pct"] = errors.set_index("type").loc[table["type"], "expected_error"].to_numpy() * 100
    return table, _headline_sentences(one, rules, walls_part)


def _wall_parts(one: Results, rules: list[str], types: np.ndarray) -> dict[str, np.ndarray]:
    """Per particle type (``types``' order), the energy (J) each simpler split moves to or from the type's
    particles through their wall contacts: the split's total error less the part of the particle pairs,
    recomputed from each pair's material-law shares ``u1``, ``u2`` and the radii (50/50: u/2 each; radius:
    r1/(r1 + r2) of u to body 1). Empty without the per-contact table or the particle radii."""
    c, p = one.raw.contacts, one.raw.particles
    if not {"id1", "id2", "wall", "u1", "u2"} <= set(c.columns) or "radius" not in p or not len(c):
        return {}
    index = pd.Index(p["id"].to_numpy())
    pairs = c[c["wall"].to_numpy() < 0]
    rows1, rows2 = index.get_indexer(pairs["id1"].to_numpy()), index.get_indexer(pairs["id2"].to_numpy())
    if (rows1 < 0).any() or (rows2 < 0).any():
        return {}
    u1, u2 = pairs["u1"].to_numpy(), pairs["u2"].to_numpy()
    r = p["radius"].to_numpy()
    s1 = {"equal": np.full(len(pairs), 0.5), "radius": r[rows1] / (r[rows1] + r[rows2])}
    type_row = pd.Index(types).get_indexer(p["type"].to_numpy())
    out = {}
    for rule in rules:
        moved = np.zeros(len(types))
        np.add.at(moved, type_row[rows1], s1[rule] * (u1 + u2) - u1)
        np.add.at(moved, type_row[rows2], (1 - s1[rule]) * (u1 + u2) - u2)
        error = (p.groupby("type")[f"u_{rule}"].sum() - p.groupby("type")["u"].sum()).reindex(types).to_numpy()
        out[rule] = error - moved
    return out


def _headline_sentences(one: Results, rules: list[str], walls_part: Mapping[str, np.ndarray]) -> list[str]:
    """What the headline's numbers mean for this run (:func:`split_headline`)."""
    materials = (one.provenance.get("scene") or {}).get("materials") or {}
    present = {int(t) for t in one.raw.particles["type"].unique()}
    elastic = {(m.get("E"), m.get("nu")) for t, m in materials.items() if int(t) in present}
    walled = len(one.raw.walls) > 0
    wall_types = {str(w.get("type")) for w in one.walls_meta or []}
    other_walls = {(m.get("E"), m.get("nu")) for t, m in materials.items() if t in wall_types} - elastic
    out = []
    if not rules:
        out.append("The 50/50 and radius splits were not computed (demsplit run --no-compare).")
    if len(elastic) == 1 and len(present) >= 1:
        ((E, nu),) = elastic
        out.append(
            f"One particle material (E = {E:g} Pa, nu = {nu:g}): between two particles the material law "
            "splits by compliance, (1 - nu^2)/E, which is the same for both, so it gives each half: there it "
            "is the 50/50 split"
            + (
                ", and the difference to 50/50 above comes from the wall contacts, whose material differs."
                if walled and other_walls
                else " (the walls too are of this material)."
                if walled
                else "."
            )
        )
    if "radius" in rules:
        out.append(
            "The radius split gives body 1 the share r1/(r1 + r2) of a contact (the split behind LIGGGHTS' "
            "contact point and Aspherix): between particles it favours the larger one, which the material "
            "law, by compliance, does not"
            + (
                "; against a wall it gives the particle r1/(r1 + r_wall), the whole contact where the wall is "
                "flat (r_wall = inf, LIGGGHTS' walls), where the material law gives the wall its compliance's "
                "share: 'radius off by walls' is that part of the error, in percentage points."
                if walled and "radius" in walls_part
                else "."
            )
        )
    return out


def _headline_shown(table: pd.DataFrame) -> pd.DataFrame:
    """The headline table for display: energies in 4 significant digits, percentages signed in 3, the headers
    with their units (:data:`HEADLINE_COLUMNS`)."""
    out = _fmt(table)
    for column in table.columns:
        if column.endswith("_pct") and column != "share_pct":
            out[column] = [UNDEFINED_TEXT if not np.isfinite(v) else f"{v:+.3g}" for v in table[column]]
    return out.rename(columns=HEADLINE_COLUMNS)


AGREES_PCT = 1e-6
"""A split off by less than this (%) agrees with the material law (rounding: one material, where both are 1/2)."""


def headline_lead(table: pd.DataFrame, names: Mapping[int, str]) -> str:
    """One sentence: how far each simpler split is off at worst, and for which material (:func:`split_headline`)."""
    parts = []
    for rule, label in SPLIT_NAMES.items():
        off = table.get(f"{rule}_off_pct")
        if off is None or not np.isfinite(off.to_numpy(dtype=float)).any():
            continue
        k = int(np.nanargmax(np.abs(off.to_numpy(dtype=float))))
        who = _type_label(table["type"].iloc[k], names)
        if abs(off.iloc[k]) < AGREES_PCT:
            parts.append(f"the {label} split agrees with it")
            continue
        parts.append(
            f"the {label} split gives {who} {abs(off.iloc[k]):.3g} % too "
            f"{'much' if off.iloc[k] > 0 else 'little'} energy"
        )
    return ("Against the material law, " + " and ".join(parts) + " (the worst material of each).") if parts else ""


def _headline_text(one: Results, names: Mapping[int, str]) -> list[str]:
    """The headline as the terminal summary's first lines."""
    table, sentences = split_headline(one, names)
    lead = headline_lead(table, names)
    return (
        [f"  {lead}" if lead else "  Energy per material under the material law:"]
        + ["    " + line for line in _headline_shown(table).to_string(index=False).splitlines()]
        + [f"  {sentence}" for sentence in sentences]
    )


HEADLINE_COLUMNS = {
    "particles": "particles (1)",
    "material_law": "material law (J)",
    "share_pct": "share (%)",
    "equal": "50/50 (J)",
    "equal_off_pct": "50/50 off (%)",
    "equal_off_walls_pct": "50/50 off by walls (%)",
    "radius": "radius (J)",
    "radius_off_pct": "radius off (%)",
    "radius_off_walls_pct": "radius off by walls (%)",
    "expected_error_pct": "expected error (%)",
}
"""The headline table's column headers, with their units."""


def text_summary(results: Results, step: int | None = None, names: Mapping[int, str] | None = None) -> str:
    """The per-type summary of frame ``step`` (default: the last), as plain text; ``names``: material
    names of types (added to the provenance's, see :meth:`Results.type_names`)."""
    step = _pick_step(results, step)
    one = results.frame(step)
    fr = one.raw.frames.iloc[0]
    names = results.type_names(names)
    modes = elastic_columns(one.raw.frames)
    u_total = sum(fr[m] for m in modes)
    parts = ", ".join(f"{MODE_NAMES.get(m, m)} {_mode_total(fr, one.raw.contacts, m)}" for m in modes)
    lines = [
        f"demsplit results: {len(results.steps)} frame(s); frame at timestep {step}"
        + (f" (t = {fr['time']:.6g} s)" if known(fr.get("time")) else ""),
    ]
    if u_total > 0:
        lines += _headline_text(one, names)
    missing = not_computed(results, fr)
    if missing:
        lines += ["  NOT COMPUTED (these values are unknown, not 0; they are left out of every total below):"]
        lines += [f"    - {n}" for n in missing]
    lines.append(
        f"  {int(fr['n_particles'])} particles, {int(fr['n_contacts'])} contacts "
        f"({int(fr['n_wall_contacts'])} with walls); elastic contact energy {u_total:.6g} J ({parts})"
        + (f"; cohesion work {_mode_total(fr, one.raw.contacts, 'u_adh')}, apart" if "u_adh" in fr else "")
    )
    lines += [f"  {line}" for line in simulator_energies(results, step, fr)]
    model = results.provenance.get("model")
    if model:
        params = ", ".join(
            f"{k}={v!r}" for k, v in sorted(model.get("params", {}).items()) if v is not None and v != "off"
        )
        lines.append(f"  contact law: {model.get('law')}" + (f" ({params})" if params else ""))
    if known(fr.get("overlap_max_rel_error")):
        bound = fr["overlap_max_rel_error"]
        shown = "unbounded (a contact the printed positions may hide)" if bound >= UNBOUNDED else f"{bound:.3g}"
        lines.append(
            "  overlaps recomputed from printed positions (contacts without a dumped delta, e.g. primitive "
            f"walls): max relative error bound {shown}"
        )
    if u_total == 0:  # nothing to distribute: no table of shares and inequalities of zeros
        lines += ["", EMPTY_FRAME]
        return _closing(results, lines)
    cols = ["type", "count", "total", "share_of_total", "mean", "p50", "p95", "top10_share", "gini"]
    table = one.per_type()
    cols += ["expected_error"] if "expected_error" in table else []
    cols += ["n_not_computed"] if "n_not_computed" in table and table["n_not_computed"].any() else []
    table = table[cols]
    if names:
        table = table.assign(material=[names.get(int(t), "") for t in table["type"]])
    lines += [
        "",
        "Energy per particle type (J; material distribution law; expected_error: the split's expected "
        "relative error, finite-element model):",
        _fmt(table).to_string(index=False),
    ]
    if {"u_equal", "u_radius"} <= set(one.raw.particles.columns):
        sc = one.split_comparison()
        sc = sc[["type"] + [c for c in sc.columns if c.startswith(("total_", "misattribution_"))]]
        lines += [
            "",
            "Split comparison (J; misattribution in % of the material-law total):",
            _fmt(sc).to_string(index=False),
        ]
    if len(one.raw.walls):
        we = one.wall_energy()
        lines += [
            "",
            "Walls (J):",
            _fmt(
                we[[c for c in ("wall", "name", "kind", "u", *energy_modes(we), "n_contacts", "share") if c in we]],
                not_computed_mask(we),
            ).to_string(index=False),
        ]
    if {"cpx_sim", "cpy_sim", "cpz_sim"} <= set(one.raw.contacts.columns):
        lines += [
            "",
            "Contact point: |cp - cp_simulator| / overlap (print_bound_median: what the dump's printed "
            "digits alone allow; a shift not far above it measures the print precision):",
            _fmt(one.contact_point_shift()).to_string(index=False),
        ]
    if "share_n1_error" in one.raw.contacts:
        lines += ["", accuracy_line(one.raw.contacts, results.provenance.get("options", {}).get("split", "material"))]
    return _closing(results, lines)


EMPTY_FRAME = "This frame holds no elastic energy (no contact): nothing to split, no shares or inequality to show."
"""What a report says of a frame without energy, instead of tables of ratios of zeros."""


def _closing(results: Results, lines: list[str]) -> str:
    """``lines`` and the energy balance of every frame (over the frames that hold energy), as the summary's
    text."""
    pf = results.per_frame()
    held = pf[pf["u_contacts"] > 0]
    if len(held):
        lines += [
            "",
            f"Energy balance over {len(held)} frame(s) with energy: max |sum particles + sum walls - sum "
            f"contacts| / sum contacts = {held['balance_rel_error'].max():.3g}",
        ]
    return "\n".join(lines) + "\n"


def accuracy_line(contacts: pd.DataFrame, split: str) -> str:
    """How far this frame's split can be trusted (finite-element error model, docs/accuracy.md): the
    share of the normal energy in contacts whose expected share error exceeds 1 %, the contacts
    beyond the Hertz range a/R > 0.1, and those beyond the model's fit a/R > 0.3, whose expected error is
    the model's value at the edge of its fit (an extrapolation)."""
    from ..physics.accuracy import FIT_A_OVER_R, HERTZ_VALIDITY

    u = contacts["u_n"].to_numpy()
    err = np.abs(contacts["share_n1_error"].to_numpy())
    big = err > 0.01
    a_over_r = contacts[["a_over_r1", "a_over_r2"]].to_numpy()
    beyond = (a_over_r > HERTZ_VALIDITY).any(axis=1)
    extrapolated = (a_over_r > FIT_A_OVER_R).any(axis=1)
    total = u.sum()
    frac = u[big].sum() / total if total > 0 else 0.0
    weighted = (err * u).sum() / total if total > 0 else 0.0
    return (
        f"Accuracy of the split ({split}; finite-element error model, docs/accuracy.md): expected share "
        f"error {weighted:.2%} energy-weighted, max {err.max() if len(err) else 0:.2%}; {frac:.1%} of the "
        f"normal energy in contacts beyond 1 % expected error; {int(beyond.sum())} contact(s) beyond the Hertz "
        f"range a/R > {HERTZ_VALIDITY}, {int(extrapolated.sum())} beyond the model's fit a/R > {FIT_A_OVER_R} "
        "(their expected error extrapolated)"
    )


# --------------------------------------------------------------------------- figures


def _png(fig, alt: str) -> str:
    """The figure as an <img> tag with a base64 PNG data URI (closes the figure)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def _figure(fig, caption: str, alt: str) -> str:
    return f"<figure>{_png(fig, alt)}<figcaption>{caption}</figcaption></figure>"


def _subset(particles: pd.DataFrame) -> tuple[pd.DataFrame, str]:
    if len(particles) > SCATTER_MAX_POINTS:
        return (
            particles.sample(SCATTER_MAX_POINTS, random_state=0),
            f" (a random subset of {SCATTER_MAX_POINTS} of the {len(particles)} particles)",
        )
    return particles, ""


def _fig_histogram(particles: pd.DataFrame, step: int, names: Mapping[int, str]):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    positive = particles[particles["u"] > 0]
    if len(positive):
        edges = np.geomspace(positive["u"].min(), positive["u"].max() * (1 + 1e-12), 41)
        for t, sub in positive.groupby("type"):
            ax.hist(
                sub["u"], bins=edges, histtype="step", linewidth=1.5, label=f"{_type_label(t, names)} (n = {len(sub)})"
            )
        ax.set_xscale("log")
        ax.legend()
    ax.set_xlabel("particle elastic energy u (J)")
    ax.set_ylabel("particles")
    ax.set_title(f"Energy per particle, timestep {step} ({(particles['u'] <= 0).sum()} particles with u = 0 not shown)")
    return fig


def _fig_distribution(particles: pd.DataFrame, step: int, names: Mapping[int, str]):
    """P(u/<u>) (density over log-spaced bins) and the CCDF P(u/<u> > x), all particles and per type."""
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    groups = [("all particles", particles)]
    if particles["type"].nunique() > 1:
        groups += [(_type_label(t, names), sub) for t, sub in particles.groupby("type")]
    drawn = False
    for label, sub in groups:
        u = sub["u"].to_numpy()
        mean = u.mean() if len(u) else 0.0
        if not mean > 0:
            continue
        x = u / mean
        pos = np.sort(x[x > 0])
        if len(pos) < 2:
            continue
        drawn = True
        edges = np.geomspace(pos[0], pos[-1] * (1 + 1e-12), 31)
        counts, _ = np.histogram(pos, bins=edges)
        density = counts / (len(x) * np.diff(edges))  # zeros count in the normalisation
        mid = np.sqrt(edges[:-1] * edges[1:])
        keep = counts > 0
        ax1.plot(mid[keep], density[keep], "o-", ms=3, label=f"{label} (n = {len(x)})")
        ccdf = 1.0 - np.arange(len(pos)) / len(x) - (len(x) - len(pos)) / len(x)
        ax2.step(pos, ccdf, where="post", label=label)
    if drawn:
        for ax in (ax1, ax2):
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.legend(fontsize=8)
    ax1.set_xlabel("u / <u>")
    ax1.set_ylabel("P(u/<u>)")
    ax1.set_title(f"Normalised distribution, timestep {step}")
    ax2.set_xlabel("x = u / <u>")
    ax2.set_ylabel("P(u/<u> >= x)")
    ax2.set_title("Complementary cumulative distribution")
    return fig


def _fig_radius(particles: pd.DataFrame, step: int, names: Mapping[int, str]) -> tuple[object, str]:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    df, note = _subset(particles[particles["u"] > 0])
    for t, sub in df.groupby("type"):
        ax.scatter(sub["radius"], sub["u"], s=6, alpha=0.6, label=_type_label(t, names))
    if len(df):
        ax.set_yscale("log")
        ax.legend()
    ax.set_xlabel("radius (m)")
    ax.set_ylabel("u (J)")
    ax.set_title(f"Energy against radius, timestep {step}")
    return fig, note


def _fig_height(particles: pd.DataFrame, step: int, names: Mapping[int, str]):
    """Mean energy per particle and share of the total in horizontal slabs of z."""
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    z = particles["z"].to_numpy()
    lo, hi = (z.min(), z.max()) if len(z) else (0.0, 1.0)
    edges = np.linspace(lo, hi if hi > lo else lo + 1.0, HEIGHT_BINS + 1)
    mid = 0.5 * (edges[:-1] + edges[1:])
    total = particles["u"].sum()
    groups = [("all particles", particles)]
    if particles["type"].nunique() > 1:
        groups += [(_type_label(t, names), sub) for t, sub in particles.groupby("type")]
    for label, sub in groups:
        k = np.clip(np.searchsorted(edges, sub["z"].to_numpy(), side="right") - 1, 0, HEIGHT_BINS - 1)
        n = np.bincount(k, minlength=HEIGHT_BINS)
        s = np.bincount(k, sub["u"].to_numpy(), minlength=HEIGHT_BINS)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.where(n > 0, s / n, np.nan)
        style = "k-o" if label == "all particles" else "-o"
        ax1.plot(mean, mid, style, ms=3, label=label)
        if total > 0:
            ax2.plot(s / total, mid, style, ms=3, label=label)
    if np.nanmax(np.r_[particles["u"].to_numpy(), 0.0]) > 0:
        ax1.set_xscale("log")
    ax1.set_xlabel("mean u per particle in the slab (J)")
    ax1.set_ylabel("height z (m)")
    ax1.set_title(f"Energy against height, timestep {step}")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("share of the frame's particle energy in the slab")
    ax2.set_title(f"{HEIGHT_BINS} slabs of equal thickness")
    return fig


def _fig_views(particles: pd.DataFrame, step: int) -> tuple[object, str]:
    """A slice (particles whose sphere crosses the plane y = median y) drawn as their circles, and the
    x-z projection of every particle (high energies on top), coloured by u on a log scale."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection
    from matplotlib.colors import LogNorm

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 5))
    u = particles["u"].to_numpy()
    pos = u[u > 0]
    norm = LogNorm(vmin=pos.min(), vmax=pos.max()) if len(pos) and pos.max() > pos.min() else None
    cmap = plt.get_cmap("viridis").with_extremes(bad="lightgrey")
    y0 = float(np.median(particles["y"])) if len(particles) else 0.0
    r = particles["radius"].to_numpy()
    cut = np.abs(particles["y"].to_numpy() - y0) < r
    sl = particles[cut]
    rc = np.sqrt(np.maximum(sl["radius"].to_numpy() ** 2 - (sl["y"].to_numpy() - y0) ** 2, 0.0))
    coll = EllipseCollection(
        2 * rc,
        2 * rc,
        np.zeros(len(sl)),
        units="xy",
        offsets=sl[["x", "z"]].to_numpy(),
        offset_transform=ax1.transData,
        cmap=cmap,
        norm=norm,
        edgecolors="k",
        linewidths=0.2,
    )
    coll.set_array(np.where(sl["u"].to_numpy() > 0, sl["u"].to_numpy(), np.nan))
    ax1.add_collection(coll)
    if len(particles):
        pad = r.max()
        ax1.set_xlim(particles["x"].min() - pad, particles["x"].max() + pad)
        ax1.set_ylim(particles["z"].min() - pad, particles["z"].max() + pad)
    ax1.set_aspect("equal")
    ax1.set_xlabel("x (m)")
    ax1.set_ylabel("z (m)")
    ax1.set_title(f"Slice y = {y0:.4g} m ({len(sl)} particles), timestep {step}", fontsize=10)
    sub, note = _subset(particles)
    sub = sub.sort_values("u", kind="stable")
    su = sub["u"].to_numpy()
    ax2.scatter(sub["x"], sub["z"], c=np.where(su > 0, su, np.nan), cmap=cmap, norm=norm, s=8, linewidths=0)
    ax2.set_aspect("equal")
    ax2.set_xlabel("x (m)")
    ax2.set_title("Projection on x-z (highest energies drawn on top)", fontsize=10)
    if norm is not None:
        fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label="u (J)", shrink=0.8)
    return fig, note


def _fig_size(per_size: pd.DataFrame, step: int):
    """Total and mean energy per radius class, each bar spanning its class [r_lo, r_hi]."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    lo, hi = per_size["r_lo"].to_numpy(), per_size["r_hi"].to_numpy()
    width = np.where(hi > lo, hi - lo, np.maximum(hi, 1e-300) * 0.02)  # one size: a thin bar at it
    for ax, col, label in ((ax1, "total", "total u in the class (J)"), (ax2, "mean", "mean u per particle (J)")):
        ax.bar(lo, per_size[col].to_numpy(), width=width, align="edge", edgecolor="k", linewidth=0.5)
        ax.set_xlabel("radius class (m)")
        ax.set_ylabel(label)
        if (per_size[col] > 0).any():
            ax.set_yscale("log")
    for ax in (ax1, ax2):
        if len(lo) and lo.min() > 0 and hi.max() / lo.min() > 3:
            ax.set_xscale("log")
        else:
            ax.xaxis.set_major_locator(MaxNLocator(4))
    ax1.set_title(f"Energy per size class, timestep {step}")
    ax2.set_title("Mean energy per particle of the class")
    return fig


def _fig_misattribution(particles: pd.DataFrame, step: int):
    """Distribution over particles of (u_split - u)/u for the 50/50 and radius splits."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    p = particles[particles["u"] > 0]
    errs = {
        label: ((p[col] - p["u"]) / p["u"]).to_numpy()
        for col, label in (
            ("u_equal", "50/50 split"),
            ("u_radius", "radius-weighted split"),
            ("u_springs", "series springs"),
        )
        if col in p
    }
    values = np.concatenate(list(errs.values())) if errs else np.empty(0)
    values = values[np.isfinite(values)]
    if len(values):
        lo, hi = min(values.min(), -1e-3), max(np.quantile(values, 0.995), 1e-3)
        edges = np.linspace(lo, hi, 61)
        for label, e in errs.items():
            ax.hist(np.clip(e[np.isfinite(e)], lo, hi), bins=edges, histtype="step", linewidth=1.5, label=label)
        ax.set_yscale("log")
        ax.legend()
    ax.axvline(0.0, color="k", linewidth=0.5)
    ax.set_xlabel("(u_split - u) / u per particle")
    ax.set_ylabel("particles")
    ax.set_title(f"Misattribution of the simpler splits, timestep {step}")
    return fig


def misattribution_table(particles: pd.DataFrame) -> pd.DataFrame:
    """Per rule: quantiles of the per-particle (u_split - u)/u over particles with u > 0, and the share of
    particles whose energy the rule misplaces by more than 10 %."""
    p = particles[particles["u"] > 0]
    rows = []
    for col, label in (("u_equal", "50/50"), ("u_radius", "radius"), ("u_springs", "springs")):
        if col not in p or not len(p):
            continue
        e = ((p[col] - p["u"]) / p["u"]).to_numpy()
        q = np.quantile(e, [0.05, 0.5, 0.95])
        rows.append(
            {
                "split": label,
                "particles": len(e),
                "p05": q[0],
                "median": q[1],
                "p95": q[2],
                "max_abs": float(np.abs(e).max()),
                "beyond_10pct": float((np.abs(e) > 0.1).mean()),
            }
        )
    return pd.DataFrame(rows)


def _fig_frames(pf: pd.DataFrame):
    """Every energy column of the frames on a log axis (|u_adh| dashed: it is signed)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    use_time = "time" in pf and len(pf) > 0 and pf["time"].map(known).all()
    x = pf["time"] if use_time else pf["step"]
    marker = "o" if len(pf) < 50 else None
    ax.plot(x, pf["u_contacts"], "k-", marker=marker, linewidth=2, label="elastic total (contacts)")
    for col in energy_modes(pf):
        y = pf[col].to_numpy(dtype=np.float64)
        if col == "u_adh":
            ax.plot(x, np.abs(y), "--", marker=marker, label="|cohesion work u_adh| (signed: see table)")
        else:
            ax.plot(x, y, "-", marker=marker, label=mode_label(col))
    if "u_walls" in pf:
        ax.plot(x, pf["u_walls"], ":", marker=marker, label="held by walls")
    ax.set_yscale("log")
    ax.set_xlabel("time (s)" if use_time else "timestep")
    ax.set_ylabel("energy (J)")
    ax.set_title("Energy per frame (log axis; zero values are not drawn)")
    ax.legend(fontsize=8)
    return fig


def _fig_split(sc: pd.DataFrame, step: int, names: Mapping[int, str]):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    types = sc["type"].to_numpy()
    x = np.arange(len(types))
    labels = {
        "material": "material law (Feng & Gao)",
        "equal": "50/50",
        "radius": "radius-weighted",
        "springs": "series springs (YADE linear law)",
    }
    rules = [r for r in labels if f"total_{r}" in sc]
    width = 0.8 / len(rules)
    for k, rule in enumerate(rules):
        ax.bar(x + (k - (len(rules) - 1) / 2) * width, sc[f"total_{rule}"], width=width, label=labels[rule])
    ax.set_xticks(x, [_type_label(t, names) for t in types])
    ax.set_ylabel("energy held by the type (J)")
    ax.set_title(f"Energy per type under {len(rules)} splits, timestep {step}")
    ax.legend()
    return fig


def _fig_cp(contacts: pd.DataFrame, step: int):
    import matplotlib.pyplot as plt

    cp = contacts[["cpx", "cpy", "cpz"]].to_numpy()
    sim = contacts[["cpx_sim", "cpy_sim", "cpz_sim"]].to_numpy()
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.linalg.norm(cp - sim, axis=1) / contacts["delta"].to_numpy()
    fig, ax = plt.subplots(figsize=(7, 4))
    for kind, mask in (("pair", contacts["wall"].to_numpy() < 0), ("wall", contacts["wall"].to_numpy() >= 0)):
        dk = d[mask & np.isfinite(d)]
        if len(dk):
            ax.hist(dk, bins=40, histtype="step", linewidth=1.5, label=f"{kind} contacts (n = {len(dk)})")
    ax.set_xlabel("|cp - cp_simulator| / overlap")
    ax.set_ylabel("contacts")
    ax.set_title(f"Material-weighted against simulator contact point, timestep {step}")
    ax.legend()
    return fig


# --------------------------------------------------------------------------- page

_CSS = """body{font-family:sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0 1.5em}
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}
th{background:#eee}figure{margin:1em 0}figcaption{font-size:0.85em;color:#555}img{max-width:100%}
pre{background:#f6f6f6;padding:0.5em;font-size:0.8em;overflow-x:auto}
.missing{border:2px solid #c60;background:#fff4e8;padding:0.5em 1em}.ok{color:#060}
.summary{border:2px solid #246;background:#f2f6fb;padding:0.2em 1em 0.5em;margin-bottom:1.5em}
.summary table{font-size:0.95em}.summary td{white-space:nowrap}.lead{font-size:1.15em;font-weight:bold}
details{margin:1em 0}summary{cursor:pointer;font-weight:bold}"""


LABEL_COLUMNS = frozenset(
    {"step", "type", "material", "wall", "name", "kind", "mode", "column", "split", "size_class", "frame"}
)
"""Columns that name or number a row: shown without a unit."""

STAT_UNITS = {
    **dict.fromkeys(("total", "mean", "std", "p05", "p25", "p50", "p75", "p95", "u_contacts"), "J"),
    **dict.fromkeys(
        (
            "count",
            "share_of_total",
            "top1_share",
            "top10_share",
            "gini",
            "expected_error",
            "share",
            "balance_rel_error",
            "nu",
        ),
        "1",
    ),
    "r_lo": "m",
    "r_hi": "m",
    "E": "Pa",
}
"""Units of the report's derived columns (the statistics of the per-type, per-size and per-frame tables, the
materials'); the stored columns' are :data:`~demsplit.results.schema.UNITS`."""


def column_unit(column: str, units: Mapping[str, str] | None = None) -> str:
    """The unit of a report table's ``column``: ``units`` (the table's own, where a name means something else
    than elsewhere), ``%`` for ``*_pct``, :data:`STAT_UNITS`, the store's :data:`~demsplit.results.schema.UNITS`,
    then a statistic of one split (``total_radius``: that of ``total``). An unknown column is a KeyError: every
    table the report shows gives every number its unit."""
    if units and column in units:
        return units[column]
    if column.endswith("_pct"):
        return "%"
    if column in STAT_UNITS:
        return STAT_UNITS[column]
    if column in UNITS:
        return UNITS[column]
    base, _, rule = column.rpartition("_")
    if rule in ("material", *SPLIT_NAMES, "springs") and base in STAT_UNITS:
        return STAT_UNITS[base]
    raise KeyError(f"the report has no unit for the column {column!r}")


def _table(
    df: pd.DataFrame, unknown: Mapping[str, np.ndarray] | None = None, units: Mapping[str, str] | None = None
) -> str:
    """``df`` as an HTML table (:func:`_fmt`), each number column's header with its unit (:func:`column_unit`)."""
    out = _fmt(df, unknown)
    out.columns = [c if c in LABEL_COLUMNS else f"{c} ({column_unit(c, units)})" for c in out.columns]
    return out.to_html(index=False, border=0, escape=True)


RELATIVE_UNITS = {
    c: "1"
    for c in ("particles", "p05", "median", "p95", "max", "max_abs", "beyond_10pct", "n_missing", "print_bound_median")
}
"""Units of the misattribution and contact-point tables, whose statistics are of relative values."""


def _mode_table(one: Results) -> pd.DataFrame:
    """Frame totals of every energy mode over contacts, particles and walls (J), and how many contacts
    each total leaves out as not computed (``contacts_not_computed``)."""
    rows = []
    unknown = not_computed_mask(one.raw.contacts)
    found = dict.fromkeys([*one.raw.frames.columns, *one.raw.contacts.columns, *one.raw.particles.columns])
    for col in energy_modes(pd.DataFrame(columns=list(found))):
        table = one.raw.frames if col in one.raw.frames else one.raw.contacts if col in one.raw.contacts else None
        total = table[col].sum() if table is not None else np.nan
        rows.append(
            {
                "mode": MODE_NAMES.get(col, col),
                "column": col,
                "contacts": float(total),
                "particles": float(one.raw.particles[col].sum()) if col in one.raw.particles else np.nan,
                "walls": float(one.raw.walls[col].sum()) if col in one.raw.walls else np.nan,
                "contacts_not_computed": int(unknown[col].sum()) if col in unknown else 0,
            }
        )
    return pd.DataFrame(rows, columns=["mode", "column", "contacts", "particles", "walls", "contacts_not_computed"])


def _energy_sections(one: Results, step: int, names: Mapping[int, str]) -> list[str]:
    """The report's sections on how a frame's energy is distributed: per type, its distribution, against
    radius and height, per size class, and the split comparison."""
    esc = html.escape
    body: list[str] = []
    cols = [
        "type",
        "count",
        "total",
        "share_of_total",
        "mean",
        "std",
        "p05",
        "p50",
        "p95",
        "top1_share",
        "top10_share",
        "gini",
    ]
    per_type = one.per_type()
    cols += ["expected_error"] if "expected_error" in per_type else []
    body += [
        "<h2>Energy per particle type</h2>",
        _table(
            _with_names(
                per_type[
                    cols
                    + (["n_not_computed"] if "n_not_computed" in per_type and per_type["n_not_computed"].any() else [])
                ],
                names,
            )
        ),
        _figure(
            _fig_histogram(one.raw.particles, step, names),
            "Histogram of per-particle elastic energy (material distribution law).",
            "Energy histogram per type",
        ),
    ]
    body += [
        "<h2>Distribution</h2>",
        _figure(
            _fig_distribution(one.raw.particles, step, names),
            "Left: probability density of u/&lt;u&gt; over log-spaced bins, &lt;u&gt; the mean over every particle of "
            "the group (particles with u = 0 count in the normalisation, not in the curve). Right: the complementary "
            "cumulative distribution P(u/&lt;u&gt; &ge; x). Log axes: a power-law tail is a straight line.",
            "Normalised distribution and CCDF",
        ),
    ]
    fig, note = _fig_radius(one.raw.particles, step, names)
    body.append(_figure(fig, f"Particle energy against radius{esc(note)}.", "Energy against radius"))
    if {"x", "y", "z"} <= set(one.raw.particles.columns):
        body += [
            "<h2>Where the energy sits</h2>",
            _figure(
                _fig_height(one.raw.particles, step, names),
                f"Mean energy per particle (left) and share of the frame's particle energy (right) in "
                f"{HEIGHT_BINS} horizontal slabs of z (particles by their centre).",
                "Energy against height",
            ),
        ]
        fig, note = _fig_views(one.raw.particles, step)
        body.append(
            _figure(
                fig,
                "Left: the particles cut by the plane y = median y, drawn as their cross-sections "
                "and coloured by u (log scale; grey: u = 0). Right: every particle's centre projected on "
                f"the x-z plane{esc(note)}, the highest energies drawn last.",
                "Slice and projection",
            )
        )
    per_size = one.per_size()
    body += [
        "<h2>Energy per size class</h2>",
        _figure(
            _fig_size(per_size, step),
            "Each bar spans its radius class [r_lo, r_hi] (log-spaced classes "
            "between the smallest and the largest radius of this frame); log energy axes.",
            "Energy per size class",
        ),
        _table(per_size),
    ]
    if {"u_equal", "u_radius"} <= set(one.raw.particles.columns):
        sc = one.split_comparison()
        body += [
            "<h2>Split comparison</h2>",
            _figure(
                _fig_split(sc, step, names),
                "Energy held per type under the material law, the 50/50 split and the radius-weighted split; "
                "misattribution = (split total - material total)/material total.",
                "Energy per type under each split",
            ),
            _table(
                _with_names(
                    sc[
                        ["step", "type", "count"]
                        + [c for c in sc.columns if c.startswith(("total_", "misattribution_", "gini_"))]
                    ],
                    names,
                )
            ),
            _figure(
                _fig_misattribution(one.raw.particles, step),
                "Per-particle misattribution (u_split - u)/u of the simpler splits, over the particles with "
                "u &gt; 0 (values beyond the 99.5th percentile are gathered in the last bin). -1: the split "
                "gives the particle nothing; +1: twice its energy.",
                "Per-particle misattribution",
            ),
            _table(misattribution_table(one.raw.particles), units=RELATIVE_UNITS),
        ]
    return body


def _summary_box(results: Results, one: Results, step: int, names: Mapping[int, str], u_total: float) -> list[str]:
    """The report's first screen: per material, the material-law energy and how far the 50/50 and radius
    splits are off (:func:`split_headline`), what they mean, the expected error of the material law, then
    what was not computed."""
    esc = html.escape
    fr = one.raw.frames.iloc[0]
    out = ["<div class='summary' id='summary'>", f"<h2>Summary: the elastic energy per material, timestep {step}</h2>"]
    if u_total > 0:
        table, sentences = split_headline(one, names)
        lead = headline_lead(table, names)
        out += [
            f"<p class='lead'>{esc(lead)}</p>" if lead else "",
            f"<p>{u_total:.4g} J of elastic energy in {int(fr['n_contacts'])} contacts, held by the particles "
            "as the material law (Feng &amp; Gao) splits it, and where the two simpler splits other tools use "
            "put it instead (off: (split &minus; material law)/material law).</p>",
            _headline_shown(table).to_html(index=False, border=0, escape=True),
            *(f"<p>{esc(sentence)}</p>" for sentence in sentences),
        ]
        split = (results.provenance.get("options") or {}).get("split", "material")
        out.append(
            f"<p>{esc(accuracy_line(one.raw.contacts, split))}</p>"
            if "share_n1_error" in one.raw.contacts
            else "<p>The expected error of the split was not computed (demsplit run --no-accuracy, or a "
            "store without contacts).</p>"
        )
    else:
        out.append(f"<p>{esc(EMPTY_FRAME)}</p>")
    missing = not_computed(results, fr)
    if missing:
        out += [
            "<div class='missing' id='not-computed'><h3>Not computed</h3><p>These values are unknown, not 0; "
            "they are left out of every total below.</p><ul>",
            *(f"<li>{esc(m)}</li>" for m in missing),
            "</ul></div>",
        ]
    else:
        out.append(
            "<p class='ok' id='not-computed'>Not computed: nothing (the store records no mode, wall or "
            "contact left out).</p>"
        )
    return [*out, "</div>"]


def _frames_summary(pf: pd.DataFrame) -> str:
    """The per-frame series in three rows (the first frame, the last, the one of most elastic energy), for the
    page; the whole table is folded below it."""
    if not len(pf):
        return ""
    picks = {"first": 0, "last": len(pf) - 1, "most energy": int(np.argmax(pf["u_contacts"].to_numpy()))}
    cols = [
        c
        for c in ("step", "time", "n_particles", "n_contacts", "u_contacts", "u_walls", "balance_rel_error")
        if c in pf
    ]
    rows = pf.iloc[list(picks.values())][cols].reset_index(drop=True)
    rows.insert(0, "frame", list(picks))
    worst = pf["balance_rel_error"].max() if "balance_rel_error" in pf else np.nan
    return (
        f"<p>{len(pf)} frames; largest energy balance error |sum particles + sum walls &minus; sum contacts| / "
        f"sum contacts: {'-' if not np.isfinite(worst) else f'{worst:.3g}'}.</p>" + _table(rows)
    )


def _shown_path(text: str) -> str:
    """A run's source for the page's first lines: relative to the current directory when it is a file below it
    (the provenance, folded at the bottom, keeps the absolute path)."""
    path = Path(text)
    if path.is_absolute() and path.is_file() and path.is_relative_to(Path.cwd()):
        return str(path.relative_to(Path.cwd()))
    return text


def write_html(
    results: Results,
    path: str | Path,
    step: int | None = None,
    names: Mapping[int, str] | None = None,
    *,
    inputs: Iterable[str | Path] = (),
    overwrite: bool = False,
) -> Path:
    """Write the HTML report of frame ``step`` (default: the last) and the per-frame series to ``path``
    (atomically: ``path.tmp``, then renamed); ``names``: material names of types (:meth:`Results.type_names`).
    ``path`` is never one of ``inputs``, nor an existing file that is not a demsplit report unless
    ``overwrite`` (:mod:`demsplit.outputs`): checked before the page is made, and again when it is written."""
    check_output_path(path, inputs, kind=REPORT, overwrite=overwrite)
    import matplotlib

    matplotlib.use("Agg")
    step = _pick_step(results, step)
    one = results.frame(step)
    fr = one.raw.frames.iloc[0]
    names = results.type_names(names)
    pf = results.per_frame()
    prov = results.provenance or {}
    esc = html.escape
    time = f" (t = {fr['time']:.6g} s)" if known(fr.get("time")) else ""
    steps = results.steps
    head = [
        f"<h1>demsplit report</h1><p>{len(steps)} frame(s), timesteps {int(steps.min())} to {int(steps.max())}; "
        f"detailed frame: <b>timestep {step}</b>{esc(time)} (another: <code>demsplit report FILE --step N</code>)."
    ]
    source = (prov.get("scene") or {}).get("source")
    model = prov.get("model") or {}
    if source or model:
        head.append(f"<br>Run: {esc(_shown_path(str(source or '?')))}; contact law {esc(str(model.get('law', '?')))}.")
    head.append(
        f"<br>{int(fr['n_particles'])} particles, {int(fr['n_contacts'])} contacts "
        f"({int(fr['n_wall_contacts'])} with walls).</p>"
    )
    u_total = sum(fr[m] for m in elastic_columns(one.raw.frames))
    head += _summary_box(results, one, step, names, u_total)
    other = [n for n in prov.get("notes", []) if "NOT COMPUTED" not in n]
    if other:
        head += [
            "<details><summary>Notes of the run</summary><ul>",
            *(f"<li>{esc(n)}</li>" for n in other),
            "</ul></details>",
        ]
    body = [
        *head,
        "<h2>Energy per mode</h2>",
        "<p>Totals of this frame (J). The elastic modes sum to the elastic total; the cohesion work "
        "<code>u_adh</code>, where present, is signed and kept apart.</p>",
        _table(_mode_table(one), units={"contacts": "J", "particles": "J", "walls": "J", "contacts_not_computed": "1"}),
    ]
    own = simulator_energies(results, step, fr)
    if own:
        body += [
            "<p id='simulator-energies'>The simulator's own numbers of this instant:</p><ul>",
            *(f"<li>{esc(line)}</li>" for line in own),
            "</ul>",
        ]
    if "share_n1_error" in one.raw.contacts:
        body.append(f"<p>{esc(accuracy_line(one.raw.contacts, prov.get('options', {}).get('split', 'material')))}</p>")
    body += _energy_sections(one, step, names) if u_total > 0 else [f"<p>{esc(EMPTY_FRAME)}</p>"]
    frame_cols = [
        "step",
        "time",
        "n_particles",
        "n_contacts",
        "n_wall_contacts",
        "u_contacts",
        *energy_modes(pf),
        "u_walls",
        "balance_rel_error",
        "gini",
    ]
    body += [
        "<h2>Frames</h2>",
        _figure(
            _fig_frames(pf),
            "Elastic total, every energy mode and the energy held by "
            "walls per frame, on a log axis so that small terms are visible.",
            "Energy per frame",
        ),
        _frames_summary(pf),
        f"<details id='frames-table'><summary>The per-frame table ({len(pf)} rows)</summary>",
        _table(pf[[c for c in dict.fromkeys(frame_cols) if c in pf]]),
        "</details>",
    ]
    if len(one.raw.walls):
        we = one.wall_energy()
        body += ["<h2>Walls</h2>", _table(_with_names(we, names), not_computed_mask(we))]
    if {"cpx_sim", "cpy_sim", "cpz_sim"} <= set(one.raw.contacts.columns) and len(one.raw.contacts):
        body += [
            "<h2>Contact point</h2>",
            _figure(
                _fig_cp(one.raw.contacts, step),
                "Distance between the material-weighted contact point and the simulator's "
                "own, in units of the overlap.",
                "Contact point shift",
            ),
            _table(one.contact_point_shift(), units=RELATIVE_UNITS),
        ]
    materials = (prov.get("scene") or {}).get("materials") or {}
    if materials or names:
        rows = {int(t): {k: v for k, v in (m or {}).items() if k != "name"} for t, m in materials.items()}
        body += [
            "<h2>Materials</h2>",
            _table(
                pd.DataFrame(
                    [{"type": t, "material": names.get(t, ""), **rows.get(t, {})} for t in sorted({*rows, *names})]
                )
            ),
        ]
    body += [
        "<details id='provenance'><summary>Provenance (inputs with their BLAKE3 digest, options, scene, "
        "demsplit version)</summary>",
        f"<pre>{esc(json.dumps(prov, indent=2, sort_keys=True, default=str))}</pre></details>",
    ]
    page = (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'>{REPORT_GENERATOR}<title>demsplit report</title>"
        f"<style>{_CSS}</style></head><body>{''.join(body)}</body></html>"
    )
    return write_output(path, page, kind=REPORT, inputs=inputs, overwrite=overwrite)
