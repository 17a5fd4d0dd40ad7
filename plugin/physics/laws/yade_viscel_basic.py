"""YADE ``Law2_ScGeom_ViscElPhys_Basic`` (``ViscoelasticPM.cpp``): linear spring-dashpots, the
workhorse of granular-flow scripts.

YADE stores kn and ks (N/m) per interaction (from the materials' kn/ks, or from
the collision time tc and the restitution coefficients en, et); the normal
force kn delta + cn v_n includes the dashpot, so the elastic normal energy is
u_n = kn delta^2/2; ``shearForce`` is the elastic shear spring only (the
viscous shear force is applied, not stored): u_t = |F_t|^2/(2 ks). The
dashpots dissipate; they store nothing. A saved state's overlap is delta = Fn/kn, with Fn the elastic part
of the normal force YADE stores apart from the viscous one.

The law never reads the materials' ``young`` and ``poisson`` when they give kn, ks, cn, cs or the
collision time tc (``ViscElMat`` inherits their defaults, 1e9 Pa and 0.25): the split's moduli must then
come from the user (``--material``). Built from ``young`` alone (kn_i = 2 E_i R_i, ks_i = poisson kn_i),
its springs are FrictPhys' (``moduli = "springs"``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..elastic import hooke_energy, overlap
from . import register
from ._yade import SHEAR_FORCE, Phys, Table, YadeScGeomLaw, where_known
from .base import ContactRows, LawEnergy

STIFFNESS_ATTRIBUTES = ("kn", "ks", "tc")
"""ViscElMat attributes that, when set (finite), make the law's stiffness without young and poisson
(Ip2_ViscElMat_ViscElMat_ViscElPhys: from kn, ks with cn, cs, or from the collision time tc with en, et)."""
FUNCTOR_ATTRIBUTES = ("tc", "en", "et")
"""Ip2_ViscElMat_ViscElMat_ViscElPhys attributes (MatchMakers) that, set together, make the stiffness from the
collision time whatever the materials give."""


@register
class YadeViscElBasic(YadeScGeomLaw):
    key = "yade:Law2_ScGeom_ViscElPhys_Basic"
    summary = "linear spring-dashpots: u_n = kn delta^2/2 and u_t = |F_t|^2/(2 ks), YADE's stored kn, ks"
    contact_columns = ("kn",)
    phys = (SHEAR_FORCE, Phys("kn", "kn", "kn"), Phys("ks", "ks", "ks"), Phys("Fn", "fn_elastic"))
    moduli = "springs"

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.shear_energy(rows)
        return LawEnergy({"u_n": hooke_energy(rows.delta, rows.column("kn")), **modes}, skipped)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return rows.column("kn") * overlap(rows.delta)

    def depth_from_phys(self, t: Table) -> np.ndarray:
        """delta = Fn/kn from the elastic normal force (the law keeps only contacts with delta >= 0)."""
        return where_known(t["kn"] > 0, t["fn_elastic"] / t["kn"])

    def split_moduli(self, material: Mapping, physics: Sequence[Mapping] = ()) -> tuple[float, float] | str:
        given = [
            a for a in STIFFNESS_ATTRIBUTES if isinstance(material.get(a), (int, float)) and math.isfinite(material[a])
        ]
        if given:
            return (
                f"it gives {', '.join(given)}, so {self.key} never reads its young and poisson (ViscElMat's "
                "defaults, not moduli of the material)"
            )
        for f in physics:
            if all(f.get("attrs", {}).get(a) is not None for a in FUNCTOR_ATTRIBUTES):
                return (
                    f"{f['class']} sets tc, en and et, so {self.key} never reads its young and poisson "
                    "(ViscElMat's defaults, not moduli of the material)"
                )
        return super().split_moduli(material, physics)
