"""LAMMPS ``pair_style granular`` normal model ``hooke`` (pair_granular.cpp:355-356).

A linear spring of the line's k_n: F_ne = k_n delta (N), u_n = k_n delta^2/2 (J); tsuji damping uses
kn_fac = k_n. The line holds no E and nu: the split takes them from ``--material`` (and ``--wall-material``).
Sub-models: :mod:`._lammps`.
"""

from __future__ import annotations

import numpy as np

from . import register
from ._lammps import LammpsModel
from .base import ContactLaw


@register
class LammpsHooke(LammpsModel):
    key = "lammps:hooke"
    line_coefficients = ("kn", "damp")
    summary = "linear spring F_ne = k_n delta, u_n = k_n delta^2/2"
    parameters = {"kn": (ContactLaw.REQUIRED, "normal stiffness k_n (N/m)"), **LammpsModel.parameters}
    example_params = {"kn": 1e5, **LammpsModel.example_params, "tangential": "linear_history", "kt": 4e4}

    def normal_coefficient(self) -> float:
        return float(self.params["kn"])

    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne = k_n delta (N)."""
        return self.kn * delta

    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n = k_n delta^2/2 (J)."""
        return 0.5 * self.kn * delta * delta

    def damping_stiffness(self, a: np.ndarray) -> np.ndarray:
        """kn_fac = k_n (pair_granular.cpp:356)."""
        return np.full_like(a, self.kn)
