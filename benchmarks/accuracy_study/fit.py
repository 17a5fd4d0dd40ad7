"""The fit of the split's error model on the fit sweep, and its check on the held-out sweep.

Reads results/sweep_fit/ and results/sweep_heldout/ (sweep.py; two seeds: no held-out point is in the fit)
and, for each FE material (``neohooke``, the runtime's reference, and ``small``):

1. chooses the model's blocks (plugin/physics/accuracy.py, ``FORM``: which of x, x^2, x^3, f y, f y x enter
   and to which power of nu) by 10-fold cross-validation on the fit sweep alone (fold = point index mod 10):
   every candidate of the grid below, the same blocks for both materials; the rule: the fewest terms among the
   candidates whose cross-validated rms share error (the worse of the two materials) is within 5 % of the
   best, then the smallest such error;
2. fits the coefficients, least squares of y = ln((S1/S2)_FE / (c1/c2)) = k1 - k2 over every converged point
   of the fit sweep (a plane is a block of 2000 R1 in the FE, a half-space as in the runtime);
3. reports the share error of body 1 (FE share minus the model's; absolute, in share units), rms and max:
   the fit residual, the cross-validated error, and the error on the held-out sweep, by a/R1 band too,
   beside the law's error, the radius split's and 50/50's.

Writes results/fit.json, results/fit.md (the tables of docs/accuracy.md section 3), results/model_selection.md,
results/heldout_predictions.csv (each held-out point with the runtime's prediction: tests/validation/test_fe.py
checks plugin/physics/accuracy.py against it) and the generated block (FORM, COEFFICIENTS) of
plugin/physics/accuracy.py.

Run (seconds; no FE)::

    python benchmarks/accuracy_study/fit.py
"""

from __future__ import annotations

import csv
import importlib.util
import itertools
import json
import re
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
RESULTS = HERE / "results"
ACCURACY = REPO / "plugin" / "physics" / "accuracy.py"
MODELS = ("neohooke", "small")
sys.path.insert(0, str(HERE))

from sweep import read_rows  # noqa: E402

# candidate blocks: (monomial, numbers of nu powers tried; 0 = left out)
GRID = (("x", (3, 4)), ("x2", (0, 1, 2, 3)), ("x3", (0, 1, 2, 3)), ("fy", (1, 2, 3)), ("fyx", (0, 1, 2, 3)))
CV_FOLDS = 10
CV_TOLERANCE = 1.05


def load_accuracy():
    """plugin/physics/accuracy.py loaded by path (numpy only; no package import needed)."""
    spec = importlib.util.spec_from_file_location("accuracy", ACCURACY)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


ACC = load_accuracy()


def load(name: str, model: str) -> tuple[list[dict], list[dict]]:
    """(usable rows, all rows) of a sweep: usable = converged, body 2 stores energy (not near-rigid to 0)."""
    rows = read_rows(RESULTS / f"sweep_{name}" / f"sweep_{model}.csv")  # [] if the sweep is not there
    return [r for r in rows if r["converged"] and r["U2"] > 0], rows


def columns(rows) -> dict:
    keys = (
        "a_over_R1",
        "a_over_R2",
        "nu1",
        "nu2",
        "E1",
        "E2",
        "R1",
        "R2",
        "share_fe",
        "share_law",
        "ratio_fe",
        "ratio_law",
        "i",
    )
    return {k: np.array([float(r[k]) for r in rows]) for k in keys}


def design(c: dict, form) -> np.ndarray:
    """Rows: points; columns: the model's terms of k1 - k2."""
    x1, x2, f1 = c["a_over_R1"], c["a_over_R2"], c["share_law"]
    y = x1 + x2
    return (ACC.body_terms(x1, f1, y, c["nu1"], form) - ACC.body_terms(x2, 1.0 - f1, y, c["nu2"], form)).T


def share_from(f1, d):
    """Share of body 1 from the law's share f1 and the log-ratio correction d = k1 - k2."""
    return f1 / (f1 + (1 - f1) * np.exp(-d))


def target(c: dict) -> np.ndarray:
    return np.log(c["ratio_fe"] / c["ratio_law"])


def stats(err) -> dict:
    err = np.asarray(err)
    return {"n": int(err.size), "rms": float(np.sqrt(np.mean(err**2))), "max_abs": float(np.max(np.abs(err)))}


def cross_validated(c: dict, form) -> np.ndarray:
    """Share errors of each fit point predicted by the model fitted on the other folds (fold = i mod 10)."""
    X, y = design(c, form), target(c)
    fold = c["i"].astype(int) % CV_FOLDS
    err = np.empty(len(y))
    for k in range(CV_FOLDS):
        te = fold == k
        coef, *_ = np.linalg.lstsq(X[~te], y[~te], rcond=None)
        err[te] = c["share_fe"][te] - share_from(c["share_law"][te], X[te] @ coef)
    return err


def select_form(fitcols: dict) -> tuple[tuple, list[dict]]:
    """The grid's candidates with their cross-validated errors, and the chosen blocks (module doc, step 1)."""
    table = []
    for combo in itertools.product(*(n for _, n in GRID)):
        form = tuple((m, n) for (m, _), n in zip(GRID, combo) if n > 0)
        row = {"form": form, "terms": sum(n for _, n in form)}
        for model in MODELS:
            s = stats(cross_validated(fitcols[model], form))
            row[model] = s
        row["worst_rms"] = max(row[m]["rms"] for m in MODELS)
        table.append(row)
    best = min(r["worst_rms"] for r in table)
    ok = [r for r in table if r["worst_rms"] <= CV_TOLERANCE * best]
    chosen = min(ok, key=lambda r: (r["terms"], r["worst_rms"]))
    return chosen["form"], sorted(table, key=lambda r: r["worst_rms"])


def form_text(form) -> str:
    return " + ".join(f"{m}(nu^0..{n - 1})" for m, n in form)


def write_generated_block(form, coefficients: dict) -> None:
    """Rewrite FORM and COEFFICIENTS of plugin/physics/accuracy.py between its generated-block markers."""
    text = ACCURACY.read_text()
    lines = [f"FORM = {tuple(form)!r}", "COEFFICIENTS = {"]
    for model in MODELS:
        lines.append(f'    "{model}": (')
        nums = [f"{v:.12e}," for v in coefficients[model]]
        for k in range(0, len(nums), 5):
            lines.append("        " + " ".join(nums[k : k + 5]))
        lines.append("    ),")
    lines.append("}")
    head = (
        "# --- generated by benchmarks/accuracy_study/fit.py (from benchmarks/accuracy_study/results/fit.json); "
        "do not edit ---"
    )
    tail = "# --- end of the generated block ---"
    pat = re.compile(r"# --- generated by [^\n]*\n.*?(" + re.escape(tail) + r")", re.S)  # whichever path it names
    new, n = pat.subn(lambda m: head + "\n" + "\n".join(lines) + "\n" + m.group(1), text)
    if n != 1:
        raise RuntimeError("generated block markers not found in " + str(ACCURACY))
    ACCURACY.write_text(new)


def radius_share(c: dict) -> np.ndarray:
    """demsplit's radius split r1/(r1 + r2) (1 against a plane), from a/R1 and a/R2."""
    x1, x2 = c["a_over_R1"], c["a_over_R2"]
    return np.where(x2 == 0, 1.0, x2 / np.where(x1 + x2 > 0, x1 + x2, 1.0))


def main():
    data = {m: {s: load(s, m) for s in ("fit", "heldout")} for m in MODELS}
    fitcols = {m: columns(data[m]["fit"][0]) for m in MODELS}
    form, table = select_form(fitcols)
    out = {
        "command": "python benchmarks/accuracy_study/fit.py",
        "form": [list(f) for f in form],
        "terms": ACC.term_names(form),
        "selection": {"folds": CV_FOLDS, "tolerance": CV_TOLERANCE, "candidates": len(table)},
        "models": {},
    }
    coefficients, held_rows = {}, []
    for model in MODELS:
        fit_ok, fit_all = data[model]["fit"]
        held_ok, held_all = data[model]["heldout"]
        c = fitcols[model]
        h = columns(held_ok) if held_ok else None  # (no held-out sweep yet: the fit alone)
        X = design(c, form)
        coef, *_ = np.linalg.lstsq(X, target(c), rcond=None)
        coefficients[model] = [float(v) for v in coef]
        e = {
            "coefficients": coefficients[model],
            "fit_points": len(fit_ok),
            "heldout_points": len(held_ok),
            "fit_not_usable": sorted({r["i"] for r in fit_all} - {r["i"] for r in fit_ok}),
            "heldout_not_usable": sorted({r["i"] for r in held_all} - {r["i"] for r in held_ok}),
        }
        for name, cc in (("fit", c), ("heldout", h)) if held_ok else (("fit", c),):
            pred = share_from(cc["share_law"], design(cc, form) @ coef)
            e[name] = {
                "model_error": stats(cc["share_fe"] - pred),
                "law_error": stats(cc["share_fe"] - cc["share_law"]),
                "radius_error": stats(cc["share_fe"] - radius_share(cc)),
                "equal_error": stats(cc["share_fe"] - 0.5),
            }
            for lo, hi in ((0.0, 0.1), (0.1, 0.2), (0.2, 0.3)):
                band = (cc["a_over_R1"] >= lo) & (cc["a_over_R1"] < hi)
                e[name][f"model_error_a_over_R1_{lo:g}_{hi:g}"] = stats((cc["share_fe"] - pred)[band])
            plane = np.isinf(cc["R2"])
            e[name]["model_error_planes"] = stats((cc["share_fe"] - pred)[plane])
            e[name]["model_error_spheres"] = stats((cc["share_fe"] - pred)[~plane])
            if name == "heldout":
                for k in range(len(cc["i"])):
                    held_rows.append(
                        {
                            "model": model,
                            "i": int(cc["i"][k]),
                            **{
                                q: float(cc[q][k])
                                for q in (
                                    "a_over_R1",
                                    "a_over_R2",
                                    "nu1",
                                    "nu2",
                                    "E1",
                                    "E2",
                                    "R2",
                                    "share_law",
                                    "share_fe",
                                )
                            },
                            "share_model": float(pred[k]),
                            "predicted_error": float(pred[k] - cc["share_law"][k]),
                        }
                    )
        e["fit"]["cross_validated_error"] = stats(cross_validated(c, form))
        out["models"][model] = e
        print(model, json.dumps({k: e[k] for k in ("fit", "heldout") if k in e}, indent=1))
    (RESULTS / "fit.json").write_text(json.dumps(out, indent=1) + "\n")
    write_generated_block(form, coefficients)
    (RESULTS / "model_selection.md").write_text(selection_md(table, form))
    print(form_text(form))
    if not held_rows:
        print("no held-out sweep (results/sweep_heldout/): the fit alone")
        return
    with open(RESULTS / "heldout_predictions.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(held_rows[0].keys()))
        w.writeheader()
        w.writerows(held_rows)
    md = fit_md(out)
    (RESULTS / "fit.md").write_text(md)
    print(md)


def pct(s: dict, digits: int = 3) -> str:
    return f"{100 * s['rms']:.{digits}f} % / {100 * s['max_abs']:.{digits}f} %"


def selection_md(table, form) -> str:
    head = ["| blocks | terms | CV neohooke: rms / max | CV small: rms / max | chosen |", "|---|---|---|---|---|"]
    rows = [
        f"| {form_text(r['form'])} | {r['terms']} | {pct(r['neohooke'])} | {pct(r['small'])} | "
        f"{'yes' if r['form'] == form else ''} |"
        for r in table[:15]
    ]
    if all(r["form"] != form for r in table[:15]):
        r = next(r for r in table if r["form"] == form)
        rows.append(f"| {form_text(r['form'])} | {r['terms']} | {pct(r['neohooke'])} | {pct(r['small'])} | yes |")
    base = next(r for r in table if r["form"] == (("x", 3), ("fy", 2)))
    rows.append(
        f"| {form_text(base['form'])} (the earlier model's terms) | {base['terms']} | "
        f"{pct(base['neohooke'])} | {pct(base['small'])} | |"
    )
    return "\n".join(head + rows) + "\n"


def fit_md(out) -> str:
    names = out["terms"]
    lines = ["| reference | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for model in MODELS:
        lines.append(f"| {model} | " + " | ".join(f"{v:+.4g}" for v in out["models"][model]["coefficients"]) + " |")
    lines += [
        "",
        "| reference | points fit + held out | law, held out: rms / max | model, fit residual: rms / max | "
        "model, cross-validated on the fit sweep: rms / max | model, held out: rms / max |",
        "|---|---|---|---|---|---|",
    ]
    for model in MODELS:
        e = out["models"][model]
        lines.append(
            f"| {model} | {e['fit_points']} + {e['heldout_points']} | "
            f"{pct(e['heldout']['law_error'], 2)} | {pct(e['fit']['model_error'])} | "
            f"{pct(e['fit']['cross_validated_error'])} | {pct(e['heldout']['model_error'])} |"
        )
    lines += [
        "",
        "| reference | held out, a/R1 < 0.1: rms / max | 0.1-0.2 | 0.2-0.3 | spheres | planes |",
        "|---|---|---|---|---|---|",
    ]
    for model in MODELS:
        h = out["models"][model]["heldout"]
        lines.append(
            f"| {model} | {pct(h['model_error_a_over_R1_0_0.1'])} | "
            f"{pct(h['model_error_a_over_R1_0.1_0.2'])} | {pct(h['model_error_a_over_R1_0.2_0.3'])} | "
            f"{pct(h['model_error_spheres'])} | {pct(h['model_error_planes'])} |"
        )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
