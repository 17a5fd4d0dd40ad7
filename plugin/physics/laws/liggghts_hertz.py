"""LIGGGHTS ``pair_style gran model hertz`` (``normal_model_hertz.h``).

Normal force F_n = kn delta with kn = (4/3) E* sqrt(R* delta), i.e.
F_n = (4/3) E* sqrt(R*) delta^(3/2), energy u_n = (8/15) E* sqrt(R* delta) delta^2
(eq. 13). The model sets kt = 8 G* sqrt(R* delta) for ``tangential history``:
u_t = kt |shear|^2 / 2. E*, G*, R* as LIGGGHTS builds them from the two types'
youngsModulus and poissonsRatio and the radii (``global_properties.cpp``).

The force it applies is damped (:meth:`LiggghtsHertz.damping`, ``normal_model_hertz.h:231-263``):
gamma = -2 sqrt(5/6) beta sqrt(S m*), S_n = 2 E* sqrt(R* delta), S_t = kt, with
beta = ln e/sqrt(ln^2 e + pi^2) of the coefficient of restitution e (``global_properties.cpp:516, 539``).
"""

from __future__ import annotations

import numpy as np

from ..elastic import hertz_energy_from_moduli, hertz_force_from_moduli, history_spring_energy, overlap
from ..formulas import hertz_kt_formula
from ..moduli import curvature_error, effective_modulus, effective_radius, effective_shear_modulus
from . import register
from ._liggghts import SHEAR, LiggghtsNormalModel
from .base import ContactRows

SQRT_FIVE_OVER_SIX = 0.91287092917527685576161630466800355658790782499663875
"""sqrt(5/6), as ``normal_model_hertz.h`` writes it."""


def hertz_damping(stiffness: np.ndarray, m_eff: np.ndarray, restitution: np.ndarray | float) -> np.ndarray:
    """LIGGGHTS hertz's damping coefficient (kg/s) of a stiffness S (N/m; S_n = 2 E* sqrt(R* delta) for the normal
    force, S_t = kt for the tangential one): -2 sqrt(5/6) beta sqrt(S m*), beta = ln e/sqrt(ln^2 e + pi^2), with
    m* (kg) and the coefficient of restitution e."""
    log_e = np.log(restitution)
    beta = log_e / np.sqrt(log_e**2 + np.pi**2)
    return -2.0 * SQRT_FIVE_OVER_SIX * beta * np.sqrt(stiffness * m_eff)


@register
class LiggghtsHertz(LiggghtsNormalModel):
    key = "liggghts:hertz"
    summary = (
        "Hertz u_n = (8/15) E* sqrt(R* delta) delta^2; tangential history u_t = kt |shear|^2/2 with "
        "kt = 8 G* sqrt(R* delta)"
    )
    compiled = True
    applied_force = True

    def normal_and_tangential(self, rows: ContactRows, with_shear: bool, compiled: bool) -> dict[str, np.ndarray]:
        if compiled:  # one pass over the contacts (demsplit.kernels)
            from ...kernels import hertz_history_energies

            shear = [rows.column(c) for c in SHEAR] if with_shear else [rows.delta] * 3
            E_eff, code = rows.pair_values(effective_modulus)
            G_eff = rows.pair_values(effective_shear_modulus)[0] if with_shear else E_eff
            u_n, u_t, bad = hertz_history_energies(rows.delta, rows.r1, rows.r2, E_eff, G_eff, code, *shear, with_shear)
            if bad >= 0:
                raise curvature_error()
        else:
            u_n = self.normal_energy(rows)
            if with_shear:
                u_t = history_spring_energy(rows.delta, self.shear(rows), self.kt(rows))
        return {"u_n": u_n, "u_t": u_t} if with_shear else {"u_n": u_n}

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return hertz_energy_from_moduli(
            rows.delta, effective_radius(rows.r1, rows.r2), rows.per_pair(effective_modulus)
        )

    def kn(self, rows: ContactRows) -> np.ndarray:
        """kn = (4/3) E* sqrt(R* delta) (N/m), ``normal_model_hertz.h``."""
        return (
            (4.0 / 3.0)
            * rows.per_pair(effective_modulus)
            * np.sqrt(effective_radius(rows.r1, rows.r2) * overlap(rows.delta))
        )

    def kt(self, rows: ContactRows) -> np.ndarray:
        """kt = 8 G* sqrt(R* delta) (N/m), ``normal_model_hertz.h``."""
        return hertz_kt_formula(
            overlap(rows.delta), effective_radius(rows.r1, rows.r2), rows.per_pair(effective_shear_modulus)
        )

    def damping(self, rows: ContactRows, restitution: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """gamma_n, gamma_t (kg/s) of :func:`hertz_damping` (module docstring)."""
        m_eff = rows.reduced_mass()
        s_n = 2.0 * rows.per_pair(effective_modulus) * np.sqrt(effective_radius(rows.r1, rows.r2) * overlap(rows.delta))
        return hertz_damping(s_n, m_eff, restitution), hertz_damping(self.kt(rows), m_eff, restitution)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return hertz_force_from_moduli(rows.delta, effective_radius(rows.r1, rows.r2), rows.per_pair(effective_modulus))
