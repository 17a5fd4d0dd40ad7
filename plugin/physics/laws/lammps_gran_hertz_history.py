"""LAMMPS legacy ``pair_style gran/hertz/history`` (pair_gran_hertz_history.cpp:183-236) and
``fix wall/gran hertz/history`` (fix_wall_gran.cpp:1020: R with the wall's curvature).

With p = sqrt(R delta): F_n = p (k_n delta - m* gamma_n v_n), u_n = 2/5 k_n sqrt(R) delta^(5/2); the tangential
spring p k_t holds F_el, u_t = |F_el|^2/(2 p k_t) (J). See :class:`._lammps.LammpsLegacyModel`.
"""

from __future__ import annotations

from . import register
from ._lammps import LammpsLegacyModel


@register
class LammpsGranHertzHistory(LammpsLegacyModel):
    key = "lammps:gran/hertz/history"
    summary = "Hertz u_n = 2/5 k_n sqrt(R) delta^(5/2); tangential spring u_t = |F_el|^2/(2 p k_t), p = sqrt(R delta)"
    has_spring = True
    hertzian = True
