"""MDAnalysis bridge: per-particle energies as selectable atom attributes.

>>> from demsplit.mda import universe_with_energies          # doctest: +SKIP
>>> u = universe_with_energies("atoms.dump", results, step=20000)
>>> hot = u.select_atoms("type 2 and prop energy > 1e-6")
>>> hot.energies, hot.positions                             # J, m (float32)

Importing this module registers these per-atom float attributes with
MDAnalysis (so ``prop NAME > value`` selections accept them):

==================  ==================  ================  ====
attribute (plural)  singular / ``prop``  Results column    unit
==================  ==================  ================  ====
``energies``        ``energy``          ``u``             J
``energies_n``      ``energy_n``        ``u_n``           J
``energies_t``      ``energy_t``        ``u_t``           J
``energies_equal``  ``energy_equal``    ``u_equal``       J
``energies_radius`` ``energy_radius``   ``u_radius``      J
``contact_counts``  ``contact_count``   ``n_contacts``    1
==================  ==================  ================  ====

(MDAnalysis names ``u`` the universe by convention, hence ``energy`` rather
than ``u``.) Topology attributes are static: they hold the energies of one
frame. After moving the trajectory to another frame call
:func:`set_energies` with that frame's step.

MDAnalysis facts this module accounts for (MDAnalysis 2.11,
``coordinates/LAMMPS.py`` ``DumpReader``):

- positions are float32 (about 7 significant digits: at |x| = 0.05 m the
  resolution is 3.7e-9 m, coarser than typical DEM overlaps);
- atoms are sorted by id, the topology (ids, types, masses) comes from the
  first frame, and a frame with another number of atoms is an error (runs that
  insert particles cannot be read);
- the reader shifts positions by -(xlo, ylo, zlo) so the box starts at the
  origin; :func:`universe_with_energies` adds the frame's lower bounds back
  (a trajectory transformation), so positions are in the simulation's frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from MDAnalysis.core.topologyattrs import AtomAttr

from .errors import InputFormatError
from .results import Results

ENERGY_ATTRIBUTES = {  # Results column -> (singular, plural, dtype)
    "u": ("energy", "energies", float),
    "u_n": ("energy_n", "energies_n", float),
    "u_t": ("energy_t", "energies_t", float),
    "u_equal": ("energy_equal", "energies_equal", float),
    "u_radius": ("energy_radius", "energies_radius", float),
    "n_contacts": ("contact_count", "contact_counts", int),
}


def _zeros(na, nr, ns, _dtype=float):
    return np.zeros(na, dtype=_dtype)


_ATTR_CLASSES = {
    column: type(
        f"DemsplitAttr_{singular}",
        (AtomAttr,),
        {
            "attrname": plural,
            "singular": singular,
            "dtype": dtype,
            "_gen_initial_values": staticmethod(lambda na, nr, ns, _d=dtype: _zeros(na, nr, ns, _d)),
            "__doc__": f"demsplit per-particle {column} of one frame.",
        },
    )
    for column, (singular, plural, dtype) in ENERGY_ATTRIBUTES.items()
}


def _box_lo(path: Path, offset: int) -> np.ndarray:
    """(xlo, ylo, zlo) of the frame at ``offset`` (m), computed as MDAnalysis does (for triclinic boxes,
    from the bounding box and the tilts). The file is opened the way MDAnalysis indexed it
    (``anyopen``: a ``.gz`` or ``.bz2`` dump decompressed), so that its offsets point into the same text."""
    from MDAnalysis.lib.util import anyopen

    with anyopen(str(path)) as f:
        f.seek(offset)
        head = [f.readline() for _ in range(8)]
    if not head[0].startswith("ITEM: TIMESTEP") or not head[4].startswith("ITEM: BOX BOUNDS"):
        raise InputFormatError(
            "cannot find the frame header MDAnalysis indexed.",
            file=path,
            fix="check that the file is an unmodified LAMMPS/LIGGGHTS dump.",
        )
    rows = [np.array(line.split(), dtype=np.float64) for line in head[5:8]]
    lo = np.array([r[0] for r in rows])
    if len(rows[0]) == 3:  # triclinic: bounds are of the bounding box
        xy, xz, yz = rows[0][2], rows[1][2], rows[2][2]
        lo[0] -= min(0.0, xy, xz, xy + xz)
        lo[1] -= min(0.0, yz)
    return lo


def _restore_origin(path: Path, offsets: np.ndarray):
    """Trajectory transformation adding the frame's box lower bounds back to
    MDAnalysis's shifted positions."""

    def transform(ts):
        ts.positions += _box_lo(path, int(offsets[ts.frame])).astype(np.float32)
        return ts

    return transform


def set_energies(universe, results: Results, step: int) -> None:
    """Attach (or overwrite) the per-particle results of frame ``step`` as atom
    attributes, matched by particle id. Every atom must have a result row and
    every result row an atom."""
    particles = results.particles
    rows = particles[particles["step"] == step]
    if len(rows) == 0:
        steps = results.steps
        raise InputFormatError(
            f"the results hold no particles for timestep {step} "
            f"(they hold {len(steps)} frame(s), timesteps {steps.min() if len(steps) else '-'}"
            f"..{steps.max() if len(steps) else '-'}).",
            step=step,
            fix="pick a timestep present in both the dump and the results.",
        )
    res_ids = rows["id"].to_numpy()
    order = np.argsort(res_ids, kind="stable")
    sorted_ids = res_ids[order]
    atom_ids = np.asarray(universe.atoms.ids, dtype=np.int64)
    pos = np.minimum(np.searchsorted(sorted_ids, atom_ids), len(sorted_ids) - 1)
    matched = sorted_ids[pos] == atom_ids
    if not matched.all() or len(res_ids) != len(atom_ids) or len(np.unique(res_ids)) != len(res_ids):
        missing = atom_ids[~matched][:5].tolist()
        raise InputFormatError(
            f"the dump has {len(atom_ids)} atoms and the results {len(res_ids)} particles at this timestep; "
            f"ids must match one to one" + (f" (e.g. atom ids {missing} have no result)." if missing else "."),
            step=step,
            fix="use the atom dump the results were computed from.",
        )
    take = order[pos]
    for column, attr_class in _ATTR_CLASSES.items():
        if column not in rows:
            continue
        values = rows[column].to_numpy()[take].astype(attr_class.dtype)
        if hasattr(universe.atoms, attr_class.attrname):
            setattr(universe.atoms, attr_class.attrname, values)
        else:
            universe.add_TopologyAttr(attr_class.attrname, values)


def universe_with_energies(atom_dump_path: str | Path, results: Results, step: int, *, restore_origin: bool = True):
    """An ``MDAnalysis.Universe`` of a LAMMPS/LIGGGHTS atom dump, moved to the
    frame with timestep ``step``, with that frame's energies attached (see the
    module docstring for the attribute names). With ``restore_origin`` the
    positions are in the simulation's coordinates (MDAnalysis otherwise shifts
    them by the box's lower bounds)."""
    import MDAnalysis as mda

    path = Path(atom_dump_path)
    try:
        u = mda.Universe(str(path), format="LAMMPSDUMP")
    except (ValueError, OSError) as exc:
        raise InputFormatError(
            f"MDAnalysis cannot read this atom dump: {exc}.",
            file=path,
            fix="pass a LAMMPS/LIGGGHTS 'dump custom' file with an id column.",
        ) from exc
    if restore_origin:
        u.trajectory.add_transformations(_restore_origin(path, np.asarray(u.trajectory._offsets)))
    try:
        for ts in u.trajectory:
            if ts.data["step"] == step:
                break
        else:
            raise InputFormatError(
                f"the dump has no frame with timestep {step}.",
                file=path,
                step=step,
                fix="pick a timestep present in the dump.",
            )
    except ValueError as exc:  # e.g. "Number of atoms in trajectory changed"
        raise InputFormatError(
            f"MDAnalysis cannot read this dump: {exc}.",
            file=path,
            step=step,
            fix="MDAnalysis needs a constant number of atoms; use demsplit's own reader "
            "for runs that insert or delete particles.",
        ) from exc
    set_energies(u, results, step)
    return u
