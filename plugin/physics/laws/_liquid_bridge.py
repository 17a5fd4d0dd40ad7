"""LIGGGHTS' liquid-bridge cohesion models ``easo/capillary/viscous`` and ``washino/capillary/viscous``.

As Debian's LIGGGHTS 3.8.0 computes them (``cohesion_model_easo_capillary_viscous.h`` and
``cohesion_model_washino_capillary_viscous.h`` of the 3.8.0 release). A bridge forms when two
bodies touch (``surfacesIntersect`` sets the contact's history value ``contflag``), a washino
bridge also as they approach (its ``surfacesClose`` makes one wherever the gap is below rupture;
easo's returns unless ``contflag`` is set), and pulls them together, once they part, until their
gap s = -delta (m) reaches the rupture distance

    s_rup = min((1 + theta/2) V^(1/3),  (maxSeparationDistanceRatio - 1)(r1 + r2'),  (cdf - 1) S')

(Lian's criterion; beyond the second LIGGGHTS always breaks it; beyond the third, S' = r1 + r2 for
a pair and r1 on a wall, LIGGGHTS no longer evaluates the contact: cdf is its contact distance
factor, the larger of ``neigh_modify contact_distance_factor`` and 1.1 maxSeparationDistanceRatio).
On a wall LIGGGHTS takes r2' = r1 wherever these models need a second radius; elsewhere r2' = r2.

Liquid: particle i holds V_i = 1.333333333 pi r_i^3 c_i (m^3; LIGGGHTS' rounded 4/3), c_i its
``surfaceLiquidContent`` (the per-atom property LIGGGHTS creates, dumped as
``f_surfaceLiquidContent``); walls are dry. The bridge volume V (m^3):

- easo: V = V_1/2 (1 - sqrt(1 - r2'^2/S^2)) + V_2/2 (1 - sqrt(1 - r1^2/S^2)), S = r1 + r2 (a wall:
  S = r1, so V = V_1/2);
- washino: V = f (V_1 + V_2), f = 0.05, or ``lbVolumeFraction`` with ``modifyLbVolume on``.

The contact angle is theta = theta_1 theta_2/2 (rad) of the two types' ``contactAngle`` in 3.8.0
(the LIGGGHTS-PUBLIC sources from January 2019 on take the mean, (theta_1 + theta_2)/2).

Capillary force F (N, along the normal, negative: attractive), gamma = ``surfaceTension`` (N/m):

- easo (Soulie et al. 2006, eqs. 13-14): with v = V/R2^3, R2 = max(r1, r2'),
  A = -1.1 v^-0.53, B = (-0.148 ln v - 0.96) theta^2 - 0.0082 ln v + 0.48, C = 0.0018 ln v + 0.078:
  touching F = -pi gamma sqrt(r1 r2') (e^B + C), apart F = -pi gamma sqrt(r1 r2') (e^(A s/R2 + B) + C);
- washino (Rabinovich et al. 2005): touching F = -2 pi R gamma cos(theta) (1 + delta sqrt(pi R/(2V)))
  with R = r1 r2/(r1 + r2), 0 on a wall (LIGGGHTS leaves the wall's radius at 0 there); apart, with
  R = r1 r2'/(r1 + r2') (r1/2 on a wall), c = 2V/(pi R), q = sqrt(s^2 + c), u = q - s and
  alpha = sqrt(u/R): F = -2 pi R gamma (cos(theta) u/q + sin(alpha) sin(alpha + theta)).

LIGGGHTS applies no force to a bridge of V < 1e-17 m^3 (1000 V < 1e-14 in its units). The viscous
force of both models (Stokes drag on the normal and relative tangential velocities) is dissipative:
it stores no energy and is not computed here.

The cohesion work (J) is the work of the capillary force from the current state to rupture, the
potential whose derivative in delta is F (as ``sjkr``'s, negative where the bridge holds the bodies):

    u_adh(delta) = int_{-s_rup}^{delta} F d(delta') = -int_s^{s_rup} |F| ds'   (apart),

and, touching, that of delta = 0 plus int_0^delta F. Closed forms but for washino's
sin(alpha) sin(alpha + theta) term apart, integrated exactly by Gauss-Legendre quadrature in
ln(alpha), where it is an entire function (:func:`_washino_sine_work`).
"""

from __future__ import annotations

import numpy as np

BRIDGE_MODELS = ("easo/capillary/viscous", "washino/capillary/viscous")
"""LIGGGHTS ``cohesion`` models that are liquid bridges."""
FORMED_ON_TOUCH = {"easo/capillary/viscous": True, "washino/capillary/viscous": False}
"""Whether a model's bridge forms only when the bodies touch, so that a gap below rupture holds one only if the
contact's history says so (module docstring)."""
FOUR_THIRDS = 1.333333333
"""LIGGGHTS' 4/3 in the liquid volume of a particle (``1333.333333`` in units of 1000 m^3)."""
MIN_VOLUME = 1e-17
"""Bridge volume (m^3) below which LIGGGHTS applies no force (``volBond1000 < 1e-14``)."""
WASHINO_FRACTION = 0.05
"""The fraction of the two particles' liquid a washino bridge holds without ``modifyLbVolume on``."""
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(24)


class LiquidBridges:
    """The liquid bridges of some contacts, one per row (module docstring for every symbol).

    ``model`` one of :data:`BRIDGE_MODELS`; ``r1``, ``r2`` radii (m, r2 = inf: a wall); ``c1``, ``c2``
    the particles' liquid contents (c2 is not read on a wall); ``theta`` the contact angle (rad);
    ``gamma`` the surface tension (N/m); ``max_ratio`` maxSeparationDistanceRatio; ``cdf`` the contact
    distance factor; ``fraction`` washino's bridge volume fraction.
    """

    def __init__(
        self,
        model: str,
        r1: np.ndarray,
        r2: np.ndarray,
        c1: np.ndarray,
        c2: np.ndarray,
        theta: np.ndarray | float,
        gamma: float,
        max_ratio: float,
        cdf: float,
        fraction: float = WASHINO_FRACTION,
    ) -> None:
        if model not in BRIDGE_MODELS:
            raise ValueError(f"{model!r} is not a liquid-bridge model ({', '.join(BRIDGE_MODELS)})")
        self.model = model
        self.wall = np.isinf(r2)
        self.r1 = r1
        self.r2 = np.where(self.wall, r1, r2)  # r2': LIGGGHTS' radj = radi on a wall
        self.theta = np.broadcast_to(np.asarray(theta, dtype=np.float64), r1.shape)
        self.gamma = gamma
        v1 = FOUR_THIRDS * np.pi * r1**3 * c1
        v2 = FOUR_THIRDS * np.pi * self.r2**3 * np.where(self.wall, 0.0, c2)  # walls are dry
        if model == BRIDGE_MODELS[0]:
            S = np.where(self.wall, r1, r1 + self.r2)
            self.volume = 0.5 * v1 * (1.0 - np.sqrt(1.0 - self.r2**2 / S**2)) + 0.5 * v2 * (
                1.0 - np.sqrt(1.0 - r1**2 / S**2)
            )
        else:
            self.volume = fraction * (v1 + v2)
        self.present = self.volume >= MIN_VOLUME
        reach = (cdf - 1.0) * np.where(self.wall, r1, r1 + self.r2)
        self.rupture = np.minimum(
            np.minimum((1.0 + 0.5 * self.theta) * np.cbrt(self.volume), (max_ratio - 1.0) * (r1 + self.r2)), reach
        )
        """s_rup (m): the bridge acts while the gap is below it."""

    # -- the force and its work ------------------------------------------------------------------

    def force(self, delta: np.ndarray) -> np.ndarray:
        """The capillary force F(delta) of every bridge (N, negative: attractive), 0 from rupture on."""
        touching, apart = self._branches(delta)
        s = np.where(apart, -delta, 0.0)
        if self.model == BRIDGE_MODELS[0]:
            P, A, B, C, R2 = self._easo()
            f_touching = -P * (np.exp(B) + C)
            f_apart = -P * (np.exp(A * s / R2 + B) + C)
        else:
            R, k = self._washino_touching()
            f_touching = -2.0 * np.pi * R * self.gamma * np.cos(self.theta) * (1.0 + np.where(touching, delta, 0.0) * k)
            Ra, c, q, u = self._washino_apart(s)
            alpha = np.sqrt(u / Ra)
            f_apart = (
                -2.0
                * np.pi
                * Ra
                * self.gamma
                * (np.cos(self.theta) * u / q + np.sin(alpha) * np.sin(alpha + self.theta))
            )
        return np.where(touching, f_touching, np.where(apart, f_apart, 0.0))

    def work(self, delta: np.ndarray) -> np.ndarray:
        """u_adh(delta) = int_{-s_rup}^delta F (J, module docstring): 0 from rupture on."""
        touching, apart = self._branches(delta)
        s = np.where(apart, -delta, 0.0)  # touching: the apart branch's work from the touch, s = 0
        gap = self.rupture - s  # > 0 where the bridge acts apart, and for a touching one
        if self.model == BRIDGE_MODELS[0]:
            P, A, B, C, R2 = self._easo()
            a = A / R2  # < 0
            w_apart = -P * (np.exp(B + a * s) * np.expm1(a * gap) / a + C * gap)
            w_touching = -P * (np.exp(B) + C) * np.where(touching, delta, 0.0)
        else:
            R, k = self._washino_touching()
            d = np.where(touching, delta, 0.0)
            w_touching = -2.0 * np.pi * R * self.gamma * np.cos(self.theta) * d * (1.0 + 0.5 * k * d)
            Ra, c, q, u = self._washino_apart(s)
            _, _, q_rup, u_rup = self._washino_apart(self.rupture)
            # int_s^s_rup u/q ds' = u(s) - u(s_rup), written without cancellation
            w_cos = np.cos(self.theta) * gap * (u + u_rup) / (q + q_rup)
            w_apart = -2.0 * np.pi * Ra * self.gamma * (w_cos + _washino_sine_work(u, u_rup, Ra, c, self.theta))
        return np.where(touching | apart, w_apart + w_touching, 0.0)

    # -- the pieces --------------------------------------------------------------------------

    def _branches(self, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rows touching (delta > 0) and rows apart within rupture, both with a bridge of V >= 1e-17 m^3."""
        touching = self.present & (delta > 0)
        return touching, self.present & ~(delta > 0) & (-delta < self.rupture)

    def _easo(self) -> tuple[np.ndarray, ...]:
        """pi gamma sqrt(r1 r2'), A, B, C and R2 of Soulie's fit (module docstring)."""
        R2 = np.maximum(self.r1, self.r2)
        v = np.where(self.present, self.volume, 1.0) / R2**3
        ln_v = np.log(v)
        A = -1.1 * v**-0.53
        B = (-0.148 * ln_v - 0.96) * self.theta**2 - 0.0082 * ln_v + 0.48
        C = 0.0018 * ln_v + 0.078
        return np.pi * self.gamma * np.sqrt(self.r1 * self.r2), A, B, C, R2

    def _washino_touching(self) -> tuple[np.ndarray, np.ndarray]:
        """R (0 on a wall) and k = sqrt(pi R/(2V)) (1/m) of washino's touching branch."""
        R = np.where(self.wall, 0.0, self.r1 * self.r2 / (self.r1 + self.r2))
        return R, np.sqrt(np.pi * R / (2.0 * np.where(self.present, self.volume, 1.0)))

    def _washino_apart(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """R, c = 2V/(pi R) (m^2), q = sqrt(s^2 + c) and u = q - s = c/(q + s) (m) of washino's apart branch."""
        R = self.r1 * self.r2 / (self.r1 + self.r2)
        c = 2.0 * np.where(self.present, self.volume, 1.0) / (np.pi * R)
        q = np.sqrt(s * s + c)
        return R, c, q, c / (q + s)


def _washino_sine_work(u: np.ndarray, u_rup: np.ndarray, R: np.ndarray, c: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """int_s^s_rup sin(alpha) sin(alpha + theta) ds' (m), alpha = sqrt(u/R), u = c/(sqrt(s^2 + c) + s).

    With s = (c - u^2)/(2u) and u = R alpha^2, ds = -(c/(R alpha^3) + R alpha) d(alpha); in t = ln(alpha)
    the integral runs over [ln alpha_rup, ln alpha] of sin(alpha) sin(alpha + theta) (c/(R alpha^2) + R alpha^2),
    an entire function of t on an interval of length ln(alpha/alpha_rup) <= ln(1 + 2 s_rup/sqrt(c))/2 (a few
    units at most), where 24 Gauss-Legendre nodes agree with 40-digit quadrature to 1e-12 of the work, as
    tests/test_liggghts_submodels.py asserts."""
    t_hi = 0.5 * np.log(u / R)
    t_lo = 0.5 * np.log(u_rup / R)
    mid, half = 0.5 * (t_hi + t_lo), 0.5 * (t_hi - t_lo)
    total = np.zeros_like(mid)
    for x, w in zip(_NODES, _WEIGHTS):
        alpha = np.exp(mid + half * x)
        a2 = alpha * alpha
        total += w * np.sin(alpha) * np.sin(alpha + theta) * (c / (R * a2) + R * a2)
    return half * total
