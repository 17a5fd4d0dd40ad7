"""Reader of the snapshot files written by :func:`demsplit.yade.snapshot`.

``open_yade_snapshot(path)`` returns a :class:`YadeSnapshotRun`: its
``.scene`` (materials keyed by YADE material id, the contact model from the
Law2 functor, the non-sphere bodies as walls) and, when iterated, one
:class:`demsplit.frame.Frame` per snapshot, read one at a time. Both storage
formats (HDF5, numpy-only record stream) are read by the same code.

Contacts follow :mod:`demsplit.frame`: ``id1`` is always a particle (sphere).
YADE puts the wall, facet or box first, so such rows are swapped: the normal
and the shear force change sign and refR1/refR2 trade places. ``delta`` is
YADE's ``penetrationDepth``; ``r1 r2`` are its ``refR1 refR2`` (walls and boxes
act as a sphere of the particle's radius, facets of twice it, as YADE built
kno) unless ``plane_as_plane=True``.
"""

from __future__ import annotations

import io
import json
import math
import zlib
from collections.abc import Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from demsplit.errors import (
    ContactError,
    DemsplitError,
    InputFormatError,
    MaterialError,
    TruncatedFileError,
    UnsupportedModelError,
    plain,
)
from demsplit.frame import Box, Frame, Table
from demsplit.physics import laws as law_registry
from demsplit.physics.laws._yade import ENGINE_PHYS, SCALAR, SPRINGS, VECTOR, Phys, YadeLaw, magnitude
from demsplit.scene import ContactModel, Material, Scene, Wall
from demsplit.validate import typed_columns
from demsplit.yade import (
    FORMAT_NAME,
    FORMAT_VERSION,
    HDF5_SIGNATURE,
    NPY_STREAM_MAGIC,
    RECORD_TAIL,
    YADE_PREFIX,
    npy_records,
    sniff_format,
)

from .base import MATERIALS, Option, Run
from .hdf5_inputs import refuse_foreign_storage
from .lammps_input import excerpt

LAW_MODELS = {
    key[len(YADE_PREFIX) :]: ContactModel(key) for key in law_registry.supported() if key.startswith(YADE_PREFIX)
}
"""YADE Law2 functor class -> the contact model (its law's registry key is ``yade:`` + the class)."""

PLANE_AS_PLANE = Option(
    "plane_as_plane",
    ("--plane-as-plane",),
    "treat YADE walls/facets/boxes as planes (R = inf) instead of YADE's refR",
    {"action": "store_true"},
)
"""The option of the YADE readers whose laws can rebuild their normal stiffness from the materials."""

WALL_KINDS = {"wall": "yade_wall", "facet": "facet", "box": "box"}
"""Body kind in the snapshot -> :class:`demsplit.scene.Wall` kind."""

RawSnapshot = tuple[dict, dict[str, Table]]


# --------------------------------------------------------------------------
# Storage: both formats behind count / meta(k) / snapshot(k)
# --------------------------------------------------------------------------

BODY_COLUMNS = {
    "id": "int",
    "kind": "text",
    "shape_class": "text",
    "material": "int",
    "radius": "real",
    "x": "real",
    "y": "real",
    "z": "real",
    "xw": "real",
    "yw": "real",
    "zw": "real",
    "vx": "real",
    "vy": "real",
    "vz": "real",
    "mass": "real",
    "clump": "int",
    "wall_axis": "int",
}
OPTIONAL_BODY_COLUMNS = {"wx": "real", "wy": "real", "wz": "real"}
"""The angular velocity (rad/s), which steps a clump's members back along its rotation (format 2 on)."""
INTERACTION_COLUMNS = {
    **{c: "int" for c in ("id1", "id2", "cdx", "cdy", "cdz")},
    **{c: "real" for c in ("depth", "nx", "ny", "nz", "cpx", "cpy", "cpz", "refR1", "refR2")},
}
"""The columns of a snapshot's tables this reader uses, and their kinds (demsplit.validate.typed_columns):
the bodies, and the geometry of every interaction; the columns of the interactions' physics are those its
laws declare (:func:`phys_attributes`)."""
OPTIONAL_INTERACTION_COLUMNS = {"depth_text": "text"}
FIX_DAMAGED = (
    "the snapshot file is damaged or was not written by demsplit.yade.snapshot(): rewrite it (rerun the simulation)."
)


@contextmanager
def _reading(path: Path, what: str):
    """Turn what h5py, numpy and json raise on a damaged file into one InputFormatError naming ``what``."""
    try:
        yield
    except DemsplitError:
        raise
    except (OSError, KeyError, ValueError, TypeError, IndexError, EOFError, SyntaxError, RuntimeError) as exc:
        cause = " ".join(str(exc).split())[:160].encode("ascii", "backslashreplace").decode()
        raise InputFormatError(
            f"{what} cannot be read ({type(exc).__name__}: {cause}).", file=path, fix=FIX_DAMAGED
        ) from None


class _Hdf5Store:
    def __init__(self, path: Path) -> None:
        import h5py

        self.path = path
        try:
            self._file = h5py.File(path, "r")
        except OSError as err:
            raise TruncatedFileError(
                f"the HDF5 snapshot file cannot be opened ({err}); it is cut short or damaged.",
                file=path,
                fix="rerun the simulation to rewrite it; the numpy-only format "
                "(snapshot(..., format='npy')) keeps the complete snapshots readable "
                "after a crash.",
            ) from None
        with _reading(path, "the HDF5 file's layout"):
            if self._file.attrs.get("format") != FORMAT_NAME:
                raise InputFormatError(
                    f"HDF5 file without the {FORMAT_NAME!r} format attribute "
                    f"(found {excerpt(str(plain(self._file.attrs.get('format'))))}).",
                    file=path,
                    fix="give the file written by demsplit.yade.snapshot().",
                )
            refuse_foreign_storage(self._file, path)
            snaps = self._file.get("snapshots")
            if snaps is not None and not isinstance(snaps, h5py.Group):
                raise InputFormatError("/snapshots is not a group.", file=path, fix=FIX_DAMAGED)
            self._names = sorted(snaps) if snaps is not None else []

    def __len__(self) -> int:
        return len(self._names)

    def _group(self, k: int):
        import h5py

        g = self._file["snapshots"][self._names[k]]
        if not isinstance(g, h5py.Group):
            raise InputFormatError(
                f"snapshot {k} (/snapshots/{self._names[k]}) is not a group.", file=self.path, fix=FIX_DAMAGED
            )
        return g

    def problem(self, k: int) -> str | None:
        with _reading(self.path, f"snapshot {k} (/snapshots/{self._names[k]})"):
            complete = self._group(k).attrs.get("complete", False)
        if not (isinstance(complete, (bool, np.bool_)) and complete):
            return f"snapshot {k} (group /snapshots/{self._names[k]}) was cut short: it has no 'complete' mark"
        return None

    def meta(self, k: int) -> dict:
        with _reading(self.path, f"the metadata of snapshot {k} (/snapshots/{self._names[k]})"):
            text = self._group(k).attrs["meta_json"]
            if not isinstance(text, (str, bytes)):
                raise TypeError(f"meta_json is {type(text).__name__}, not text")
            return json.loads(text)

    def snapshot(self, k: int) -> RawSnapshot:
        import h5py

        tables: dict[str, Table] = {}
        for t in ("bodies", "interactions"):
            with _reading(self.path, f"table {t} of snapshot {k} (/snapshots/{self._names[k]})"):
                group = self._group(k).get(t)
                if not isinstance(group, h5py.Group):
                    raise InputFormatError(f"snapshot {k}: table {t} is missing.", file=self.path, fix=FIX_DAMAGED)
                tables[t] = {}
                for c in group:
                    ds = group[c]
                    if not isinstance(ds, h5py.Dataset):
                        raise InputFormatError(
                            f"snapshot {k}: {t}/{c} is not a dataset.", file=self.path, fix=FIX_DAMAGED
                        )
                    tables[t][c] = ds[()]
        return self.meta(k), tables

    def close(self) -> None:
        self._file.close()


class _NpyStore:
    def __init__(self, path: Path) -> None:
        self.path = path
        self._records, self._problem = npy_records(path)

    def __len__(self) -> int:
        return len(self._records) + (self._problem is not None)

    def problem(self, k: int) -> str | None:
        return self._problem if k == len(self._records) else None

    def _payload(self, k: int) -> bytes:
        offset, length = self._records[k]
        with open(self.path, "rb") as f:
            f.seek(offset)
            payload = f.read(length)
            tail = f.read(RECORD_TAIL)
        try:
            crc = int(tail[6:14], 16)
        except ValueError:
            crc = None
        if crc != zlib.crc32(payload) & 0xFFFFFFFF:
            raise InputFormatError(
                f"snapshot {k} at byte {offset}: crc32 mismatch, the record is damaged.",
                file=self.path,
                fix="rewrite the snapshot file (rerun the simulation).",
            )
        return payload

    def meta(self, k: int) -> dict:
        with _reading(self.path, f"the metadata of snapshot {k}"):
            return json.loads(np.load(io.BytesIO(self._payload(k)), allow_pickle=False).tobytes())

    def snapshot(self, k: int) -> RawSnapshot:
        buf = io.BytesIO(self._payload(k))
        with _reading(self.path, f"snapshot {k}"):
            meta = json.loads(np.load(buf, allow_pickle=False).tobytes())
            if not isinstance(meta, dict) or not isinstance(meta.get("columns"), list):
                raise InputFormatError(f"snapshot {k}: the record lists no columns.", file=self.path, fix=FIX_DAMAGED)
            tables: dict[str, Table] = {"bodies": {}, "interactions": {}}
            for t, c in meta.pop("columns"):
                tables.setdefault(str(t), {})[str(c)] = np.load(buf, allow_pickle=False)
        return meta, tables

    def close(self) -> None:
        pass


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_real(v) -> bool:
    """A finite JSON number (an integer beyond the doubles, 2^1100, is not one)."""
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def checked_meta(meta, *, path: Path, k: int) -> dict:
    """A snapshot's metadata, or the InputFormatError of the first entry this reader needs that is missing
    or of the wrong type: ``iter`` (an integer in [0, 2^63)), ``time`` (finite, >= 0), ``periodic`` (a
    boolean) with ``hSize`` and, when given, ``velGrad`` (nine finite numbers), ``materials`` (objects with an
    integer ``id``), ``engines``, ``functors.law`` and ``functors.phys`` (objects with a ``class`` name; a law's
    ``attrs`` an object), the interaction counts (integers >= 0)."""

    def need(ok: bool, what: str) -> None:
        if not ok:
            raise InputFormatError(f"snapshot {k}: the metadata's {what}.", file=path, fix=FIX_DAMAGED)

    def named(items, what: str) -> None:
        need(
            isinstance(items, list) and all(isinstance(e, dict) and isinstance(e.get("class"), str) for e in items),
            f"{what} is not a list of objects with a class name",
        )

    need(isinstance(meta, dict), "record is not a JSON object")
    need(_is_int(meta.get("iter")) and 0 <= meta["iter"] < 2**63, "'iter' is not an iteration number")
    need(_is_real(meta.get("time")) and meta["time"] >= 0, "'time' is not a finite time >= 0")
    need(isinstance(meta.get("periodic"), bool), "'periodic' is not true or false")
    if meta["periodic"]:
        for key in ("hSize", "velGrad") if meta.get("velGrad") is not None else ("hSize",):
            h = meta.get(key)
            rows = h if isinstance(h, list) and all(isinstance(r, list) for r in h) else [h]
            flat = [v for r in rows if isinstance(r, list) for v in r]
            need(len(flat) == 9 and all(_is_real(v) for v in flat), f"{key!r} is not a 3x3 matrix of finite numbers")
    need(
        isinstance(meta.get("materials"), list)
        and all(isinstance(m, dict) and _is_int(m.get("id")) for m in meta["materials"]),
        "'materials' is not a list of objects with an integer id",
    )
    named(meta.get("engines"), "'engines'")
    functors = meta.get("functors")
    need(isinstance(functors, dict), "'functors' is not an object")
    named(functors.get("law"), "'functors.law'")
    named(functors.get("phys", []), "'functors.phys'")
    need(all(isinstance(f.get("attrs", {}), dict) for f in functors["law"]), "law attrs are not an object")
    need(all(isinstance(f.get("attrs", {}), dict) for f in functors.get("phys", [])), "phys attrs are not an object")
    for key in ("law_energies", "energy"):  # YADE's own energies, printed beside demsplit's
        values = meta.get(key, {})
        need(
            isinstance(values, dict) and all(_is_real(v) for v in values.values()),
            f"{key!r} is not an object of finite numbers",
        )
    for key in ("n_interactions_potential", "n_interactions_real"):
        need(_is_int(meta.get(key)) and 0 <= meta[key] < 2**63, f"{key!r} is not a count")
    need(_is_int(meta.get("format_version", 0)), "'format_version' is not an integer")
    return meta


def phys_attributes(meta: dict) -> tuple[Phys, ...]:
    """The interaction attributes the snapshot's Law2 functors declare (``phys`` of their laws; a law
    demsplit does not have: the normal and shear springs), and those of the engines beside them."""
    found: list[Phys] = []
    for f in meta["functors"]["law"]:
        model = LAW_MODELS.get(f["class"])
        found += model.contact_law.phys if model is not None else SPRINGS
    for e in meta["engines"]:
        found += ENGINE_PHYS.get(e["class"], ())
    return tuple(dict.fromkeys(found))


def checked_tables(tables: dict, meta: dict, *, path: Path, k: int) -> dict[str, Table]:
    """A snapshot's tables with the columns this reader uses, typed (:func:`demsplit.validate.typed_columns`):
    the geometry, and of each attribute the laws declare (:func:`phys_attributes`) all its columns or none (a
    file of an older format may lack an attribute; the law then says which energy it cannot compute)."""
    where = {"file": path, "step": meta["iter"], "where": f"snapshot {k}"}
    inter = tables.get("interactions")
    schema = dict(INTERACTION_COLUMNS)
    for a in phys_attributes(meta):
        if isinstance(inter, dict) and any(c in inter for c in a.columns):
            schema.update({c: "real" for c in a.columns})
    return {
        "bodies": typed_columns(
            tables.get("bodies"), BODY_COLUMNS, name="bodies", optional=OPTIONAL_BODY_COLUMNS, **where
        ),
        "interactions": typed_columns(
            inter, schema, name="interactions", optional=OPTIONAL_INTERACTION_COLUMNS, **where
        ),
    }


def _open_store(path: Path):
    fmt = sniff_format(path)
    if fmt is None:
        raise InputFormatError(
            "the snapshot file is missing or empty.",
            file=path,
            fix="check the path; the PyRunner calling demsplit.yade.snapshot() may not have run.",
        )
    return _Hdf5Store(path) if fmt == "hdf5" else _NpyStore(path)


def raw_snapshot(path: Path, k: int = 0) -> RawSnapshot:
    """Snapshot ``k`` of a snapshot file as checked metadata and typed tables, without building its scene: what
    can be described of a snapshot whose law or materials demsplit does not analyse (``demsplit info``)."""
    store = _open_store(path)
    try:
        problem = store.problem(k) if k < len(store) else f"the file holds no snapshot {k}"
        if problem:
            raise InputFormatError(f"{problem}.", file=path, fix=FIX_DAMAGED)
        meta, tables = store.snapshot(k)
        meta = checked_meta(meta, path=path, k=k)
        return meta, checked_tables(tables, meta, path=path, k=k)
    finally:
        store.close()


# --------------------------------------------------------------------------
# Scene and frames
# --------------------------------------------------------------------------


def _text(col: np.ndarray) -> np.ndarray:
    return col.astype(str)


@dataclass
class SceneParts:
    """What a snapshot's metadata gives: the scene, the materials the split cannot use (type -> why) and what
    the reader says about the materials."""

    scene: Scene
    unusable: dict[int, str]
    notes: list[str]


def scene_from_snapshot(
    meta: dict,
    bodies: Table,
    *,
    path: Path,
    step: int | None = None,
    plane_as_plane: bool = False,
    materials: Mapping[int, Material] | None = None,
) -> SceneParts:
    """Materials (keyed by the material id of the snapshot: YADE's, then the inline ones), contact model and
    walls of a snapshot. Each material's moduli for the split are the law's reading of it
    (:meth:`~demsplit.physics.laws._yade.YadeLaw.split_moduli`) unless ``materials`` (``--material``) gives
    them; a material the law gives none for is refused when a contact touches it. With ``plane_as_plane`` a
    law that stores its normal stiffness rebuilds it from the materials and the radii instead (its
    ``normal_stiffness`` parameter)."""
    laws = [f["class"] for f in meta["functors"]["law"]]
    known = [law for law in laws if law in LAW_MODELS]
    if len(known) != 1 or len(laws) != 1:
        raise UnsupportedModelError(
            f"the InteractionLoop has Law2 functor(s) {laws}; demsplit reads runs with exactly one of "
            f"{sorted(LAW_MODELS)}.",
            file=path,
            step=step,
            fix=f"use {' or '.join(sorted(LAW_MODELS))}.",
        )
    model = LAW_MODELS[known[0]]
    attrs = meta["functors"]["law"][0].get("attrs", {})
    given = {name: attrs[attr] for attr, name in model.contact_law.simulator_parameters.items() if attr in attrs}
    if given:  # the functor's own settings (Mindlin's includeAdhesion, ...)
        model = ContactModel(model.law, {**model.params, **given})
    law = model.contact_law
    scene_materials, unusable, notes = _split_materials(meta, law, materials or {}, path=path, step=step)
    kinds = _text(bodies["kind"])
    walls = []
    for row in np.flatnonzero(np.isin(kinds, list(WALL_KINDS))):
        kind = WALL_KINDS[kinds[row]]
        axis = int(bodies["wall_axis"][row]) if kind == "yade_wall" else 2
        if axis not in (0, 1, 2):
            raise InputFormatError(
                f"body {int(bodies['id'][row])} is a wall along axis {axis}, not 0, 1 or 2.",
                file=path,
                step=step,
                fix=FIX_DAMAGED,
            )
        pos = (bodies["x"][row], bodies["y"][row], bodies["z"][row])[axis]
        walls.append(
            Wall(
                name=f"body {int(bodies['id'][row])} ({kind})",
                kind=kind,
                type=int(bodies["material"][row]),
                axis=axis,
                position=float(pos),
            )
        )
    if plane_as_plane and "normal_stiffness" in law.parameters:
        model = ContactModel(model.law, {**model.params, "normal_stiffness": "materials"})
    elif plane_as_plane and "kno" in law.contact_columns:
        raise UnsupportedModelError(
            f"--plane-as-plane rebuilds a plane contact's Hertz stiffness from the materials, but "
            f"{known[0]} reads the stiffness kno that YADE stored for each interaction, which YADE computed "
            "with the plane as a sphere of the particle's radius; this law cannot take the plane as a plane.",
            file=path,
            step=step,
            fix="run without --plane-as-plane: the plane contacts are then analysed as YADE computed them "
            "(a sphere of the particle's radius).",
        )
    scene = Scene(
        materials=scene_materials,
        model=model,
        walls=walls,
        source=f"{path} (YADE {meta.get('yade_version', '?')}, {meta.get('precision_name', '?')})",
    )
    return SceneParts(scene, unusable, notes)


def _split_materials(
    meta: dict, law, given: Mapping[int, Material], *, path: Path, step: int | None
) -> tuple[dict[int, Material], dict[int, str], list[str]]:
    """The split's moduli of every material of the snapshot: given (``--material``), else the law's reading
    of it; the materials the law gives none for, with why; a note on the law's reading when it is not the
    materials' own (E, nu)."""
    ids = {int(m["id"]) for m in meta["materials"]}
    unknown = sorted(set(given) - ids)
    if unknown:
        raise MaterialError(
            f"--material names material id(s) {unknown}, which the run does not have (it has {sorted(ids)}).",
            file=path,
            step=step,
            fix="give the ids 'demsplit info' lists for the run's materials.",
        )
    materials, unusable, read = {}, {}, False
    for m in meta["materials"]:
        t, name = int(m["id"]), str(m.get("label") or "")
        if not all(
            isinstance(m.get(a, 0.0), (int, float)) and not isinstance(m.get(a), bool) for a in ("young", "poisson")
        ):
            raise MaterialError(
                f"YADE material {t}: young {excerpt(repr(m.get('young')))} and poisson "
                f"{excerpt(repr(m.get('poisson')))} are not both finite numbers.",
                file=path,
                step=step,
                fix=FIX_DAMAGED,
            )
        if t in given:
            materials[t] = Material(given[t].E, given[t].nu, name=name or given[t].name)
            continue
        moduli = law.split_moduli(m, meta["functors"].get("phys", []))
        what = f"YADE material {t} ({name or m.get('class', '?')})"
        if isinstance(moduli, str):
            unusable[t] = f"{what}: {moduli}"
            continue
        try:
            materials[t] = Material(*moduli, name=name)
        except MaterialError as err:
            unusable[t] = f"{what}: {err.message}"
            continue
        read = True
    note = law.moduli_note() if read else None
    return materials, unusable, [note] if note else []


def _cell_box(hsize: np.ndarray | None) -> Box | None:
    """The periodic cell of column vectors ``hsize`` as a Box (origin 0, LAMMPS tilt from an upper-triangular
    hSize); None for a run that is not periodic."""
    if hsize is None:
        return None
    return Box(
        lo=np.zeros(3),
        hi=np.diag(hsize).copy(),
        periodic=(True, True, True),
        tilt=np.array([hsize[0, 1], hsize[0, 2], hsize[1, 2]]),
    )


def _matrix(value) -> np.ndarray:
    return np.asarray(value, dtype=np.float64).reshape(3, 3)


CAPILLARY_ENGINE = "Law2_ScGeom_CapillaryPhys_Capillarity"


def _capillary_note(meta: dict, inter: Table, path: Path, step: int) -> str | None:
    """What the capillary law adds: nothing to say without it; a note when every capillary force is 0
    (YADE found no capillary tables M(r=1)...M(r=10) in its working directory, and Debian ships none);
    an error when there are capillary forces, whose work (an integral over the meniscus tables) the
    snapshot does not hold, or when the snapshot does not hold them at all."""
    if CAPILLARY_ENGINE not in [e["class"] for e in meta["engines"]]:
        return None
    if "fcapx" not in inter:
        raise UnsupportedModelError(
            f"the run has {CAPILLARY_ENGINE}, but the snapshot holds no capillary forces (fCap), so demsplit "
            "cannot tell whether the bridges hold energy.",
            file=path,
            step=step,
            fix="write the snapshot again with this demsplit (demsplit.yade.snapshot exports fCap).",
        )
    if np.any(np.nan_to_num(magnitude(inter, "fcap")) > 0):
        raise UnsupportedModelError(
            f"the run has {CAPILLARY_ENGINE} with nonzero capillary forces; their work (the cohesion energy "
            "u_adh) needs YADE's meniscus tables, which demsplit does not read.",
            file=path,
            step=step,
            fix="leave the capillary bridges out of this analysis, or analyse a run without them.",
        )
    return (
        f"{CAPILLARY_ENGINE} is in the engines but every capillary force is 0: YADE found no capillary "
        "tables (M(r=1) ... M(r=10)) in its working directory (Debian ships none), so the bridges add no "
        "force and no energy"
    )


INSTANT_TOLERANCE = 1e-6
"""The largest distance (relative to the sphere's radius) of a sphere's centre from the line through YADE's
contact point along its normal at which an overlap is still taken from the positions (:func:`_line_residual`):
at the positions the geometry was computed from it is rounding (1e-16 |x|/R), one step off it is v dt/R."""


def _line_residual(
    pos: np.ndarray, inter: Table, sphere1: np.ndarray, shift: np.ndarray, ra: np.ndarray, rb: np.ndarray
) -> np.ndarray:
    """|(x - cp) x n| / R per interaction: how far the centre x of a sphere of it (body 2 at pos + hSize.cellDist)
    lies from the line through YADE's contact point cp along its normal n, relative to its radius R, the larger
    of the two spheres' of a pair. Every Ig2 functor puts the spheres' centres on that line (Sphere-Sphere:
    cp = x1 + (r1 - delta/2) n, x2 + shift = x1 + |x2 + shift - x1| n; Facet and Box: cp = x2 - (R - delta/2) n;
    Wall: cp is x2 projected onto the wall), so it is 0, up to rounding, at the positions and the periodic cell
    the geometry was computed from."""
    n = np.stack([inter["nx"], inter["ny"], inter["nz"]], axis=-1)
    cp = np.stack([inter["cpx"], inter["cpy"], inter["cpz"]], axis=-1)
    second = np.linalg.norm(np.cross(pos[rb] + shift - cp, n), axis=1) / inter["refR2"]
    first = np.linalg.norm(np.cross(pos[ra] - cp, n), axis=1) / inter["refR1"]
    return np.where(sphere1, np.maximum(first, second), second)


def _step_move(bodies: Table, pos: np.ndarray, dt: float, rows) -> np.ndarray:
    """How far NewtonIntegrator moved each body in its last step: v dt (it moves a body by its velocity after
    the step's update, which YADE saves); a clump member along its clump's rotation, x_m - (X_c - V_c dt +
    Rot(-w_c dt)(x_m - X_c)) with the clump's centre X_c, velocity V_c and angular velocity w_c (Clump::moveMembers
    places the members from the clump), exact to the rotation's second order. ``rows``: body ids -> rows."""
    move = np.stack([bodies["vx"], bodies["vy"], bodies["vz"]], axis=-1) * dt
    members = np.flatnonzero((bodies["clump"] >= 0) & (_text(bodies["kind"]) == "sphere"))
    if "wx" not in bodies or not len(members):
        return move
    c = rows(bodies["clump"][members], "clumpId")
    r = pos[members] - pos[c]
    w = np.stack([bodies["wx"], bodies["wy"], bodies["wz"]], axis=-1)[c] * -dt  # the rotation to undo
    angle = np.linalg.norm(w, axis=1)
    axis = np.divide(w, angle[:, None], out=np.zeros_like(w), where=angle[:, None] > 0)
    cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
    rotated = (
        r * cos + np.cross(axis, r) * sin + axis * np.einsum("ij,ij->i", axis, r)[:, None] * (1.0 - cos)
    )  # Rodrigues' formula
    move[members] = pos[members] - (pos[c] - move[c] + rotated)
    return move


def _forces_instant(
    meta: dict, inter: Table, pos: np.ndarray, move: np.ndarray, sphere1: np.ndarray, ra: np.ndarray, rb: np.ndarray
) -> tuple[bool, np.ndarray | None, np.ndarray, np.ndarray]:
    """Which positions and periodic cell the saved geometry was computed from: the saved ones, or those one
    NewtonIntegrator step before (``pos - move``, a snapshot or state saved after the integrator moved the
    bodies); the saved cell ``hSize``, or the one a step before, (I + dt velGrad)^-1 hSize (saved after YADE
    moved the cell at the start of the next step, before its InteractionLoop; ``O.load`` loses
    ``prevHSize``). The candidate whose sphere centres lie closest to their contact
    lines (:func:`_line_residual`) wins; ties (bodies at rest) keep the saved ones. Returns (stepped back,
    the cell (None: not periodic), each interaction's shift hSize.cellDist of body 2, the residuals)."""
    cells: list[np.ndarray | None] = [None]
    if meta["periodic"]:
        cells = [_matrix(meta["hSize"])]
        if meta.get("velGrad") is not None and np.any(_matrix(meta["velGrad"])):  # Cell::integrateAndUpdate undone
            cells.append(np.linalg.solve(np.eye(3) + float(meta["dt"]) * _matrix(meta["velGrad"]), cells[0]))
    dist = np.stack([inter["cdx"], inter["cdy"], inter["cdz"]], axis=-1).astype(np.float64)
    best = None
    for stepped in (False, True):
        for h in cells:
            shift = np.zeros((len(ra), 3)) if h is None else dist @ h.T
            r = _line_residual(pos - move if stepped else pos, inter, sphere1, shift, ra, rb)
            score = float(np.sum(r * r))
            if best is None or score < best[0]:
                best = (score, stepped, h, shift, r)
    return best[1], best[2], best[3], best[4]


def _depth_from_geometry(
    pos: np.ndarray,
    inter: Table,
    kind1: np.ndarray,
    sphere1: np.ndarray,
    shift: np.ndarray,
    ra: np.ndarray,
    rb: np.ndarray,
) -> np.ndarray:
    """penetrationDepth (m) as YADE's Ig2 functors compute it from the positions ``pos`` (those the geometry
    was computed from) and the saved contact point and normal: r1 + r2 - |x2 + hSize.cellDist - x1| for two
    spheres (Ig2_Sphere_Sphere_ScGeom); from the sphere's centre x_s along the normal n, R - |(x_s - cp).n| on a
    Wall and 2 (R - (x_s - cp).n) on a Facet or a Box (whose contact point is the midpoint of the overlap)."""
    pair = sphere1 & (kind1 == "sphere")
    gap = np.linalg.norm(pos[rb] + shift - pos[ra], axis=1)
    n = np.stack([inter["nx"], inter["ny"], inter["nz"]], axis=-1)
    cp = np.stack([inter["cpx"], inter["cpy"], inter["cpz"]], axis=-1)
    along = np.einsum("ij,ij->i", pos[rb] + shift - cp, n)  # the sphere is body 2 (YADE's order for a wall)
    radius = inter["refR2"]
    plane = np.where(kind1 == "wall", radius - np.abs(along), 2.0 * (radius - along))
    return np.where(pair, inter["refR1"] + inter["refR2"] - gap, plane)


def _wrapped(x: np.ndarray, hsize: np.ndarray) -> np.ndarray:
    """Positions (n, 3) wrapped into the periodic cell of column vectors ``hsize`` (YADE's ``O.cell.wrap``)."""
    frac = np.linalg.solve(hsize, x.T).T
    return (frac - np.floor(frac)) @ hsize.T


def particle_first(
    t: Table, sphere1: np.ndarray, wall1: np.ndarray, wall2: np.ndarray, attributes: tuple[Phys, ...] = ()
) -> Table:
    """Canonical contacts (:mod:`demsplit.frame`) from interactions in YADE's order.

    ``t`` holds ``id1 id2 delta nx ny nz refR1 refR2``, the centres ``xa ya za``
    of body 1 and ``xb yb zb`` of body 2 in the frame of the normal (body 2
    shifted by hSize.cellDist), and optionally ``type_a type_b``, ``cpx cpy cpz``
    and the columns of the physics' ``attributes`` (:class:`~demsplit.physics.laws._yade.Phys`), which give the
    contact columns the laws read. ``sphere1`` says whether YADE's body 1 is a sphere;
    ``wall1``/``wall2`` give the wall index of each body (-1 for a sphere).

    Where body 1 is a wall, facet or box (YADE's usual order), the particle
    (body 2) becomes body 1: the normal and a vector attribute (a force on YADE's body 2) change sign,
    refR1/refR2 trade places.
    """
    swap = ~np.asarray(sphere1, dtype=bool)
    sign = np.where(swap, -1.0, 1.0)
    pair = (wall1 < 0) & (wall2 < 0)

    def pick(a: str, b: str) -> np.ndarray:
        return np.where(swap, t[b], t[a])

    out = {
        "id1": pick("id1", "id2").astype(np.int64),
        "id2": np.where(pair, t["id2"], -1).astype(np.int64),
        "wall": np.where(pair, -1, np.where(swap, wall1, wall2)).astype(np.int64),
        "delta": np.asarray(t["delta"], dtype=np.float64),
        "nx": sign * t["nx"],
        "ny": sign * t["ny"],
        "nz": sign * t["nz"],
        "x1": pick("xa", "xb"),
        "y1": pick("ya", "yb"),
        "z1": pick("za", "zb"),
        "r1": pick("refR1", "refR2"),
        "r2": pick("refR2", "refR1"),
    }
    if "type_a" in t:
        out["type1"] = pick("type_a", "type_b").astype(np.int32)
        out["type2"] = pick("type_b", "type_a").astype(np.int32)
    for c in ("cpx", "cpy", "cpz"):
        if c in t:
            out[c] = np.asarray(t[c], dtype=np.float64)
    for a in attributes:
        if a.contact is None or not all(c in t and _written(t[c]) for c in a.columns):
            continue
        if a.shape == SCALAR:
            out[a.contact] = np.asarray(t[a.column], dtype=np.float64)
        elif a.shape == VECTOR:
            out.update({a.contact + x: sign * t[a.column + x] for x in "xyz"})
        else:
            out[a.contact] = magnitude(t, a.column)
    return out


def _written(col: np.ndarray) -> bool:
    """Whether the interactions' physics have the attribute of column ``col``: the exporter writes NaN for an
    attribute a phys lacks; a snapshot without interactions says nothing against it (the columns, and so the
    energy modes, of a run do not depend on whether a frame has contacts: a first snapshot without any made
    the later frames' tables another layout, which the store refused)."""
    return len(col) == 0 or bool(np.isfinite(col).any())


def frame_from_snapshot(
    meta: dict,
    tables: dict[str, Table],
    scene_walls: dict[int, int],
    *,
    path: Path,
    law: YadeLaw,
    plane_as_plane: bool = False,
    unusable: Mapping[int, str] | None = None,
) -> tuple[Frame, np.ndarray]:
    """One Frame from one raw snapshot, and the rows of the interactions table
    that became contacts (to align per-interaction extras such as ``depth_text``).

    The frame is of the instant of the interactions' forces: where the saved positions are one
    NewtonIntegrator step after it (a snapshot or a state saved after the integrator moved the bodies), they
    are stepped back by v dt (:func:`_line_residual` tells which). A state loaded with ``O.load`` has no
    penetrationDepth: the law gives it from its stored physics (:meth:`YadeLaw.depth_from_phys`), the
    geometry at that instant where it does not (:func:`_depth_from_geometry`). ``law``: the scene's law;
    ``unusable``: the materials the split has no moduli for (type -> why), refused when a contact touches one.
    """
    step = int(meta["iter"])
    bodies, inter = tables["bodies"], tables["interactions"]
    kinds = _text(bodies["kind"])
    ids = bodies["id"]
    order = np.argsort(ids, kind="stable")  # ids present, sorted: memory by the bodies, not the largest id
    sorted_ids = ids[order]
    periodic = bool(meta["periodic"])

    def rows(body_ids: np.ndarray, which: str) -> np.ndarray:
        at = np.clip(np.searchsorted(sorted_ids, body_ids), 0, max(len(ids) - 1, 0))
        r = np.where(sorted_ids[at] == body_ids, order[at], -1) if len(ids) else np.full(len(body_ids), -1)
        if (r < 0).any():
            bad = int(body_ids[r < 0][0])
            raise ContactError(
                f"interaction names body {bad} ({which}), which is not in the bodies table.",
                file=path,
                step=step,
                fix="rewrite the snapshot (the file is inconsistent).",
            )
        return r

    ra, rb = rows(inter["id1"], "id1"), rows(inter["id2"], "id2")
    sa, sb = kinds[ra] == "sphere", kinds[rb] == "sphere"
    bad = ~(sa | sb) | np.isin(kinds[ra], ["other", "clump"]) | np.isin(kinds[rb], ["other", "clump"])
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise UnsupportedModelError(
            f"{int(bad.sum())} interaction(s) involve no sphere or an unsupported shape, e.g. bodies "
            f"{int(inter['id1'][i])} ({bodies['shape_class'][ra[i]].decode()}) and "
            f"{int(inter['id2'][i])} ({bodies['shape_class'][rb[i]].decode()}).",
            file=path,
            step=step,
            fix="demsplit reads sphere-sphere, sphere-Wall, sphere-Facet and sphere-Box contacts.",
        )

    pos = np.stack([bodies["x"], bodies["y"], bodies["z"]], axis=-1)
    move = _step_move(bodies, pos, float(meta.get("dt", 0.0)), rows)
    stepped, hsize, shift, residual = _forces_instant(meta, inter, pos, move, sa, ra, rb)
    notes = [f"YADE {meta.get('yade_version', '?')} {meta.get('precision_name', '?')}"]
    if stepped:
        pos = pos - move
        notes.append(
            "the positions were saved one NewtonIntegrator step after the forces: stepped back by v dt "
            "to the forces' instant"
        )
    if periodic and hsize is not None and not np.array_equal(hsize, _matrix(meta["hSize"])):
        notes.append(
            "the periodic cell was saved one step after the forces (before the InteractionLoop): "
            "stepped back by velGrad dt to the forces' instant"
        )
    if len(residual) and residual.max() > INSTANT_TOLERANCE:
        notes.append(
            f"the positions match the contact geometry to {residual.max():.2g} of a radius only "
            "(at neither the forces' instant nor one step after it): particle centres and contact "
            "points are that far off"
        )
    depth = inter["depth"]
    overlap_source = "YADE penetrationDepth (double)"
    if meta.get("loaded_state"):  # YADE does not save penetrationDepth
        depth = law.depth_from_phys(inter)
        geometric = np.isnan(depth)
        overlap_source = f"from the forces and stiffnesses {law.key} stored (YADE does not save penetrationDepth)"
        if geometric.any():
            off = residual[geometric].max()
            if off > INSTANT_TOLERANCE:
                raise ContactError(
                    f"{int(geometric.sum())} interaction(s) of {law.key} hold no force or stiffness that gives "
                    "their overlap, and the saved positions are of neither the instant of the forces nor one "
                    f"integrator step after it (the sphere centres lie up to {off:.2g} of a radius off their "
                    "contact lines), so their overlap cannot be recovered.",
                    file=path,
                    step=step,
                    fix="save the state from a PyRunner between the InteractionLoop and the NewtonIntegrator, "
                    "or write demsplit.yade.snapshot() there (docs/yade.md).",
                )
            depth = np.where(geometric, _depth_from_geometry(pos, inter, kinds[ra], sa, shift, ra, rb), depth)
            overlap_source += f"; {int(geometric.sum())} from the geometry at the forces' instant"
    sphere = kinds == "sphere"
    if not periodic:
        x = pos
    elif stepped or not np.array_equal(hsize, _matrix(meta["hSize"])):  # in the cell (YADE's O.cell.wrap)
        x = _wrapped(pos, hsize)
    else:
        x = np.stack([bodies["xw"], bodies["yw"], bodies["zw"]], axis=-1)
    particles = {
        "id": ids[sphere].astype(np.int64),
        "type": bodies["material"][sphere].astype(np.int32),
        "x": x[sphere, 0],
        "y": x[sphere, 1],
        "z": x[sphere, 2],
        "radius": bodies["radius"][sphere],
        "mass": bodies["mass"][sphere],
        "vx": bodies["vx"][sphere],
        "vy": bodies["vy"][sphere],
        "vz": bodies["vz"][sphere],
        "clump": bodies["clump"][sphere].astype(np.int64),
    }
    xa, xb = pos[ra], pos[rb] + shift

    wall_of_row = np.full(len(ids), -1, dtype=np.int64)  # wall index of each body row (-1: not a wall)
    for body_id, index in scene_walls.items():
        wall_of_row[rows(np.array([body_id]), "wall")] = index
    yade_order = {
        **inter,
        "delta": depth,
        "xa": xa[:, 0],
        "ya": xa[:, 1],
        "za": xa[:, 2],
        "xb": xb[:, 0],
        "yb": xb[:, 1],
        "zb": xb[:, 2],
        "type_a": bodies["material"][ra],
        "type_b": bodies["material"][rb],
    }
    contacts = particle_first(yade_order, sa, wall_of_row[ra], wall_of_row[rb], law.phys)
    pair = sa & sb
    if plane_as_plane:
        contacts["r2"] = np.where(pair, contacts["r2"], np.inf)
        contacts.pop("kno", None)

    n_virtual = int(meta["n_interactions_potential"]) - int(meta["n_interactions_real"])
    if n_virtual:
        notes.append(f"{n_virtual} potential (non-real) interaction(s) not in the contacts table")
    # a NaN depth is kept, for the validation to name it; a cohesive bond holds energy in tension
    keep = np.ones(len(depth), bool) if law.normal_from_stored_force else ~(depth < 0)
    if not keep.all():
        notes.append(
            f"{int((~keep).sum())} real interaction(s) with penetrationDepth < 0 (neverErase) "
            "left out of the contacts table: they carry no elastic energy"
        )
        contacts = {c: v[keep] for c, v in contacts.items()}
    _refuse_unusable(contacts, unusable or {}, path=path, step=step)
    capillary = _capillary_note(meta, inter, path, step)
    if capillary:
        notes.append(capillary)
    frame = Frame(
        step=step,
        particles=particles,
        contacts=contacts,
        box=_cell_box(hsize),
        time=float(meta["time"]),
        source=(str(path),),
        overlap_source=overlap_source,
        overlap_error=None,
        notes=notes,
    )
    return frame, np.flatnonzero(keep)


def _refuse_unusable(contacts: Table, unusable: Mapping[int, str], *, path: Path, step: int) -> None:
    """The MaterialError of the first material the split has no moduli for that a contact touches."""
    if not unusable:
        return
    touched = np.isin(contacts["type1"], list(unusable)) | np.isin(contacts["type2"], list(unusable))
    if touched.any():
        t = (
            int(contacts["type1"][touched][0])
            if contacts["type1"][touched][0] in unusable
            else int(contacts["type2"][touched][0])
        )
        raise MaterialError(
            f"{unusable[t]}; {int(touched.sum())} contact(s) need its moduli for the split.",
            file=path,
            step=step,
            fix=f"give the split's moduli of material {t} with --material {t}:E:NU (Pa, -).",
        )


class YadeSnapshotRun(Run):
    """A snapshot file opened for reading: ``.scene``, ``len(run)``,
    ``run.meta(k)`` (the snapshot's metadata: ``energy``, ``law_energies``,
    functors, ...) and iteration over Frames, one snapshot at a time.

    A snapshot that was cut short raises :class:`TruncatedFileError` when the
    iteration reaches it (the complete ones before it are yielded).
    """

    format_name = "yade-snapshot"
    formats = ("a YADE snapshot file written by demsplit.yade.snapshot() (HDF5 or npy stream)",)
    cli_group = "YADE inputs"
    cli_options = (PLANE_AS_PLANE, MATERIALS)

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is not None and (head.startswith(HDF5_SIGNATURE) or head.startswith(NPY_STREAM_MAGIC))

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """Snapshots, iterations, bodies and interactions, the law, materials, walls and functors."""
        with cls(path) as run:
            scene = run.scene
            meta0 = run.meta(0)
            lines = [
                f"{path}: demsplit.yade snapshot file",
                f"  snapshots: {len(run)}",
                f"  YADE {meta0.get('yade_version')}, {meta0.get('precision_name')}, periodic {meta0.get('periodic')}",
                f"  model:    {scene.model.describe()}",
                "  materials: " + material_list(run),
                "  walls:    " + (", ".join(f"{w.name} ({w.kind}, type {w.type})" for w in scene.walls) or "none"),
                "  iteration   time (s)       bodies  interactions (real)",
            ]
            for k in range(len(run)):
                try:
                    meta = run.meta(k)
                    frame = run.frame(k)
                except DemsplitError as exc:
                    lines.append(f"  snapshot {k}: {exc}")
                    continue
                lines.append(
                    f"  {meta['iter']:>9}   {meta.get('time', float('nan')):<13.6g}  "
                    f"{frame.n_particles + len(scene.walls):>6}  {frame.n_contacts:>12}"
                )
            functors = meta0.get("functors")
            if isinstance(functors, dict):
                for kind, items in functors.items():
                    lines.append(f"  functors {kind}: " + ", ".join(i.get("class", "?") for i in items))
        return "\n".join(lines)

    def __init__(
        self, path: str | Path, *, plane_as_plane: bool = False, materials: Mapping[int, Material] | None = None
    ) -> None:
        self.path = Path(path)
        self.plane_as_plane = plane_as_plane
        self._store = _open_store(self.path)
        if len(self._store) == 0:
            raise InputFormatError(
                "the snapshot file holds no snapshot.",
                file=self.path,
                fix="run the simulation until the snapshot PyRunner has fired.",
            )
        meta, tables = self.read(0)
        if int(meta.get("format_version", 0)) > FORMAT_VERSION:
            raise InputFormatError(
                f"snapshot format version {meta['format_version']} is newer than this reader ({FORMAT_VERSION}).",
                file=self.path,
                fix="update demsplit.",
            )
        parts = scene_from_snapshot(
            meta,
            tables["bodies"],
            path=self.path,
            step=int(meta["iter"]),
            plane_as_plane=plane_as_plane,
            materials=materials,
        )
        self.scene, self._unusable, self.notes = parts.scene, parts.unusable, parts.notes
        self.sources = [self.path]
        complete = [k for k in range(len(self._store)) if not self._store.problem(k)]
        if complete != list(range(len(complete))):
            raise InputFormatError(
                f"snapshot {len(complete)} is incomplete, but a later one is complete: the file "
                "is damaged (only the last snapshot can be cut short).",
                file=self.path,
                fix=FIX_DAMAGED,
            )
        metas = [self.meta(k) for k in complete]
        self.steps = np.array([m["iter"] for m in metas], dtype=np.int64)
        self.yade_energies = [e for m in metas for e in yade_energies(m, self.scene.model.contact_law)]
        first: dict[int, int] = {}
        for k, step in enumerate(self.steps.tolist()):
            if step in first:
                raise InputFormatError(
                    f"iteration {step} is in the file twice (snapshots {first[step]} and {k}).",
                    file=self.path,
                    step=step,
                    fix="write each iteration once (a restarted run appends to a new file).",
                )
            first[step] = k
        kinds = _text(tables["bodies"]["kind"])
        wall_ids = tables["bodies"]["id"][np.isin(kinds, list(WALL_KINDS))]
        self._walls = {int(b): k for k, b in enumerate(wall_ids)}
        self._wall_ids = wall_ids

    def __len__(self) -> int:
        return len(self._store)

    def _check(self, k: int) -> None:
        problem = self._store.problem(k)
        if problem:
            step = self.meta(k - 1)["iter"] if k > 0 else None
            raise TruncatedFileError(
                f"{problem}; it is not read. {k} complete snapshot(s) precede it"
                + (f" (the last at iteration {step})." if step is not None else "."),
                file=self.path,
                fix="rerun or resume the simulation to rewrite the snapshot file; "
                "the complete snapshots before it are read normally.",
            )

    def read(self, k: int) -> RawSnapshot:
        """Snapshot ``k`` as checked metadata and typed tables (:func:`checked_meta`, :func:`checked_tables`)."""
        self._check(k)
        meta, tables = self._store.snapshot(k)
        meta = checked_meta(meta, path=self.path, k=k)
        return meta, checked_tables(tables, meta, path=self.path, k=k)

    def meta(self, k: int) -> dict:
        """Metadata of snapshot ``k`` without reading its tables."""
        self._check(k)
        return checked_meta(self._store.meta(k), path=self.path, k=k)

    def frame(self, k: int) -> Frame:
        return self._frame(*self.read(k))[0]

    def _frame(self, meta: dict, tables: dict[str, Table]) -> tuple[Frame, np.ndarray]:
        ids = tables["bodies"]["id"][np.isin(_text(tables["bodies"]["kind"]), list(WALL_KINDS))]
        if not np.array_equal(ids, self._wall_ids):
            raise InputFormatError(
                f"the walls/facets/boxes changed (body ids {self._wall_ids.tolist()} in the first snapshot, "
                f"{ids.tolist()} here).",
                file=self.path,
                step=int(meta["iter"]),
                fix="write snapshots of runs whose non-sphere bodies stay the same to one file each.",
            )
        return frame_from_snapshot(
            meta,
            tables,
            self._walls,
            path=self.path,
            law=self.scene.model.contact_law,
            plane_as_plane=self.plane_as_plane,
            unusable=self._unusable,
        )

    def depth_text(self, k: int) -> np.ndarray | None:
        """penetrationDepth of the contacts of frame ``k`` as decimal strings at
        the build's full precision (high-precision builds only, else None)."""
        meta, tables = self.read(k)
        if "depth_text" not in tables["interactions"]:
            return None
        _, rows = self._frame(meta, tables)
        return _text(tables["interactions"]["depth_text"][rows])

    def materials_without_moduli(self) -> dict[int, str]:
        """The materials the split has no moduli for (id -> why): refused when a contact touches one."""
        return dict(self._unusable)

    def describe(self) -> dict:
        """The file, and YADE's own elastic energies of each snapshot (:func:`yade_energies`)."""
        return {
            "kind": self.format_name,
            "path": str(self.path),
            "plane_as_plane": self.plane_as_plane,
            "yade_energies": self.yade_energies,
        }

    def close(self) -> None:
        self._store.close()


def material_list(run: YadeSnapshotRun) -> str:
    """Every material id of a run with its split moduli, or why it has none (for ``info``)."""
    items = {
        t: f"{t}: E={m.E:g} Pa nu={m.nu:g}" + (f" ({m.name})" if m.name else "") for t, m in run.scene.materials.items()
    }
    items.update(
        {
            t: f"{t}: no moduli for the split ({why}; --material {t}:E:NU)"
            for t, why in run.materials_without_moduli().items()
        }
    )
    return ", ".join(items[t] for t in sorted(items))


def yade_energies(meta: dict, law: YadeLaw) -> list[dict]:
    """YADE's own elastic energies (J) of a snapshot's instant, as the report prints them beside demsplit's:
    the law's energy functions the snapshot recorded (``law_energies``; a state loaded with ``O.load`` has none)
    and, when the run tracks ``O.energy``, the entries the law fills there (``tracked_energies``). Each:
    ``{"step", "name", "value", "modes"}``, ``modes`` the demsplit energy columns whose sum it is."""
    out = []
    for name, (method, modes) in law.simulator_energies.items():
        if name in meta.get("law_energies", {}):
            out.append(
                {
                    "step": int(meta["iter"]),
                    "name": f"{method}()",
                    "value": meta["law_energies"][name],
                    "modes": list(modes),
                }
            )
    if meta.get("track_energy"):
        for name, modes in law.tracked_energies.items():
            if name in meta.get("energy", {}):
                out.append(
                    {
                        "step": int(meta["iter"]),
                        "name": f"O.energy['{name}']",
                        "value": meta["energy"][name],
                        "modes": list(modes),
                    }
                )
    return out


def open_yade_snapshot(
    path: str | Path, *, plane_as_plane: bool = False, materials: Mapping[int, Material] | None = None
) -> YadeSnapshotRun:
    """Open a file written by :func:`demsplit.yade.snapshot` (HDF5 or npy stream).

    plane_as_plane
        False (default): ``r1 r2`` are YADE's refR1/refR2 and ``kno`` is kept,
        so the energy is the one YADE's forces imply (a Wall or Box acts as a
        sphere of the particle's radius, a Facet as one of twice it). True:
        ``r2 = inf`` for walls, facets and boxes and ``kno`` is dropped, so
        Hertz is recomputed for a sphere on a plane (not what YADE computed).
    materials
        the split's moduli by material id, instead of the law's reading of YADE's materials (``--material``).
    """
    return YadeSnapshotRun(path, plane_as_plane=plane_as_plane, materials=materials)
