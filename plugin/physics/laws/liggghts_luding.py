"""LIGGGHTS ``pair_style gran model luding`` (``normal_model_luding.h``).

Luding's hysteretic spring (:mod:`._hysteresis`) with its own stiffnesses per
pair of types: k1 = LoadingStiffness (N/m), k2Max = k1 UnloadingStiffness,
kc = k1 coefficientAdhesionStiffness, delta_lim = k2Max/(k2Max - k1)
coefficientPlasticityDepth 2 R*, plus a constant pull-off force f0
(pullOffForce, N). u_n = f^2/(2 k2) (the energy given back unloading along the
current k2 line); the pull-off force's work f0 delta is cohesion work (u_adh,
apart from the elastic total). kt = k1: u_t = k1 |shear|^2/2. The history holds
delta_max, then kc and f0 (for ``tangential tan_luding``).
"""

from __future__ import annotations

import numpy as np

from . import register
from ._hysteresis import DELTA_MAX, hysteresis_of, unloading_energy
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows


@register
class LiggghtsLuding(LiggghtsNormalModel):
    key = "liggghts:luding"
    summary = (
        "Luding hysteretic spring (loading k1, unloading k2 through delta_max), u_n = f^2/(2 k2); "
        "tangential history u_t = k1 |shear|^2/2; pull-off work f0 delta in u_adh"
    )
    mode_columns = {**LiggghtsNormalModel.mode_columns, "u_n": (DELTA_MAX,)}
    normal_history = (DELTA_MAX, "luding_kc", "luding_fo")
    parameters = {
        **LiggghtsNormalModel.parameters,
        "loading_stiffness": (ContactLaw.REQUIRED, "LoadingStiffness k1 per type pair (N/m)"),
        "unloading_stiffness": (ContactLaw.REQUIRED, "UnloadingStiffness k2Max/k1 per type pair"),
        "adhesion_stiffness": (ContactLaw.REQUIRED, "coefficientAdhesionStiffness kc/k1 per type pair"),
        "plasticity_depth": (ContactLaw.REQUIRED, "coefficientPlasticityDepth phiF per type pair"),
        "pull_off_force": (ContactLaw.REQUIRED, "pullOffForce f0 per type pair (N)"),
    }
    example_params = {
        "loading_stiffness": 1e5,
        "unloading_stiffness": 2.0,
        "adhesion_stiffness": 0.0,
        "plasticity_depth": 0.05,
        "pull_off_force": 0.0,
    }

    def check(self) -> None:
        super().check()
        for name in ("loading_stiffness", "unloading_stiffness", "adhesion_stiffness", "plasticity_depth"):
            self.params[name] = self.table(name)

    def kn(self, rows: ContactRows) -> np.ndarray:
        return np.broadcast_to(rows.type_pair(self.params["loading_stiffness"]), rows.delta.shape)

    def kt(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows)

    def force_and_k2(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray]:
        p = self.params
        return hysteresis_of(
            rows, self.kn(rows), p["unloading_stiffness"], p["adhesion_stiffness"], p["plasticity_depth"]
        )

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return unloading_energy(*self.force_and_k2(rows))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.force_and_k2(rows)[0]
