"""LIGGGHTS ``pair_style gran model thornton_ning`` (``normal_model_thornton_ning.h``), without surface energy.

Thornton and Ning's elasto-plastic sphere model. LIGGGHTS integrates its
force step by step, f += df, with the slope df/d(delta) at the new overlap:
2 E* sqrt(R* delta) while elastic (the Hertzian slope), 2 E* a_y on plastic
loading once the contact radius reached a_y = coefficientYieldRatio r_i; on
unloading and reloading below the largest overlap the slope is Hertzian
again (with surfaceEnergy 0 the source's modified radius R_p equals R*), and
a force that would turn negative is set to 0 until the overlap comes back.
The force is therefore path dependent: not a function of delta. Its history
holds, per contact, the overlap delta_h and the force f_h it wrote at its
last evaluation (at an output step, the dumped overlap and normal force).

The elastic energy is what the contact gives back unloading from there along
its Hertzian branch f(s) = f_h + k (s^(3/2) - delta_h^(3/2)), k = (4/3) E* sqrt(R*),
to zero force at s0 = (delta_h^(3/2) - f_h/k)^(2/3) (or to separation, s0 = 0,
when f_h exceeds k delta_h^(3/2)): with C = f_h - k delta_h^(3/2),

    u_n = int_s0^delta f(s) ds = C delta + (2/5) k delta^(5/2)                         (C >= 0),
    u_n = k (u - v)^2 (2/5 u^3 + 4/5 u^2 v + 6/5 u v^2 + 3/5 v^3)                     (C < 0),

u = sqrt(delta), v = sqrt(s0), u - v = (f(delta)/k)/(u^2 + u v + v^2): the
integral k [(delta^(5/2) - s0^(5/2))/(5/2) - s0^(3/2) (delta - s0)] factored so
that it does not cancel for a nearly unloaded contact, and is exactly 0 for a
detached one (f_h = 0). Its derivative in delta along the branch is the force
f(delta) (f_h at the dumped overlap). kt = 8 G* sqrt(R* delta), u_t = kt |shear|^2/2. The model
sets no normal stiffness kn for the sub-models (``sidata.kn`` is never
assigned), so ``rolling_friction epsd|epsd3`` (kr from kn) is refused; with
surfaceEnergy > 0 its adhesive (JKR) branch is refused (see :meth:`check`).
"""

from __future__ import annotations

import numpy as np

from ...errors import UnsupportedModelError
from ..elastic import overlap
from ..formulas import hertz_kt_formula
from ..moduli import effective_modulus, effective_radius, effective_shear_modulus
from . import register
from ._liggghts import LiggghtsNormalModel
from .base import ContactRows

DELTA_OLD = "tn_delta_old"
"""Contact column of the overlap at the model's last evaluation, delta_h (m)."""
FORCE_OLD = "tn_force_old"
"""Contact column of the normal force at the model's last evaluation, f_h (N)."""


@register
class LiggghtsThorntonNing(LiggghtsNormalModel):
    key = "liggghts:thornton_ning"
    summary = (
        "Thornton-Ning elasto-plastic (force integrated step by step), u_n = the energy given back along "
        "the Hertzian unloading branch from the stored force; tangential history u_t = kt |shear|^2/2 "
        "with kt = 8 G* sqrt(R* delta)"
    )
    mode_columns = {**LiggghtsNormalModel.mode_columns, "u_n": (DELTA_OLD, FORCE_OLD)}
    normal_history = (
        "tn_virgin_flag",
        DELTA_OLD,
        "tn_delta_max",
        FORCE_OLD,
        "tn_force_max",
        "tn_adhesion_flag",
        "tn_detaching_delta",
        "tn_detaching_flag",
        "tn_detaching_force",
        "tn_yielding_flag",
        "tn_kc",
        "tn_fo",
    )
    parameters = {
        **LiggghtsNormalModel.parameters,
        "surface_energy": (0.0, "surfaceEnergy per type pair (J/m^2); only 0 is supported"),
    }

    def check(self) -> None:
        if self.params["rolling"] in ("epsd", "epsd3"):
            raise self.no_kn()
        super().check()
        self.params["surface_energy"] = self.table("surface_energy")
        if np.any(np.asarray(self.params["surface_energy"]) != 0):
            raise UnsupportedModelError(
                f"{self.key} with surfaceEnergy > 0 is not supported: LIGGGHTS then follows a JKR branch whose "
                "radius and pull-off force change with yield, switches it by flags and detaches the contact at a "
                "force that depends on the step size (normal_model_thornton_ning.h), so its elastic and adhesive "
                "energies cannot be rebuilt from a dump.",
                fix="analyse a run with surfaceEnergy 0, or leave it out.",
            )

    def no_kn(self) -> UnsupportedModelError:
        """The error of a sub-model that needs kn, which this model does not set."""
        return UnsupportedModelError(
            f"{self.key} with rolling_friction {self.params['rolling']} is not supported: thornton_ning sets no "
            "normal stiffness kn (normal_model_thornton_ning.h never assigns sidata.kn), from which that rolling "
            "model takes its stiffness, so LIGGGHTS' rolling spring is undefined.",
            fix="use rolling_friction epsd2 or luding (stiffness from kt) with thornton_ning.",
        )

    def kn(self, rows: ContactRows) -> np.ndarray:
        """None: LIGGGHTS' thornton_ning sets no kn (:meth:`no_kn`)."""
        raise self.no_kn()

    def kt(self, rows: ContactRows) -> np.ndarray:
        """kt = 8 G* sqrt(R* delta) (N/m), ``normal_model_thornton_ning.h``."""
        return hertz_kt_formula(
            overlap(rows.delta), effective_radius(rows.r1, rows.r2), rows.per_pair(effective_shear_modulus)
        )

    def branch(self, rows: ContactRows) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(delta, delta_h, f_h, k): the overlap, the stored overlap and force, the Hertzian k = (4/3) E* sqrt(R*)
        (N/m^(3/2))."""
        k = (4.0 / 3.0) * rows.per_pair(effective_modulus) * np.sqrt(effective_radius(rows.r1, rows.r2))
        k = np.broadcast_to(k, rows.delta.shape)
        return overlap(rows.delta), overlap(rows.column(DELTA_OLD)), rows.column(FORCE_OLD), k

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        d, dh, fh, k = self.branch(rows)
        c = fh - k * dh**1.5
        u, v = np.sqrt(d), np.cbrt(np.maximum(-c, 0.0) / k)
        with np.errstate(divide="ignore", invalid="ignore"):  # d = 0 and v = 0: not used
            w = (fh / k + (d**1.5 - dh**1.5)) / (d + u * v + v * v)  # u - v, from f(delta)/k = u^3 - v^3
            unloading = k * w * w * (0.4 * u**3 + 0.8 * d * v + 1.2 * u * v * v + 0.6 * v**3)
        u_n = np.where(c >= 0, c * d + 0.4 * k * d**2.5, unloading)
        return np.where((d > 0) & (w > 0), u_n, 0.0)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        d, dh, fh, k = self.branch(rows)
        return np.where(d > 0, np.maximum(fh + k * (d**1.5 - dh**1.5), 0.0), 0.0)
