"""LIGGGHTS ``pair_style gran model edinburgh`` (``normal_model_edinburgh.h``), without surface energy.

The Edinburgh elasto-plastic model (Thakur et al. 2014) with n = overlapExponent:
loading F = k1 delta^n, unloading and reloading F = k2 (delta^n - delta_p^n)
through the plastic overlap delta_p, k1 = (4/3) E* sqrt(R*) (n = 1: 2 E* R*),
k2 = k1 UnloadingStiffness. On loading LIGGGHTS sets delta_p = lambda delta with
lambda = (1 - k1/k2)^(1/n), so the unloading curve passes through the current
point; the history holds the largest delta_p, the previous overlap, kc and f0.
The elastic energy is what the contact gives back along its unloading curve,

    u_n = k2 [(delta^(n+1) - dp^(n+1))/(n + 1) - dp^n (delta - dp)],  dp = min(delta_p, delta),

whose derivative is the force k2 (delta^n - dp^n) (on loading dp = lambda delta makes it k1 delta^n),

and the pull-off force f0 (pullOffForce) does the work f0 delta (u_adh, apart).
kt = 8 G* sqrt(R* delta) (n = 1: 2 E* sqrt(R* delta)); u_t = kt |shear|^2/2.
With surfaceEnergy > 0 LIGGGHTS adds an adhesive branch whose stiffness it
derives from the contact geometry step by step: refused, not approximated.
"""

from __future__ import annotations

import numpy as np

from ...errors import UnsupportedModelError
from ..elastic import overlap
from ..formulas import hertz_kt_formula
from ..moduli import effective_modulus, effective_radius, effective_shear_modulus
from . import register
from ._liggghts import LiggghtsNormalModel
from .base import ContactLaw, ContactRows

DELTA_P = "delta_p_max"
"""Contact column of the largest plastic overlap delta_p (m), the model's first history value."""


@register
class LiggghtsEdinburgh(LiggghtsNormalModel):
    key = "liggghts:edinburgh"
    summary = (
        "Edinburgh elasto-plastic (loading k1 delta^n, unloading k2 (delta^n - dp^n)), u_n = the energy "
        "given back along the unloading curve; tangential history u_t = kt |shear|^2/2"
    )
    mode_columns = {**LiggghtsNormalModel.mode_columns, "u_n": (DELTA_P,)}
    normal_history = (DELTA_P, "edinburgh_old_delta", "edinburgh_kc", "edinburgh_fo")
    parameters = {
        **LiggghtsNormalModel.parameters,
        "overlap_exponent": (ContactLaw.REQUIRED, "overlapExponent n"),
        "unloading_stiffness": (ContactLaw.REQUIRED, "UnloadingStiffness k2/k1 per type pair (> 1)"),
        "surface_energy": (0.0, "surfaceEnergy per type pair (J/m^2); only 0 is supported"),
        "pull_off_force": (0.0, "pullOffForce f0 per type pair (N)"),
    }
    example_params = {"overlap_exponent": 1.5, "unloading_stiffness": 5.0}

    def check(self) -> None:
        super().check()
        for name in ("unloading_stiffness", "surface_energy"):
            self.params[name] = self.table(name)
        if np.any(np.asarray(self.params["surface_energy"]) != 0):
            raise UnsupportedModelError(
                f"{self.key} with surfaceEnergy > 0 is not supported: LIGGGHTS then derives an adhesive branch "
                "from the contact geometry step by step, whose elastic energy demsplit cannot rebuild from a dump.",
                fix="analyse a run with surfaceEnergy 0, or leave this run out.",
            )
        if np.any(np.asarray(self.params["unloading_stiffness"]) <= 1):
            raise UnsupportedModelError(
                f"{self.key}: UnloadingStiffness must exceed 1 (k2 > k1), got {self.params['unloading_stiffness']!r}."
            )
        self.params["overlap_exponent"] = float(self.params["overlap_exponent"])
        if not self.params["overlap_exponent"] > 0:
            raise UnsupportedModelError(f"{self.key}: overlapExponent must be > 0.")

    def k1(self, rows: ContactRows) -> np.ndarray:
        """Loading stiffness (N/m^n): (4/3) E* sqrt(R*), or 2 E* R* for n = 1."""
        E, R = rows.per_pair(effective_modulus), effective_radius(rows.r1, rows.r2)
        return 2.0 * E * R if self.params["overlap_exponent"] == 1 else (4.0 / 3.0) * E * np.sqrt(R)

    def kn(self, rows: ContactRows) -> np.ndarray:
        return np.broadcast_to(self.k1(rows), rows.delta.shape)

    def kt(self, rows: ContactRows) -> np.ndarray:
        d, R = overlap(rows.delta), effective_radius(rows.r1, rows.r2)
        if self.params["overlap_exponent"] == 1:
            return 2.0 * rows.per_pair(effective_modulus) * np.sqrt(R * d)
        return hertz_kt_formula(d, R, rows.per_pair(effective_shear_modulus))

    def curve(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """(delta, dp, k2, n): the overlap, the plastic overlap of the current unloading curve, k2."""
        n = self.params["overlap_exponent"]
        k1 = self.k1(rows)
        k2 = k1 * rows.type_pair(self.params["unloading_stiffness"])
        d = overlap(rows.delta)
        return d, np.minimum(rows.column(DELTA_P), d), k2, n

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        d, dp, k2, n = self.curve(rows)
        return k2 * ((d ** (n + 1) - dp ** (n + 1)) / (n + 1) - dp**n * (d - dp))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d, dp, k2, n = self.curve(rows)
        return k2 * (d**n - dp**n)
