"""YADE ``Law2_ScGeom_ViscoFrictPhys_CundallStrack``: CundallStrack with a creeping shear spring.

The same springs as :mod:`.yade_cundall_strack` (kn of two springs E_i r_i in
series, F_n = kn delta): u_n = kn delta^2/2 and u_t = |F_t|^2/(2 ks) from the
stored, possibly relaxed (``shearCreep``) shear force, which is what YADE's own
``elasticEnergy()`` sums.
"""

from __future__ import annotations

from . import register
from .yade_cundall_strack import YadeCundallStrack


@register
class YadeViscoFrictCundallStrack(YadeCundallStrack):
    key = "yade:Law2_ScGeom_ViscoFrictPhys_CundallStrack"
    summary = (
        "linear springs with shear creep: u_n = kn delta^2/2 and u_t = |F_t|^2/(2 ks) with YADE's stored "
        "kn, ks and (relaxed) shear force"
    )
    simulator_energies = {"viscofrict_elasticEnergy": ("elasticEnergy", ("u_n", "u_t"))}
