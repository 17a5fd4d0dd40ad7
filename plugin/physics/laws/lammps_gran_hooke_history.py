"""LAMMPS legacy ``pair_style gran/hooke/history`` (pair_gran_hooke_history.cpp:244-330) and
``fix wall/gran hooke/history``.

F_n = k_n delta - m* gamma_n v_n, u_n = k_n delta^2/2; the tangential spring k_t holds F_el,
u_t = |F_el|^2/(2 k_t) (J). See :class:`._lammps.LammpsLegacyModel`.
"""

from __future__ import annotations

from . import register
from ._lammps import LammpsLegacyModel


@register
class LammpsGranHookeHistory(LammpsLegacyModel):
    key = "lammps:gran/hooke/history"
    summary = "linear spring u_n = k_n delta^2/2; tangential spring u_t = |F_el|^2/(2 k_t)"
    has_spring = True
