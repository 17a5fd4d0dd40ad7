"""LIGGGHTS ``pair_style gran model hooke/hysteresis`` (``normal_model_hooke_hysteresis.h``).

The hysteretic linear spring of :mod:`._hysteresis` with k1 the ``hooke`` normal
stiffness kn(E*, R*, m*, characteristicVelocity), k2Max = kn
coefficientMaxElasticStiffness, kc = kn coefficientAdhesionStiffness and
delta_lim = k2Max/(k2Max - kn) coefficientPlasticityDepth 2 R*; the history holds
delta_max. u_n = f^2/(2 k2) (the energy given back unloading along the current
k2 line); the tangential stiffness is kt = kn, u_t = kt |shear|^2/2. The force it
applies is damped with gamma_n = gamma_t = sqrt(4 m* kn/(1 + (pi/ln e)^2)), hooke's coefficient as
``normal_model_hooke_hysteresis.h:139-200`` writes it. The elastic force f of a contact gives its
delta_max back (:func:`~._hysteresis.delta_max_of_force`).
"""

from __future__ import annotations

import numpy as np

from ..moduli import effective_modulus, effective_radius
from . import register
from ._hysteresis import DELTA_MAX, delta_max_of_force, hysteresis_of, hysteresis_parameters, unloading_energy
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows
from .liggghts_hooke import liggghts_hooke_kn


def hooke_hysteresis_damping(kn: np.ndarray, m_eff: np.ndarray, restitution: np.ndarray | float) -> np.ndarray:
    """LIGGGHTS hooke/hysteresis's damping coefficient (kg/s), normal and tangential:
    sqrt(4 m* kn/(1 + (pi/ln e)^2)), kn (N/m), m* (kg), e the coefficient of restitution."""
    ratio = np.pi / np.log(restitution)
    return np.sqrt(4.0 * m_eff * kn / (1.0 + ratio * ratio))


@register
class LiggghtsHookeHysteresis(LiggghtsNormalModel):
    key = "liggghts:hooke/hysteresis"
    summary = (
        "hysteretic spring (loading kn, unloading k2 through delta_max), u_n = f^2/(2 k2); tangential "
        "history u_t = kn |shear|^2/2"
    )
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
    example_params = {
        "characteristic_velocity": 1.0,
        "max_elastic_stiffness": 2.0,
        "adhesion_stiffness": 0.0,
        "plasticity_depth": 0.05,
    }
    applied_force = True

    def check(self) -> None:
        super().check()
        for name in ("max_elastic_stiffness", "adhesion_stiffness", "plasticity_depth"):
            self.params[name] = self.table(name)

    def kn(self, rows: ContactRows) -> np.ndarray:
        """The ``hooke`` normal stiffness kn(E*, R*, m*, V) (N/m)."""
        return liggghts_hooke_kn(
            effective_radius(rows.r1, rows.r2),
            rows.per_pair(effective_modulus),
            rows.reduced_mass(),
            float(self.params["characteristic_velocity"]),
        )

    def kt(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows)

    def force_and_k2(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray]:
        p = self.params
        return hysteresis_of(
            rows, self.kn(rows), p["max_elastic_stiffness"], p["adhesion_stiffness"], p["plasticity_depth"]
        )

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return unloading_energy(*self.force_and_k2(rows))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.force_and_k2(rows)[0]

    def damping(self, rows: ContactRows, restitution: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """gamma_n = gamma_t (kg/s) of :func:`hooke_hysteresis_damping`."""
        gamma = hooke_hysteresis_damping(self.kn(rows), rows.reduced_mass(), restitution)
        return gamma, gamma

    def normal_history_of_force(self, rows: ContactRows, f: np.ndarray) -> dict[str, np.ndarray]:
        """delta_max (m) of every row whose elastic normal force is ``f`` (N):
        :func:`~._hysteresis.delta_max_of_force`."""
        p = self.params
        k1 = self.kn(rows)
        k2max, _, lim = hysteresis_parameters(
            rows, k1, p["max_elastic_stiffness"], p["adhesion_stiffness"], p["plasticity_depth"]
        )
        return {DELTA_MAX: delta_max_of_force(f, rows.delta, k1, k2max, lim)}
