"""YADE ``Law2_ScGeom_ViscElPhys_Basic`` (``ViscoelasticPM.cpp``): linear spring-dashpots, the
workhorse of granular-flow scripts.

YADE stores kn and ks (N/m) per interaction (from the materials' kn/ks, or from
the collision time tc and the restitution coefficients en, et); the normal
force kn delta + cn v_n includes the dashpot, so the elastic normal energy is
u_n = kn delta^2/2; ``shearForce`` is the elastic shear spring only (the
viscous shear force is applied, not stored): u_t = |F_t|^2/(2 ks). The
dashpots dissipate; they store nothing.
"""

from __future__ import annotations

import numpy as np

from ..elastic import hooke_energy, overlap
from . import register
from ._yade import YadeScGeomLaw
from .base import ContactRows, LawEnergy


@register
class YadeViscElBasic(YadeScGeomLaw):
    key = "yade:Law2_ScGeom_ViscElPhys_Basic"
    summary = "linear spring-dashpots: u_n = kn delta^2/2 and u_t = |F_t|^2/(2 ks), YADE's stored kn, ks"
    contact_columns = ("kn",)

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.shear_energy(rows)
        return LawEnergy({"u_n": hooke_energy(rows.delta, rows.column("kn")), **modes}, skipped)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return rows.column("kn") * overlap(rows.delta)
