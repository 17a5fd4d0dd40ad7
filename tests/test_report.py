"""Terminal summary and self-contained HTML report."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import SAMPLES, require_program
from demsplit.errors import StoreError
from demsplit.results import Results, load_results
from demsplit.results.report import text_summary, write_html
from result_frames import PROVENANCE, WALLS_META, synthetic_frame


def frame(step: int, simulator_point: bool = True, extra_modes: bool = False) -> dict:
    """A synthetic frame with particle positions, and with ``extra_modes`` a rolling energy u_r and a
    signed cohesion work u_adh on contacts, particles and frames."""
    f = synthetic_frame(step, simulator_point=simulator_point)
    rng = np.random.default_rng(step)
    n = len(f["particles"]["id"])
    for k, axis in enumerate("xyz"):
        f["particles"][axis] = rng.uniform(0.0, 0.05, n) + 0.1 * k
    if extra_modes:
        for table in ("contacts", "particles"):
            m = len(f[table]["u_n"])
            f[table]["u_r"] = 1e-3 * f[table]["u_n"]
            f[table]["u_adh"] = -rng.uniform(0.0, 1e-9, m)
        f["frames"]["u_r"] = np.array([f["contacts"]["u_r"].sum()])
        f["frames"]["u_adh"] = np.array([f["contacts"]["u_adh"].sum()])
    return f


def results(simulator_point: bool = True, extra_modes: bool = False, provenance: dict | None = None) -> Results:
    return Results.from_frames(
        [frame(s, simulator_point, extra_modes) for s in (0, 100, 200)], provenance or PROVENANCE, WALLS_META
    )


def test_text_summary_shows_the_last_frame_per_type():
    res = results()
    text = text_summary(res)
    assert "frame at timestep 200" in text and "contact law: liggghts:hertz (tangential='history')" in text
    per_type = res.per_type().query("step == 200").set_index("type")
    table = text[text.index("Energy per particle type") :].splitlines()
    for t, row in per_type.iterrows():
        line = next(l for l in table if re.match(rf"\s*{t}\s+{int(row['count'])}\s", l))
        assert f"{row['total']:.4g}" in line and f"{row['gini']:.4g}" in line
    assert "floor" in text and "drum" in text
    assert "|cp - cp_simulator| / overlap" in text
    assert "timestep 100" in text_summary(res, step=100)
    with pytest.raises(StoreError, match="no frame with timestep 7"):
        text_summary(res, step=7)
    with pytest.raises(StoreError, match="the results hold no frames"):
        text_summary(Results.from_frames([]))


@pytest.mark.slow
@pytest.mark.parametrize("simulator_point, n_figures", [(True, 10), (False, 9)])
def test_html_has_every_figure_and_is_self_contained(tmp_path, simulator_point, n_figures):
    out = write_html(results(simulator_point), tmp_path / "report.html")
    page = out.read_text()
    figures = re.findall(r'<img[^>]*src="data:image/png;base64,[A-Za-z0-9+/=]{1000,}"', page)
    assert len(figures) == n_figures
    assert len(re.findall(r"<img", page)) == n_figures
    assert not re.search(r'(src|href)="(?!data:)', page)  # nothing fetched from outside the page
    for heading in (
        "Energy per mode",
        "Energy per particle type",
        "Distribution",
        "Where the energy sits",
        "Energy per size class",
        "Frames",
        "Split comparison",
        "Walls",
        "Materials",
    ):
        assert f"<h2>{heading}</h2>" in page, heading
    for alt in (
        "Normalised distribution and CCDF",
        "Energy against height",
        "Slice and projection",
        "Per-particle misattribution",
        "Energy per size class",
    ):
        assert f'alt="{alt}"' in page, alt
    assert [p.name for p in tmp_path.iterdir()] == ["report.html"]


@pytest.mark.slow
def test_html_provenance_is_folded_and_nothing_missing_is_said(tmp_path):
    page = write_html(results(), tmp_path / "r.html").read_text()
    folded = re.search(
        r"<details id='provenance'><summary>Provenance[^<]*</summary><pre>(.*?)</pre></details>", page, re.S
    )
    assert folded and "/data/run.dump" in folded.group(1)
    assert "/data/run.dump" not in page.replace(folded.group(0), "")
    assert "Not computed: nothing" in page and "class='missing'" not in page


@pytest.mark.slow
def test_not_computed_is_stated_at_the_top(tmp_path):
    prov = {
        **PROVENANCE,
        "not_computed": {"u_tw": "the law has no twisting spring", "floor": {"missing": True}},
        "skipped": {"u_r": "hertz without rolling friction"},
        "notes": ["wall 'drum' NOT COMPUTED: its contacts were not dumped", "an ordinary note"],
        "scene": {**PROVENANCE["scene"], "walls": [{"name": "lid", "missing": "no wall dump"}]},
    }
    res = results(provenance=prov)
    page = write_html(res, tmp_path / "r.html").read_text()
    box = re.search(r"<div class='missing' id='not-computed'>(.*?)</div>", page, re.S)
    assert box and page.index(box.group(0)) < page.index("<h2>Energy per mode</h2>")
    items = re.findall(r"<li>(.*?)</li>", box.group(1))
    assert items[0] == "u_tw: the law has no twisting spring" and items[1].startswith("floor: {&quot;missing")
    assert "wall &#x27;drum&#x27; NOT COMPUTED" in items[2] and items[3].startswith("u_r (not computed by the law)")
    assert items[4] == "wall &#x27;lid&#x27;: no wall dump" and len(items) == 5
    assert "an ordinary note" not in box.group(1) and "an ordinary note" in page
    text = text_summary(res).splitlines()
    at = next(k for k, line in enumerate(text) if line.startswith("  NOT COMPUTED"))
    assert text[1].startswith("  Against the material law")  # the headline first, then what was not computed
    assert at < next(k for k, line in enumerate(text) if line.startswith("Energy per particle type"))
    assert text[at + 1] == "    - u_tw: the law has no twisting spring"
    assert text[at + 5] == "    - wall 'lid': no wall dump"


@pytest.mark.slow
def test_every_energy_column_is_shown(tmp_path):
    """Modes are found from the columns: a rolling u_r and the signed cohesion work u_adh appear in the
    mode table and the per-frame table without being named in the report's code."""
    res = results(extra_modes=True)
    page = write_html(res, tmp_path / "r.html").read_text()
    modes = page[page.index("<h2>Energy per mode</h2>") : page.index("<h2>Energy per particle type</h2>")]
    rows = re.findall(r"<tr>\s*<td>([^<]*)</td>\s*<td>([^<]*)</td>\s*<td>([^<]*)</td>", modes)
    assert [r[1] for r in rows] == ["u_n", "u_t", "u_r", "u_adh"]
    last = res.frames.iloc[-1]
    assert rows[2][2] == f"{last['u_r']:.4g}" and rows[3][2] == f"{last['u_adh']:.4g}" and last["u_adh"] < 0
    frames = page[page.index("<h2>Frames</h2>") :]
    assert "<th>u_r (J)</th>" in frames and "<th>u_adh (J)</th>" in frames


@pytest.mark.slow
def test_material_names_and_step(tmp_path):
    prov = {
        **PROVENANCE,
        "scene": {"materials": {"1": {"E": 1e7, "nu": 0.3, "name": "soft"}, "2": {"E": 5e7, "nu": 0.25}}},
    }
    res = results(provenance=prov)
    page = write_html(res, tmp_path / "r.html", step=100, names={2: "glass", 3: "steel"}).read_text()
    assert "detailed frame: <b>timestep 100</b>" in page
    per_type = page[page.index("<h2>Energy per particle type</h2>") : page.index("<figure>")]
    assert re.search(r"<td>1</td>\s*<td>soft</td>", per_type) and re.search(r"<td>2</td>\s*<td>glass</td>", per_type)
    materials = page[page.index("<h2>Materials</h2>") :]
    assert re.search(r"<td>3</td>\s*<td>steel</td>", materials)  # the walls' type
    walls = page[page.index("<h2>Walls</h2>") : page.index("<h2>Contact point</h2>")]
    assert walls.count("<td>steel</td>") == 2
    text = text_summary(res, step=100, names={2: "glass"})
    assert "frame at timestep 100" in text
    assert re.search(r"\n\s*1\s+\d+ .* soft\n", text) and re.search(r"\n\s*2\s+\d+ .* glass\n", text)
    with pytest.raises(StoreError, match="no frame with timestep 7"):
        write_html(res, tmp_path / "x.html", step=7)


@pytest.mark.slow
def test_report_command_options(tmp_path, capsys):
    from demsplit import cli

    out = tmp_path / "o.h5"
    assert cli.main(["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(out), "-q"]) == 0
    assert capsys.readouterr().out == ""
    assert cli.main(["report", str(out), "--step", "24000"]) == 0
    text = capsys.readouterr().out
    assert "frame at timestep 24000" in text and re.search(r"\n\s*0\s+80 .* soft\n", text)  # YADE's labels
    assert cli.main(["report", str(out), "-q"]) == 0 and capsys.readouterr().out == ""
    html_out = tmp_path / "r.html"
    assert cli.main(["report", str(out), "-o", str(html_out), "--type-name", "1=steel", "-q"]) == 0
    assert capsys.readouterr().out == ""
    page = html_out.read_text()
    assert re.search(r"<td>0</td>\s*<td>soft</td>", page) and re.search(r"<td>1</td>\s*<td>steel</td>", page)
    with pytest.raises(SystemExit):
        cli.main(["report", str(out), "--type-name", "steel"])
    assert "expected TYPE=NAME" in capsys.readouterr().err


def test_run_type_names_travel_to_the_report(tmp_path, capsys):
    """Names given to LIGGGHTS types at run time are stored and named by every later report."""
    from demsplit import cli

    out = tmp_path / "o.h5"
    assert (
        cli.main(
            [
                "run",
                str(SAMPLES / "liggghts" / "packing" / "in.packing"),
                "-o",
                str(out),
                "-q",
                "--type-name",
                "1=glass",
                "--type-name",
                "2=steel",
            ]
        )
        == 0
    )
    assert load_results(out).type_names() == {1: "glass", 2: "steel"}
    assert cli.main(["report", str(out), "--type-name", "2=brass"]) == 0  # the report's option wins
    text = capsys.readouterr().out
    assert re.search(r"\n\s*1\s+\d+ .* glass\n", text) and re.search(r"\n\s*2\s+\d+ .* brass\n", text)


def browser_check(page: Path, tmp_path: Path) -> tuple[int, int, list[str]]:
    """Load ``page`` in headless Chromium: (images, images decoded, console messages). A copy of the page
    gets a script that, on load, counts the images whose pixels decoded (naturalWidth > 0)."""
    chromium = require_program("chromium")
    probe = (
        "<script>window.addEventListener('load', () => { const imgs = [...document.images]; "
        "document.body.setAttribute('data-images', imgs.length + ' ' + "
        "imgs.filter(i => i.complete && i.naturalWidth > 0).length); });</script>"
    )
    copy = tmp_path / ("probe-" + page.name)
    copy.write_text(page.read_text().replace("</body>", probe + "</body>"))
    proc = subprocess.run(
        [
            chromium,
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--enable-logging=stderr",
            "--v=0",
            f"--user-data-dir={tmp_path / 'chromium-profile'}",
            "--dump-dom",
            copy.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=180,
        env={**os.environ, "HOME": str(tmp_path)},
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    found = re.search(r'data-images="(\d+) (\d+)"', proc.stdout)
    assert found, "the page did not finish loading: " + proc.stderr[-2000:]
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    return int(found.group(1)), int(found.group(2)), console


@pytest.fixture(scope="module")
def packing_store(tmp_path_factory) -> Path:
    """The LIGGGHTS packing sample's result store (two particle materials, a mesh floor, primitive walls)."""
    from demsplit import cli

    out = tmp_path_factory.mktemp("packing") / "o.h5"
    assert cli.main(["run", str(SAMPLES / "liggghts" / "packing" / "in.packing"), "-o", str(out), "-q"]) == 0
    return out


UNIT_HEADER = re.compile(r".* \((J|m|s|Pa|1|%)\)$")


@pytest.mark.slow
def test_the_report_opens_with_the_headline(packing_store, tmp_path):
    """The first screen: per material the material-law energy and how far the 50/50 and radius splits are off
    (recomputed here from the stored particles), the part of that error the wall contacts make (recomputed
    from the contacts: 50/50 gives the particle u/2, the radius split against a LIGGGHTS wall all of u), the
    expected error, what was not computed; the per-frame table folded; a unit on every number column."""
    from demsplit.results.report import LABEL_COLUMNS, split_headline

    res = load_results(packing_store)
    step = int(res.steps.max())
    one = res.frame(step)
    page = write_html(res, tmp_path / "r.html").read_text()
    start = page.index("<div class='summary' id='summary'>")
    assert start < page.index("<figure>") and start < page.index("<h2>Energy per mode</h2>")
    box = page[start : page.index("<h2>Energy per mode</h2>")]
    assert "id='not-computed'" in box and "expected share error" in box
    p, c = one.raw.particles, one.raw.contacts
    u, equal, radius = (p.groupby("type")[col].sum() for col in ("u", "u_equal", "u_radius"))
    lead = re.search(r"<p class='lead'>(.*?)</p>", box).group(1)
    worst = ((equal - u) / u * 100).abs().idxmax()
    assert f"the 50/50 split gives type {worst} {abs((equal - u) / u * 100)[worst]:.3g} % too" in lead
    rows = re.findall(r"<tr>\s*" + r"\s*".join([r"<td>([^<]*)</td>"] * 11), box)
    assert [int(r[0]) for r in rows] == u.index.tolist() == [1, 2]
    for r in rows:
        t = int(r[0])
        assert int(r[1]) == (p["type"] == t).sum() and r[2] == f"{u[t]:.4g}"
        assert r[5] == f"{(equal[t] - u[t]) / u[t] * 100:+.3g}" and r[8] == f"{(radius[t] - u[t]) / u[t] * 100:+.3g}"
    table, _ = split_headline(one, {})
    walls = c[c["wall"] >= 0]
    of_type = p.set_index("id").loc[walls["id1"], "type"].to_numpy()
    for t in (1, 2):
        w = walls[of_type == t]
        row = table.set_index("type").loc[t]
        np.testing.assert_allclose(
            row["equal_off_walls_pct"], ((w["u1"] + w["u2"]) / 2 - w["u1"]).sum() / u[t] * 100, rtol=1e-9
        )
        np.testing.assert_allclose(row["radius_off_walls_pct"], w["u2"].sum() / u[t] * 100, rtol=1e-9)
    folded = re.search(
        r"<details id='frames-table'><summary>The per-frame table \((\d+) rows\)</summary>(.*?)"
        r"</details>",
        page,
        re.S,
    )
    assert folded and int(folded.group(1)) == len(res.steps) == folded.group(2).count("<tr>")  # header: <tr style
    headers = [h for h in re.findall(r"<th>([^<]*)</th>", page) if h not in LABEL_COLUMNS]
    assert headers and all(UNIT_HEADER.match(h) for h in headers), [h for h in headers if not UNIT_HEADER.match(h)]
    text = text_summary(res).splitlines()
    assert text[1] == "  " + re.sub(r"<[^>]+>", "", lead)
    assert text.index(next(line for line in text if line.startswith("  NOT COMPUTED"))) > 4


@pytest.mark.slow
def test_the_report_renders_in_a_browser(packing_store, tmp_path):
    """The report of the LIGGGHTS sample in headless Chromium: every figure decodes, no console message."""
    from demsplit import cli

    out = packing_store
    page = tmp_path / "report.html"
    assert cli.main(["report", str(out), "-o", str(page), "-q"]) == 0
    images, decoded, console = browser_check(page, tmp_path)
    assert images == 10 and decoded == images and console == []
    # the check can fail: a damaged figure and a script error are seen
    broken = tmp_path / "broken.html"
    broken.write_text(
        page.read_text()
        .replace("base64,iVBOR", "base64,AAAA", 1)
        .replace("</body>", "<script>undefinedFunction()</script></body>")
    )
    images, decoded, console = browser_check(broken, tmp_path)
    assert (images, decoded) == (10, 9) and len(console) == 1 and "undefinedFunction" in console[0]


def test_run_summary_reads_one_frame_and_equals_the_full_summary(packing_store):
    """demsplit run prints its summary from the last frame's tables and the
    frames table (memory independent of the number of frames): the same text
    as from the whole store, and only the last frame's particles are read."""
    from demsplit.results.store import read_last_frame

    out = packing_store
    full, last = load_results(out), read_last_frame(out)
    step = int(full.steps[-1])
    assert len(full.steps) == 3 and last.steps.tolist() == full.steps.tolist()
    assert set(last.particles["step"]) == {step} and len(last.particles) == (full.particles["step"] == step).sum()
    assert set(last.contacts["step"]) == {step}
    assert text_summary(last) == text_summary(full)
    pf = full.per_frame()  # the recorded sums are the particles' and walls' own (the known parts, as stored)
    per_step = full.raw.particles.groupby("step")["u"].sum().to_numpy()
    assert (pf["u_particles"] - per_step).abs().max() <= 1e-15 * pf["u_contacts"].max()


@pytest.mark.slow
def test_a_run_without_contacts_or_comparison_is_reported(tmp_path):
    """run --no-contacts --no-compare: no contacts table, no u_equal/u_radius; the report leaves out what
    needs them."""
    frames = []
    for s in (0, 100):
        f = {k: v for k, v in frame(s).items() if k != "contacts"}
        f["particles"] = {k: v for k, v in f["particles"].items() if k not in ("u_equal", "u_radius")}
        frames.append(f)
    res = Results.from_frames(frames, PROVENANCE, WALLS_META)
    assert res.contacts.columns.empty
    page = write_html(res, tmp_path / "r.html", step=0).read_text()
    assert len(re.findall(r"<img", page)) == 7 and "<h2>Split comparison</h2>" not in page
    assert "frame at timestep 0" in text_summary(res, step=0)


def test_a_frame_without_energy_reports_empty_not_nan(tmp_path):
    """A run's first frames often hold no contact yet (particles still falling): the report says the frame
    holds no energy instead of printing shares and Gini coefficients of zeros (NaN)."""
    frames = [synthetic_frame(0, n_pairs=0, n_wall_contacts=0), synthetic_frame(1000)]
    res = Results.from_frames(frames, PROVENANCE, WALLS_META)
    text = text_summary(res, step=0)
    assert "no elastic energy" in text and "nan" not in text.lower()
    page = write_html(res, tmp_path / "r.html", step=0).read_text()
    assert "no elastic energy" in page and ">nan<" not in page.lower()
    assert "nan" not in text_summary(res, step=1000).lower()
