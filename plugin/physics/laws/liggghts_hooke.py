"""LIGGGHTS ``pair_style gran model hooke`` (``normal_model_hooke.h``).

A linear spring F_n = kn delta whose stiffness LIGGGHTS derives from the
materials, the radii, the masses and the ``characteristicVelocity`` V:

    kn = (16/15) sqrt(R*) E* (15 m* V^2 / (16 sqrt(R*) E*))^(1/5),

m* = m1 m2/(m1 + m2) (m* = m1 on a wall); u_n = kn delta^2 / 2. With
``tangential history`` kt = kn (``ktToKnUser on``: kt = 2/7 kn) and
u_t = kt |shear|^2 / 2. The force it applies is damped with
gamma_n = gamma_t = sqrt(4 m* kn ln^2 e/(ln^2 e + pi^2)) (``normal_model_hooke.h:269-292``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..elastic import hooke_energy, overlap
from ..moduli import effective_modulus, effective_radius, f64
from . import register
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows


def liggghts_hooke_kn(R_eff: ArrayLike, E_eff: ArrayLike, m_eff: ArrayLike, v_char: float) -> np.ndarray:
    """LIGGGHTS ``model hooke`` normal stiffness (N/m):
    kn = (16/15) sqrt(R*) E* (15 m* V^2 / (16 sqrt(R*) E*))^(1/5), V = ``characteristicVelocity`` (m/s)."""
    sqR = np.sqrt(f64(R_eff))
    E_eff = f64(E_eff)
    return (16.0 / 15.0) * sqR * E_eff * (15.0 * f64(m_eff) * v_char**2 / (16.0 * sqR * E_eff)) ** 0.2


def hooke_damping(kn: np.ndarray, m_eff: np.ndarray, restitution: np.ndarray | float) -> np.ndarray:
    """LIGGGHTS hooke's damping coefficient (kg/s) for both the normal and the tangential force:
    sqrt(4 m* kn ln^2 e/(ln^2 e + pi^2)), kn (N/m), m* (kg), e the coefficient of restitution."""
    log_e_sq = np.log(restitution) ** 2
    return np.sqrt(4.0 * m_eff * kn * log_e_sq / (log_e_sq + np.pi * np.pi))


@register
class LiggghtsHooke(LiggghtsNormalModel):
    key = "liggghts:hooke"
    summary = (
        "linear spring u_n = kn delta^2/2 with kn(E*, R*, m*, characteristicVelocity); tangential "
        "history u_t = kt |shear|^2/2 with kt = kt_to_kn kn"
    )
    particle_columns = ("mass",)
    parameters = {
        **LiggghtsNormalModel.parameters,
        "characteristic_velocity": (ContactLaw.REQUIRED, "characteristicVelocity V (m/s)"),
        "kt_to_kn": (1.0, "kt/kn: 1, or 2/7 with ktToKnUser on"),
    }
    example_params = {"characteristic_velocity": 1.0}
    applied_force = True

    def kn(self, rows: ContactRows) -> np.ndarray:
        """Normal stiffness of every row (N/m)."""
        return liggghts_hooke_kn(
            effective_radius(rows.r1, rows.r2),
            rows.per_pair(effective_modulus),
            rows.reduced_mass(),
            float(self.params["characteristic_velocity"]),
        )

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return hooke_energy(rows.delta, self.kn(rows))

    def kt(self, rows: ContactRows) -> np.ndarray:
        """kt = kt_to_kn kn (N/m)."""
        return self.params["kt_to_kn"] * self.kn(rows)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows) * overlap(rows.delta)

    def damping(self, rows: ContactRows, restitution: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """gamma_n = gamma_t (kg/s) of :func:`hooke_damping`."""
        gamma = hooke_damping(self.kn(rows), rows.reduced_mass(), restitution)
        return gamma, gamma
