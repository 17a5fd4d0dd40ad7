"""LIGGGHTS 3.8.0's liquid-bridge capillary force, transcribed from its C++ for the tests (independent of demsplit's
:mod:`demsplit.physics.laws._liquid_bridge`)."""

from __future__ import annotations

import mpmath

BRIDGE_MODELS = ("easo/capillary/viscous", "washino/capillary/viscous")


def liggghts_capillary(
    model: str,
    ri: float,
    rj: float | None,
    ci: float,
    cj: float,
    theta_i: float,
    theta_j: float,
    gamma: float,
    max_ratio: float,
    cdf: float,
):
    """LIGGGHTS 3.8.0's capillary force F(delta) (N) and rupture gap (m) in mpmath's working precision, transcribed from
    cohesion_model_{easo,washino}_capillary_viscous.h of the 3.8.0 release (rj None: a wall; angles in degrees)."""
    mp = mpmath
    wall = rj is None
    radi = mp.mpf(ri)
    radj = radi if wall else mp.mpf(rj)  # surfacesClose: radj = radi on a wall
    radsum = radi if wall else radi + radj
    th = mp.mpf(0.5) * (mp.mpf(theta_i) * mp.pi / 180) * (mp.mpf(theta_j) * mp.pi / 180)
    gamma = mp.mpf(gamma)
    vol_li = mp.mpf("1333.333333") * mp.pi * radi**3 * mp.mpf(ci)
    vol_lj = 0 if wall else mp.mpf("1333.333333") * mp.pi * radj**3 * mp.mpf(cj)
    if model == BRIDGE_MODELS[0]:
        vol = 0.5 * vol_li * (1 - mp.sqrt(1 - radj**2 / radsum**2)) + 0.5 * vol_lj * (
            1 - mp.sqrt(1 - radi**2 / radsum**2)
        )
    else:
        vol = (vol_li + vol_lj) * mp.mpf("0.05")
    dist_max = (1 + 0.5 * th) * mp.cbrt(vol) * mp.mpf("0.1")
    rupture = min(dist_max, (mp.mpf(max_ratio) - 1) * (radi + radj), (mp.mpf(cdf) - 1) * radsum)

    def force(delta):
        dist = -mp.mpf(delta)
        if model == BRIDGE_MODELS[0]:
            R2 = max(radi, radj)
            vs = vol / R2**3 * mp.mpf("0.001")
            A = -mp.mpf("1.1") * vs ** mp.mpf("-0.53")
            B = (
                (-mp.mpf("0.148") * mp.log(vs) - mp.mpf("0.96")) * th * th
                - mp.mpf("0.0082") * mp.log(vs)
                + mp.mpf("0.48")
            )
            C = mp.mpf("0.0018") * mp.log(vs) + mp.mpf("0.078")
            if dist < 0:
                return -mp.pi * gamma * mp.sqrt(radi * radj) * (mp.exp(B) + C)
            return -mp.pi * gamma * mp.sqrt(radi * radj) * (mp.exp(A * dist / R2 + B) + C) if dist < rupture else 0
        if dist < 0:
            rj_t = 0 if wall else radj  # surfacesIntersect: the wall's radj is 0
            reff = radi * rj_t / (radi + rj_t)
            return -2 * mp.pi * reff * gamma * mp.cos(th) * (1 - dist * mp.sqrt(1000 * mp.pi * reff / (2 * vol)))
        if dist >= rupture:
            return 0
        reff = radi * radj / (radi + radj)
        prefactor = -1 + mp.sqrt(1 + 2 * vol / (mp.pi * reff * 1000 * dist * dist))
        d_sp = 0.5 * dist * prefactor
        alpha = mp.sqrt(dist / reff * prefactor)
        return -2 * mp.pi * reff * gamma * (mp.cos(th) / (1 + dist / (2 * d_sp)) + mp.sin(alpha) * mp.sin(alpha + th))

    return force, rupture
