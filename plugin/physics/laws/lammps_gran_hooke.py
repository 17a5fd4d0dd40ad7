"""LAMMPS legacy ``pair_style gran/hooke`` (pair_gran_hooke.cpp:160-200) and ``fix wall/gran hooke``.

F_n = k_n delta - m* gamma_n v_n, u_n = k_n delta^2/2 (J); the tangential force is viscous only,
-min(mu |F_n|, m* gamma_t |v_t|) along v_t: no spring, u_t = 0. See :class:`._lammps.LammpsLegacyModel`.
"""

from __future__ import annotations

from . import register
from ._lammps import LammpsLegacyModel


@register
class LammpsGranHooke(LammpsLegacyModel):
    key = "lammps:gran/hooke"
    summary = "linear spring u_n = k_n delta^2/2; viscous tangential force without spring"
    has_spring = False
