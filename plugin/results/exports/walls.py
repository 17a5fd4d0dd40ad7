"""Wall geometry for the 3D exports: each wall of a run as triangles (m), from what the store holds of it
(the scene's walls in the provenance, the frames' simulation box).

- ``mesh`` (LIGGGHTS ``fix mesh/surface``): its STL file (ASCII or binary) with the fix line's ``scale``,
  ``move`` and ``rotate`` applied in the order they appear on the line, as LIGGGHTS' ``FixMesh`` applies
  them: scaling about the origin, rotation about an axis through the origin (right-hand rule, degrees);
- ``plane`` (LIGGGHTS ``xplane``/``yplane``/``zplane``) and ``yade_wall`` (YADE's axis-aligned ``Wall``):
  the rectangle of the plane inside the box;
- ``cylinder`` (LIGGGHTS ``x/y/zcylinder``): its surface, :data:`CYLINDER_FACETS` flat facets around, along
  its axis across the box.

The box is the frame's simulation box (``box_*`` columns of the frames table) where the store has it,
else the extent of the frame's particles (their centres plus their radius) and of the mesh walls. YADE
facets and boxes are not drawn: the store holds no geometry of them. A mesh moved during the run
(``fix move/mesh``) is drawn where its file and fix line put it.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ...errors import InputFormatError

CYLINDER_FACETS = 64
"""Flat facets around a cylinder wall: the drawn surface is within r (1 - cos(pi/64)) = 1.2e-3 r of it."""

FLAT = ("plane", "yade_wall")
"""Wall kinds that are axis-aligned planes at ``position`` along ``axis``."""


def read_stl(path: str | Path) -> np.ndarray:
    """The triangles of an STL file, shape (n, 3, 3) (its own length unit; LIGGGHTS reads it as m): binary
    (80-byte header, a count, 50 bytes per triangle) when the size says so, else ASCII ``vertex`` lines."""
    path = Path(path)
    data = path.read_bytes()
    if len(data) >= 84:
        (n,) = struct.unpack_from("<I", data, 80)
        if len(data) == 84 + 50 * n:
            rows = np.frombuffer(
                data, dtype=np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), count=n, offset=84
            )
            return rows["v"].astype(np.float64)
    try:
        words = [line.split() for line in data.decode("ascii").splitlines()]
        vertices = np.array([w[1:4] for w in words if w and w[0] == "vertex"], dtype=np.float64)
    except (UnicodeDecodeError, ValueError, IndexError):
        raise InputFormatError(
            "not an STL file (neither binary nor ASCII 'vertex' lines).",
            file=path,
            fix="give the mesh file the run's 'fix mesh/surface' read.",
        ) from None
    if len(vertices) % 3 or not len(vertices):
        raise InputFormatError(
            f"an ASCII STL file with {len(vertices)} vertices: not whole triangles.",
            file=path,
            fix="give the mesh file the run's 'fix mesh/surface' read.",
        )
    return vertices.reshape(-1, 3, 3)


def transformed(triangles: np.ndarray, transforms: Sequence[Sequence]) -> np.ndarray:
    """``triangles`` (n, 3, 3) after the ``scale``/``move``/``rotate`` operations of a ``fix mesh/surface``
    line, in order (module docstring): ``("scale", (s,))``, ``("move", (dx, dy, dz))`` (m), ``("rotate", (ax,
    ay, az, angle))`` (degrees, about the axis through the origin; Rodrigues' formula)."""
    out = np.array(triangles, dtype=np.float64)
    for name, values in transforms:
        if name == "scale":
            out *= float(values[0])
        elif name == "move":
            out += np.asarray(values, dtype=np.float64)
        elif name == "rotate":
            axis = np.asarray(values[:3], dtype=np.float64)
            k = axis / np.linalg.norm(axis)
            angle = math.radians(float(values[3]))
            cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            rotation = np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross
            out = out @ rotation.T
        else:
            raise ValueError(f"unknown mesh transform {name!r}")
    return out


def _plane(axis: int, position: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Two triangles: the plane x[axis] = position across the box [lo, hi] in the other two axes."""
    a, b = (axis + 1) % 3, (axis + 2) % 3
    corners = np.zeros((4, 3))
    corners[:, axis] = position
    corners[:, a] = [lo[a], hi[a], hi[a], lo[a]]
    corners[:, b] = [lo[b], lo[b], hi[b], hi[b]]
    return corners[[[0, 1, 2], [0, 2, 3]]]


def _cylinder(axis: int, radius: float, center: Sequence[float], lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The surface of the cylinder of ``radius`` about ``axis`` through ``center`` (the two other
    coordinates in LIGGGHTS' cyclic order: x: (y, z), y: (z, x), z: (x, y)) from lo to hi along the axis, as
    2 :data:`CYLINDER_FACETS` triangles."""
    a, b = (axis + 1) % 3, (axis + 2) % 3
    phi = np.linspace(0.0, 2 * math.pi, CYLINDER_FACETS + 1)
    ring = np.zeros((CYLINDER_FACETS + 1, 3))
    ring[:, a] = center[0] + radius * np.cos(phi)
    ring[:, b] = center[1] + radius * np.sin(phi)
    bottom, top = ring.copy(), ring.copy()
    bottom[:, axis], top[:, axis] = lo[axis], hi[axis]
    k = np.arange(CYLINDER_FACETS)
    quads = np.stack([bottom[k], bottom[k + 1], top[k + 1], top[k]], axis=1)
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def wall_triangles(
    wall: Mapping, lo: np.ndarray, hi: np.ndarray, meshes: dict[str, np.ndarray]
) -> tuple[np.ndarray | None, str]:
    """The triangles of one wall of the provenance's scene (module docstring) in the box [lo, hi] (m), or
    None and why it is not drawn (no geometry in the store, a mesh file gone, a description that is not numbers).
    ``meshes``: mesh files already read, by path (filled in)."""
    try:
        triangles, why = _triangles(wall, lo, hi, meshes)
    except (TypeError, ValueError, IndexError, KeyError, AttributeError) as exc:  # a damaged provenance
        return None, f"the store's description of it is not a geometry ({type(exc).__name__})"
    if triangles is not None and not np.isfinite(triangles).all():
        return None, "its geometry in the store is not finite"
    return triangles, why


def _triangles(
    wall: Mapping, lo: np.ndarray, hi: np.ndarray, meshes: dict[str, np.ndarray]
) -> tuple[np.ndarray | None, str]:
    kind = wall.get("kind")
    if kind == "mesh":
        file = wall.get("file")
        if not file or not Path(file).is_file():
            return None, f"its mesh file {file} is not there"
        if file not in meshes:
            meshes[file] = read_stl(file)
        return transformed(meshes[file], wall.get("transforms") or ()), ""
    if kind in FLAT:
        return _plane(int(wall["axis"]), float(wall["position"]), lo, hi), ""
    if kind == "cylinder":
        return _cylinder(int(wall["axis"]), float(wall["radius"]), wall.get("center") or (0.0, 0.0), lo, hi), ""
    return None, f"the store holds no geometry of a {kind} wall"


def mesh_extent(walls: Sequence[Mapping], meshes: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray] | None:
    """The bounding box (m) of the mesh walls that can be drawn, or None."""
    points = [wall_triangles(w, np.zeros(3), np.zeros(3), meshes)[0] for w in walls if w.get("kind") == "mesh"]
    points = [p.reshape(-1, 3) for p in points if p is not None]
    if not points:
        return None
    every = np.concatenate(points)
    return every.min(axis=0), every.max(axis=0)
