"""docs/accuracy.md shows only what the committed commands wrote: every row of its tables is a row of a table in
benchmarks/accuracy_study/results/*.md (convergence.py, paper_tables.py, e12.py, fit.py, cost.py write them)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def table_rows(text: str) -> list[str]:
    return [line.strip() for line in text.splitlines() if line.startswith("|") and not line.startswith("|---")]


def test_every_table_row_of_the_accuracy_doc_is_a_committed_result():
    results = set()
    for path in (REPO / "benchmarks" / "accuracy_study" / "results").glob("*.md"):
        results.update(table_rows(path.read_text()))
    doc = table_rows((REPO / "docs" / "accuracy.md").read_text())
    assert len(doc) > 50
    missing = [row for row in doc if row not in results]
    assert not missing, missing
