"""Results as VTK files for ParaView (and any VTK reader): one file per frame and a ``.pvd`` series of each.

:func:`export_vtk` writes, for every frame of a result set,

- ``particles_<step>.vtu``: the particles as points at their centres, with every per-particle column (id,
  type, radius, the energy of every mode, ``u``, the comparison splits, ``n_contacts``);
- ``contacts_<step>.vtu`` (when the store has the per-contact table): each contact as a line cell between
  the two bodies, from the centre of particle ``id1`` to the centre of ``id2`` (its nearest periodic image,
  with the frame's box), or to the contact point for a wall contact, with the contact's columns as cell
  data (ids, wall, overlap, the energy of every mode, ``u`` = u1 + u2, shares, ``u1 u2 depth1``, the contact
  point ``cpx cpy cpz``): the force-chain picture. The store keeps no contact force, so none is written;
- ``walls_<step>.vtu``: each wall as triangles (:mod:`demsplit.results.exports.walls`: mesh walls from their
  STL file, primitive planes clipped to the box, cylinders as surfaces, YADE's axis-aligned walls) with the
  wall's energies of that frame as cell data (``wall u u_n u_t n_contacts ...``); a wall the store has no
  geometry of (a YADE facet or box) is left out, and said (``not_drawn``);

plus ``particles.pvd``, ``contacts.pvd`` and ``walls.pvd``: ParaView opens a ``.pvd`` as one time series.
Units are SI (m, J): every array carries its unit as VTK's ``UNITS_LABEL`` information key (VTK's XML
``<InformationKey name="UNITS_LABEL">``, which VTK's reader gives back as
``array.GetInformation().Get(vtkDataArray.UNITS_LABEL())``; ``1``: a count or a ratio), not as a string array,
which meshio cannot read. A value that was not computed (the row's ``not_computed`` bits, which are written too)
is NaN, never the store's 0. Where types have material names (YADE's material labels, ``demsplit run
--type-name``), the field data carries them as two parallel arrays, ``type_id`` (integers) and ``material``
(strings; VTK's reader reads them, meshio does not). The files are VTK XML unstructured grids written by
meshio: pure Python and a small fraction of VTK's size (docs/performance.md, "Standing decisions").
"""

from __future__ import annotations

import re
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pandas as pd

from ...errors import StoreError
from ...outputs import OutputFolder
from ..schema import UNITS
from ..tables import Results
from .walls import mesh_extent, wall_triangles

SERIES = ("particles", "contacts", "walls")
"""The series written, in order: one ``.vtu`` per frame and one ``.pvd`` each."""

BOX = tuple(f"box_{axis}{end}" for end in ("lo", "hi") for axis in "xyz")
"""The frames table's simulation box columns: lo x y z, then hi x y z (m)."""

EXTRA_UNITS = {"u": "J"}
"""Units of the arrays the export derives (the contacts' elastic total ``u`` = u1 + u2)."""


def export_vtk(
    results: Results,
    directory: str | Path,
    inputs: Iterable[str | Path] = (),
    *,
    overwrite: bool = False,
    progress: bool | None = None,
    not_drawn: list[str] | None = None,
) -> list[Path]:
    """Write the VTK series of ``results`` into ``directory`` (module docstring); return the files written.
    The files are written together, all or none, into a new or empty folder or over an earlier VTK export,
    whose series is replaced whole; never over one of ``inputs`` (:class:`demsplit.outputs.OutputFolder`;
    ``overwrite``: into a folder holding other files too). ``progress``: a bar on stderr (None: when it is a
    terminal); ``not_drawn``: filled with the walls left out of the walls series, and why, once each."""
    try:
        import meshio
    except ImportError:
        raise StoreError(
            "the VTK export needs meshio, which is not installed.", fix="pip install 'demsplit[vtk]'."
        ) from None
    from tqdm import tqdm

    steps = [int(s) for s in results.steps]
    walls = list((results.provenance.get("scene") or {}).get("walls") or [])
    series = [
        name
        for name in SERIES
        if name == "particles" or (name == "contacts" and not results.contacts.empty) or (name == "walls" and walls)
    ]
    plan = {name: [(step, f"{name}_{step:012d}.vtu") for step in steps] for name in series}
    files = [f for name, frames in plan.items() for f in [*dict(frames).values(), f"{name}.pvd"]]
    folder = OutputFolder(directory, files, inputs, kind="vtk", overwrite=overwrite)
    names = _material_field_data(results.type_names())
    by_step = {
        name: dict(tuple(getattr(results, name).groupby("step", sort=False)))
        for name in ("particles", "contacts", "walls")
    }
    frames = results.frames.set_index("step")
    meshes: dict[str, np.ndarray] = {}
    extent = mesh_extent(walls, meshes)
    written = []
    with folder:
        show = sys.stderr.isatty() if progress is None else progress
        for step in tqdm(steps, unit="frame", desc="demsplit export --vtk", disable=not show):
            tables = {name: by_step[name].get(step, _empty(getattr(results, name))) for name in by_step}
            box = _box(frames.loc[step] if step in frames.index else None, tables["particles"], extent)
            for name in series:
                if name == "particles":
                    points, cells, data, where, left_out = _particles(tables["particles"])
                elif name == "contacts":
                    points, cells, data, where, left_out = _contacts(tables["contacts"], tables["particles"], box, step)
                else:
                    points, cells, data, where, left_out = _walls(tables["walls"], walls, box, meshes)
                if not_drawn is not None:
                    not_drawn += [wall for wall in left_out if wall not in not_drawn]
                mesh = meshio.Mesh(
                    points, cells, **{f"{where}_data": data if where == "point" else {c: [v] for c, v in data.items()}}
                )
                written.append(
                    folder.write(
                        dict(plan[name])[step], lambda tmp, m=mesh, d=data: _write_vtu(meshio, tmp, m, d, names)
                    )
                )
        for name in series:
            rows = "\n".join(
                f'    <DataSet timestep="{step}" part="0" file={quoteattr(file)}/>' for step, file in plan[name]
            )
            text = (
                '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
                f"{rows}\n  </Collection>\n</VTKFile>\n"
            )
            written.append(folder.write(f"{name}.pvd", lambda tmp, t=text: tmp.write_text(t)))
    return written


def _write_vtu(meshio, tmp: Path, mesh, data: Mapping[str, np.ndarray], names: bytes) -> None:
    """One frame's ``.vtu`` at ``tmp``: meshio's file with each array's unit and the material names' field data."""
    meshio.write(tmp, mesh, file_format="vtu", binary=True, compression=None)
    text = _with_units(tmp.read_bytes(), data)
    if names:
        grid = b"<UnstructuredGrid>"
        text = text.replace(grid, grid + b"<FieldData>" + names + b"</FieldData>", 1)
    tmp.write_bytes(text)


def _empty(table: pd.DataFrame) -> pd.DataFrame:
    return table.iloc[:0]


def _box(
    frame: pd.Series | None, particles: pd.DataFrame, extent: tuple[np.ndarray, np.ndarray] | None
) -> tuple[np.ndarray, np.ndarray]:
    """The frame's simulation box (m), else the extent of its particles (centre +- radius) and the mesh walls."""
    if frame is not None and all(c in frame.index for c in BOX):
        values = frame[list(BOX)].to_numpy(dtype=np.float64)
        return values[:3], values[3:]
    boxes = [extent] if extent is not None else []
    if len(particles):
        xyz = particles[["x", "y", "z"]].to_numpy(dtype=np.float64)
        r = particles["radius"].to_numpy(dtype=np.float64)[:, None]
        boxes.append(((xyz - r).min(axis=0), (xyz + r).max(axis=0)))
    if not boxes:
        return np.zeros(3), np.zeros(3)
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def _columns(table: pd.DataFrame, leave: Iterable[str]) -> dict[str, np.ndarray]:
    return {c: table[c].to_numpy() for c in table.columns if c not in (*leave, "step")}


def _particles(particles: pd.DataFrame):
    """Points at the particle centres, every per-particle column as point data."""
    points = particles[["x", "y", "z"]].to_numpy(dtype=np.float64)
    return (
        points,
        [("vertex", np.arange(len(points)).reshape(-1, 1))],
        _columns(particles, ("x", "y", "z")),
        "point",
        [],
    )


def _contacts(contacts: pd.DataFrame, particles: pd.DataFrame, box: tuple[np.ndarray, np.ndarray], step: int):
    """A line cell per contact between its two bodies (module docstring), the contact's columns as cell data."""
    ids = pd.Index(particles["id"].to_numpy())
    xyz = particles[["x", "y", "z"]].to_numpy(dtype=np.float64)
    rows1 = ids.get_indexer(contacts["id1"].to_numpy())
    pair = contacts["wall"].to_numpy() < 0
    rows2 = np.where(pair, ids.get_indexer(contacts["id2"].to_numpy()), 0)
    if (rows1 < 0).any() or (rows2 < 0).any():
        raise StoreError(
            "a contact names a particle that the frame's particle table does not hold.",
            step=step,
            fix="the store is inconsistent: run demsplit run again to rewrite it.",
        )
    start = xyz[rows1]
    end = contacts[["cpx", "cpy", "cpz"]].to_numpy(dtype=np.float64).copy()
    d = xyz[rows2[pair]] - start[pair]
    length = box[1] - box[0]
    across = (np.abs(d) > length / 2) & (length > 0)  # a contact across a periodic boundary: the nearest image
    d = d - np.where(across, np.sign(d) * length, 0.0)
    end[pair] = start[pair] + d
    points = np.empty((2 * len(contacts), 3))
    points[0::2], points[1::2] = start, end
    data = _columns(contacts, ())
    data["u"] = contacts["u1"].to_numpy() + contacts["u2"].to_numpy()
    return points, [("line", np.arange(len(points)).reshape(-1, 2))], data, "cell", []


def _walls(rows: pd.DataFrame, walls: list[Mapping], box: tuple[np.ndarray, np.ndarray], meshes: dict[str, np.ndarray]):
    """Triangles of the walls that have a row in this frame, each triangle with its wall's row as cell data;
    the names of the walls left out and why."""
    parts, data_rows, not_drawn = [], [], []
    for k, row in rows.reset_index(drop=True).iterrows():
        wall = walls[int(row["wall"])] if 0 <= int(row["wall"]) < len(walls) else {}
        triangles, why = wall_triangles(wall, *box, meshes)
        if triangles is None:
            not_drawn.append(f"{wall.get('name', row['wall'])}: {why}")
            continue
        parts.append(triangles)
        data_rows.append(np.full(len(triangles), k))
    points = np.concatenate(parts).reshape(-1, 3) if parts else np.zeros((0, 3))
    take = np.concatenate(data_rows) if data_rows else np.zeros(0, dtype=np.int64)
    data = {c: v[take] for c, v in _columns(rows.reset_index(drop=True), ()).items()}
    return points, [("triangle", np.arange(len(points)).reshape(-1, 3))], data, "cell", not_drawn


def _strings(name: str, values: list[str]) -> bytes:
    """A VTK XML string array, ASCII format (a string is its characters' codes ended by 0, as VTK's own XML
    writer writes it)."""
    codes = " ".join(" ".join(str(b) for b in v.encode("utf-8")) + " 0" for v in values)
    return (
        f'<Array type="String" Name={quoteattr(name)} NumberOfTuples="{len(values)}" format="ascii">{codes}</Array>'
    ).encode("ascii")


_DATA_ARRAY = re.compile(rb'(<DataArray[^>]*\bName="([^"]*)"[^>]*>)([^<]*)(</DataArray>)')


def _with_units(text: bytes, data: Mapping[str, np.ndarray]) -> bytes:
    """The VTK XML ``text`` with a ``UNITS_LABEL`` information key in each data array of ``data`` and in the
    points (m), as VTK's own XML writer writes one."""

    def unit(match: re.Match) -> bytes:
        name = match.group(2).decode()
        if name != "Points" and name not in data:
            return match.group(0)
        label = "m" if name == "Points" else EXTRA_UNITS.get(name, UNITS.get(name, ""))
        key = f'<InformationKey name="UNITS_LABEL" location="vtkDataArray">{label}</InformationKey>'.encode()
        return match.group(1) + match.group(3) + key + match.group(4)

    return _DATA_ARRAY.sub(unit, text)


def _material_field_data(names: dict[int, str]) -> bytes:
    """The arrays ``type_id`` and ``material`` of the types that have a name; empty when none has."""
    if not names:
        return b""
    types = sorted(names)
    return (
        f'<DataArray type="Int32" Name="type_id" NumberOfTuples="{len(types)}" format="ascii">'
        f"{' '.join(str(t) for t in types)}</DataArray>"
    ).encode("ascii") + _strings("material", [names[t] for t in types])
