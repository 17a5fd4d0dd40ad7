"""The VTK export read back by VTK's own XML reader: every frame's particles at their centres, contacts as lines
between the two bodies, walls as surfaces, with the store's energies and each array's unit, and a .pvd series
listing every frame."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from demsplit.cli import main
from demsplit.results import load_results
from demsplit.results.tables import with_not_computed_as_nan

vtk_numpy = pytest.importorskip("vtkmodules.util.numpy_support")
meshio = pytest.importorskip("meshio")
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader  # noqa: E402

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


def read_vtu(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The points and the point data (vertex files) or the cell data (line and triangle files) of a file."""
    grid = read_grid(path)
    data = grid.GetCellData() if grid.GetCellData().GetNumberOfArrays() else grid.GetPointData()
    arrays = {data.GetArrayName(k): vtk_numpy.vtk_to_numpy(data.GetArray(k)) for k in range(data.GetNumberOfArrays())}
    return vtk_numpy.vtk_to_numpy(grid.GetPoints().GetData()).reshape(-1, 3), arrays


def read_grid(path: Path):
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def units_of(grid, data) -> dict[str, str]:
    """The UNITS_LABEL information key of every array of ``data`` (a grid's point or cell data)."""
    from vtkmodules.vtkCommonCore import vtkDataArray

    arrays = [data.GetArray(k) for k in range(data.GetNumberOfArrays())]
    return {a.GetName(): a.GetInformation().Get(vtkDataArray.UNITS_LABEL()) for a in arrays}


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """run and export --vtk of a sample: (store, vtk directory, what export printed)."""
    made = {}

    def export(run: str):
        if run not in made:
            root = tmp_path_factory.mktemp(run.replace("/", "_"))
            store = root / "out.h5"
            assert main(["run", str(SAMPLES / run), "-o", str(store), "-q"]) == 0
            import contextlib
            import io

            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                assert main(["export", str(store), "--vtk", str(root / "vtk")]) == 0
            made[run] = store, root / "vtk", printed.getvalue()
        return made[run]

    return export


def frames_of(vtk: Path, series: str, steps: list[int]) -> list[tuple[int, Path]]:
    sets = ET.parse(vtk / f"{series}.pvd").getroot().findall("./Collection/DataSet")
    assert [int(d.get("timestep")) for d in sets] == steps
    return [(int(d.get("timestep")), vtk / d.get("file")) for d in sets]


@pytest.mark.parametrize("run", ["liggghts/packing/in.packing", "yade/mindlin_box.h5", "liggghts/periodic/in.periodic"])
def test_vtk_particles_and_contacts_as_lines_between_the_bodies(run, exported):
    """Particles at their centres; each contact a line from the centre of id1 to the centre of id2 (its
    nearest periodic image: the line is r1 + r2 - delta long) or to the contact point of a wall, with the
    store's values as cell data, NaN where not computed (packing: primitive-wall u_t), u = u1 + u2."""
    store, vtk, printed = exported(run)
    res = load_results(store)
    steps = res.steps.tolist()
    assert printed.count("\n") == 1 and printed.startswith(f"wrote {3 * len(steps)} VTK files")
    for step, path in frames_of(vtk, "particles", steps):
        points, arrays = read_vtu(path)
        frame = with_not_computed_as_nan(res.particles)[lambda df, s=step: df["step"] == s]
        np.testing.assert_array_equal(points, frame[["x", "y", "z"]].to_numpy())
        for column in ("u", "id", "type", "radius", "n_contacts"):
            np.testing.assert_array_equal(arrays[column], frame[column].to_numpy(), err_msg=column)
    for step, path in frames_of(vtk, "contacts", steps):
        grid = read_grid(path)
        assert {grid.GetCellType(k) for k in range(grid.GetNumberOfCells())} == {3}  # VTK_LINE
        points, arrays = read_vtu(path)
        contacts = with_not_computed_as_nan(res.contacts)[lambda df, s=step: df["step"] == s]
        particles = res.particles[res.particles["step"] == step].set_index("id")
        start, end = points[0::2], points[1::2]
        np.testing.assert_array_equal(start, particles.loc[contacts["id1"], ["x", "y", "z"]].to_numpy())
        wall = contacts["wall"].to_numpy() >= 0
        np.testing.assert_array_equal(end[wall], contacts.loc[wall, ["cpx", "cpy", "cpz"]].to_numpy())
        pairs = contacts[~wall]
        r1 = particles.loc[pairs["id1"], "radius"].to_numpy()
        r2 = particles.loc[pairs["id2"], "radius"].to_numpy()
        length = np.linalg.norm(end[~wall] - start[~wall], axis=1)
        np.testing.assert_allclose(length, r1 + r2 - pairs["delta"].to_numpy(), rtol=1e-6)
        for column in ("u_n", "u_t", "u1", "u2", "share_n1", "id1", "id2", "wall"):
            np.testing.assert_array_equal(arrays[column], contacts[column].to_numpy(), err_msg=column)
        np.testing.assert_array_equal(arrays["u"], (contacts["u1"] + contacts["u2"]).to_numpy())


def test_vtk_walls_are_drawn_with_their_energies(exported):
    """The packing sample's walls: the mesh floor as its STL's triangles, the four planes clipped to the
    simulation box, the post as a cylinder of radius 4 mm; each triangle carries its wall's row."""
    from demsplit.results.exports.walls import read_stl

    store, vtk, _ = exported("liggghts/packing/in.packing")
    res = load_results(store)
    stl = read_stl(SAMPLES / "liggghts" / "packing" / "floor.stl")
    for step, path in frames_of(vtk, "walls", res.steps.tolist()):
        points, arrays = read_vtu(path)
        triangles = points.reshape(-1, 3, 3)
        walls = with_not_computed_as_nan(res.walls)[lambda df, s=step: df["step"] == s].set_index("wall")
        box = res.frames.set_index("step").loc[step]
        lo = box[["box_xlo", "box_ylo", "box_zlo"]].to_numpy()
        hi = box[["box_xhi", "box_yhi", "box_zhi"]].to_numpy()
        np.testing.assert_array_equal(lo, [-0.023, -0.023, -0.002])  # region domain of in.packing
        np.testing.assert_array_equal(hi, [0.023, 0.023, 0.06])
        of = arrays["wall"]
        np.testing.assert_array_equal(triangles[of == 0], stl)
        for wall, (axis, position) in {1: (0, -0.02), 2: (0, 0.02), 3: (1, -0.02), 4: (1, 0.02)}.items():
            corners = triangles[of == wall].reshape(-1, 3)
            assert np.all(corners[:, axis] == position)
            other = [a for a in range(3) if a != axis]
            np.testing.assert_array_equal(corners[:, other].min(axis=0), lo[other])
            np.testing.assert_array_equal(corners[:, other].max(axis=0), hi[other])
        post = triangles[of == 5].reshape(-1, 3)
        np.testing.assert_allclose(np.hypot(post[:, 0], post[:, 1]), 0.004, rtol=1e-12)
        assert post[:, 2].min() == lo[2] and post[:, 2].max() == hi[2]
        for column in ("u", "u_n", "u_t", "n_contacts"):
            np.testing.assert_array_equal(arrays[column], walls.loc[of, column].to_numpy(), err_msg=column)
        assert np.isnan(arrays["u"][of == 1]).all()  # a primitive wall's u_t is not computed


def _points_data(grid):
    """The grid's points array as a one-array collection, for :func:`units_of`."""
    from vtkmodules.vtkCommonDataModel import vtkFieldData

    data = vtkFieldData()
    data.AddArray(grid.GetPoints().GetData())
    return data


@pytest.mark.parametrize("series", ["particles", "contacts", "walls"])
def test_every_vtk_array_has_its_unit(exported, series):
    store, vtk, _ = exported("liggghts/packing/in.packing")
    files = sorted(vtk.glob(f"{series}_*.vtu"))
    assert len(files) == len(load_results(store).steps)
    for path in files:
        grid = read_grid(path)
        units = units_of(grid, grid.GetPointData() if series == "particles" else grid.GetCellData())
        _, arrays = read_vtu(path)
        assert set(units) == set(arrays) and all(units.values()), units
        column, unit = {"particles": ("radius", "m"), "contacts": ("delta", "m"), "walls": ("n_contacts", "1")}[series]
        assert units["u"] == "J" and units[column] == unit
        assert units_of(grid, _points_data(grid)) == {"Points": "m"}
        mesh = meshio.read(path)  # meshio, which reads no string array, reads the files
        assert len(mesh.points) == grid.GetNumberOfPoints()


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


@pytest.mark.slow
@pytest.mark.simulator
def test_a_mesh_wall_is_drawn_where_liggghts_put_it(tmp_path):
    """A floor STL scaled, rotated by 8 degrees and moved on its fix line, in a LIGGGHTS run: every contact
    point LIGGGHTS dumps for it lies on the exported surface (to 1e-10 m; the operations in another order put
    the surface 4.9e-6 m away)."""
    import shutil

    from test_user_loop import HEAD, liggghts_run

    shutil.copy(SAMPLES / "liggghts" / "packing" / "floor.stl", tmp_path / "floor.stl")
    floor = b"fix floor all wall/gran model hertz tangential history primitive type 2 zplane 0.0"
    assert floor in HEAD
    script = tmp_path / "in.mesh"
    script.write_bytes(
        HEAD.replace(b"PAIR_EXTRA", b"").replace(
            floor,
            (
                b"fix floor all mesh/surface file floor.stl type 2 scale 0.25 rotate axis 0 1 0 angle 8 "
                b"move 0 0 0.0005\n"
                b"fix wfloor all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor"
            ),
        )
        + b"run 30000\n"
    )
    assert main(["prepare", str(script), "--every", "10000", "-q"]) == 0
    liggghts_run(script.with_name("in.mesh.demsplit"))
    store = tmp_path / "r.h5"
    assert main(["run", str(script.with_name("in.mesh.demsplit")), "-o", str(store), "-q"]) == 0
    assert main(["export", str(store), "--vtk", str(tmp_path / "vtk"), "-q"]) == 0
    res = load_results(store)
    step = int(res.steps.max())
    points, arrays = read_vtu(tmp_path / "vtk" / f"walls_{step:012d}.vtu")
    floor_triangles = points.reshape(-1, 3, 3)[arrays["wall"] == 0]
    assert res.walls_meta[0]["name"] == "floor" and len(floor_triangles) == 32
    a, b, c = floor_triangles[0]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal)
    np.testing.assert_allclose(normal, [np.sin(np.radians(8)), 0, np.cos(np.radians(8))], atol=1e-15)
    assert np.abs((floor_triangles.reshape(-1, 3) - a) @ normal).max() < 1e-15
    contacts = res.contacts[(res.contacts["step"] == step) & (res.contacts["wall"] == 0)]
    assert len(contacts) > 10
    dumped = contacts[["cpx_sim", "cpy_sim", "cpz_sim"]].to_numpy()
    assert np.abs((dumped - a) @ normal).max() < 1e-10
