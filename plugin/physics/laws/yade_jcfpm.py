"""YADE ``Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM`` (``JointedCohesiveFrictionalPM.cpp``).

The jointed cohesive frictional particle model of bonded rock: bonds form at
a distance (``interactionDetectionFactor`` > 1) and carry tension until they
break, so most bonds hold energy at delta < 0. YADE stores each interaction's
normal and shear force and stiffnesses (``JCFpmPhys``): u_n = |F_n|^2/(2 kn),
u_t = |F_s|^2/(2 ks), from the stored forces (the normal force is
kn (delta - initD), not kn delta).

A contact across a smooth joint (``isOnJoint`` with the law's ``smoothJoint``, parameter ``smooth_joint``)
acts along the joint's normal on the distance of the centres along it, not on delta: the spheres slide
past each other and may overlap by more than the smaller radius (up to r1 + r2), and its overlap is not a
function of its force. A saved state's overlap is delta = F_n/kn + initD elsewhere.
"""

from __future__ import annotations

import numpy as np

from . import register
from ._yade import SPRINGS, Phys, Table, YadeStoredSprings, along_normal, where_known
from .base import ContactRows, LawEnergy


@register
class YadeJCFpm(YadeStoredSprings):
    key = "yade:Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM"
    summary = (
        "bonded springs: u_n = |F_n|^2/(2 kn), u_t = |F_s|^2/(2 ks) from YADE's stored forces and "
        "stiffnesses, bonds in tension included"
    )
    phys = (*SPRINGS, Phys("initD", "init_d"), Phys("isOnJoint", "on_joint", "on_joint"))
    parameters = {"smooth_joint": (False, "smoothJoint: contacts on a joint act along the joint's normal")}
    simulator_parameters = {"smoothJoint": "smooth_joint"}

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        return LawEnergy(*self.spring_energies(rows))

    def depth_from_phys(self, t: Table) -> np.ndarray:
        """delta = F_n/kn + initD, the law's F_n = kn (delta - initD) inverted; unknown on a smooth joint (its
        force is along the joint's normal) and where YADE zeroed the normal force (a broken bond kept by
        ``neverErase``)."""
        fn = along_normal(t, "fn")
        smooth = (t["on_joint"] != 0) & bool(self.params["smooth_joint"])
        return where_known((fn != 0) & ~smooth, fn / t["kn"] + t["init_d"])

    def overlap_limit(self, contacts: Table) -> np.ndarray:
        """r1 + r2 on a smooth joint (the spheres slide past each other), the smaller radius elsewhere."""
        smaller = np.minimum(contacts["r1"], contacts["r2"])
        if not self.params["smooth_joint"] or "on_joint" not in contacts:
            return smaller
        return np.where(contacts["on_joint"] != 0, contacts["r1"] + contacts["r2"], smaller)
