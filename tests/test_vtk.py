"""The VTK export read back by VTK's own XML reader: every frame's particles at their centres and contacts at
their contact points, with the store's energies, and a .pvd series listing every frame."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from demsplit.cli import main
from demsplit.results import load_results
from demsplit.results.tables import with_not_computed_as_nan

vtk_numpy = pytest.importorskip("vtkmodules.util.numpy_support")
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader  # noqa: E402

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


def read_vtu(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    data = grid.GetPointData()
    arrays = {data.GetArrayName(k): vtk_numpy.vtk_to_numpy(data.GetArray(k)) for k in range(data.GetNumberOfArrays())}
    return vtk_numpy.vtk_to_numpy(grid.GetPoints().GetData()), arrays


@pytest.mark.parametrize("run", ["liggghts/packing/in.packing", "yade/mindlin_box.h5"])
def test_vtk_series_holds_the_stores_particles_and_contacts(run, tmp_path):
    """Every value as the store has it, but NaN where not computed (packing: primitive-wall u_t)."""
    store = tmp_path / "out.h5"
    assert main(["run", str(SAMPLES / run), "-o", str(store), "-q"]) == 0
    assert main(["export", str(store), "--vtk", str(tmp_path / "vtk"), "-q"]) == 0
    res = load_results(store)
    for table, position in (("particles", ["x", "y", "z"]), ("contacts", ["cpx", "cpy", "cpz"])):
        pvd = ET.parse(tmp_path / "vtk" / f"{table}.pvd").getroot()
        sets = pvd.findall("./Collection/DataSet")
        assert [int(d.get("timestep")) for d in sets] == res.steps.tolist()
        for d in sets:
            step = int(d.get("timestep"))
            points, arrays = read_vtu(tmp_path / "vtk" / d.get("file"))
            frame = with_not_computed_as_nan(getattr(res, table))[lambda df, s=step: df["step"] == s]
            np.testing.assert_array_equal(points, frame[position].to_numpy())
            for column in ("u", "id", "type", "radius", "n_contacts") if table == "particles" else \
                    ("u_n", "u_t", "u1", "u2", "share_n1", "id1", "id2", "wall"):
                np.testing.assert_array_equal(arrays[column], frame[column].to_numpy(), err_msg=column)


def test_vtk_files_carry_the_material_names(tmp_path):
    """YADE's material labels (and names from run --type-name) are in every file's field data."""
    store = tmp_path / "out.h5"
    assert main(["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(store), "-q", "--type-name", "7=rock"]) == 0
    assert main(["export", str(store), "--vtk", str(tmp_path / "vtk"), "-q"]) == 0
    expected = load_results(store).type_names()
    assert expected[7] == "rock" and len(expected) >= 2
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(sorted((tmp_path / "vtk").glob("particles_*.vtu"))[-1]))
    reader.Update()
    fields = reader.GetOutput().GetFieldData()
    ids = vtk_numpy.vtk_to_numpy(fields.GetArray("type_id")).tolist()
    labels = fields.GetAbstractArray("material")
    assert dict(zip(ids, (labels.GetValue(k) for k in range(labels.GetNumberOfValues())))) == expected


def test_the_export_never_writes_over_its_store(tmp_path, capsys):
    store = tmp_path / "out.h5"
    assert main(["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(store), "-q"]) == 0
    (tmp_path / "vtk").mkdir()
    (tmp_path / "vtk" / "particles.pvd").hardlink_to(store)
    assert main(["export", str(store), "--vtk", str(tmp_path / "vtk"), "-q"]) == 2
    assert "one of the run's inputs" in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "vtk").iterdir()) == ["particles.pvd"]  # nothing written
