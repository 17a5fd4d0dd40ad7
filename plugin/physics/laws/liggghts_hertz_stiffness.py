"""LIGGGHTS ``pair_style gran model hertz/stiffness`` (``normal_model_hertz_stiffness.h``).

Hertz with the stiffnesses given per pair of types (``fix property/global kn|kt
peratomtypepair``) instead of built from the materials: kn_c = kn sqrt(R* delta),
F_n = kn sqrt(R*) delta^(3/2), so u_n = (2/5) kn sqrt(R*) delta^(5/2); the
tangential spring has kt_c = kt sqrt(R* delta): u_t = kt_c |shear|^2/2.
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap
from ..moduli import effective_radius
from . import register
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows


@register
class LiggghtsHertzStiffness(LiggghtsNormalModel):
    key = "liggghts:hertz/stiffness"
    summary = (
        "Hertz with given stiffness, u_n = (2/5) kn sqrt(R*) delta^(5/2); tangential history "
        "u_t = kt sqrt(R* delta) |shear|^2/2"
    )
    parameters = {
        **LiggghtsNormalModel.parameters,
        "kn": (ContactLaw.REQUIRED, "kn per type pair (N/m^(3/2))"),
        "kt": (ContactLaw.REQUIRED, "kt per type pair (N/m^(3/2))"),
    }
    example_params = {
        "kn": ((2e9, 3e9, 2.5e9), (3e9, 4e9, 3.5e9), (2.5e9, 3.5e9, 5e9)),
        "kt": ((1e9, 1.5e9, 1.2e9), (1.5e9, 2e9, 1.7e9), (1.2e9, 1.7e9, 2.5e9)),
    }

    def check(self) -> None:
        super().check()
        self.params["kn"], self.params["kt"] = self.table("kn"), self.table("kt")

    def root(self, rows: ContactRows) -> np.ndarray:
        """sqrt(R* delta) (m)."""
        return np.sqrt(effective_radius(rows.r1, rows.r2) * overlap(rows.delta))

    def kn(self, rows: ContactRows) -> np.ndarray:
        return rows.type_pair(self.params["kn"]) * self.root(rows)

    def kt(self, rows: ContactRows) -> np.ndarray:
        return rows.type_pair(self.params["kt"]) * self.root(rows)

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return 0.4 * self.kn(rows) * overlap(rows.delta) ** 2

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows) * overlap(rows.delta)
