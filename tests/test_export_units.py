"""Units and wall names where CSV and notebook users look: ``units.csv`` beside the CSV tables, the
wall names in ``walls.csv``, a clear message when the Parquet extra is missing, and a short ``repr``
and ``_repr_html_`` of :class:`Results`."""

from __future__ import annotations

import builtins
import re

import pandas as pd
import pytest
from demsplit.errors import StoreError
from demsplit.results import Results
from demsplit.results.exports.tables import export_tables
from demsplit.results.schema import TABLES
from result_frames import PROVENANCE, WALLS_META, synthetic_frame


def results() -> Results:
    return Results.from_frames([synthetic_frame(s) for s in (0, 100)], PROVENANCE, WALLS_META)


def test_csv_export_has_units_and_wall_names(tmp_path):
    res = results()
    written = export_tables(res, tmp_path, "csv")
    assert sorted(p.name for p in written) == sorted([f"{t}.csv" for t in TABLES] + ["units.csv", "provenance.json"])
    units = pd.read_csv(tmp_path / "units.csv", keep_default_na=False)
    for name in TABLES:
        df = getattr(res, name)
        listed = units[units["table"] == name]
        assert listed["column"].tolist() == list(pd.read_csv(tmp_path / f"{name}.csv", nrows=0).columns)
        for col, unit in zip(listed["column"], listed["unit"]):
            assert unit == df.attrs["units"].get(col, ""), (name, col)
    by = units.set_index(["table", "column"])["unit"]
    assert by["particles", "u"] == "J" and by["particles", "radius"] == "m" and by["frames", "time"] == "s"
    walls = pd.read_csv(tmp_path / "walls.csv")
    assert walls[["wall", "u"]].equals(res.walls[["wall", "u"]])  # the table itself is unchanged
    names = dict(zip(walls["wall"], walls["name"]))
    assert names == {0: "floor", 1: "drum"} and set(walls["kind"]) == {"plane", "cylinder"}
    assert by["walls", "name"] == ""


def test_parquet_without_pyarrow_names_the_extra(tmp_path, monkeypatch):
    real_import = builtins.__import__

    def no_pyarrow(name, *args, **kwargs):
        if name.split(".")[0] == "pyarrow":
            raise ImportError("No module named 'pyarrow'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pyarrow)
    with pytest.raises(StoreError, match=re.escape("pip install 'demsplit[parquet]'")):
        export_tables(results(), tmp_path / "pq", "parquet")
    assert not (tmp_path / "pq").exists() or not list((tmp_path / "pq").iterdir())


def test_repr_is_short_and_names_units_and_walls():
    res = results()
    text = repr(res)
    assert text.startswith("<demsplit Results: 2 frame(s), timesteps 0..100") and "law liggghts:hertz" in text
    assert len(text.splitlines()) == 6 and max(map(len, text.splitlines())) < 160
    assert re.search(rf"particles +{len(res.particles)} rows: step, id, type, radius \(m\), u \(J\)", text)
    assert "wall names: floor, drum>" in text
    page = res._repr_html_()
    assert page.startswith("<div><b>demsplit Results</b>") and "<td>contacts</td>" not in page
    assert f"<td><code>contacts</code></td><td>{len(res.contacts)}</td>" in page and "u_n (J)" in page
    assert "floor, drum" in page and len(page) < 5000
