"""Terminal summary and self-contained HTML report."""

from __future__ import annotations

import re

import pytest
from demsplit.errors import StoreError
from demsplit.results import Results
from demsplit.results.report import text_summary, write_html
from result_frames import PROVENANCE, WALLS_META, synthetic_frame


def results(simulator_point: bool = True) -> Results:
    return Results.from_frames([synthetic_frame(s, simulator_point=simulator_point) for s in (0, 100, 200)],
                               PROVENANCE, WALLS_META)


def test_text_summary_shows_the_last_frame_per_type():
    res = results()
    text = text_summary(res)
    assert "frame at timestep 200" in text and "contact law: liggghts:hertz (tangential='history')" in text
    per_type = res.per_type().query("step == 200").set_index("type")
    for t, row in per_type.iterrows():
        line = next(l for l in text.splitlines() if re.match(rf"\s*{t}\s+{int(row['count'])}\s", l))
        assert f"{row['total']:.4g}" in line and f"{row['gini']:.4g}" in line
    assert "floor" in text and "drum" in text
    assert "|cp - cp_simulator| / overlap" in text
    assert "timestep 100" in text_summary(res, step=100)
    with pytest.raises(StoreError, match="no frame with timestep 7"):
        text_summary(res, step=7)
    with pytest.raises(StoreError, match="the results hold no frames"):
        text_summary(Results.from_frames([]))


@pytest.mark.parametrize("simulator_point, n_figures", [(True, 5), (False, 4)])
def test_html_has_every_figure_and_is_self_contained(tmp_path, simulator_point, n_figures):
    out = write_html(results(simulator_point), tmp_path / "report.html")
    page = out.read_text()
    figures = re.findall(r'<img[^>]*src="data:image/png;base64,[A-Za-z0-9+/=]{1000,}"', page)
    assert len(figures) == n_figures
    assert len(re.findall(r"<img", page)) == n_figures
    assert not re.search(r'(src|href)="(?!data:)', page)  # nothing fetched from outside the page
    for heading in ("Energy per particle type", "Frames", "Split comparison", "Walls", "Provenance"):
        assert f"<h2>{heading}</h2>" in page
    assert [p.name for p in tmp_path.iterdir()] == ["report.html"]


def test_run_summary_reads_one_frame_and_equals_the_full_summary(tmp_path):
    """demsplit run prints its summary from the last frame's tables and the
    frames table (memory independent of the number of frames): the same text
    as from the whole store, and only the last frame's particles are read."""
    from pathlib import Path

    from demsplit import cli
    from demsplit.results import load_results
    from demsplit.results.store import read_last_frame

    script = Path(__file__).resolve().parent.parent / "sample_dumps" / "liggghts" / "packing" / "in.packing"
    out = tmp_path / "o.h5"
    assert cli.main(["run", str(script), "-o", str(out), "-q"]) == 0
    full, last = load_results(out), read_last_frame(out)
    step = int(full.steps[-1])
    assert len(full.steps) == 3 and last.steps.tolist() == full.steps.tolist()
    assert set(last.particles["step"]) == {step} and len(last.particles) == (full.particles["step"] == step).sum()
    assert set(last.contacts["step"]) == {step}
    assert text_summary(last) == text_summary(full)
    pf = full.per_frame()  # the recorded sums are the particles' and walls' own
    per_step = full.particles.groupby("step")["u"].sum().to_numpy()
    assert (pf["u_particles"] - per_step).abs().max() <= 1e-15 * pf["u_contacts"].max()
