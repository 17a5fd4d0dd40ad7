"""YADE ``Law2_ScGeom_MindlinPhys_MindlinDeresiewitz`` as Debian's 2023.02a builds it.

The normal force is Hertz, F_n = kno delta^(3/2): u_n = (2/5) kno delta^(5/2).
The law's shear update is compiled out in this YADE (``#if 0`` in
``pkg/dem/HertzMindlin.cpp``): ``shearForce`` stays 0 and ``kn``, ``ks`` stay 0
while ``usTotal`` grows, so the contact holds no shear spring energy and no
formula may divide by those stiffnesses: the law has the normal mode only.
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap
from . import register
from .base import ContactLaw, ContactRows, LawEnergy
from .yade_mindlin import hertz_energy_from_kno


@register
class YadeMindlinDeresiewitz(ContactLaw):
    key = "yade:Law2_ScGeom_MindlinPhys_MindlinDeresiewitz"
    summary = "Hertz u_n = (2/5) kno delta^(5/2) with YADE's stored kno; no shear spring (compiled out in 2023.02a)"
    modes = ("u_n",)
    contact_columns = ("kno",)

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        return LawEnergy({"u_n": hertz_energy_from_kno(rows.delta, rows.column("kno"))})

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d = overlap(rows.delta)
        return rows.column("kno") * np.sqrt(d) * d
