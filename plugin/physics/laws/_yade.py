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
        """``({"u_t": energy}, {})``, or ``({}, {"u_t": why not})`` when the columns are absent; the shear
        stiffness is the last column of the law's ``u_t`` columns (``ks``, or ``kso`` for a law that keeps
        its shear stiffness there)."""
        why = self.missing_mode(rows, "u_t")
        if why:
            return {}, {"u_t": why}
        columns = self.mode_columns["u_t"]
        ft = np.stack([rows.column(c) for c in columns[:3]], axis=-1)
        return {"u_t": stored_shear_energy(rows.delta, ft, rows.column(columns[3]))}, {}


def stored_spring_energy(force: np.ndarray, k: np.ndarray) -> np.ndarray:
    """|F|^2/(2 k) (J) of a spring whose force (or moment) magnitude and stiffness the simulator stored;
    0 where k = 0 (a spring YADE has not set)."""
    return np.divide(force * force, 2.0 * k, out=np.zeros_like(force), where=k > 0)


class YadeStoredSprings(YadeScGeomLaw):
    """A YADE law whose normal and shear springs' forces and stiffnesses are stored and may hold energy
    without overlap (bonds in tension): u_n = |F_n|^2/(2 kn), u_t = |F_s|^2/(2 ks), kept where delta < 0."""

    contact_columns = ("fn", "kn")
    normal_from_stored_force = True

    def spring_energies(self, rows: ContactRows) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """``u_n`` and, when its columns are there, ``u_t`` (else the ``skipped`` entry)."""
        modes, skipped = {"u_n": stored_spring_energy(rows.column("fn"), rows.column("kn"))}, {}
        why = self.missing_mode(rows, "u_t")
        if why:
            skipped["u_t"] = why
        else:
            ft = np.sqrt(sum(rows.column(c) ** 2 for c in SHEAR_FORCE[:3]))
            modes["u_t"] = stored_spring_energy(ft, rows.column("ks"))
        return modes, skipped

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return rows.column("fn")
