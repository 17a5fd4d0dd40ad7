"""YADE ``Law2_ScGeom6D_CohFrictPhys_CohesionMoment`` (``CohesiveFrictionalContactLaw.cpp``).

Cohesive-frictional contacts with four elastic springs whose forces and
stiffnesses YADE stores per interaction (``CohFrictPhys``): normal F_n (kn),
shear F_s (ks), bending moment M_b (kr) and twisting moment M_tw (ktw). Each
spring's energy is |F|^2/(2 k), the sums YADE's own ``normElastEnergy()``,
``shearElastEnergy()``, ``bendingElastEnergy()`` and ``twistElastEnergy()``
compute: u_n, u_t, u_r (bending) and u_tw (twisting). A bond in tension stores
energy too (F_n < 0, |F_n|^2/(2 kn)). The normal energy comes from the stored
force, not from delta (a broken or plastically shifted bond's force is not
kn delta), so dU_n/d(delta) is not defined from the columns alone.
"""

from __future__ import annotations


from . import register
from ._yade import YadeScGeomLaw, YadeStoredSprings, stored_spring_energy
from .base import ContactRows, LawEnergy

MOMENTS = {"u_r": ("mb", "kr"), "u_tw": ("mtw", "ktw")}
"""Energy mode -> (moment magnitude column, N m; stiffness column, N m/rad)."""


@register
class YadeCohesionMoment(YadeStoredSprings):
    key = "yade:Law2_ScGeom6D_CohFrictPhys_CohesionMoment"
    summary = ("cohesive-frictional springs: u_n = |F_n|^2/(2 kn), u_t = |F_s|^2/(2 ks), bending u_r = |M_b|^2/(2 kr), "
               "twisting u_tw = |M_tw|^2/(2 ktw), YADE's stored forces, moments and stiffnesses")
    modes = ("u_n", "u_t", "u_r", "u_tw")
    mode_columns = {**YadeScGeomLaw.mode_columns, **MOMENTS}
    simulator_energies = {"cohfrict_normElastEnergy": ("normElastEnergy", ("u_n",)),
                          "cohfrict_shearElastEnergy": ("shearElastEnergy", ("u_t",)),
                          "cohfrict_bendingElastEnergy": ("bendingElastEnergy", ("u_r",)),
                          "cohfrict_twistElastEnergy": ("twistElastEnergy", ("u_tw",))}

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.spring_energies(rows)
        for mode, (moment, k) in MOMENTS.items():
            why = self.missing_mode(rows, mode)
            if why:
                skipped[mode] = why
            else:
                modes[mode] = stored_spring_energy(rows.column(moment), rows.column(k))
        return LawEnergy(modes, skipped)
