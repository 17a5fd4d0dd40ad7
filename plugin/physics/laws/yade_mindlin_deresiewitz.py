"""YADE ``Law2_ScGeom_MindlinPhys_MindlinDeresiewitz`` as Debian's 2023.02a builds it.

The normal force is Hertz, F_n = kno delta^(3/2): u_n = (2/5) kno delta^(5/2).
The law's shear update is compiled out in this YADE (``#if 0`` in
``pkg/dem/HertzMindlin.cpp``): ``shearForce`` stays 0 and ``kn``, ``ks`` stay 0
while ``usTotal`` grows, so the contact holds no shear spring energy and no
formula may divide by those stiffnesses: the law has the normal mode only.
A saved state's overlap is delta = (|F_n| / kno)^(2/3).
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap
from . import register
from ._yade import KNO, NORMAL_FORCE, Table, YadeLaw
from .base import ContactRows, LawEnergy
from .yade_hertz_linear_shear import hertz_depth
from .yade_mindlin import hertz_energy_from_kno


@register
class YadeMindlinDeresiewitz(YadeLaw):
    key = "yade:Law2_ScGeom_MindlinPhys_MindlinDeresiewitz"
    summary = "Hertz u_n = (2/5) kno delta^(5/2) with YADE's stored kno; no shear spring (compiled out in 2023.02a)"
    modes = ("u_n",)
    contact_columns = ("kno",)
    phys = (NORMAL_FORCE, KNO)

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        return LawEnergy({"u_n": hertz_energy_from_kno(rows.delta, rows.column("kno"))})

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d = overlap(rows.delta)
        return rows.column("kno") * np.sqrt(d) * d

    def depth_from_phys(self, t: Table) -> np.ndarray:
        return hertz_depth(t)
