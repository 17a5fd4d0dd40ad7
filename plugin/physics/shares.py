"""The distribution rules: which share of a contact's energy each body stores, and the contact point.

Feng & Gao show that under the Hertz assumptions the energy stored in each
body is proportional to its compliance, whatever the radii (eqs. 14-15):

    S1/S2 = c1/c2,   c_i = (1 - nu_i^2)/E_i,   share1 = c1/(c1 + c2),

and that the same ratio splits the overlap (eq. 31): delta1 = share1 delta.
The tangential (Mindlin) energy splits by t_i = (2 - nu_i)/G_i (the paper's
eq. 22 factor (1 - 2 nu)/G is wrong; see ``docs/physics.md``). Which rule a
mode of energy follows is said once, in :mod:`demsplit.physics.modes`; the
comparison splits (50/50, radius, series springs) are here too.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ContactError
from .formulas import contact_point_coordinate
from .moduli import mindlin_compliance, paper_tangential_compliance, plane_strain_compliance, torsional_compliance

SPLITS = ("material", "equal", "radius", "springs")
"""Distribution laws: ``material`` (Feng & Gao), ``equal`` (50/50: LAMMPS
``compute pe/atom``, Kratos), ``radius`` (share1 = r1/(r1 + r2), the split
implied by the radius-weighted contact point of LIGGGHTS and Aspherix),
``springs`` (share1 = E2 r2/(E1 r1 + E2 r2), the series springs k_i = E_i r_i
behind YADE's linear ``FrictPhys`` stiffness)."""

TANGENTIAL_RULES = ("mindlin", "paper")


def _scalar_or_array(x: np.ndarray) -> np.ndarray | np.float64:
    return x[()] if x.ndim == 0 else x


def share_from_compliances(c1: ArrayLike, c2: ArrayLike) -> np.ndarray:
    """Fraction c1/(c1 + c2) of a series-spring energy stored in body 1.

    The smaller of the two fractions is computed directly and the larger as
    its complement, so a rigid body (c = 0) gets exactly 0, its partner exactly
    1, equal compliances exactly 1/2, and the two shares add to 1 exactly.
    Both compliances 0 (two rigid bodies) is a :class:`ContactError`.
    """
    c1 = np.asarray(c1, dtype=np.float64)
    c2 = np.asarray(c2, dtype=np.float64)
    total = c1 + c2
    if np.any(total == 0):
        raise ContactError(
            "two rigid bodies are in contact: neither can store elastic energy.",
            fix="give at least one of the two bodies a finite Young's modulus.",
        )
    with np.errstate(invalid="ignore"):
        share = np.where(c1 <= c2, c1 / total, 1.0 - c2 / total)
    return _scalar_or_array(share)


def normal_share(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Fraction of the normal elastic energy stored in body 1 (eqs. 14-15).

    share1 = c1/(c1 + c2) = E*/E1',  c_i = (1 - nu_i^2)/E_i = 1/E_i'.

    Dimensionless, in [0, 1]; E = inf (rigid) gives exactly 0 and its partner 1.
    """
    return share_from_compliances(plane_strain_compliance(E1, nu1), plane_strain_compliance(E2, nu2))


def tangential_share(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike, rule: str = "mindlin") -> np.ndarray:
    """Fraction of the tangential elastic energy stored in body 1.

    ``rule="mindlin"`` (default): share1 = t1/(t1 + t2), t_i = (2 - nu_i)/G_i.
    Under the full-stick Mindlin traction each half-space's tangential surface
    displacement is (2 - nu_i) Q/(8 G_i a), uniform over the contact, so the
    energy ½ Q u_i of body i is proportional to t_i. This is also the series
    split behind 1/G* = t1 + t2, the G* LIGGGHTS and YADE use.

    ``rule="paper"``: the paper's eq. (22), t_i = (1 - 2 nu_i)/G_i. That factor
    is the normal-tangential coupling compliance, not the tangential
    displacement; it predicts no tangential energy in an incompressible body
    (nu = 0.5), which the Mindlin solution contradicts. Offered for
    comparison. Where both factors vanish (nu1 = nu2 = 0.5, or nu = 0.5 against
    a rigid body) the result is the limit nu1 = nu2 -> 0.5 of the rule,
    share1 = (1/G1)/(1/G1 + 1/G2).
    """
    if rule == "mindlin":
        return share_from_compliances(mindlin_compliance(E1, nu1), mindlin_compliance(E2, nu2))
    if rule != "paper":
        raise ValueError(f"unknown tangential rule {rule!r}; use one of {TANGENTIAL_RULES}")
    t1 = paper_tangential_compliance(E1, nu1)
    t2 = paper_tangential_compliance(E2, nu2)
    # limit along nu1 = nu2 -> 0.5: the (1 - 2 nu) factors cancel, leaving 1/G = 2 (1 + nu)/E
    both_zero = (t1 + t2) == 0
    g1 = 2.0 * (1.0 + np.asarray(nu1, dtype=np.float64)) / np.asarray(E1, dtype=np.float64)
    g2 = 2.0 * (1.0 + np.asarray(nu2, dtype=np.float64)) / np.asarray(E2, dtype=np.float64)
    return share_from_compliances(np.where(both_zero, g1, t1), np.where(both_zero, g2, t2))


def twisting_share(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Fraction of a twisting spring's energy stored in body 1: (1/G1)/(1/G1 + 1/G2),
    G = E/(2 (1 + nu)) (the torsional traction's rotation scales with 1/G)."""
    return share_from_compliances(torsional_compliance(E1, nu1), torsional_compliance(E2, nu2))


def radius_share(r1: ArrayLike, r2: ArrayLike) -> np.ndarray:
    """Radius-weighted share of body 1: r1/(r1 + r2).

    It is the overlap split implied by LIGGGHTS' ``contactPoint``
    (x1 r2 + x2 r1)/(r1 + r2) (and Aspherix's radius split): body 1 takes
    delta1 = r1 delta/(r1 + r2). Against a plane (r2 = inf) LIGGGHTS puts the
    contact point on the wall surface, i.e. the particle takes the whole
    overlap: share 1.
    """
    r1 = np.asarray(r1, dtype=np.float64)
    r2 = np.asarray(r2, dtype=np.float64)
    plane = np.isinf(r2)
    with np.errstate(invalid="ignore"):
        share = np.asarray(r1 / (r1 + r2), dtype=np.float64)
    share[plane] = 1.0
    return _scalar_or_array(share)


def springs_share(E1: ArrayLike, r1: ArrayLike, E2: ArrayLike, r2: ArrayLike) -> np.ndarray:
    """Share of body 1 for two springs k_i = E_i r_i in series (YADE ``FrictPhys``):
    the energy F^2/(2 k_i) of each spring gives share1 = (1/k1)/(1/k1 + 1/k2)."""
    return share_from_compliances(
        1.0 / (np.asarray(E1, dtype=np.float64) * np.asarray(r1, dtype=np.float64)),
        1.0 / (np.asarray(E2, dtype=np.float64) * np.asarray(r2, dtype=np.float64)),
    )


def overlap_depths(delta: ArrayLike, share1: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Approach of each body, delta1 = share1 delta and delta2 = delta - delta1 (m), eq. (31)."""
    delta = np.asarray(delta, dtype=np.float64)
    d1 = np.asarray(share1, dtype=np.float64) * delta
    return d1, delta - d1


def contact_point(x1: ArrayLike, n: ArrayLike, r1: ArrayLike, delta: ArrayLike, share1: ArrayLike) -> np.ndarray:
    """Material-weighted contact point x_c = x1 + (r1 - share1 delta) n (m), eq. (31).

    x1 : centre of body 1, shape (..., 3) (m); n : unit normal from body 1 to
    body 2, shape (..., 3); r1 : radius of body 1 (m); delta : overlap (m).
    Equal materials give the middle of the overlap; a rigid partner
    (share1 = 1) puts the point on its surface.
    """
    depth1, _ = overlap_depths(delta, share1)
    return contact_point_coordinate(
        np.asarray(x1, dtype=np.float64),
        np.asarray(n, dtype=np.float64),
        np.asarray(r1, dtype=np.float64)[..., None],
        depth1[..., None],
    )
