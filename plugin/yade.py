"""The YADE side of demsplit: a full-precision snapshot exporter that runs
inside a YADE script.

Use it from a ``PyRunner``, best placed between ``InteractionLoop`` and
``NewtonIntegrator``, where geometry, forces and positions are of the same
instant (from a PyRunner after the integrator, the reader steps the positions
back to the forces' instant)::

    import site; site.addsitedir("<site-packages of the Python where demsplit is installed>")
    import demsplit.yade
    O.engines = [ForceResetter(), InsertionSortCollider([...]),
                 InteractionLoop([...], [...], [...]),
                 PyRunner(command='demsplit.yade.snapshot("run.h5")', iterPeriod=1000),
                 NewtonIntegrator(...)]

Each call appends one snapshot (bodies, real interactions with the attributes
of their physics their law declares, every material, inline ones included,
the Ip2/Law2 functors and their attributes, the periodic cell, ``O.energy``
and the laws' own elastic energies for validation) to one file. The file is HDF5 when
``h5py`` is importable, otherwise an append-only stream of ``.npy`` records
that needs nothing but numpy; :func:`demsplit.readers.yade_snapshot.open_yade_snapshot`
reads both. Reals are stored as float64; in high-precision builds (mpmath
scalars) ``penetrationDepth`` is also stored as decimal strings at the build's
full precision.

This module imports only numpy (and h5py lazily): it must import inside
YADE's own Python, with Debian's numpy. ``yade`` itself is imported only by
:func:`snapshot` and :func:`collect`.
"""

from __future__ import annotations

import io
import json
import os
import zlib
from pathlib import Path

import numpy as np

from .errors import InputFormatError, TruncatedFileError

FORMAT_NAME = "demsplit-yade-snapshot"
FORMAT_VERSION = 2
"""2: the physics' columns are those the laws declare (Mindlin's elastic shear force ``fsex fsey fsez``, ...),
inline materials are listed, a state loaded with ``O.load`` says so. Version 1 files are read too."""

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
NPY_STREAM_MAGIC = b"DEMSPLIT-YADE-SNAPSHOT npy-stream v1\n"
"""First line of the numpy-only format. The rest of the file is a sequence of
records ``b"DSREC <16-digit payload length>\\n" payload b"DSEND <8-hex crc32>\\n"``;
the payload is ``np.save`` of the UTF-8 JSON metadata (a uint8 array) followed
by ``np.save`` of every column listed in ``meta["columns"]``, in that order."""
RECORD_HEAD = 6 + 16 + 1
RECORD_TAIL = 6 + 8 + 1

SHAPE_KINDS = {"Sphere": "sphere", "Wall": "wall", "Facet": "facet", "Box": "box", "Clump": "clump"}
"""YADE shape class -> the ``kind`` column of the bodies table (else ``other``)."""

YADE_PREFIX = "yade:"
"""A YADE law's registry key is this prefix + its Law2 functor's class name."""


# --------------------------------------------------------------------------
# Collecting the state of a running YADE simulation
# --------------------------------------------------------------------------


def _plain(value):
    """A JSON-able copy of a YADE attribute value: mpf -> float, vectors,
    matrices and quaternions -> lists, anything else unknown -> its str."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if type(value).__name__ == "mpf":
        return float(value)
    if type(value).__name__.startswith(("Vector", "Matrix", "Quaternion")):
        try:
            return [_plain(v) for v in value]
        except TypeError:
            pass
    if hasattr(value, "dict") and callable(value.dict):  # a YADE Serializable
        return {"class": type(value).__name__, **_plain(value.dict())}
    return str(value)


def _functor_list(functors) -> list[dict]:
    return [{"class": type(f).__name__, "attrs": _plain(f.dict())} for f in functors]


def _engines(O) -> tuple[list[dict], dict]:
    """Engine order (class names, PyRunner commands) and the functors of the
    InteractionLoop(s)."""
    order, functors = [], {"geom": [], "phys": [], "law": []}
    for e in O.engines:
        entry = {"class": type(e).__name__}
        if entry["class"] == "PyRunner":
            entry["command"] = e.command
        if entry["class"] == "InteractionLoop":
            functors["geom"] += _functor_list(e.geomDispatcher.functors)
            functors["phys"] += _functor_list(e.physDispatcher.functors)
            functors["law"] += _functor_list(e.lawDispatcher.functors)
        order.append(entry)
    return order, functors


def _law_functors(O) -> list:
    """The Law2 functors of the InteractionLoop(s)."""
    return [f for e in O.engines if type(e).__name__ == "InteractionLoop" for f in e.lawDispatcher.functors]


def _law_energies(O) -> dict:
    """The laws' own elastic energies (J), for validation: each registered law's
    ``simulator_energies`` (e.g. Mindlin's ``normElastEnergy()``)."""
    from .physics import laws

    out = {}
    for f in _law_functors(O):
        key = YADE_PREFIX + type(f).__name__
        if key in laws.supported():
            for name, (method, _) in laws.law_class(key).simulator_energies.items():
                if hasattr(f, method):
                    out[name] = float(getattr(f, method)())
    return out


def _phys_attributes(O) -> list:
    """The interaction attributes to export: those each law of the InteractionLoop declares (its ``phys``;
    a law demsplit does not have: the normal and shear springs), and those of the engines beside it (the
    capillary force)."""
    from .physics import laws
    from .physics.laws._yade import ENGINE_PHYS, SPRINGS

    found = []
    for f in _law_functors(O):
        key = YADE_PREFIX + type(f).__name__
        found += getattr(laws.law_class(key), "phys", SPRINGS) if key in laws.supported() else SPRINGS
    for e in O.engines:
        found += ENGINE_PHYS.get(type(e).__name__, ())
    return list(dict.fromkeys(found))


def _materials(O) -> tuple[list[dict], dict]:
    """Every material of the scene: ``O.materials`` (id = its index) and the materials of bodies made inline
    (``material=FrictMat(...)`` in ``utils.sphere``/``facet``/``wall``, not in ``O.materials``, all with id -1),
    numbered after them, one per distinct class and attributes, flagged ``inline``. Returns the list and
    the id of each inline material by its key (:func:`_material_key`)."""
    out = [{"class": type(m).__name__, **_plain(m.dict())} for m in O.materials]
    inline: dict = {}
    for b in O.bodies:
        m = None if b is None else b.material
        if m is None or m.id >= 0:
            continue
        key = _material_key(m)
        if key not in inline:
            inline[key] = len(out)
            out.append(
                {
                    "class": type(m).__name__,
                    **_plain(m.dict()),
                    "id": len(out),
                    "inline": True,
                    "label": m.label or "inline %s of body %d" % (type(m).__name__, b.id),
                }
            )
    return out, inline


def _material_key(m) -> str:
    return json.dumps([type(m).__name__, _plain(m.dict())], sort_keys=True)


def _vec(v) -> tuple[float, ...]:
    return tuple(float(x) for x in v)


def _body_table(O, inline: dict) -> dict[str, np.ndarray]:
    """One row per body. Positions are YADE's (unwrapped) ``state.pos`` and,
    for periodic runs, ``O.cell.wrap(pos)``; facet vertices are global; ``material`` is the material's id
    in :func:`_materials` (``inline``: the ids of inline materials), -1 for a body without one."""
    periodic = bool(O.periodic)
    nan3 = (np.nan,) * 3
    rows = []
    for b in O.bodies:
        if b is None:  # erased body: its id stays free
            continue
        shape_class = type(b.shape).__name__ if b.shape is not None else "None"
        kind = SHAPE_KINDS.get(shape_class, "other")
        pos = b.state.pos
        mat = b.material
        radius = float(b.shape.radius) if kind == "sphere" else np.nan
        axis, sense = (int(b.shape.axis), int(b.shape.sense)) if kind == "wall" else (-1, 0)
        if kind == "facet":
            verts = sum((_vec(pos + b.state.ori * v) for v in b.shape.vertices), ())
        else:
            verts = nan3 * 3
        rows.append(
            (
                b.id,
                kind,
                shape_class,
                -1 if mat is None else mat.id if mat.id >= 0 else inline[_material_key(mat)],
                float(getattr(mat, "young", np.nan)),
                float(getattr(mat, "poisson", np.nan)),
                float(getattr(mat, "density", np.nan)),
                radius,
                *_vec(pos),
                *_vec(O.cell.wrap(pos) if periodic else pos),
                *_vec(b.state.vel),
                *_vec(b.state.angVel),
                float(b.state.mass),
                *_vec(b.state.ori),
                b.clumpId,
                bool(b.dynamic),
                axis,
                sense,
                *(_vec(b.shape.extents) if kind == "box" else nan3),
                *verts,
            )
        )
    cols = (
        "id kind shape_class material young poisson density radius x y z xw yw zw "
        "vx vy vz wx wy wz mass qx qy qz qw clump dynamic wall_axis wall_sense ex ey ez "
        "v0x v0y v0z v1x v1y v1z v2x v2y v2z"
    ).split()
    data = list(zip(*rows)) if rows else [()] * len(cols)
    dtypes = {
        "id": np.int64,
        "material": np.int64,
        "clump": np.int64,
        "dynamic": np.bool_,
        "wall_axis": np.int8,
        "wall_sense": np.int8,
        "kind": "S8",
        "shape_class": "S32",
    }
    return {c: np.asarray(d, dtype=dtypes.get(c, np.float64)) for c, d in zip(cols, data)}


GEOMETRY_COLUMNS = (
    "id1 id2 geom_class phys_class depth nx ny nz cpx cpy cpz refR1 refR2 cdx cdy cdz iter_made_real"
).split()
"""The interactions table's columns every interaction has (its ScGeom); the physics' columns follow, as the
laws declare them (:class:`demsplit.physics.laws._yade.Phys`)."""


def _interaction_table(O, high_precision: bool, attributes: list) -> dict[str, np.ndarray]:
    """One row per real interaction (``for i in O.interactions`` visits only
    real ones), YADE's order of id1/id2 kept: the geometry, then each of
    ``attributes`` (NaN where an interaction's physics lacks it; a boolean as 0 or 1)."""
    rows, depth_text = [], []
    nan, nan3 = np.nan, (np.nan,) * 3
    for i in O.interactions:
        g, p = i.geom, i.phys
        d = g.penetrationDepth
        row = [
            i.id1,
            i.id2,
            type(g).__name__,
            type(p).__name__,
            float(d),
            *_vec(g.normal),
            *_vec(g.contactPoint),
            float(g.refR1),
            float(g.refR2),
            *(int(c) for c in i.cellDist),
            i.iterMadeReal,
        ]
        for a in attributes:
            row += [float(getattr(p, a.yade, nan))] if a.shape == "scalar" else _vec(getattr(p, a.yade, nan3))
        rows.append(row)
        if high_precision:
            depth_text.append(str(d))
    cols = GEOMETRY_COLUMNS + [c for a in attributes for c in a.columns]
    data = list(zip(*rows)) if rows else [()] * len(cols)
    dtypes = {
        "id1": np.int64,
        "id2": np.int64,
        "cdx": np.int64,
        "cdy": np.int64,
        "cdz": np.int64,
        "iter_made_real": np.int64,
        "geom_class": "S32",
        "phys_class": "S32",
    }
    table = {c: np.asarray(d, dtype=dtypes.get(c, np.float64)) for c, d in zip(cols, data)}
    if high_precision:
        table["depth_text"] = np.asarray(depth_text, dtype=bytes) if depth_text else np.zeros(0, "S1")
    return table


def collect(
    O=None, *, law_energies: bool = True, loaded: bool = False
) -> tuple[dict, dict[str, dict[str, np.ndarray]]]:
    """The current state of YADE's ``O`` as ``(meta, tables)``.

    ``tables`` has ``bodies`` and ``interactions`` (column name -> array);
    ``meta`` is JSON-able: iteration, time, dt, cell, materials (inline ones
    included, :func:`_materials`), engines, functors with their attributes,
    ``O.energy``, the laws' elastic energies (``law_energies=False`` leaves them
    out), interaction counts and the build's precision.

    ``loaded``: the scene is a state just loaded with ``O.load`` (``meta["loaded_state"]``): its
    ``penetrationDepth`` is NaN (YADE does not save it; the reader recovers it), and its law functors have
    no scene until the next step (YADE 2023.02a crashes calling their energy functions), so the laws'
    energies are left out.
    """
    import yade
    import yade.config

    if O is None:
        O = yade.Omega()
    name = str(getattr(yade.config, "highPrecisionName", "PrecisionDouble"))
    high_precision = name != "PrecisionDouble"
    engines, functors = _engines(O)
    materials, inline = _materials(O)
    n_potential = len(O.interactions)
    n_real = O.interactions.countReal()
    meta = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "yade_version": str(yade.config.version),
        "precision_name": name,
        "precision_decimal_places": int(getattr(yade.config, "highPrecisionDecimalPlaces", 15)),
        "high_precision": high_precision,
        "iter": int(O.iter),
        "time": float(O.time),
        "dt": float(O.dt),
        "periodic": bool(O.periodic),
        "hSize": _plain(O.cell.hSize) if O.periodic else None,
        "velGrad": _plain(O.cell.velGrad) if O.periodic else None,
        "materials": materials,
        "engines": engines,
        "functors": functors,
        "energy": {k: float(v) for k, v in O.energy.items()},
        "track_energy": bool(O.trackEnergy),
        "law_energies": _law_energies(O) if law_energies and not loaded else {},
        "loaded_state": loaded,
        "n_interactions_potential": n_potential,
        "n_interactions_real": n_real,
    }
    tables = {
        "bodies": _body_table(O, inline),
        "interactions": _interaction_table(O, high_precision, _phys_attributes(O)),
    }
    if len(tables["interactions"]["id1"]) != n_real:
        raise InputFormatError(
            f"iterating O.interactions gave {len(tables['interactions']['id1'])} interactions "
            f"but O.interactions.countReal() is {n_real}.",
            step=int(O.iter),
            fix="report this YADE version to the demsplit developers.",
        )
    return meta, tables


# --------------------------------------------------------------------------
# Writing: one snapshot per call, appended atomically
# --------------------------------------------------------------------------


def h5py_or_none():
    """The h5py module, or None when it cannot be imported (Debian's YADE
    Python has no h5py unless python3-h5py is installed)."""
    try:
        import h5py
    except Exception:  # ImportError, or an ABI mismatch with this numpy
        return None
    return h5py


def sniff_format(path: str | Path) -> str | None:
    """``"hdf5"``, ``"npy"`` or None (missing or empty file); anything else
    raises :class:`InputFormatError`."""
    path = Path(path)
    if not path.exists() or path.stat().st_size == 0:
        return None
    with open(path, "rb") as f:
        head = f.read(len(NPY_STREAM_MAGIC))
    if head.startswith(HDF5_SIGNATURE):
        return "hdf5"
    if head == NPY_STREAM_MAGIC:
        return "npy"
    raise InputFormatError(
        f"not a demsplit YADE snapshot file: it starts with {head[:16]!r}, expected the HDF5 "
        f"signature or {NPY_STREAM_MAGIC.strip()!r}.",
        file=path,
        fix="give the file written by demsplit.yade.snapshot().",
    )


def snapshot(path: str | Path, *, format: str = "auto", O=None, law_energies: bool = True) -> int:
    """Append a snapshot of the running simulation to ``path``; return its
    index (0 for the first).

    format
        ``"auto"`` (default): continue the existing file in its own format;
        for a new file, HDF5 when h5py is importable, else the npy stream.
        ``"hdf5"`` or ``"npy"`` force a format (an existing file must match).
    law_energies
        record the laws' own energy functions (see :func:`collect`).
    """
    meta, tables = collect(O, law_energies=law_energies)
    return write_snapshot(path, meta, tables, format=format)


def write_snapshot(
    path: str | Path, meta: dict, tables: dict[str, dict[str, np.ndarray]], *, format: str = "auto"
) -> int:
    """Append one snapshot ``(meta, tables)`` to ``path`` (see :func:`snapshot`)."""
    path = Path(path)
    existing = sniff_format(path)
    if format == "auto":
        format = existing or ("hdf5" if h5py_or_none() is not None else "npy")
    if format not in ("hdf5", "npy"):
        raise ValueError(f"format must be 'auto', 'hdf5' or 'npy', got {format!r}")
    if existing is not None and existing != format:
        raise InputFormatError(
            f"the file is in the {existing} snapshot format; cannot append a {format} snapshot.",
            file=path,
            fix="use a new file name or format='auto'.",
        )
    if format == "hdf5":
        return _write_hdf5(path, meta, tables)
    return _write_npy(path, meta, tables)


def _write_hdf5(path: Path, meta: dict, tables: dict) -> int:
    """Group ``/snapshots/NNNNNN`` with a subgroup per table and a dataset per
    column; attribute ``complete`` is set last, so a snapshot cut short (crash,
    full disk) is recognisable. The file is opened and closed per snapshot."""
    h5py = h5py_or_none()
    if h5py is None:
        raise InputFormatError(
            "h5py cannot be imported in this Python.",
            file=path,
            fix="continue this run in a new file with format='npy'.",
        )
    with h5py.File(path, "a") as f:
        f.attrs["format"] = FORMAT_NAME
        f.attrs["format_version"] = FORMAT_VERSION
        snaps = f.require_group("snapshots")
        for name in snaps:
            if not snaps[name].attrs.get("complete", False):
                raise TruncatedFileError(
                    f"snapshot group {name!r} is incomplete (a previous write was cut short).",
                    file=path,
                    fix="start a new snapshot file; the reader reports the broken snapshot.",
                )
        index = len(snaps)
        g = snaps.create_group(f"{index:06d}")
        g.attrs["iter"] = meta["iter"]
        g.attrs["time"] = meta["time"]
        g.attrs["meta_json"] = json.dumps(meta)
        for tname, table in tables.items():
            tg = g.create_group(tname)
            for cname, col in table.items():
                tg.create_dataset(cname, data=col)
        f.flush()
        g.attrs["complete"] = True
    return index


def _npy_payload(meta: dict, tables: dict) -> bytes:
    columns = [[t, c] for t, table in tables.items() for c in table]
    buf = io.BytesIO()
    header = json.dumps({**meta, "columns": columns}).encode()
    np.save(buf, np.frombuffer(header, dtype=np.uint8), allow_pickle=False)
    for t, c in columns:
        np.save(buf, np.ascontiguousarray(tables[t][c]), allow_pickle=False)
    return buf.getvalue()


def npy_records(path: Path) -> tuple[list[tuple[int, int]], str | None]:
    """Scan a npy-stream file: ``([(payload offset, payload length), ...],
    problem)`` where ``problem`` describes a cut-short or damaged last record
    (None when the file ends cleanly after a complete record)."""
    size = path.stat().st_size
    records = []
    with open(path, "rb") as f:
        offset = len(NPY_STREAM_MAGIC)
        while offset < size:
            f.seek(offset)
            head = f.read(RECORD_HEAD)
            k = len(records)
            if len(head) < RECORD_HEAD or not head.startswith(b"DSREC ") or head[-1:] != b"\n":
                return records, (
                    f"snapshot {k} at byte {offset} is cut short or damaged: its record header reads {head[:24]!r}"
                )
            try:
                length = int(head[6:22])
            except ValueError:
                length = -1
            if length < 0:  # a record always moves forward; beyond the file, the end marker check below fails
                return records, (
                    f"snapshot {k} at byte {offset} is cut short or damaged: its record header "
                    f"declares a length of {head[6:22]!r}"
                )
            end = offset + RECORD_HEAD + length
            tail = b""
            if end + RECORD_TAIL <= size:  # else the file ends before the record does
                f.seek(end)
                tail = f.read(RECORD_TAIL)
            if len(tail) < RECORD_TAIL or not tail.startswith(b"DSEND ") or tail[-1:] != b"\n":
                return records, (
                    f"snapshot {k} at byte {offset} is cut short or damaged: it declares {length} "
                    f"bytes but the file ends or is damaged before its end marker"
                )
            records.append((offset + RECORD_HEAD, length))
            offset = end + RECORD_TAIL
    return records, None


def _write_npy(path: Path, meta: dict, tables: dict) -> int:
    """Append one record, built in memory and written with one ``write`` and
    an ``fsync``; the length prefix and crc32 end marker make a record cut
    short detectable."""
    if path.exists() and path.stat().st_size > 0:
        records, problem = npy_records(path)
        if problem:
            raise TruncatedFileError(
                f"cannot append: {problem}.",
                file=path,
                fix="start a new snapshot file; the reader reports the broken snapshot.",
            )
        index, prefix = len(records), b""
    else:
        index, prefix = 0, NPY_STREAM_MAGIC
    payload = _npy_payload(meta, tables)
    record = prefix + b"DSREC %016d\n" % len(payload) + payload + b"DSEND %08x\n" % (zlib.crc32(payload) & 0xFFFFFFFF)
    with open(path, "ab") as f:
        f.write(record)
        f.flush()
        os.fsync(f.fileno())
    return index
