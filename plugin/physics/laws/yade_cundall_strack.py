"""YADE ``Law2_ScGeom_FrictPhys_CundallStrack`` (``ElasticContactLaw.cpp``): linear normal and shear springs.

YADE stores the normal stiffness kn (N/m) per interaction (``FrictPhys``, two
springs k_i = E_i r_i in series), F_n = kn delta: u_n = kn delta^2 / 2. The
shear spring is the stored incremental one: u_t = |F_t|^2 / (2 ks). Besides
the 50/50 and radius splits, the series-spring split of kn is reported for
comparison. A saved state's overlap is delta = |F_n| / kn. YADE fills
``O.energy['elastPotential']`` with u_n + u_t of every contact at each step.
"""

from __future__ import annotations

import numpy as np

from ..elastic import hooke_energy, overlap
from . import register
from ._yade import Table, YadeScGeomLaw, magnitude, where_known
from .base import ContactRows, LawEnergy


@register
class YadeCundallStrack(YadeScGeomLaw):
    key = "yade:Law2_ScGeom_FrictPhys_CundallStrack"
    summary = "linear springs: u_n = kn delta^2/2 and u_t = |F_t|^2/(2 ks) with YADE's stored kn, ks"
    contact_columns = ("kn",)
    comparison_splits = ("equal", "radius", "springs")
    moduli = "springs"
    simulator_energies = {"cundallstrack_elasticEnergy": ("elasticEnergy", ("u_n", "u_t"))}
    tracked_energies = {"elastPotential": ("u_n", "u_t")}

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.shear_energy(rows)
        return LawEnergy({"u_n": hooke_energy(rows.delta, rows.column("kn")), **modes}, skipped)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return rows.column("kn") * overlap(rows.delta)

    def depth_from_phys(self, t: Table) -> np.ndarray:
        """delta = |F_n| / kn; unknown where F_n = 0 (a contact apart, kept by ``neverErase``)."""
        fn = magnitude(t, "fn")
        return where_known(fn > 0, fn / t["kn"])
