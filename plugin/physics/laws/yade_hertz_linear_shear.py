"""YADE ``Law2_ScGeom_MindlinPhys_HertzWithLinearShear`` (``HertzMindlin.cpp``, ``nonLin=0``).

Hertz normal force F_n = kno delta^(3/2) with YADE's stored kno, so
u_n = (2/5) kno delta^(5/2); the shear spring's stiffness is the constant
``kso`` (``ks`` and ``kn`` stay 0 in this law), so u_t = |F_t|^2/(2 kso).
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap
from . import register
from ._yade import YadeScGeomLaw
from .base import ContactRows, LawEnergy
from .yade_mindlin import hertz_energy_from_kno


@register
class YadeHertzWithLinearShear(YadeScGeomLaw):
    key = "yade:Law2_ScGeom_MindlinPhys_HertzWithLinearShear"
    summary = "Hertz u_n = (2/5) kno delta^(5/2); linear shear u_t = |F_t|^2/(2 kso), YADE's stored kno, kso"
    contact_columns = ("kno",)
    mode_columns = {"u_t": ("ftx", "fty", "ftz", "kso")}

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.shear_energy(rows)
        return LawEnergy({"u_n": hertz_energy_from_kno(rows.delta, rows.column("kno")), **modes}, skipped)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d = overlap(rows.delta)
        return rows.column("kno") * np.sqrt(d) * d
