"""Results as VTK files for ParaView (and any VTK reader): one file per frame and a ``.pvd`` series.

:func:`export_vtk` writes, for every frame of a result set, the particles as
points (``particles_<step>.vtu``: the centre, with every per-particle column:
id, type, radius, the energy of every mode, ``u``, the comparison splits,
``n_contacts``) and, when the store has the per-contact table, the contacts
as points at the material-weighted contact point (``contacts_<step>.vtu``:
ids, wall, overlap, the energies, shares, ``u1 u2 depth1``), plus
``particles.pvd`` and ``contacts.pvd``: ParaView opens a ``.pvd`` as one time
series. Units are SI (m, J). A value that was not computed (the row's ``not_computed`` bits, which
are written too) is NaN, never the store's 0. Where types have material names (YADE's material
labels, ``demsplit run --type-name``), every file's field data carries them as two
parallel arrays, ``type_id`` (integers) and ``material`` (strings). The files are VTK XML unstructured grids of
vertex cells, written by meshio: pure Python and a small fraction of VTK's
size (docs/performance.md, "Standing decisions").
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ...errors import StoreError
from ...outputs import OutputFolder
from ..tables import Results

POSITIONS = {"particles": ("x", "y", "z"), "contacts": ("cpx", "cpy", "cpz")}
"""Where each table's rows are drawn: the particle centre, the contact point (m)."""


def export_vtk(results: Results, directory: str | Path, inputs: Iterable[str | Path] = (), *,
               overwrite: bool = False) -> list[Path]:
    """Write the VTK series of ``results`` into ``directory`` (module docstring); return the files written.
    The files are written together, all or none, into a new or empty folder or over an earlier VTK export,
    whose series is replaced whole; never over one of ``inputs`` (:class:`demsplit.outputs.OutputFolder`;
    ``overwrite``: into a folder holding other files too)."""
    try:
        import meshio
    except ImportError:
        raise StoreError("the VTK export needs meshio, which is not installed.",
                         fix="pip install 'demsplit[vtk]'.") from None
    tables = {name: getattr(results, name) for name, position in POSITIONS.items()
              if not getattr(results, name).empty and set(position) <= set(getattr(results, name).columns)}
    plan = {name: [(int(step), f"{name}_{int(step):012d}.vtu") for step in df["step"].unique()]
            for name, df in tables.items()}
    names = [f for name, files in plan.items() for f in [*dict(files).values(), f"{name}.pvd"]]
    folder = OutputFolder(directory, names, inputs, kind="vtk", overwrite=overwrite)
    field_data = _material_field_data(results.type_names())
    written = []
    with folder:
        for name, df in tables.items():
            position = POSITIONS[name]
            file_of = dict(plan[name])
            for step, frame in df.groupby("step", sort=False):
                points = frame[list(position)].to_numpy(dtype=np.float64)
                data = {c: frame[c].to_numpy() for c in frame.columns if c not in (*position, "step")}
                mesh = meshio.Mesh(points, [("vertex", np.arange(len(points)).reshape(-1, 1))], point_data=data)
                written.append(folder.write(file_of[int(step)], lambda tmp, m=mesh: _write_vtu(meshio, tmp, m,
                                                                                                 field_data)))
            rows = "\n".join(f'    <DataSet timestep="{step}" part="0" file={quoteattr(file)}/>'
                             for step, file in plan[name])
            text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
                    f"{rows}\n  </Collection>\n</VTKFile>\n")
            written.append(folder.write(f"{name}.pvd", lambda tmp, t=text: tmp.write_text(t)))
    return written


def _write_vtu(meshio, tmp: Path, mesh, field_data: bytes) -> None:
    """One frame's ``.vtu`` at ``tmp``, with the material names' field data."""
    meshio.write(tmp, mesh, file_format="vtu", binary=True, compression=None)
    if field_data:
        grid = b"<UnstructuredGrid>"
        tmp.write_bytes(tmp.read_bytes().replace(grid, grid + field_data, 1))


def _material_field_data(names: dict[int, str]) -> bytes:
    """VTK XML ``<FieldData>`` with the arrays ``type_id`` and ``material`` (ASCII format: a string
    array is its characters' codes, each string ended by 0, as VTK's own XML writer writes it);
    empty when no type has a name."""
    if not names:
        return b""
    types = sorted(names)
    codes = " ".join(" ".join(str(b) for b in names[t].encode("utf-8")) + " 0" for t in types)
    return ("<FieldData>"
            f'<DataArray type="Int32" Name="type_id" NumberOfTuples="{len(types)}" format="ascii">'
            f'{" ".join(str(t) for t in types)}</DataArray>'
            f'<Array type="String" Name="material" NumberOfTuples="{len(types)}" format="ascii">{codes}</Array>'
            "</FieldData>").encode("ascii")
