"""What YADE's ScGeom laws share: the incremental shear spring whose force and stiffness YADE stores.

YADE keeps the elastic shear force F_t (``shearForce``, N) and the shear
stiffness ``ks`` (N/m) of every interaction, so the tangential spring energy
is |F_t|^2 / (2 ks) (0 where ks = 0: YADE zeroes it on separation). Not a law
itself: the YADE laws derive from :class:`YadeScGeomLaw`.
"""

from __future__ import annotations

import numpy as np

from ..elastic import stored_shear_energy
from .base import ContactLaw, ContactRows

SHEAR_FORCE = ("ftx", "fty", "ftz", "ks")
"""Contact columns of the incremental shear spring: force (N) and stiffness (N/m)."""


class YadeScGeomLaw(ContactLaw):
    """A YADE law with a normal energy (subclasses) and the stored incremental shear spring."""

    modes = ("u_n", "u_t")
    mode_columns = {"u_t": SHEAR_FORCE}

    def shear_energy(self, rows: ContactRows) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """``({"u_t": energy}, {})``, or ``({}, {"u_t": why not})`` when the columns are absent."""
        why = self.missing_mode(rows, "u_t")
        if why:
            return {}, {"u_t": why}
        ft = np.stack([rows.column(c) for c in SHEAR_FORCE[:3]], axis=-1)
        return {"u_t": stored_shear_energy(rows.delta, ft, rows.column("ks"))}, {}
