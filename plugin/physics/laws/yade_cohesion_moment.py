"""YADE ``Law2_ScGeom6D_CohFrictPhys_CohesionMoment`` (``CohesiveFrictionalContactLaw.cpp``).

Cohesive-frictional contacts with four elastic springs whose forces and
stiffnesses YADE stores per interaction (``CohFrictPhys``): normal F_n (kn),
shear F_s (ks), bending moment M_b (kr) and twisting moment M_tw (ktw). Each
spring's energy is |F|^2/(2 k), the sums YADE's own ``normElastEnergy()``,
``shearElastEnergy()``, ``bendingElastEnergy()`` and ``twistElastEnergy()``
compute: u_n, u_t, u_r (bending) and u_tw (twisting). A bond in tension stores
energy too (F_n < 0, |F_n|^2/(2 kn)). The normal energy comes from the stored
force, not from delta (a broken or plastically shifted bond's force is not
kn delta), so dU_n/d(delta) is not defined from the columns alone. A saved state's overlap is
delta = F_n/kn + unp (F_n signed along the normal, unp the bond's plastic normal displacement).
"""

from __future__ import annotations

import numpy as np

from . import register
from ._yade import (
    NORM,
    SPRINGS,
    Phys,
    Table,
    YadeScGeomLaw,
    YadeStoredSprings,
    along_normal,
    stored_spring_energy,
    where_known,
)
from .base import ContactRows, LawEnergy

MOMENTS = {"u_r": ("mb", "kr"), "u_tw": ("mtw", "ktw")}
"""Energy mode -> (moment magnitude column, N m; stiffness column, N m/rad)."""


@register
class YadeCohesionMoment(YadeStoredSprings):
    key = "yade:Law2_ScGeom6D_CohFrictPhys_CohesionMoment"
    summary = (
        "cohesive-frictional springs: u_n = |F_n|^2/(2 kn), u_t = |F_s|^2/(2 ks), bending u_r = |M_b|^2/(2 kr), "
        "twisting u_tw = |M_tw|^2/(2 ktw), YADE's stored forces, moments and stiffnesses"
    )
    modes = ("u_n", "u_t", "u_r", "u_tw")
    mode_columns = {**YadeScGeomLaw.mode_columns, **MOMENTS}
    phys = (
        *SPRINGS,
        Phys("moment_bending", "mb", "mb", NORM),
        Phys("moment_twist", "mtw", "mtw", NORM),
        Phys("kr", "kr", "kr"),
        Phys("ktw", "ktw", "ktw"),
        Phys("unp", "unp"),
    )
    simulator_energies = {
        "cohfrict_normElastEnergy": ("normElastEnergy", ("u_n",)),
        "cohfrict_shearElastEnergy": ("shearElastEnergy", ("u_t",)),
        "cohfrict_bendingElastEnergy": ("bendingElastEnergy", ("u_r",)),
        "cohfrict_twistElastEnergy": ("twistElastEnergy", ("u_tw",)),
    }

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.spring_energies(rows)
        for mode, (moment, k) in MOMENTS.items():
            why = self.missing_mode(rows, mode)
            if why:
                skipped[mode] = why
            else:
                modes[mode] = stored_spring_energy(rows.column(moment), rows.column(k))
        return LawEnergy(modes, skipped)

    def depth_from_phys(self, t: Table) -> np.ndarray:
        """delta = F_n/kn + unp, the law's F_n = kn (delta - unp) inverted; unknown where YADE zeroed the normal
        force (a bond sliding in tension)."""
        fn = along_normal(t, "fn")
        return where_known(fn != 0, fn / t["kn"] + t["unp"])
