"""LIGGGHTS ``pair_style gran model hooke/stiffness`` (``normal_model_hooke_stiffness.h``).

A linear spring with the stiffnesses given per pair of types (``fix
property/global kn|kt peratomtypepair``, N/m): F_n = kn delta, u_n = kn delta^2/2;
tangential history u_t = kt |shear|^2/2.
"""

from __future__ import annotations

import numpy as np

from ..elastic import hooke_energy, overlap
from . import register
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows


@register
class LiggghtsHookeStiffness(LiggghtsNormalModel):
    key = "liggghts:hooke/stiffness"
    summary = "linear spring with given stiffness, u_n = kn delta^2/2; tangential history u_t = kt |shear|^2/2"
    parameters = {
        **LiggghtsNormalModel.parameters,
        "kn": (ContactLaw.REQUIRED, "kn per type pair (N/m)"),
        "kt": (ContactLaw.REQUIRED, "kt per type pair (N/m)"),
    }
    example_params = {
        "kn": ((2e5, 3e5, 2.5e5), (3e5, 4e5, 3.5e5), (2.5e5, 3.5e5, 5e5)),
        "kt": ((1e5, 1.5e5, 1.2e5), (1.5e5, 2e5, 1.7e5), (1.2e5, 1.7e5, 2.5e5)),
    }

    def check(self) -> None:
        super().check()
        self.params["kn"], self.params["kt"] = self.table("kn"), self.table("kt")

    def kn(self, rows: ContactRows) -> np.ndarray:
        return np.broadcast_to(rows.type_pair(self.params["kn"]), rows.delta.shape)

    def kt(self, rows: ContactRows) -> np.ndarray:
        return np.broadcast_to(rows.type_pair(self.params["kt"]), rows.delta.shape)

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return hooke_energy(rows.delta, self.kn(rows))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows) * overlap(rows.delta)
