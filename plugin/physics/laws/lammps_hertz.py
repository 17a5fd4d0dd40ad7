"""LAMMPS ``pair_style granular`` normal model ``hertz`` (pair_granular.cpp:357-358).

F_ne = k_n a delta with a = sqrt(R delta) and the line's k_n (N/m^(3/2)); u_n = 2/5 k_n a delta^2 (J), whose
derivative is F_ne. The line holds no E and nu: the split takes them from ``--material``. Sub-models:
:mod:`._lammps`.
"""

from __future__ import annotations

import numpy as np

from . import register
from ._lammps import LammpsModel, hertz_energy
from .base import ContactLaw


@register
class LammpsHertz(LammpsModel):
    key = "lammps:hertz"
    line_coefficients = ("kn", "damp")
    summary = "Hertz F_ne = k_n a delta, u_n = 2/5 k_n a delta^2 (a = sqrt(R delta))"
    parameters = {"kn": (ContactLaw.REQUIRED, "normal stiffness k_n (N/m^(3/2))"), **LammpsModel.parameters}
    example_params = {"kn": 1e9, **LammpsModel.example_params, "kt": 8e8}

    def normal_coefficient(self) -> float:
        return float(self.params["kn"])

    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne = k_n a delta (N)."""
        return self.kn * a * delta

    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n = 2/5 k_n a delta^2 (J)."""
        return hertz_energy(self.kn, delta, a)
