"""One validation for every reader's frames: dtypes, finiteness, ranges and plausibility, before any physics.

Readers parse; this module checks what they hand over, the same way for every
format (docs/design.md, "Validation and errors"), so a NaN in a YADE snapshot,
an ``inf`` position in a binary dump or an ``int8`` stiffness never reaches an
energy. :func:`validated_frame` returns the frame with every column in its
canonical dtype (integers as int64, types as int32, reals as float64: safe
upcasts only) or raises one :class:`~demsplit.errors.InputFormatError` (a
:class:`~demsplit.errors.ContactError` for implausible geometry) that names
the file, the timestep, the table, the column and the row. The checks:

* integer columns hold integers (an integer dtype, or floats with integral
  values); real columns are numbers (no strings or objects);
* every real is finite, except ``r2 = inf`` (a plane);
* radius, r1, r2 > 0; stored stiffnesses (``kn ks kno kso``) >= 0; the normal
  is a unit vector (to 1e-5, the precision of ``%g`` exports);
* the box is finite with lo < hi; the frame's time, when known, is finite and >= 0;
* an overlap is not larger than the one its law allows (:meth:`~demsplit.physics.laws.ContactLaw.overlap_limit`,
  asked of the law that acts on the contact: a JCFpm smooth joint, r1 + r2), by default the smaller of the two
  radii.

:func:`typed_columns` is the same layer one step earlier, for a reader's raw
records (a YADE snapshot's tables, before the reader combines their columns):
every column the reader needs is there, one-dimensional, as long as the
others, and of its kind (integers, reals or text), cast safely to int64,
float64 or bytes, so that no reader computes in a narrow or foreign dtype.

:func:`check_finite_energies` refuses a result that is not finite (a dumped
shear history of 1e200 gives ``inf`` energies) before it is stored.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .errors import ContactError, InputFormatError
from .frame import Frame, Table
from .physics.bodies import FrameContacts
from .physics.partition import law_groups
from .scene import Scene

INTEGER_COLUMNS = {
    "id": np.int64,
    "type": np.int32,
    "clump": np.int64,
    "id1": np.int64,
    "id2": np.int64,
    "wall": np.int64,
    "type1": np.int64,
    "type2": np.int64,
    "history_unknown": np.int8,
    "unknown_modes": np.int8,
    "unknown_why": np.int8,
}
"""Integer columns and their canonical dtypes; every other column is a real (float64)."""
NOT_NEGATIVE = ("kn", "ks", "kno", "kso", "kr", "ktw", "mb", "mtw", "mass")
MAY_BE_INFINITE = ("r2",)  # a plane: R = inf
UNIT_TOLERANCE = 1e-5
POSITIVE = ("radius", "r1", "r2")


def validated_frame(frame: Frame, scene: Scene) -> Frame:
    """``frame`` with canonical dtypes, or the error of its first invalid value (module docstring); ``scene``:
    the run's, whose laws say how deep their contacts may overlap."""
    source = frame.source[-1] if frame.source else None  # the contact file of a joined LIGGGHTS frame
    where = {"file": frame.source[0] if frame.source else None, "step": frame.step}
    particles = _canonical("particles", frame.particles, where)
    contacts = _canonical("contacts", frame.contacts, {**where, "file": source})
    if frame.box is not None:
        lo, hi = frame.box.lo, frame.box.hi
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo < hi)):
            raise InputFormatError(
                f"the box bounds are not finite with lo < hi (lo {lo.tolist()}, hi {hi.tolist()}).",
                **where,
                fix="check the box lines of the file.",
            )
    if frame.time is not None and not (np.isfinite(frame.time) and frame.time >= 0):
        raise InputFormatError(
            f"the frame's time {float(frame.time)!r} s is not a finite time >= 0.",
            **where,
            fix="check the run's timestep and the frame's step.",
        )
    if contacts and len(contacts["delta"]):
        _check_geometry(contacts, particles, scene, {**where, "file": source})
    return replace(frame, particles=particles, contacts=contacts)


def _who(table: str, t: Table, row: int) -> str:
    if table == "particles":
        return f"particle {int(t['id'][row])}" if "id" in t else f"particle row {row}"
    if int(t["wall"][row]) >= 0:
        return f"the contact of particle {int(t['id1'][row])} with wall {int(t['wall'][row])}"
    return f"the contact of particles {int(t['id1'][row])}-{int(t['id2'][row])}"


def _canonical(table: str, t: Table, where: dict) -> Table:
    out: Table = {}
    for col, values in t.items():
        values = np.asarray(values)
        if col in INTEGER_COLUMNS:
            out[col] = _integers(table, col, values, INTEGER_COLUMNS[col], where)
            continue
        if values.dtype.kind not in "fiub":
            raise InputFormatError(
                f"column {table}.{col} holds {values.dtype} values, not numbers.",
                **where,
                fix="the reader or the file is damaged: check the file.",
            )
        values = values.astype(np.float64, copy=False)
        bad = ~np.isfinite(values)
        if col in MAY_BE_INFINITE:
            bad &= ~(values == np.inf)
        _refuse(bad, table, col, values, "is not a finite number", t, where)
        if col in POSITIVE:
            _refuse(~(values > 0), table, col, values, "must be > 0", t, where)
        elif col in NOT_NEGATIVE:
            _refuse(values < 0, table, col, values, "must be >= 0", t, where)
        out[col] = values
    return out


def _integers(table: str, col: str, values: np.ndarray, dtype, where: dict) -> np.ndarray:
    if values.dtype.kind in "iu":
        info = np.iinfo(dtype)
        if len(values) and (values.min() < info.min or values.max() > info.max):
            raise InputFormatError(
                f"column {table}.{col} has values beyond {np.dtype(dtype).name}.",
                **where,
                fix="check the file: ids and types this large are not a DEM run's.",
            )
        return values.astype(dtype, copy=False)
    if values.dtype.kind == "f":
        bad = ~np.isfinite(values) | (values != np.round(values))
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise InputFormatError(
                f"column {table}.{col} must hold integers, row {row} holds {float(values[row])!r}.",
                **where,
                fix="check the file: ids and types are exact integers.",
            )
        return values.astype(dtype)
    raise InputFormatError(
        f"column {table}.{col} holds {values.dtype} values, not integers.",
        **where,
        fix="the reader or the file is damaged: check the file.",
    )


def _refuse(bad: np.ndarray, table: str, col: str, values: np.ndarray, what: str, t: Table, where: dict) -> None:
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise InputFormatError(
            f"{_who(table, t, row)} (row {row}): {col} = {float(values[row])!r} {what}; "
            f"{int(np.count_nonzero(bad))} such value(s) in column {table}.{col}.",
            **where,
            fix="check the file at that row: a damaged or foreign value.",
        )


def _check_geometry(c: Table, particles: Table, scene: Scene, where: dict) -> None:
    norm = np.sqrt(c["nx"] ** 2 + c["ny"] ** 2 + c["nz"] ** 2)
    _refuse(np.abs(norm - 1.0) > UNIT_TOLERANCE, "contacts", "|n|", norm, "is not a unit normal", c, where)
    limit = overlap_limit(c, scene, particles)
    too_deep = c["delta"] > limit
    if too_deep.any():
        row = int(np.flatnonzero(too_deep)[0])
        radius = limit[row] == min(c["r1"][row], c["r2"][row])
        what = "its smaller radius" if radius else "the largest its law allows"
        raise ContactError(
            f"{_who('contacts', c, row)} (row {row}) has an overlap of {float(c['delta'][row]):g} m, larger than "
            f"{what} ({float(limit[row]):g} m): not a plausible DEM contact; "
            f"{int(np.count_nonzero(too_deep))} such contact(s).",
            **where,
            fix="check that the contact and atom dumps belong to the same run and timestep.",
        )


def overlap_limit(c: Table, scene: Scene, particles: Table | None = None) -> np.ndarray:
    """The largest plausible overlap (m) of each contact: what the law that acts on it allows
    (:meth:`~demsplit.physics.laws.ContactLaw.overlap_limit`), by default the smaller of r1 and r2; ``particles``
    gives the types where the law depends on the pair of types (``Scene.pair_models``)."""
    limit = np.minimum(c["r1"], c["r2"])
    types = FrameContacts(c, scene, particles).types() if scene.pair_models and len(limit) else None
    for model, rows in law_groups(c, scene, types):
        law_limit = model.contact_law.overlap_limit({k: np.asarray(v)[rows] for k, v in c.items()})
        if law_limit is not None:
            limit[rows] = law_limit
    return limit


def check_finite_energies(u: np.ndarray, contacts: Table, *, file: str | None, step: int) -> None:
    """Refuse energies (shape (modes, n) or (n,)) that are not finite, naming the first contact."""
    bad = ~np.isfinite(u)
    if bad.ndim == 2:
        bad = bad.any(axis=0)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ContactError(
            f"{_who('contacts', contacts, row)} (row {row}) has an energy that is not finite: "
            "a stored force, stiffness or spring history of an implausible size; "
            f"{int(np.count_nonzero(bad))} such contact(s).",
            file=file,
            step=step,
            fix="check the contact file at that row (a damaged or foreign value).",
        )


COLUMN_KINDS = ("int", "real", "text")


def typed_columns(
    table,
    schema: dict[str, str],
    *,
    name: str,
    optional: dict[str, str] | None = None,
    file=None,
    step: int | None = None,
    where: str = "",
) -> dict[str, np.ndarray]:
    """The columns of a reader's raw ``table`` named in ``schema`` (required) and ``optional`` (kept when
    present), each cast to its kind (:data:`COLUMN_KINDS`): ``int`` to int64 (integer dtypes within its
    range, or finite integral reals), ``real`` to float64 (integer, real or boolean dtypes; values are
    checked later, on the frame), ``text`` to bytes. Columns named in neither are dropped. A missing
    column, one that is not 1-D, of another length or of another kind is an :class:`InputFormatError`
    naming ``where`` (e.g. ``"snapshot 2"``), the table ``name`` and the column."""
    prefix = f"{where}: " if where else ""

    def bad(col: str, what: str) -> InputFormatError:
        return InputFormatError(
            f"{prefix}column {name}.{col} {what}.",
            file=file,
            step=step,
            fix="the file is damaged or was not written by the simulator's exporter: "
            "rewrite it (rerun the simulation).",
        )

    if not isinstance(table, dict):
        raise InputFormatError(
            f"{prefix}table {name} is missing or not a table of columns.",
            file=file,
            step=step,
            fix="the file is damaged: rewrite it (rerun the simulation).",
        )
    out: dict[str, np.ndarray] = {}
    length = None
    for col, kind in {**schema, **(optional or {})}.items():
        if col not in table:
            if col in schema:
                raise bad(col, "is missing")
            continue
        values = np.asarray(table[col])
        if values.ndim != 1:
            raise bad(col, f"has shape {values.shape}, expected one value per row")
        if length is None:
            length = len(values)
        elif len(values) != length:
            raise bad(col, f"has {len(values)} rows, the table's other columns {length}")
        out[col] = _as_kind(values, kind, lambda what, c=col: bad(c, what))
    return out


def _as_kind(values: np.ndarray, kind: str, bad) -> np.ndarray:
    dt = values.dtype
    if kind == "text":
        if dt.kind == "S":
            if len(values) and np.any(np.frombuffer(values.tobytes(), np.uint8) >= 0x80):
                raise bad("holds text that is not ASCII")
            return values
        if dt.kind == "U":
            try:
                return values.astype("S")
            except UnicodeEncodeError:
                raise bad("holds text that is not ASCII") from None
        raise bad(f"holds {dt} values, expected text")
    if kind == "real":
        if dt.kind in "fiub":
            return values.astype(np.float64, copy=False)
        raise bad(f"holds {dt} values, expected numbers")
    if dt.kind in "iu":
        if dt.kind == "u" and dt.itemsize == 8 and len(values) and values.max() > np.iinfo(np.int64).max:
            raise bad("has values beyond int64")
        return values.astype(np.int64, copy=False)
    if dt.kind == "f":
        ok = np.isfinite(values) & (values == np.round(values)) & (np.abs(values) < 2.0**63)
        if not ok.all():
            row = int(np.flatnonzero(~ok)[0])
            raise bad(f"must hold integers, row {row} holds {float(values[row])!r}")
        return values.astype(np.int64)
    raise bad(f"holds {dt} values, expected integers")
