"""Every table of a run as Parquet or CSV files, with the units and the provenance beside them."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ...errors import StoreError
from ...outputs import OutputFolder
from ..schema import TABLES
from ..store import to_json
from ..tables import Results


def export_tables(
    results: Results,
    directory: str | Path,
    fmt: str = "parquet",
    inputs: Iterable[str | Path] = (),
    *,
    overwrite: bool = False,
) -> list[Path]:
    """Write each table to ``directory/<table>.parquet`` (or ``.csv``; with YADE clumps also
    ``clumps``, the per-clump sums) and the provenance to ``provenance.json``, each file atomically. Parquet files carry
    the units (field metadata ``unit``) and the provenance (schema metadata).
    CSV numbers are written with 17 significant digits (round-trip exact); CSV has no metadata, so
    ``units.csv`` lists the unit of every column of every table (``1``: dimensionless or a count; empty
    for text and ids) and the walls table gets each wall's ``name`` and ``kind``. A value that was not
    computed (the row's ``not_computed`` bits) is an empty CSV cell or a Parquet null, never the store's 0
    (:func:`~demsplit.results.tables.with_not_computed_as_nan`).
    The files are written together, all or none, into a new or empty folder or over an earlier export of
    the format, whose files are all replaced; never over one of ``inputs`` (:class:`demsplit.outputs.OutputFolder`;
    ``overwrite``: into a folder holding other files too)."""
    if fmt not in ("parquet", "csv"):
        raise StoreError(f"unknown export format {fmt!r}.", fix="use 'parquet' or 'csv'.")
    import pandas as pd

    if fmt == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise StoreError(
                "the Parquet export needs pyarrow, which is not installed.",
                fix="pip install 'demsplit[parquet]', or export with --csv DIR.",
            ) from None
    frames = {name: getattr(results, name) for name in TABLES}
    if "clump" in results.particles and (results.particles["clump"] >= 0).any():
        frames["clumps"] = results.per_clump()  # YADE clumps: the members' sums, next to the spheres
        frames["clumps"].attrs["units"] = {
            c: results.particles.attrs.get("units", {}).get(c, "") for c in frames["clumps"].columns
        }
    if fmt == "csv" and len(frames["walls"]):  # CSV has no metadata: the wall names go into the walls table
        meta = pd.DataFrame(results.walls_meta, columns=["wall", "name", "kind"])
        walls = frames["walls"].merge(meta.astype({"wall": np.int64}), on="wall", how="left")
        walls.attrs["units"] = {**frames["walls"].attrs.get("units", {}), "name": "", "kind": ""}
        frames["walls"] = walls
    extra = ["units.csv"] if fmt == "csv" else []
    folder = OutputFolder(
        directory, [*(f"{t}.{fmt}" for t in frames), *extra, "provenance.json"], inputs, kind=fmt, overwrite=overwrite
    )
    prov = to_json({"provenance": results.provenance, "walls_meta": results.walls_meta}, "provenance")
    with folder:
        return _write_tables(folder, frames, fmt, prov, results.walls_meta)


def _write_tables(folder: OutputFolder, frames: dict, fmt: str, prov: str, walls_meta: list) -> list[Path]:
    import pandas as pd

    written = []
    for name, df in frames.items():
        if fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            units = df.attrs.get("units", {})
            df = df.copy(deep=False)
            df.attrs = {"units": units, "walls": walls_meta}  # pandas keeps attrs in its own metadata
            table = pa.Table.from_pandas(df, preserve_index=False)
            fields = [f.with_metadata({"unit": units.get(f.name, "")}) for f in table.schema]
            schema = pa.schema(fields, metadata={**table.schema.metadata, b"demsplit": prov.encode()})
            table = table.cast(schema)
            written.append(folder.write(f"{name}.{fmt}", lambda tmp, t=table: pq.write_table(t, tmp)))
        else:
            written.append(
                folder.write(f"{name}.{fmt}", lambda tmp, d=df: d.to_csv(tmp, index=False, float_format="%.17g"))
            )
    if fmt == "csv":  # CSV has no metadata: the unit of every column, in a table beside them
        units = pd.DataFrame(
            [
                {"table": name, "column": c, "unit": df.attrs.get("units", {}).get(c, "")}
                for name, df in frames.items()
                for c in df.columns
            ]
        )
        written.append(folder.write("units.csv", lambda tmp: units.to_csv(tmp, index=False)))
    written.append(folder.write("provenance.json", lambda tmp: tmp.write_bytes(prov.encode())))
    return written
