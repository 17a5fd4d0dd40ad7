"""YADE ``Law2_ScGeom_MindlinPhys_HertzWithLinearShear`` (``HertzMindlin.cpp``).

Hertz normal force F_n = kno delta^(3/2) with YADE's stored kno, so
u_n = (2/5) kno delta^(5/2); the shear spring's stiffness is the constant
``kso`` with the functor's ``nonLin = 0`` (``ks`` and ``kn`` stay 0 in this law),
kso delta^(1/2) with ``nonLin > 0`` (computed in the law's step, not stored), so
u_t = |F_t|^2/(2 ks). A saved state's overlap is delta = (|F_n| / kno)^(2/3).
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap, stored_shear_energy
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
    parameters = {"non_linear": (0, "nonLin: > 0 makes the shear stiffness kso delta^(1/2) instead of kso")}
    simulator_parameters = {"nonLin": "non_linear"}

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        u_n = hertz_energy_from_kno(rows.delta, rows.column("kno"))
        why = self.missing_mode(rows, "u_t")
        if why:
            return LawEnergy({"u_n": u_n}, {"u_t": why})
        ks = rows.column("kso") * (np.sqrt(overlap(rows.delta)) if self.params["non_linear"] > 0 else 1.0)
        ft = np.stack([rows.column(c) for c in ("ftx", "fty", "ftz")], axis=-1)
        return LawEnergy({"u_n": u_n, "u_t": stored_shear_energy(rows.delta, ft, ks)})

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d = overlap(rows.delta)
        return rows.column("kno") * np.sqrt(d) * d

    def depth_from_phys(self, t: Table) -> np.ndarray:
        return hertz_depth(t)
