"""LAMMPS ``pair_style granular`` normal model ``dmt`` (pair_granular.cpp:357-358, 416).

Hertz with k_n from E and nu (as hertz/material) and a constant adhesive force: F_ne = k_n a delta - 4 pi gamma R
(N). The elastic energy is Hertz's, u_n = 2/5 k_n a delta^2, and the adhesion's work u_adh = -4 pi gamma R delta
(J, apart), so that d(u_n + u_adh)/d(delta) = F_ne. The Coulomb limit is documented as mu |F_ne + 8 pi gamma R|,
but the code reads gamma from a variable only jkr sets (pair_granular.cpp:416, single :1589): the limit of the
first pair row single() writes in a frame is whatever memory held, and a row at the limit holds a spring no dump
gives (measured, ``docs/lammps-output.md``). Sub-models: :mod:`._lammps`.
"""

from __future__ import annotations

import numpy as np

from . import register
from ._lammps import DUMP_ROW, LammpsAdhesiveModel, hertz_energy, pi_gamma_R
from .base import ContactRows


@register
class LammpsDmt(LammpsAdhesiveModel):
    key = "lammps:dmt"
    line_coefficients = ("E", "damp", "nu", "cohesion")
    summary = (
        "DMT F_ne = k_n a delta - 4 pi gamma R, u_n = 2/5 k_n a delta^2, work of adhesion u_adh = -4 pi gamma R delta"
    )

    def elastic_normal_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """F_ne = k_n a delta - 4 pi gamma R (N)."""
        return self.kn * a * delta - 4.0 * pi_gamma_R(self.params["cohesion"], R)

    def normal_energy(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_n = 2/5 k_n a delta^2 (J)."""
        return hertz_energy(self.kn, delta, a)

    def adhesion_work(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """u_adh = -4 pi gamma R delta (J)."""
        return -4.0 * pi_gamma_R(self.params["cohesion"], R) * delta

    def adhesion_force(self, delta: np.ndarray, R: np.ndarray, a: np.ndarray) -> np.ndarray:
        """d(u_adh)/d(delta) = -4 pi gamma R (N)."""
        return -4.0 * pi_gamma_R(self.params["cohesion"], R)

    def coulomb_force(self, F_ne: np.ndarray, F_n: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The documented F_ncrit = |F_ne + 8 pi gamma R| (N), which decides which rows single() capped."""
        return np.abs(F_ne + 8.0 * pi_gamma_R(self.params["cohesion"], R))

    def stale_limit(self, rows: ContactRows, capped: np.ndarray) -> np.ndarray:
        """The first pair row of the frame's dump and every pair row at its limit (module docstring); a wall's
        dumped force is the step's, whose spring is known whatever its limit was."""
        if self.params["wall"]:
            return np.zeros(len(capped), dtype=bool)
        return capped | (rows.column(DUMP_ROW) == 0) if rows.has(DUMP_ROW) else capped
