"""The result tables' schema: the single list of tables, columns, dtypes and units.

Every table of a result set is a dict of 1-D numpy arrays (or a DataFrame of
them), one row per observation; :data:`TABLES` names them in stored order,
:data:`UNITS` gives every known column's unit, :func:`canonical_table` gives
every column its canonical dtype. The tables themselves are described in
:mod:`demsplit.results.tables`. A leaf: it imports the errors only (and pandas
where a DataFrame is made).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from ..errors import StoreError

if TYPE_CHECKING:  # pandas is imported where a DataFrame is made: writing a store needs none
    import pandas as pd

Table = dict[str, np.ndarray]

TABLES = ("particles", "contacts", "walls", "frames")
"""The tables of a result set, in the order they are stored."""

_ENERGY = {
    c: "J"
    for c in (
        "u",
        "u_n",
        "u_t",
        "u_r",
        "u_tw",
        "u_adh",
        "u_n_error",
        "u_equal",
        "u_radius",
        "u_springs",
        "u1",
        "u2",
        "u_particles",
        "u_walls",
    )
}
_LENGTH = {
    c: "m"
    for c in (
        "x",
        "y",
        "z",
        "radius",
        "delta",
        "depth1",
        "cpx",
        "cpy",
        "cpz",
        "cpx_sim",
        "cpy_sim",
        "cpz_sim",
        *(f"box_{a}{end}" for a in "xyz" for end in ("lo", "hi")),
    )
}
_COUNT = {
    c: "1"
    for c in (
        "step",
        "id",
        "clump",
        "n_members",
        "id1",
        "id2",
        "wall",
        "type",
        "n_contacts",
        "n_particles",
        "n_wall_contacts",
        "n_not_computed",
        "share_n1",
        "share_t1",
        "share_r1",
        "share_tw1",
        "not_computed",
        "overlap_max_rel_error",
        "a_over_r1",
        "a_over_r2",
        "share_n1_error",
    )
}
UNITS: dict[str, str] = {**_ENERGY, **_LENGTH, **_COUNT, "time": "s"}
"""Unit of every known column; a column not listed here gets the unit ``""`` (unknown)."""

UNKNOWN = -1.0
"""What a ``frames`` column of :data:`UNKNOWN_COLUMNS` holds in a frame where its value is not known: no
stored table holds NaN or inf (docs/store.md)."""
UNKNOWN_COLUMNS = ("time", "overlap_max_rel_error")
"""``time`` (s): unknown when the run does not give it (a LIGGGHTS script without ``timestep``);
``overlap_max_rel_error``: unknown (none) when no overlap was recomputed from printed positions. Both are
>= 0 when known."""
UNBOUNDED = float(np.finfo(np.float64).max)
"""What ``overlap_max_rel_error`` holds when a contact's overlap has no finite bound (printed positions
may hide it: it is kept within its uncertainty): the largest double, above every finite bound, not inf."""


def known(value) -> bool:
    """Whether a value of an :data:`UNKNOWN_COLUMNS` column is known (>= 0; stores written before
    :data:`UNKNOWN` held NaN)."""
    return value is not None and bool(np.isfinite(value)) and value >= 0


_INT64 = (
    "step",
    "id",
    "clump",
    "n_members",
    "id1",
    "id2",
    "wall",
    "n_contacts",
    "n_particles",
    "n_wall_contacts",
    "n_not_computed",
)
_INT32 = ("type", "not_computed")


def canonical_dtype(name: str) -> np.dtype:
    """The dtype a column named ``name`` is stored in: int64 for steps, ids, wall indices and counts, int32 for
    types and the not-computed bits, float64 for everything else."""
    return np.dtype(np.int64 if name in _INT64 else np.int32 if name in _INT32 else np.float64)


def canonical_column(name: str, values: np.ndarray, *, table: str = "", step: int | None = None) -> np.ndarray:
    """``values`` as the canonical dtype of column ``name``: int64 for steps,
    ids, wall indices and counts, int32 for types, float64 for everything else.

    Integer columns given as floats must hold integral values (a NaN id or a
    ``1.23457e+06`` count is an error, never a silent cast).
    """
    values = np.asarray(values)
    dtype = canonical_dtype(name)
    if dtype.kind == "i":
        if values.dtype.kind == "f":
            bad = ~np.isfinite(values) | (values != np.round(values))
            if bad.any():
                row = int(np.flatnonzero(bad)[0])
                raise StoreError(
                    f"column {table}.{name} must hold integers, found {values[row].item()!r} in row {row}.",
                    step=step,
                    fix="pass integer arrays for ids, types, steps and counts.",
                )
        elif values.dtype.kind not in "iub":
            raise StoreError(
                f"column {table}.{name} must hold integers, found dtype {values.dtype}.",
                step=step,
                fix="pass integer arrays for ids, types, steps and counts.",
            )
        return values.astype(dtype, copy=False)
    if values.dtype.kind not in "fiub":
        raise StoreError(
            f"column {table}.{name} must be numeric, found dtype {values.dtype}.",
            step=step,
            fix="pass numeric numpy arrays for every result column.",
        )
    return values.astype(dtype, copy=False)


def canonical_table(name: str, table: Mapping[str, np.ndarray], *, step: int | None = None) -> Table:
    """Every column of ``table`` in its canonical dtype, all of one length."""
    out = {col: canonical_column(col, vals, table=name, step=step) for col, vals in table.items()}
    lengths = {col: len(v) for col, v in out.items()}
    if len(set(lengths.values())) > 1:
        raise StoreError(
            f"table {name!r} has columns of different lengths: {lengths}.",
            step=step,
            fix="give every column of a table one value per row.",
        )
    return out


def to_dataframe(table: Mapping[str, np.ndarray]) -> pd.DataFrame:
    """A DataFrame of ``table`` (column order kept) with ``attrs['units']`` set."""
    import pandas as pd

    df = pd.DataFrame({col: np.asarray(vals) for col, vals in table.items()})
    df.attrs["units"] = {col: UNITS.get(col, "") for col in df.columns}
    return df


def walls_meta_from_scene(scene) -> list[dict]:
    """``walls_meta`` (one JSON-able dict per wall index: ``wall``, ``name``,
    ``kind``, ``type``) from a :class:`demsplit.scene.Scene`."""
    return [{"wall": k, "name": w.name, "kind": w.kind, "type": int(w.type)} for k, w in enumerate(scene.walls)]
