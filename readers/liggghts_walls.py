"""Contacts with LIGGGHTS primitive walls, rebuilt from particle positions.

LIGGGHTS never dumps contacts with ``fix wall/gran ... primitive`` walls, so
they are rebuilt here exactly as ``primitive_wall_definitions.h`` finds them
(both sides of a wall are active, delta = r - d):

* ``xplane|yplane|zplane c``: d = |x_axis - c|, normal from the particle
  towards the plane, sign(c - x_axis) e_axis;
* ``xcylinder|ycylinder|zcylinder Rc c1 c2``: rho = position relative to the
  axis, d = | |rho| - Rc |; the normal points from the particle to the
  cylinder surface (outwards when inside).

LIGGGHTS uses R* = r (the wall's curvature is ignored), so ``r2 = inf``.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

import numpy as np

from ..frame import Table
from ..scene import Wall

_OTHER_AXES = {0: (1, 2), 1: (2, 0), 2: (0, 1)}  # LIGGGHTS' cyclic order for cylinder centres


def wall_distance(x: np.ndarray, wall: Wall) -> tuple[np.ndarray, np.ndarray]:
    """Distance d (m) from each centre ``x`` (shape (n, 3)) to the wall surface,
    and the unit vector from the centre towards the surface (shape (n, 3))."""
    n = np.zeros_like(x)
    if wall.kind == "plane":
        gap = wall.position - x[:, wall.axis]
        n[:, wall.axis] = np.where(gap >= 0, 1.0, -1.0)
        return np.abs(gap), n
    if wall.kind == "cylinder":
        a, b = _OTHER_AXES[wall.axis]
        rho = np.stack([x[:, a] - wall.center[0], x[:, b] - wall.center[1]], axis=-1)
        # LIGGGHTS' own arithmetic (calcRadialDistance), bit for bit: the overlap of a stored force's contact
        dist = np.sqrt(rho[:, 0] * rho[:, 0] + rho[:, 1] * rho[:, 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            radial = np.where(dist[:, None] > 0, rho / dist[:, None], 0.0)
        outward = np.where(dist < wall.radius, 1.0, -1.0)[:, None]  # inside: the surface lies outward
        n[:, a], n[:, b] = (outward * radial).T
        return np.abs(dist - wall.radius), n
    raise ValueError(f"wall {wall.name!r} of kind {wall.kind!r} is not a primitive wall")


def primitive_wall_contacts(
    particles: Table,
    walls: list[Wall],
    margin: np.ndarray | float = 0.0,
    reach: Sequence[np.ndarray | float] | None = None,
    present: Collection[int] | None = None,
) -> Table:
    """Contacts (canonical columns, see :mod:`demsplit.frame`) of the particles
    with every primitive wall (``plane``/``cylinder``) in ``walls`` that exists at this step (the indices
    ``present``; None: every one); a contact exists where delta = r - d > 0, as LIGGGHTS decides it.

    ``margin`` (m, scalar or one value per particle): also return the pairs with
    -margin < delta <= 0, whose contact the uncertainty of printed positions can
    hide (their delta stays <= 0, so they carry no energy; the caller flags them).
    ``reach`` (one entry per wall of ``walls``, m, scalar or one value per particle):
    also return the pairs with -reach < delta <= 0, that the wall's law still acts
    across (a liquid bridge, :meth:`~demsplit.physics.laws.ContactLaw.separation_limit`).
    """
    x = np.stack([particles["x"], particles["y"], particles["z"]], axis=-1).astype(np.float64)
    r = np.asarray(particles["radius"], dtype=np.float64)
    margin = np.broadcast_to(np.asarray(margin, dtype=np.float64), r.shape)
    parts: list[Table] = []
    for k, wall in enumerate(walls):
        if wall.kind not in ("plane", "cylinder") or (present is not None and k not in present):
            continue
        d, n = wall_distance(x, wall)
        delta = r - d
        apart = np.maximum(margin, 0.0 if reach is None else reach[k])
        hit = np.flatnonzero((delta > 0) | (delta > -apart))
        parts.append(
            {
                "id1": np.asarray(particles["id"], dtype=np.int64)[hit],
                "id2": np.full(len(hit), -1, np.int64),
                "wall": np.full(len(hit), k, np.int64),
                "delta": delta[hit],
                "nx": n[hit, 0],
                "ny": n[hit, 1],
                "nz": n[hit, 2],
                "x1": x[hit, 0],
                "y1": x[hit, 1],
                "z1": x[hit, 2],
                "r1": r[hit],
                "r2": np.full(len(hit), np.inf),
            }
        )
    if not parts:
        return {}
    return {c: np.concatenate([p[c] for p in parts]) for c in parts[0]}
