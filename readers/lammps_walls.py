"""The contacts of LAMMPS' granular wall fixes, rebuilt from the particles' positions as the fixes find them.

A ``fix wall/gran`` or ``wall/gran/region`` writes, with ``contacts``, one row per particle (f_ID[1] the touching
flag, [2-4] the force of the step, [5-7] the wall point x - d, [8] the radius); where a particle touches several
surfaces of one region, the row holds the last one (fix_wall_gran_region.cpp:244-254). The geometry below gives
every contact, in the fix's own order, with d (from the wall to the particle's centre), its length r
(delta = radius - r) and the curvature 1/r_w the fix gives the contact's R (0: flat):

* ``xplane|yplane|zplane LO HI`` (fix_wall_gran.cpp:633-650): the nearer of the two planes (NULL: none), d along
  the axis; the distances are those of the planes of :func:`demsplit.readers.liggghts_walls.wall_distance`;
* ``zcylinder R`` (:652-665): the cylinder about the z axis, r = |R - rho|, r_w = -2R inside, 2R outside, in
  the fix's arithmetic;
* a region (region_plane.cpp:80-93, region_cylinder.cpp:274-420, ``side in``): a plane through P with normal N,
  r = (x - P).N when 0 <= r < radius; a cylinder's side (r = R - rho, r_w = -2R), its lo cap and its hi cap
  (r_w = 0), unless ``open``; a rotating region (``rotate v_theta P A``) is evaluated in its own frame, turned
  by theta(step) about A through P (region.cpp:457-517).
"""

from __future__ import annotations

import math

import numpy as np

from ..scene import Wall
from .lammps_script import Region, WallFix
from .liggghts_walls import wall_distance

_AXES = {"x": 0, "y": 1, "z": 2}
_OTHER = {0: (1, 2), 1: (0, 2), 2: (0, 1)}
"""A LAMMPS region cylinder's c1, c2 are the coordinates of its axis in these two dimensions (x: y z, y: x z,
z: x y; region_cylinder.cpp:50-80)."""


def rotation(axis: tuple[float, float, float], theta: float) -> np.ndarray:
    """The rotation matrix by ``theta`` (rad) about the unit vector along ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * K @ K


def plane_fix_contacts(fix: WallFix, x: np.ndarray, radius: np.ndarray) -> list[tuple]:
    """The one contact of a ``xplane|yplane|zplane LO HI`` fix per particle: the nearer plane (fix_wall_gran.cpp:
    633-650). Returns ``[(d, r, curvature)]`` of every particle (the caller keeps those it needs)."""
    axis = "xyz".index(fix.geometry[0])
    big = np.full(len(radius), np.inf)
    d1, _ = wall_distance(x, Wall("lo", "plane", 0, axis, fix.lo)) if fix.lo is not None else (big, None)
    d2, _ = wall_distance(x, Wall("hi", "plane", 0, axis, fix.hi)) if fix.hi is not None else (big, None)
    lower = d1 < d2
    d = np.zeros_like(x)
    d[:, axis] = np.where(lower, d1, -d2)
    return [(d, np.where(lower, d1, d2), np.zeros(len(radius)))]


def zcylinder_contacts(fix: WallFix, x: np.ndarray, radius: np.ndarray) -> list[tuple]:
    """The contact of a ``zcylinder R`` fix, in the fix's own arithmetic (fix_wall_gran.cpp:652-665: the overlap of
    a contact of 1e-8 m is 1e-11 off in other roundings): rho = sqrt(x^2 + y^2), d = -(R - rho)/rho (x, y),
    r = |d|, r_w = -2R inside, 2R outside."""
    rho = np.sqrt(x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1])
    delr = fix.radius - rho
    d = np.zeros_like(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        d[:, 0], d[:, 1] = -delr / rho * x[:, 0], -delr / rho * x[:, 1]
    r = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    return [(d, r, np.where(rho < fix.radius, -0.5, 0.5) / fix.radius)]


def region_contacts(region: Region, x: np.ndarray, radius: np.ndarray, theta: float = 0.0) -> list[tuple]:
    """The contacts of a ``side in`` plane or cylinder region, in the region's order, each
    ``(d, r, curvature, touching)`` for every particle; a rotating region turned by ``theta`` (rad)."""
    turn = None
    if region.rotate is not None and theta != 0.0:
        point = np.asarray(region.rotate[1])
        turn = rotation(region.rotate[2], theta)
        x = (x - point) @ turn + point  # into the region's frame: R^T (x - P) + P
    if region.style == "plane":
        p, normal = np.asarray(region.args[:3]), np.asarray(region.args[3:6])
        normal = normal / np.linalg.norm(normal)
        r = (x - p) @ normal
        out = [(r[:, None] * normal, r, np.zeros(len(r)), (r >= 0) & (r < radius))]
    else:
        axis = _AXES[region.args[0]]
        c1, c2, R, lo, hi = region.args[1:6]
        a, b = _OTHER[axis]
        e1, e2 = x[:, a] - c1, x[:, b] - c2
        rho = np.sqrt(e1 * e1 + e2 * e2)
        inside = (rho <= R) & (x[:, axis] >= lo) & (x[:, axis] <= hi)
        out = []
        side = np.zeros_like(x)
        with np.errstate(invalid="ignore", divide="ignore"):
            side[:, a], side[:, b] = e1 * (1.0 - R / rho), e2 * (1.0 - R / rho)
        r_side = R - rho
        out.append(
            (side, r_side, np.full(len(rho), -0.5 / R), inside & (r_side < radius) & (rho > 0) & (3 not in region.open))
        )
        for gap, sign, face in ((x[:, axis] - lo, 1.0, 1), (hi - x[:, axis], -1.0, 2)):
            cap = np.zeros_like(x)
            cap[:, axis] = sign * gap
            out.append((cap, gap, np.zeros(len(gap)), inside & (gap < radius) & (face not in region.open)))
    if turn is not None:
        out = [(d @ turn.T, r, k, touch) for d, r, k, touch in out]
    return out


def fix_contacts(fix: WallFix, x: np.ndarray, radius: np.ndarray, theta: float = 0.0) -> list[tuple]:
    """Every contact of wall fix ``fix`` with the particles at ``x`` (``(d, r, curvature, touching)`` per
    surface, in the fix's order: the last touching one is the one its contacts array holds)."""
    if fix.geometry == "region":
        return region_contacts(fix.region, x, radius, theta)
    parts = (
        plane_fix_contacts(fix, x, radius)
        if fix.geometry in ("xplane", "yplane", "zplane")
        else zcylinder_contacts(fix, x, radius)
    )
    return [(d, r, k, r < radius) for d, r, k in parts]
