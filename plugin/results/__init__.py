"""The results: tables, the store they are written to and read from, aggregates and the report.

``schema`` (the tables, columns, dtypes and units) is the leaf; ``tables``
(:class:`Results`, DataFrames), ``store`` (the HDF5 store: written once,
resumable), ``aggregate`` (statistics per type, size, frame) and ``report``
(text and HTML) build on it. The names most callers need are here.
"""

from .schema import TABLES, UNITS, Table, canonical_table, to_dataframe, walls_meta_from_scene
from .store import load_results
from .tables import Results

__all__ = [
    "TABLES",
    "UNITS",
    "Results",
    "Table",
    "canonical_table",
    "load_results",
    "to_dataframe",
    "walls_meta_from_scene",
]
