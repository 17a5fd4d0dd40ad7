"""LAMMPS ``pair_style granular`` normal model ``jkr`` (pair_granular.cpp:328-354, 1810-1820).

JKR with k_n from E and nu (as hertz/material) and E = 3/4 k_n: the contact radius a(delta) from LAMMPS' closed
form, F_ne = k_n a^3/R - 2 pi a^2 sqrt(4 gamma E/(pi a)) (N). Its elastic energy is
u_n = 8 E a^5/(15 R^2) - 4 E a^3 D/(3 R) + E a D^2 with D = a^2/R - delta, and the work of adhesion (2 gamma per
area) u_adh = -2 pi gamma a^2 (J, apart): d(u_n + u_adh)/d(delta) = F_ne. The Coulomb limit is
mu |F_ne + 6 pi gamma R|. single() writes zeros for a pair closer than its pull-off distance |delta_pulloff|
(0 < delta < |delta_pulloff|, pair_granular.cpp:1423-1437): its springs are unknown; its u_n and u_adh are of
delta. Pairs apart (delta <= 0) that may still hold a neck are not in ``cutoff radius`` rows: energies of this law
are of touching pairs. Sub-models: :mod:`._lammps`.
"""

from __future__ import annotations

import math

import numpy as np

from . import register
from ._lammps import LammpsAdhesiveModel, pi_gamma_R
from .base import ContactRows


def jkr_contact_radius(kn: float, gamma: float, delta: np.ndarray, R: np.ndarray) -> np.ndarray:
    """LAMMPS' closed-form JKR contact radius a(delta) (m), E = 3/4 k_n (pair_granular.cpp:330-346)."""
    E = 0.75 * kn
    dR = delta * R
    R2, dR2 = R * R, dR * dR
    t0 = gamma * gamma * R2 * R2 * E
    t1 = 27.0 * math.pi**2 * t0
    t2 = 8.0 * dR * dR2 * E**3
    t3 = 4.0 * dR2 * E
    t4 = np.cbrt(t1 + t2 + 3.0 * math.sqrt(3.0) * math.pi * np.sqrt(np.maximum(0.0, t0 * (t1 + 2.0 * t2))))
    t5 = t3 / t4 + t4 / E
    t6 = np.sqrt(np.maximum(0.0, 2.0 * dR + t5))
    return (
        t6 + np.sqrt(np.maximum(0.0, 4.0 * dR - t5 + 6.0 * math.sqrt(6.0) * gamma * math.pi * R2 / (E * t6)))
    ) / math.sqrt(6.0)


def jkr_pulloff_distance(kn: float, gamma: float, R: np.ndarray) -> np.ndarray:
    """delta at pull-off (m, < 0): a^2/R - 2 sqrt(pi gamma a/E) with a = (9 pi gamma R^2/(4 E))^(1/3)
    (pair_granular.cpp:1810-1820)."""
    E = 0.75 * kn
    a = np.cbrt(9.0 * math.pi * gamma * R * R / (4.0 * E))
    return a * a / R - 2.0 * np.sqrt(math.pi * gamma * a / E)


@register
class LammpsJkr(LammpsAdhesiveModel):
    key = "lammps:jkr"
    line_coefficients = ("E", "damp", "nu", "cohesion")
    summary = (
        "JKR F_ne = k_n a^3/R - 2 pi a^2 sqrt(4 gamma E/(pi a)), u_n = 8 E a^5/(15 R^2) - 4 E a^3 D/(3 R) "
        "+ E a D^2 (D = a^2/R - delta), work of adhesion u_adh = -2 pi gamma a^2"
    )

    def contact_radius(self, delta: np.ndarray, R: np.ndarray) -> np.ndarray:
        """a(delta) of LAMMPS' closed form (m)."""
        return jkr_contact_radius(self.kn, float(self.params["cohesion"]), delta, R)

    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne = k_n a^3/R - 2 pi a^2 sqrt(4 gamma E/(pi a)) (N)."""
        E = 0.75 * self.kn
        return self.kn * a**3 / R - 2.0 * math.pi * a * a * np.sqrt(
            4.0 * self.params["cohesion"] * E / (math.pi * np.where(a > 0, a, 1.0))
        )

    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n = 8 E a^5/(15 R^2) - 4 E a^3 D/(3 R) + E a D^2, D = a^2/R - delta (J)."""
        E = 0.75 * self.kn
        D = a * a / R - delta
        return 8.0 * E * a**5 / (15.0 * R * R) - 4.0 * E * a**3 * D / (3.0 * R) + E * a * D * D

    def adhesion_work(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_adh = -2 pi gamma a^2 (J)."""
        return -2.0 * math.pi * self.params["cohesion"] * a * a

    def adhesion_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """d(u_adh)/d(delta) = -4 pi gamma a da/d(delta) (N), with d(delta)/da = 2a/R - sqrt(pi gamma/(E a))
        from delta = a^2/R - 2 sqrt(pi gamma a/E)."""
        gamma, E = float(self.params["cohesion"]), 0.75 * self.kn
        safe = np.where(a > 0, a, 1.0)
        ddelta_da = 2.0 * safe / R - np.sqrt(math.pi * gamma / (E * safe))
        return np.where(a > 0, -4.0 * math.pi * gamma * safe / ddelta_da, 0.0)

    def damping_stiffness(self, a: np.ndarray) -> np.ndarray:
        """kn_fac = k_n a with jkr's a (pair_granular.cpp:347)."""
        return self.kn * a

    def coulomb_force(self, F_ne: np.ndarray, F_n: np.ndarray, R: np.ndarray) -> np.ndarray:
        """F_ncrit = |F_ne + 6 pi gamma R| (N)."""
        return np.abs(F_ne + 6.0 * pi_gamma_R(self.params["cohesion"], R))

    def reach(self, R: np.ndarray) -> np.ndarray:
        """|delta_pulloff| (m): a pair apart by less may still hold its neck (its touch flag is in no dump)."""
        return -jkr_pulloff_distance(self.kn, float(self.params["cohesion"]), R)

    def separation_limit(self, r1: np.ndarray | float, r2: np.ndarray | float) -> np.ndarray | float:
        """|delta_pulloff| of R = r1 r2/(r1 + r2) (m): the reader writes a pair apart by less as a possible neck,
        every value of which is not computed."""
        r1, r2 = np.asarray(r1, dtype=np.float64), np.asarray(r2, dtype=np.float64)
        return self.reach(1.0 / (1.0 / r1 + 1.0 / r2))

    def unwritten(self, rows: ContactRows, R: np.ndarray) -> np.ndarray:
        """Pairs with 0 < delta < |delta_pulloff|, which single() writes as zeros (module docstring)."""
        if self.params["wall"]:
            return np.zeros(len(R), dtype=bool)
        return rows.delta < -jkr_pulloff_distance(self.kn, float(self.params["cohesion"]), R)
