"""LAMMPS ``pair_style granular`` normal model ``hertz/material`` (pair_granular.cpp:357-358, 1006-1016).

Hertz with k_n from the line's E and nu: k_n = 4/3 E/(2(1 - nu^2)) for a pair (a ``pair_coeff i i`` line of one
material gives the Hertz 4/3 E* of two bodies of it), 4/3 E/(2(1 - nu)) for a wall (fix_wall_gran.cpp:171);
F_ne = k_n a delta, u_n = 2/5 k_n a delta^2 (J). Sub-models: :mod:`._lammps`.
"""

from __future__ import annotations

import numpy as np

from . import register
from ._lammps import LammpsMaterialModel, hertz_energy


@register
class LammpsHertzMaterial(LammpsMaterialModel):
    key = "lammps:hertz/material"
    line_coefficients = ("E", "damp", "nu")
    summary = "Hertz F_ne = k_n a delta, k_n = 4/3 E/(2(1 - nu^2)), u_n = 2/5 k_n a delta^2"

    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne = k_n a delta (N)."""
        return self.kn * a * delta

    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n = 2/5 k_n a delta^2 (J)."""
        return hertz_energy(self.kn, delta, a)
