"""The power-law contact F = k delta^n of the paper (eq. 25): a law given explicitly, not read from a run.

u_n = k delta^(n+1)/(n+1) (J) for n > 0: n = 1 is a linear spring, n = 3/2
with k = (4/3) E* sqrt(R*) is Hertz. It has no tangential spring.
"""

from __future__ import annotations

import numpy as np

from ...errors import ContactError
from ..elastic import overlap, power_law_energy
from . import register
from .base import ContactLaw, ContactRows, LawEnergy


@register
class PowerLaw(ContactLaw):
    key = "demsplit:power_law"
    summary = "power law F = k delta^n, u_n = k delta^(n+1)/(n+1), no tangential spring"
    modes = ("u_n",)
    parameters = {"k": (ContactLaw.REQUIRED, "stiffness k (N/m^n)"), "n": (ContactLaw.REQUIRED, "exponent n > 0")}
    example_params = {"k": 1e7, "n": 1.5}

    def check(self) -> None:
        if not (float(self.params["n"]) > 0 and float(self.params["k"]) >= 0):
            raise ContactError(
                f"{self.key} needs n > 0 and k >= 0, got n = {self.params['n']!r}, k = {self.params['k']!r}."
            )

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        return LawEnergy({"u_n": power_law_energy(rows.delta, self.params["k"], self.params["n"])})

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return float(self.params["k"]) * overlap(rows.delta) ** float(self.params["n"])
