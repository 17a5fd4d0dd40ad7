"""LIGGGHTS ``pair_style gran model hooke/hysteresis`` (``normal_model_hooke_hysteresis.h``).

The hysteretic linear spring of :mod:`._hysteresis` with k1 the ``hooke`` normal
stiffness kn(E*, R*, m*, characteristicVelocity), k2Max = kn
coefficientMaxElasticStiffness, kc = kn coefficientAdhesionStiffness and
delta_lim = k2Max/(k2Max - kn) coefficientPlasticityDepth 2 R*; the history holds
delta_max. u_n = f^2/(2 k2) (the energy given back unloading along the current
k2 line); the tangential stiffness is kt = kn, u_t = kt |shear|^2/2.
"""

from __future__ import annotations

import numpy as np

from ..moduli import effective_modulus, effective_radius
from . import register
from ._hysteresis import DELTA_MAX, hysteresis_of, unloading_energy
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows
from .liggghts_hooke import liggghts_hooke_kn


@register
class LiggghtsHookeHysteresis(LiggghtsNormalModel):
    key = "liggghts:hooke/hysteresis"
    summary = ("hysteretic spring (loading kn, unloading k2 through delta_max), u_n = f^2/(2 k2); tangential "
               "history u_t = kn |shear|^2/2")
    particle_columns = ("mass",)
    mode_columns = {**LiggghtsNormalModel.mode_columns, "u_n": (DELTA_MAX,)}
    normal_history = (DELTA_MAX,)
    parameters = {
        **LiggghtsNormalModel.parameters,
        "characteristic_velocity": (ContactLaw.REQUIRED, "characteristicVelocity V (m/s)"),
        "max_elastic_stiffness": (ContactLaw.REQUIRED, "coefficientMaxElasticStiffness k2Max/kn per type pair"),
        "adhesion_stiffness": (ContactLaw.REQUIRED, "coefficientAdhesionStiffness kc/kn per type pair"),
        "plasticity_depth": (ContactLaw.REQUIRED, "coefficientPlasticityDepth phiF per type pair"),
    }
    example_params = {"characteristic_velocity": 1.0, "max_elastic_stiffness": 2.0, "adhesion_stiffness": 0.0,
                      "plasticity_depth": 0.05}

    def check(self) -> None:
        super().check()
        for name in ("max_elastic_stiffness", "adhesion_stiffness", "plasticity_depth"):
            self.params[name] = self.table(name)

    def kn(self, rows: ContactRows) -> np.ndarray:
        """The ``hooke`` normal stiffness kn(E*, R*, m*, V) (N/m)."""
        return liggghts_hooke_kn(effective_radius(rows.r1, rows.r2), rows.per_pair(effective_modulus),
                                 rows.reduced_mass(), float(self.params["characteristic_velocity"]))

    def kt(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows)

    def force_and_k2(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray]:
        p = self.params
        return hysteresis_of(rows, self.kn(rows), p["max_elastic_stiffness"], p["adhesion_stiffness"],
                             p["plasticity_depth"])

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return unloading_energy(*self.force_and_k2(rows))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.force_and_k2(rows)[0]
