"""YADE ``Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM`` (``JointedCohesiveFrictionalPM.cpp``).

The jointed cohesive frictional particle model of bonded rock: bonds form at
a distance (``interactionDetectionFactor`` > 1) and carry tension until they
break, so most bonds hold energy at delta < 0. YADE stores each interaction's
normal and shear force and stiffnesses (``JCFpmPhys``): u_n = |F_n|^2/(2 kn),
u_t = |F_s|^2/(2 ks), from the stored forces (the normal force is
kn (delta - initD), not kn delta).
"""

from __future__ import annotations

from . import register
from ._yade import YadeStoredSprings
from .base import ContactRows, LawEnergy


@register
class YadeJCFpm(YadeStoredSprings):
    key = "yade:Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM"
    summary = ("bonded springs: u_n = |F_n|^2/(2 kn), u_t = |F_s|^2/(2 ks) from YADE's stored forces and "
               "stiffnesses, bonds in tension included")

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        return LawEnergy(*self.spring_energies(rows))
