"""What a user reads: a terminal summary and a self-contained HTML report.

:func:`text_summary` prints the per-type table of one frame (the last by
default), the split comparison, the walls and the per-frame energy balance.
:func:`write_html` writes one HTML file with the same tables and figures
embedded as base64 PNG (matplotlib, Agg backend): energy histogram per type,
energy against radius, per-frame totals, the split comparison, and, when the
simulator's contact point is known, the contact-point shift. No file outside
the page is referenced.
"""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

import numpy as np
import pandas as pd

from ..atomic import atomic_path
from ..errors import StoreError
from .aggregate import elastic_columns
from .tables import Results

MODE_NAMES = {"u_n": "normal", "u_t": "tangential", "u_r": "rolling", "u_tw": "twisting"}

SCATTER_MAX_POINTS = 100_000
"""Energy-radius scatter plots draw at most this many particles (a seeded
random subset, stated in the caption)."""


def _pick_step(results: Results, step: int | None) -> int:
    steps = results.steps
    if len(steps) == 0:
        raise StoreError("the results hold no frames.", fix="run demsplit on a run with at least one frame.")
    if step is None:
        return int(steps.max())
    results.frame(step)  # raises with the available steps if absent
    return int(step)


def _fmt(df: pd.DataFrame) -> pd.DataFrame:
    """Floats with 4 significant digits for display."""
    return df.map(lambda v: f"{v:.4g}" if isinstance(v, float) else v)


def text_summary(results: Results, step: int | None = None) -> str:
    """The per-type summary of frame ``step`` (default: the last), as plain text."""
    step = _pick_step(results, step)
    one = results.frame(step)
    fr = one.frames.iloc[0]
    modes = elastic_columns(one.frames)
    u_total = sum(fr[m] for m in modes)
    parts = ", ".join(f"{MODE_NAMES.get(m, m)} {fr[m]:.6g} J" for m in modes)
    lines = [
        f"demsplit results: {len(results.steps)} frame(s); frame at timestep {step}"
        + (f" (t = {fr['time']:.6g} s)" if np.isfinite(fr.get("time", np.nan)) else ""),
    ]
    not_computed = [n for n in results.provenance.get("notes", []) if "NOT COMPUTED" in n]
    if not_computed or fr.get("n_not_computed", 0):
        lines += ["  NOT COMPUTED (these values are unknown, not 0; they are left out of every total below):"]
        lines += [f"    - {n}" for n in not_computed]
        if fr.get("n_not_computed", 0):
            lines.append(f"    - {int(fr['n_not_computed'])} contact(s) of this frame have modes not computed "
                         "(column not_computed)")
    lines.append(f"  {int(fr['n_particles'])} particles, {int(fr['n_contacts'])} contacts "
                 f"({int(fr['n_wall_contacts'])} with walls); elastic contact energy {u_total:.6g} J ({parts})"
                 + (f"; cohesion work {fr['u_adh']:.6g} J, apart" if "u_adh" in fr else ""))
    model = results.provenance.get("model")
    if model:
        params = ", ".join(f"{k}={v!r}" for k, v in sorted(model.get("params", {}).items())
                           if v is not None and v != "off")
        lines.append(f"  contact law: {model.get('law')}" + (f" ({params})" if params else ""))
    if np.isfinite(fr.get("overlap_max_rel_error", np.nan)):
        lines.append("  overlaps recomputed from printed positions (contacts without a dumped delta, e.g. primitive "
                     f"walls): max relative error bound {fr['overlap_max_rel_error']:.3g}")
    cols = ["type", "count", "total", "share_of_total", "mean", "p50", "p95", "top10_share", "gini"]
    table = one.per_type()
    cols += ["expected_error"] if "expected_error" in table else []
    lines += ["", "Energy per particle type (J; material distribution law; expected_error: the split's expected "
              "relative error, finite-element model):", _fmt(table[cols]).to_string(index=False)]
    if {"u_equal", "u_radius"} <= set(one.particles.columns):
        sc = one.split_comparison()
        sc = sc[["type"] + [c for c in sc.columns if c.startswith(("total_", "misattribution_"))]]
        lines += ["", "Split comparison (J; misattribution in % of the material-law total):",
                  _fmt(sc).to_string(index=False)]
    if len(one.walls):
        we = one.wall_energy()
        lines += ["", "Walls (J):", _fmt(we[[c for c in ("wall", "name", "kind", "u", "u_n", "u_t", "n_contacts",
                                                         "share") if c in we]]).to_string(index=False)]
    if {"cpx_sim", "cpy_sim", "cpz_sim"} <= set(one.contacts.columns):
        lines += ["", "Contact point: |cp - cp_simulator| / overlap (print_bound_median: what the dump's printed "
                  "digits alone allow; a shift not far above it measures the print precision):",
                  _fmt(one.contact_point_shift()).to_string(index=False)]
    if "share_n1_error" in one.contacts:
        lines += ["", accuracy_line(one.contacts, results.provenance.get("options", {}).get("split", "material"))]
    pf = results.per_frame()
    worst = pf["balance_rel_error"].max()
    lines += ["", f"Energy balance over {len(pf)} frame(s): max |sum particles + sum walls - sum contacts| "
              f"/ sum contacts = {worst:.3g}"]
    skipped = results.provenance.get("skipped")
    if skipped:
        lines += ["", "Not computed:"] + [f"  {k}: {v}" for k, v in dict(skipped).items()]
    return "\n".join(lines) + "\n"


def accuracy_line(contacts: pd.DataFrame, split: str) -> str:
    """How far this frame's split can be trusted (finite-element error model, docs/accuracy.md): the
    share of the normal energy in contacts whose expected share error exceeds 1 %, and the contacts
    beyond the Hertz range a/R > 0.1."""
    from ..physics.accuracy import HERTZ_VALIDITY

    u = contacts["u_n"].to_numpy()
    err = np.abs(contacts["share_n1_error"].to_numpy())
    big = err > 0.01
    beyond = (contacts[["a_over_r1", "a_over_r2"]].to_numpy() > HERTZ_VALIDITY).any(axis=1)
    total = u.sum()
    frac = u[big].sum() / total if total > 0 else 0.0
    weighted = (err * u).sum() / total if total > 0 else 0.0
    return (f"Accuracy of the split ({split}; finite-element error model, docs/accuracy.md): expected share "
            f"error {weighted:.2%} energy-weighted, max {err.max() if len(err) else 0:.2%}; {frac:.1%} of the "
            f"normal energy in contacts beyond 1 % expected error; {int(beyond.sum())} contact(s) beyond the Hertz "
            f"range a/R > {HERTZ_VALIDITY}")


def _png(fig) -> str:
    """The figure as an <img> tag with a base64 PNG data URI (closes the figure)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img alt="figure" src="data:image/png;base64,{data}">'


def _fig_histogram(particles: pd.DataFrame, step: int):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    positive = particles[particles["u"] > 0]
    if len(positive):
        edges = np.geomspace(positive["u"].min(), positive["u"].max() * (1 + 1e-12), 41)
        for t, sub in positive.groupby("type"):
            ax.hist(sub["u"], bins=edges, histtype="step", linewidth=1.5, label=f"type {t} (n = {len(sub)})")
        ax.set_xscale("log")
        ax.legend()
    ax.set_xlabel("particle elastic energy u (J)")
    ax.set_ylabel("particles")
    ax.set_title(f"Energy per particle, timestep {step} ({(particles['u'] <= 0).sum()} particles with u = 0 not shown)")
    return fig


def _fig_radius(particles: pd.DataFrame, step: int) -> tuple[object, str]:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    df = particles[particles["u"] > 0]
    note = ""
    if len(df) > SCATTER_MAX_POINTS:
        df = df.sample(SCATTER_MAX_POINTS, random_state=0)
        note = f" (random subset of {SCATTER_MAX_POINTS} particles)"
    for t, sub in df.groupby("type"):
        ax.scatter(sub["radius"], sub["u"], s=6, alpha=0.6, label=f"type {t}")
    if len(df):
        ax.set_yscale("log")
        ax.legend()
    ax.set_xlabel("radius (m)")
    ax.set_ylabel("u (J)")
    ax.set_title(f"Energy against radius, timestep {step}")
    return fig, note


def _fig_frames(pf: pd.DataFrame):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    use_time = "time" in pf and len(pf) > 0 and pf["time"].notna().all()
    x = pf["time"] if use_time else pf["step"]
    style = "o-" if len(pf) < 50 else "-"
    ax.plot(x, pf["u_contacts"], style, label="total (contacts)")
    ax.plot(x, pf["u_n"], style, label="normal")
    ax.plot(x, pf["u_t"], style, label="tangential")
    ax.plot(x, pf["u_walls"], style, label="held by walls")
    ax.set_xlabel("time (s)" if use_time else "timestep")
    ax.set_ylabel("elastic energy (J)")
    ax.set_title("Elastic contact energy per frame")
    ax.legend()
    return fig


def _fig_split(sc: pd.DataFrame, step: int):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    types = sc["type"].astype(str).to_numpy()
    x = np.arange(len(types))
    labels = {"material": "material law (Feng & Gao)", "equal": "50/50", "radius": "radius-weighted",
              "springs": "series springs (YADE linear law)"}
    rules = [r for r in labels if f"total_{r}" in sc]
    width = 0.8 / len(rules)
    for k, rule in enumerate(rules):
        ax.bar(x + (k - (len(rules) - 1) / 2) * width, sc[f"total_{rule}"], width=width, label=labels[rule])
    ax.set_xticks(x, [f"type {t}" for t in types])
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


_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0 1.5em}
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}
th{background:#eee}figure{margin:1em 0}figcaption{font-size:0.85em;color:#555}
pre{background:#f6f6f6;padding:0.5em;font-size:0.8em;overflow-x:auto}"""


def _table(df: pd.DataFrame) -> str:
    return _fmt(df).to_html(index=False, border=0, escape=True)


def write_html(results: Results, path: str | Path, step: int | None = None) -> Path:
    """Write the HTML report of frame ``step`` (default: the last) and the
    per-frame series to ``path`` (atomically: ``path.tmp``, then renamed)."""
    import matplotlib

    matplotlib.use("Agg")
    step = _pick_step(results, step)
    one = results.frame(step)
    pf = results.per_frame()
    cols = ["type", "count", "total", "share_of_total", "mean", "std", "p05", "p50", "p95", "top1_share",
            "top10_share", "gini"]
    body = [f"<h1>demsplit report</h1><p>{len(results.steps)} frame(s); detailed frame: timestep {step}.</p>",
            "<h2>Energy per particle type</h2>", _table(one.per_type()[cols]),
            "<figure>", _png(_fig_histogram(one.particles, step)),
            "<figcaption>Histogram of per-particle elastic energy (material distribution law).</figcaption></figure>"]
    fig, note = _fig_radius(one.particles, step)
    body += ["<figure>", _png(fig), f"<figcaption>Particle energy against radius{html.escape(note)}.</figcaption>"
             "</figure>", "<h2>Energy per size class</h2>", _table(one.per_size())]
    body += ["<h2>Frames</h2>", "<figure>", _png(_fig_frames(pf)),
             "<figcaption>Total, normal, tangential and wall-held elastic energy per frame.</figcaption></figure>",
             _table(pf[[c for c in ("step", "time", "n_particles", "n_contacts", "n_wall_contacts", "u_contacts",
                                    "u_walls", "balance_rel_error", "gini") if c in pf]])]
    if {"u_equal", "u_radius"} <= set(one.particles.columns):
        sc = one.split_comparison()
        body += ["<h2>Split comparison</h2>", "<figure>", _png(_fig_split(sc, step)),
                 "<figcaption>Energy held per type under the material law, the 50/50 split and the "
                 "radius-weighted split; misattribution = (split total - material total)/material total.</figcaption>"
                 "</figure>", _table(sc[["step", "type", "count"] + [c for c in sc.columns if c.startswith(
                     ("total_", "misattribution_", "gini_"))]])]
    if len(one.walls):
        body += ["<h2>Walls</h2>", _table(one.wall_energy())]
    if {"cpx_sim", "cpy_sim", "cpz_sim"} <= set(one.contacts.columns):
        body += ["<h2>Contact point</h2>", "<figure>", _png(_fig_cp(one.contacts, step)),
                 "<figcaption>Distance between the material-weighted contact point and the simulator's own, "
                 "in units of the overlap.</figcaption></figure>", _table(one.contact_point_shift())]
    body += ["<h2>Provenance</h2>",
             f"<pre>{html.escape(json.dumps(results.provenance, indent=2, sort_keys=True, default=str))}</pre>"]
    page = ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>demsplit report</title>"
            f"<style>{_CSS}</style></head><body>{''.join(body)}</body></html>")
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    return path
