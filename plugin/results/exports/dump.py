"""Per-particle results as a LAMMPS-style text dump, which OVITO (and MDAnalysis, LAMMPS' tools) open directly.

:func:`export_dump` writes one ``ITEM: TIMESTEP`` frame per stored frame:
``ITEM: ATOMS id type x y z radius`` followed by every other per-particle
column (``u u_n u_t``, the comparison splits, ``n_contacts``, ...), reals at
full precision (``%.17g``); a value that was not computed (the ``not_computed`` bits, also written)
is ``nan``, never the store's 0. OVITO maps ``id type x y z radius`` to its
standard properties and keeps the others under their own names, so a
``ColorCodingModifier(property='u')`` colours the particles by their energy
(``docs/visualization.md``). The store keeps no box, so each frame's box is
the particles' extent (centres +- radius), non-periodic.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ...outputs import OutputKind, atomic_path, check_output_path, output_errors
from ..tables import Results

LEADING = ("id", "type", "x", "y", "z", "radius")
"""The columns every frame starts with, in OVITO's and LAMMPS' names."""
_ATOMS = re.compile(
    rb"\AITEM: TIMESTEP\n.*?^ITEM: ATOMS " + " ".join(LEADING).encode() + rb" [^\n]*\bnot_computed\b",
    re.DOTALL | re.MULTILINE,
)


def _is_export(path: Path) -> bool:
    """Whether ``path`` starts like a dump :func:`export_dump` wrote: a frame whose columns are demsplit's
    (``id type x y z radius`` first, ``not_computed`` among them, which no simulator writes)."""
    try:
        with open(path, "rb") as f:
            return _ATOMS.match(f.read(4096)) is not None
    except OSError:
        return False


DUMP = OutputKind("per-particle dump written by demsplit export", _is_export)
"""The output kind of ``export --dump``: an existing file is replaced only when it is one."""


def export_dump(
    results: Results, path: str | Path, inputs: Iterable[str | Path] = (), *, overwrite: bool = False
) -> Path:
    """Write the per-particle table of every frame of ``results`` to the dump ``path`` (module docstring).
    ``inputs`` are never written over, nor an existing file that is not such a dump unless ``overwrite``
    (:mod:`demsplit.outputs`)."""
    path = check_output_path(path, inputs, kind=DUMP, overwrite=overwrite)
    df = results.particles
    columns = [*LEADING, *(c for c in df.columns if c not in (*LEADING, "step"))]
    integer = [df[c].dtype.kind in "iu" for c in columns]
    with output_errors(path), atomic_path(path) as tmp, open(tmp, "w") as f:
        for step, frame in df.groupby("step", sort=False):
            x = frame[["x", "y", "z"]].to_numpy()
            r = frame["radius"].to_numpy()[:, None]
            lo, hi = (x - r).min(axis=0), (x + r).max(axis=0)
            f.write(
                f"ITEM: TIMESTEP\n{int(step)}\nITEM: NUMBER OF ATOMS\n{len(frame)}\n"
                "ITEM: BOX BOUNDS ff ff ff\n"
                + "".join(f"{a!r} {b!r}\n" for a, b in zip(lo.tolist(), hi.tolist()))
                + "ITEM: ATOMS "
                + " ".join(columns)
                + "\n"
            )
            values = frame[columns].to_numpy(dtype=object) if any(integer) else frame[columns].to_numpy()
            fmt = " ".join("%d" if i else "%.17g" for i in integer)
            np.savetxt(f, values, fmt=fmt)
    return path
