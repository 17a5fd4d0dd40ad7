"""The results of a demsplit analysis as tidy pandas DataFrames.

:class:`Results` holds one DataFrame per table, one row per observation:

``particles``
    one row per particle and frame: ``step``, ``id``, ``type``, ``x y z`` (m, the centre as the
    reader gives it: wrapped into a periodic box), ``radius`` (m),
    ``u``, ``u_n``, ``u_t`` (J, material distribution law), ``u_equal`` (J, 50/50
    split), ``u_radius`` (J, radius-weighted split), ``n_contacts``, ``not_computed`` (bits of the modes
    some contact of the particle could not give), ``n_not_computed`` (those contacts); optionally
    ``u_springs`` (J).
``contacts``
    one row per contact and frame: ``step``, ``id1``, ``id2`` (-1 for a wall),
    ``wall`` (-1 for pairs), ``delta`` (m), ``u_n``, ``u_t``, ``u1``, ``u2`` (J),
    ``share_n1``, ``share_t1``, ``depth1`` (m), ``cpx cpy cpz`` (m), ``not_computed``, optionally
    ``cpx_sim cpy_sim cpz_sim`` (m, the simulator's own contact point).
``walls``
    one row per wall and frame: ``step``, ``wall``, ``u``, ``u_n``, ``u_t`` (J),
    ``n_contacts``, ``not_computed``, ``n_not_computed``.
``frames``
    one row per frame: ``step``, ``time`` (s), ``n_particles``, ``n_contacts``
    (all contacts, wall contacts included), ``n_wall_contacts``, ``u_n``, ``u_t`` (J, sums
    over contacts), ``u_particles``, ``u_walls`` (J, sums of the particles' and the
    walls' ``u``), ``n_not_computed`` (contacts with a value not computed), ``overlap_max_rel_error``.

A value that was not computed is NaN in these tables, as in every export (:func:`with_not_computed_as_nan`:
a mode whose bit is set in the row's ``not_computed``, and the totals and splits made from it).
``results.raw`` holds the tables as stored: 0 there, and every total the known part, which is what the
statistics (:meth:`Results.per_type`, ...) sum; they say how many contributions were not computed.

Every DataFrame carries ``df.attrs['units']``, a mapping column -> unit
(``"1"`` for dimensionless numbers and counts). Rows are ordered by ``step``
(stable: within a frame the pipeline's order is kept), whether the Results
come from memory (:meth:`Results.from_frames`) or from a store
(:func:`load_results`), so both give identical DataFrames.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from ..errors import StoreError
from ..frame import describe_steps
from .schema import TABLES, Table, canonical_table, to_dataframe

if TYPE_CHECKING:  # pandas is imported where a DataFrame is made: writing a store needs none
    import pandas as pd


def _sorted_by_step(table: Table) -> Table:
    if "step" not in table or len(table["step"]) == 0:
        return table
    order = np.argsort(table["step"], kind="stable")
    return {col: vals[order] for col, vals in table.items()}


@dataclass
class RawTables:
    """The tables as the store holds them: a value not computed is 0 (with its row's bit), a total the
    known part."""

    particles: pd.DataFrame
    contacts: pd.DataFrame
    walls: pd.DataFrame
    frames: pd.DataFrame


class Results:
    """Per-particle, per-contact, per-wall and per-frame results of a run (module docstring).

    Build it with :meth:`from_frames` (per-frame tables from the pipeline),
    :meth:`from_tables` (tables already holding every frame) or
    :func:`load_results` (a store written by :class:`demsplit.results.writer.ResultWriter`). The
    constructor takes the tables as stored (:class:`RawTables`).
    """

    def __init__(
        self,
        particles: pd.DataFrame,
        contacts: pd.DataFrame,
        walls: pd.DataFrame,
        frames: pd.DataFrame,
        provenance: dict | None = None,
        walls_meta: list[dict] | None = None,
    ) -> None:
        self.raw = RawTables(particles, contacts, walls, frames)
        self.provenance: dict = dict(provenance or {})
        self.walls_meta: list[dict] = list(walls_meta or [])

    @cached_property
    def particles(self) -> pd.DataFrame:
        """One row per particle and frame; NaN where not computed."""
        return with_not_computed_as_nan(self.raw.particles)

    @cached_property
    def contacts(self) -> pd.DataFrame:
        """One row per contact and frame; NaN where not computed."""
        return with_not_computed_as_nan(self.raw.contacts)

    @cached_property
    def walls(self) -> pd.DataFrame:
        """One row per wall and frame; NaN where not computed."""
        return with_not_computed_as_nan(self.raw.walls)

    @property
    def frames(self) -> pd.DataFrame:
        """One row per frame: totals of what is known, ``n_not_computed`` the contacts with a value not
        computed."""
        return self.raw.frames

    @classmethod
    def from_tables(
        cls,
        tables: Mapping[str, Mapping[str, np.ndarray]],
        provenance: dict | None = None,
        walls_meta: list[dict] | None = None,
    ) -> Results:
        """Results from tables that already hold every frame (missing tables are empty)."""
        unknown = set(tables) - set(TABLES)
        if unknown:
            raise StoreError(
                f"unknown table(s) {sorted(unknown)}; expected some of {list(TABLES)}.",
                fix="name the tables particles, contacts, walls, frames.",
            )
        frames = {name: to_dataframe(_sorted_by_step(canonical_table(name, tables.get(name, {})))) for name in TABLES}
        return cls(**frames, provenance=dict(provenance or {}), walls_meta=list(walls_meta or []))

    @classmethod
    def from_frames(
        cls,
        frames: Iterable[Mapping[str, Mapping[str, np.ndarray]]],
        provenance: dict | None = None,
        walls_meta: list[dict] | None = None,
    ) -> Results:
        """Results from per-frame tables (the dicts the pipeline hands to
        :meth:`demsplit.results.writer.ResultWriter.append`), concatenated in step order.

        Every frame must give a table the same columns (an absent table counts
        as an empty one).
        """
        parts: dict[str, list[Table]] = {name: [] for name in TABLES}
        columns: dict[str, list[str]] = {}
        for frame in frames:
            step = int(np.asarray(frame["frames"]["step"])[0]) if "frames" in frame else None
            for name, table in frame.items():
                if name not in parts:
                    raise StoreError(
                        f"unknown table {name!r}; expected some of {list(TABLES)}.",
                        step=step,
                        fix="name the tables particles, contacts, walls, frames.",
                    )
                cols = columns.setdefault(name, list(table))
                if list(table) != cols:
                    raise StoreError(
                        f"table {name!r} has columns {list(table)}, earlier frames had {cols}.",
                        step=step,
                        fix="give every frame the same columns (fill what is unknown with NaN).",
                    )
                parts[name].append(canonical_table(name, table, step=step))
        tables = {
            name: {col: np.concatenate([p[col] for p in parts[name]]) for col in columns[name]}
            for name in TABLES
            if name in columns
        }
        return cls.from_tables(tables, provenance, walls_meta)

    def _summary(self) -> tuple[str, list[tuple[str, int, list[str]]], list[str]]:
        """Head line, (table, rows, "column (unit)" list) per table, and the wall names."""
        steps = self.steps
        head = f"{len(steps)} frame(s)" + (f", timesteps {describe_steps(steps)}" if len(steps) else "")
        law = (self.provenance or {}).get("model", {}).get("law")
        head += f"; law {law}" if law else ""
        tables = []
        for name in TABLES:
            df = getattr(self, name)
            units = df.attrs.get("units", {})
            cols = [f"{c} ({units[c]})" if units.get(c) not in (None, "", "1") else c for c in df.columns]
            tables.append((name, len(df), cols))
        walls = [str(w.get("name", w.get("wall"))) for w in self.walls_meta]
        return head, tables, walls

    def __repr__(self) -> str:
        """A few lines: frames, rows and columns of each table (with units), wall names."""
        head, tables, walls = self._summary()
        lines = [f"<demsplit Results: {head}"]
        for name, rows, cols in tables:
            shown = ", ".join(cols[:8]) + (f", ... ({len(cols)} columns)" if len(cols) > 8 else "")
            lines.append(f"  {name:<9} {rows:>9} rows: {shown}")
        if walls:
            more = f", ... ({len(walls)})" if len(walls) > 10 else ""
            lines.append(f"  wall names: {', '.join(walls[:10])}{more}")
        return "\n".join(lines) + ">"

    def _repr_html_(self) -> str:
        """The summary of :meth:`__repr__` as an HTML table, for notebooks."""
        import html

        head, tables, walls = self._summary()
        rows = "".join(
            f"<tr><td><code>{name}</code></td><td>{n}</td><td>{html.escape(', '.join(cols))}</td></tr>"
            for name, n, cols in tables
        )
        wall_line = f"<p>wall names: {html.escape(', '.join(walls))}</p>" if walls else ""
        return (
            f"<div><b>demsplit Results</b>: {html.escape(head)}<table><tr><th>table</th><th>rows</th>"
            f"<th>columns (unit)</th></tr>{rows}</table>{wall_line}</div>"
        )

    def type_names(self, names: Mapping[int, str] | None = None) -> dict[int, str]:
        """Material name of each particle/wall type that has one: YADE's material labels
        (``provenance["scene"]["materials"][T]["name"]``), then the names stored by
        ``demsplit run --type-name`` (``provenance["type_names"]``), then ``names``; later ones win."""
        prov = self.provenance or {}
        out: dict[int, str] = {}
        for t, m in (prov.get("scene", {}) or {}).get("materials", {}).items():
            if isinstance(m, Mapping) and m.get("name"):
                out[int(t)] = str(m["name"])
        out.update({int(t): str(n) for t, n in (prov.get("type_names") or {}).items()})
        out.update({int(t): str(n) for t, n in (names or {}).items()})
        return out

    @property
    def steps(self) -> np.ndarray:
        """Timesteps of the frames, in stored order."""
        return self.frames["step"].to_numpy() if "step" in self.frames else np.empty(0, np.int64)

    def frame(self, step: int) -> Results:
        """The results of one frame (timestep ``step``)."""
        if step not in set(self.steps.tolist()):
            raise StoreError(
                f"no frame with timestep {step}; the results hold {len(self.steps)} frame(s), "
                f"timesteps {describe_steps(self.steps)}.",
                fix="pick one of the stored timesteps.",
            )
        pick = {name: getattr(self.raw, name) for name in TABLES}
        return Results(
            **{
                name: _with_units((df[df["step"] == step] if "step" in df else df).reset_index(drop=True), df)
                for name, df in pick.items()
            },  # a table not stored (run --no-contacts) has no columns
            provenance=self.provenance,
            walls_meta=self.walls_meta,
        )

    # Statistics (formulas in demsplit.results.aggregate)
    def per_type(self, value: str = "u", *, by_frame: bool = True) -> pd.DataFrame:
        """Distribution statistics of ``value`` per particle type (see :func:`demsplit.results.aggregate.per_type`)."""
        from .aggregate import per_type

        return per_type(self.raw.particles, value, by_frame=by_frame)

    def per_size(self, bins=None, value: str = "u", *, by_frame: bool = True) -> pd.DataFrame:
        """Statistics of ``value`` per radius class (see :func:`demsplit.results.aggregate.per_size`)."""
        from .aggregate import per_size

        return per_size(self.raw.particles, bins, value, by_frame=by_frame)

    def per_frame(self) -> pd.DataFrame:
        """Time series of totals and distribution statistics (see :func:`demsplit.results.aggregate.per_frame`)."""
        from .aggregate import per_frame

        return per_frame(self.raw.particles, self.raw.walls, self.raw.frames)

    def split_comparison(self, *, by_frame: bool = True) -> pd.DataFrame:
        """Material law against 50/50 and radius splits per type (see
        :func:`demsplit.results.aggregate.split_comparison`)."""
        from .aggregate import split_comparison

        return split_comparison(self.raw.particles, by_frame=by_frame)

    def contact_point_shift(self, *, by_frame: bool = True) -> pd.DataFrame:
        """|cp - cp_sim|/delta statistics (see :func:`demsplit.results.aggregate.contact_point_shift`)."""
        from .aggregate import contact_point_shift

        return contact_point_shift(self.raw.contacts, by_frame=by_frame)

    def per_clump(self) -> pd.DataFrame:
        """Energy per YADE clump and frame, summed over its member spheres
        (see :func:`demsplit.results.aggregate.per_clump`)."""
        from .aggregate import per_clump

        return per_clump(self.raw.particles)

    def wall_energy(self) -> pd.DataFrame:
        """Energy per wall and frame, with the wall names (see :func:`demsplit.results.aggregate.wall_energy`)."""
        from .aggregate import wall_energy

        return wall_energy(self.raw.walls, self.walls_meta, self.raw.frames)


def _with_units(df: pd.DataFrame, like: pd.DataFrame) -> pd.DataFrame:
    df.attrs["units"] = dict(like.attrs.get("units", {}))
    return df


ELASTIC_TOTALS = ("u", "u1", "u2", "u_equal", "u_radius", "u_springs", "share")
"""Columns that sum (or split, or divide) a row's elastic modes: unknown when any elastic mode is."""
DERIVED_FROM = {"u_n_error": "u_n"}
"""Columns computed from one mode: unknown when that mode is."""
NOT_COMPUTED_TEXT = "not computed"
"""What a text table shows in place of a value that was not computed."""


def not_computed_mask(df: pd.DataFrame) -> dict[str, np.ndarray]:
    """For a ``particles``, ``contacts`` or ``walls`` table: column -> boolean array of the rows whose
    value in that column is unknown (the bits of the row's ``not_computed`` column,
    :data:`demsplit.physics.modes.NOT_COMPUTED_BITS`; the column holds 0 there in the store). Mode
    columns follow their bit, :data:`ELASTIC_TOTALS` any elastic mode's, :data:`DERIVED_FROM` their
    mode's; a wall's ``n_contacts`` is unknown with its ``u_n`` (its contacts were not read). Empty
    when the table has no ``not_computed`` column or no bit set."""
    from ..physics.modes import ADHESION_COLUMN, NOT_COMPUTED_BITS

    if "not_computed" not in df or not len(df):
        return {}
    bits = df["not_computed"].to_numpy(dtype=np.int64)
    if not bits.any():
        return {}
    elastic = sum(bit for mode, bit in NOT_COMPUTED_BITS.items() if mode != ADHESION_COLUMN)
    mask = {mode: (bits & bit) != 0 for mode, bit in NOT_COMPUTED_BITS.items() if mode in df}
    mask |= {c: (bits & elastic) != 0 for c in ELASTIC_TOTALS if c in df}
    mask |= {c: (bits & NOT_COMPUTED_BITS[mode]) != 0 for c, mode in DERIVED_FROM.items() if c in df}
    if "n_contacts" in df and "wall" in df and "id" not in df:  # a wall whose contacts were not read
        mask["n_contacts"] = (bits & NOT_COMPUTED_BITS["u_n"]) != 0
    return {c: m for c, m in mask.items() if m.any()}


def with_not_computed_as_nan(df: pd.DataFrame) -> pd.DataFrame:
    """A copy of ``df`` whose not-computed values (:func:`not_computed_mask`) are NaN instead of the
    store's 0, so that no export shows an unknown energy as a measured 0 (CSV: an empty cell, Parquet:
    null, VTK and text dumps: NaN); the ``not_computed`` column stays beside them. ``df`` itself
    when nothing is unknown. Units and attrs are kept."""
    mask = not_computed_mask(df)
    if not mask:
        return df
    out = df.copy()
    for column, rows in mask.items():
        out[column] = out[column].astype(np.float64).mask(rows)
    out.attrs = dict(df.attrs)
    return out
