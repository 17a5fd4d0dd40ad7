"""YADE ``Law2_ScGeom_MindlinPhys_HertzWithLinearShear`` (``HertzMindlin.cpp``, ``nonLin=0``).

Hertz normal force F_n = kno delta^(3/2) with YADE's stored kno, so
u_n = (2/5) kno delta^(5/2); the shear spring's stiffness is the constant
``kso`` (``ks`` and ``kn`` stay 0 in this law), so u_t = |F_t|^2/(2 kso).
A saved state's overlap is delta = (|F_n| / kno)^(2/3).
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap
from . import register
from ._yade import KNO, KSO, NORMAL_FORCE, SHEAR_FORCE, Table, YadeScGeomLaw, magnitude, where_known
from .base import ContactRows, LawEnergy
from .yade_mindlin import hertz_energy_from_kno


def hertz_depth(t: Table) -> np.ndarray:
    """delta = (|F_n| / kno)^(2/3), YADE's F_n = kno delta^(3/2) inverted; unknown where F_n = 0 (a contact apart,
    kept by ``neverErase``)."""
    fn = magnitude(t, "fn")
    return where_known(fn > 0, np.cbrt((fn / t["kno"]) ** 2))


@register
class YadeHertzWithLinearShear(YadeScGeomLaw):
    key = "yade:Law2_ScGeom_MindlinPhys_HertzWithLinearShear"
    summary = "Hertz u_n = (2/5) kno delta^(5/2); linear shear u_t = |F_t|^2/(2 kso), YADE's stored kno, kso"
    contact_columns = ("kno",)
    mode_columns = {"u_t": ("ftx", "fty", "ftz", "kso")}
    phys = (NORMAL_FORCE, SHEAR_FORCE, KNO, KSO)

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.shear_energy(rows)
        return LawEnergy({"u_n": hertz_energy_from_kno(rows.delta, rows.column("kno")), **modes}, skipped)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d = overlap(rows.delta)
        return rows.column("kno") * np.sqrt(d) * d

    def depth_from_phys(self, t: Table) -> np.ndarray:
        return hertz_depth(t)
