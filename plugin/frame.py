"""The canonical in-memory form of one timestep: :class:`Frame` and :class:`Box`.

A frame is the unit of memory: readers yield one at a time. Tables are plain
``dict[str, numpy.ndarray]`` (structure of arrays; float64 for reals, int64 for
ids, int32 for types); DataFrames are only built at the user-facing edges.

``particles`` columns
    ``id`` (int64), ``type`` (int32), ``x y z`` (m), ``radius`` (m);
    optional ``mass`` (kg), ``vx vy vz`` (m/s), ``fx fy fz`` (N), and any other
    column a contact law declares in ``particle_columns`` under its dump name
    (``f_surfaceLiquidContent``, LIGGGHTS' per-atom liquid content, for its
    liquid bridges).

``contacts`` columns (one row per physical contact, never twice)
    ``id1 id2`` (int64; for a wall contact ``id1`` is the particle and ``id2``
    is -1), ``wall`` (int64, -1 for particle-particle, else an index into
    ``Scene.walls``), ``delta`` (m, overlap; negative: a gap, across which
    some laws act: a liquid bridge, a bond in tension), ``nx ny nz`` (unit normal from
    body 1 to body 2), ``x1 y1 z1`` (m, centre of body 1 in the frame of the
    normal, i.e. consistent with ``delta`` and ``n``), ``r1 r2`` (m, radii the
    contact law uses; ``inf`` for a plane).

    Optional, used when present: ``type1 type2`` (material types of the two
    bodies; a reader that knows them sets them, otherwise they come from the
    particles table and the wall list), ``m1 m2`` (kg), ``fn`` (N, elastic
    normal force), ``ftx fty ftz`` (N, elastic tangential force), ``shearx
    sheary shearz`` (m, LIGGGHTS tangential spring history), ``kn ks kno kso``
    (stiffnesses the simulator stored), ``cpx cpy cpz`` (m, the simulator's own
    contact point), ``history_unknown`` (int8, the ``not_computed`` bits of the modes whose history
    the simulator never wrote for the contact, :data:`~demsplit.physics.modes.HISTORY_LOST` for all of
    them, e.g. LIGGGHTS primitive walls: the law's modes that read a history are then "not computed" for
    that row where their bit is set), ``unknown_modes`` (int8, the bits of
    :data:`~demsplit.physics.modes.NOT_COMPUTED_BITS` of the modes whose state the reader could
    not rebuild for that row) with ``unknown_why`` (int8, the law's code of why; LAMMPS), the
    rebuilt springs of LAMMPS (``ftx_el fty_el ftz_el``, ``frx_el fry_el frz_el``, N, and
    ``wall_curvature``, 1/m: :mod:`demsplit.physics.laws._lammps`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import ContactError, InputFormatError
from .physics.formulas import minimum_image_components

Table = dict[str, np.ndarray]

PARTICLE_REQUIRED = ("id", "type", "x", "y", "z", "radius")
CONTACT_REQUIRED = ("id1", "id2", "wall", "delta", "nx", "ny", "nz", "x1", "y1", "z1", "r1", "r2")


def describe_steps(steps) -> str:
    """Human-readable range of timesteps: ``"first..last, every N"`` (``every``
    only when the spacing is regular), or ``"none"``."""
    steps = [int(x) for x in steps]
    if not steps:
        return "none"
    gaps = np.unique(np.diff(steps)) if len(steps) > 1 else []
    every = f", every {int(gaps[0])}" if len(gaps) == 1 else ""
    return f"{steps[0]}..{steps[-1]}{every}"


def table_length(table: Table) -> int:
    """Number of rows of a table (0 for an empty table)."""
    for col in table.values():
        return len(col)
    return 0


def require_columns(
    table: Table, required: tuple[str, ...], what: str, *, file: str | None = None, step: int | None = None
) -> None:
    """Raise :class:`InputFormatError` naming the canonical columns ``table`` lacks."""
    missing = [c for c in required if c not in table]
    if missing:
        raise InputFormatError(
            f"the {what} table lacks the columns {missing}.",
            file=file,
            step=step,
            fix="this is a reader's output: report it, with the input that caused it.",
        )


def take_rows(table: Table, rows: np.ndarray) -> Table:
    """The rows ``rows`` (an index or boolean mask) of every column."""
    return {name: col[rows] for name, col in table.items()}


@dataclass
class Box:
    """Simulation box: bounds (m), periodicity per axis and triclinic tilt.

    ``tilt`` holds LAMMPS's ``xy xz yz``; the periodic minimum image below is
    exact for orthogonal boxes and applies the tilt in the LAMMPS order (z, then
    y, then x) for triclinic ones.
    """

    lo: np.ndarray
    hi: np.ndarray
    periodic: tuple[bool, bool, bool] = (False, False, False)
    tilt: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        self.lo = np.asarray(self.lo, dtype=np.float64)
        self.hi = np.asarray(self.hi, dtype=np.float64)
        self.tilt = np.asarray(self.tilt, dtype=np.float64)
        self.periodic = tuple(bool(p) for p in self.periodic)

    @property
    def lengths(self) -> np.ndarray:
        """Edge lengths (m)."""
        return self.hi - self.lo

    @property
    def any_periodic(self) -> bool:
        return any(self.periodic)

    def minimum_image(self, d: np.ndarray) -> np.ndarray:
        """Minimum-image version of difference vectors ``d`` (shape (n, 3), m)."""
        d = np.array(d, dtype=np.float64, copy=True)
        d[:, 0], d[:, 1], d[:, 2] = minimum_image_components(
            d[:, 0], d[:, 1], d[:, 2], self.lengths, self.tilt, self.periodic
        )
        return d

    def wrap(self, x: np.ndarray) -> np.ndarray:
        """Positions ``x`` (shape (n, 3), m) wrapped into the box along periodic
        axes (orthogonal boxes; tilted boxes wrap in the same LAMMPS order)."""
        x = np.array(x, dtype=np.float64, copy=True)
        L = self.lengths
        xy, xz, yz = self.tilt
        if self.periodic[2]:
            k = np.floor((x[:, 2] - self.lo[2]) / L[2])
            x[:, 2] -= k * L[2]
            x[:, 1] -= k * yz
            x[:, 0] -= k * xz
        if self.periodic[1]:
            k = np.floor((x[:, 1] - self.lo[1]) / L[1])
            x[:, 1] -= k * L[1]
            x[:, 0] -= k * xy
        if self.periodic[0]:
            k = np.floor((x[:, 0] - self.lo[0]) / L[0])
            x[:, 0] -= k * L[0]
        return x


@dataclass
class Frame:
    """One timestep of a run.

    ``overlap_source`` says where ``contacts['delta']`` came from (e.g.
    ``"dumped delta"``, ``"positions, full precision"``) and
    ``overlap_error`` is the per-contact bound on the relative error of
    ``delta`` that source implies (``None`` when it is at double precision).
    ``notes`` collects what the reader could not provide and why. ``walls`` lists the indices of the
    scene's walls that exist at this step (a wall fix added after a ``run`` or removed by ``unfix``, a YADE
    body added or erased between states), ``None`` when every wall does.
    """

    step: int
    particles: Table
    contacts: Table
    box: Box | None = None
    time: float | None = None
    source: tuple[str, ...] = ()
    overlap_source: str = ""
    overlap_error: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    walls: tuple[int, ...] | None = None

    @property
    def n_particles(self) -> int:
        return table_length(self.particles)

    @property
    def n_contacts(self) -> int:
        return table_length(self.contacts)


class ParticleIndex:
    """Maps particle ids to rows of a particles table (dense 0..n-1 index).

    Uses a direct lookup array when ids are compact (the usual 1..N of
    LIGGGHTS and 0..N-1 of YADE), binary search otherwise. Duplicate ids are
    an error: one id must mean one particle.

    :meth:`contact_rows` keeps its last answer: the rows of the same id arrays
    (the same objects, not modified in place) are gathered once per frame,
    however many sums use them.
    """

    def __init__(self, ids: np.ndarray, *, file: str | None = None, step: int | None = None) -> None:
        ids = np.asarray(ids, dtype=np.int64)
        self.ids = ids
        self.file, self.step = file, step
        self._last: tuple | None = None
        n = len(ids)
        lo = int(ids.min()) if n else 0
        hi = int(ids.max()) if n else -1
        self._dense = n > 0 and lo >= 0 and hi < 8 * n + 1024
        if self._dense:
            dtype = np.int32 if n < 2**31 else np.int64  # rows of 4 bytes: less to read per contact
            row = np.full(hi + 1, -1, dtype=dtype)
            row[ids] = np.arange(n, dtype=dtype)
            dup = n - np.count_nonzero(row >= 0)
            self._row = row
        else:
            self._order = np.argsort(ids, kind="stable")
            self._sorted = ids[self._order]
            dup = int(np.count_nonzero(self._sorted[1:] == self._sorted[:-1]))
        if dup:
            counts = np.unique(ids, return_counts=True)
            dups = counts[0][counts[1] > 1][:5].tolist()
            raise InputFormatError(
                f"{dup} duplicated particle id(s) in one frame, e.g. {dups}.",
                file=file,
                step=step,
                fix="each particle must appear once per frame; check that the dump is not the "
                "concatenation of two runs or of several MPI ranks writing the same atoms.",
            )

    def rows(self, query: np.ndarray, *, what: str = "contact") -> np.ndarray:
        """Row of each id in ``query``; unknown ids are a ContactError naming them."""
        q = np.asarray(query, dtype=np.int64)
        if self._dense and (q.size == 0 or (q.min() >= 0 and q.max() < len(self._row))):
            rows = self._row.take(q).astype(np.int64)  # every id inside the table: one gather
        elif self._dense:
            inside = (q >= 0) & (q < len(self._row))
            rows = np.full(q.shape, -1, dtype=np.int64)
            rows[inside] = self._row[q[inside]]
        else:
            if len(self._sorted) == 0:
                rows = np.full(q.shape, -1, dtype=np.int64)
            else:
                pos = np.clip(np.searchsorted(self._sorted, q), 0, len(self._sorted) - 1)
                rows = np.where(self._sorted[pos] == q, self._order[pos], -1)
        bad = rows < 0
        if bad.any():
            unknown = np.unique(q[bad])[:5].tolist()
            raise ContactError(
                f"{int(bad.sum())} {what}(s) reference particle id(s) not in the atom dump, e.g. {unknown}.",
                file=self.file,
                step=self.step,
                fix="pair the contact dump with the atom dump of the same timestep "
                "(both dumps must be written every N steps with the same N).",
            )
        return rows

    def contact_rows(self, id1: np.ndarray, id2: np.ndarray, wall: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rows of body 1 and body 2 of every contact (int32 below 2^31 particles); for a
        wall contact (``wall >= 0``) rows2 is -1 - wall. An unknown id is the
        ContactError of :meth:`rows`."""
        last = self._last
        if last is not None and last[0] is id1 and last[1] is id2 and last[2] is wall:
            return last[3]
        if self._dense:
            from .kernels import contact_rows  # compiled: import demsplit stays numpy-only

            rows1, rows2, bad = contact_rows(self._row, id1, id2, wall)
            if bad >= 0:  # the error message of rows(), naming the unknown ids
                self.rows(id1)
                self.rows(id2[wall < 0])
        else:
            rows1 = self.rows(id1)
            pair = wall < 0
            rows2 = -1 - np.asarray(wall, dtype=np.int64)
            rows2[pair] = self.rows(id2[pair])
        self._last = (id1, id2, wall, (rows1, rows2))
        return rows1, rows2
