"""LIGGGHTS ``pair_style gran model hertz`` (``normal_model_hertz.h``).

Normal force F_n = kn delta with kn = (4/3) E* sqrt(R* delta), i.e.
F_n = (4/3) E* sqrt(R*) delta^(3/2), energy u_n = (8/15) E* sqrt(R* delta) delta^2
(eq. 13). The model sets kt = 8 G* sqrt(R* delta) for ``tangential history``:
u_t = kt |shear|^2 / 2. E*, G*, R* as LIGGGHTS builds them from the two types'
youngsModulus and poissonsRatio and the radii (``global_properties.cpp``).
"""

from __future__ import annotations

import numpy as np

from ..elastic import hertz_energy_from_moduli, hertz_force_from_moduli, history_spring_energy, overlap
from ..formulas import hertz_kt_formula
from ..moduli import curvature_error, effective_modulus, effective_radius, effective_shear_modulus
from . import register
from ._liggghts import SHEAR, LiggghtsNormalModel
from .base import ContactRows


@register
class LiggghtsHertz(LiggghtsNormalModel):
    key = "liggghts:hertz"
    summary = ("Hertz u_n = (8/15) E* sqrt(R* delta) delta^2; tangential history u_t = kt |shear|^2/2 with "
               "kt = 8 G* sqrt(R* delta)")
    compiled = True

    def normal_and_tangential(self, rows: ContactRows, with_shear: bool, compiled: bool) -> dict[str, np.ndarray]:
        if compiled:  # one pass over the contacts (demsplit.kernels)
            from ...kernels import hertz_history_energies

            shear = [rows.column(c) for c in SHEAR] if with_shear else [rows.delta] * 3
            E_eff, code = rows.pair_values(effective_modulus)
            G_eff = rows.pair_values(effective_shear_modulus)[0] if with_shear else E_eff
            u_n, u_t, bad = hertz_history_energies(rows.delta, rows.r1, rows.r2, E_eff, G_eff, code, *shear,
                                                   with_shear)
            if bad >= 0:
                raise curvature_error()
        else:
            u_n = self.normal_energy(rows)
            if with_shear:
                u_t = history_spring_energy(rows.delta, self.shear(rows), self.kt(rows))
        return {"u_n": u_n, "u_t": u_t} if with_shear else {"u_n": u_n}

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return hertz_energy_from_moduli(rows.delta, effective_radius(rows.r1, rows.r2),
                                        rows.per_pair(effective_modulus))

    def kn(self, rows: ContactRows) -> np.ndarray:
        """kn = (4/3) E* sqrt(R* delta) (N/m), ``normal_model_hertz.h``."""
        return (4.0 / 3.0) * rows.per_pair(effective_modulus) * np.sqrt(effective_radius(rows.r1, rows.r2)
                                                                        * overlap(rows.delta))

    def kt(self, rows: ContactRows) -> np.ndarray:
        """kt = 8 G* sqrt(R* delta) (N/m), ``normal_model_hertz.h``."""
        return hertz_kt_formula(overlap(rows.delta), effective_radius(rows.r1, rows.r2),
                                rows.per_pair(effective_shear_modulus))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return hertz_force_from_moduli(rows.delta, effective_radius(rows.r1, rows.r2),
                                       rows.per_pair(effective_modulus))
