"""How far the material split can be trusted: a fitted model of its error against finite elements.

The distribution law gives body 1 the share f1 = c1/(c1 + c2) of a Hertz contact's normal energy,
c_i = (1 - nu_i^2)/E_i. It is exact for half-spaces, small strain and no friction. Real spheres are finite
and strained; the axisymmetric finite-element reference in ``benchmarks/validation/`` (frictionless, P2,
compressible neo-Hookean or linear elastic bodies, each sphere loaded through its equatorial symmetry plane
as in Feng & Gao section 5.1) gives each body's energy S_i = f_i S (1 + k_i) to first order. The model:

    k_i = x_i (A0 + A1 nu_i + A2 nu_i^2) + f_i y (B0 + B1 nu_i),
    x_i = a/R_i (0 for a plane), y = a/R* (f_i y is proportional to body i's strain p0/E'_i),
    a = sqrt(R* delta), 1/R* = 1/R1 + 1/R2,

and the corrected ratio S1/S2 = (c1/c2) exp(k1 - k2), so the corrected share of body 1 is
c1 e^k1 / (c1 e^k1 + c2 e^k2): a rigid body (E = inf, c = 0) still takes nothing, equal bodies still
take half each. The coefficients are least-squares fits of ln((S1/S2)_FE / (c1/c2)) over the sweep of
``benchmarks/validation/sweep.py``; its fit residual and held-out check are in docs/accuracy.md.

Numpy only, pure functions; not wired into the pipeline.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

# Fitted by:  nice -n 10 python benchmarks/validation/sweep.py --points 96 --jobs 2
# (benchmarks/validation/results/fit.json; coefficient order A0 A1 A2 B0 B1)
COEFFICIENTS = {
    "neohooke": (-0.055894526585, -1.838829407441, 2.517207085089, -0.403530061527, 0.90398061817),
    "small": (-0.053583422186, -2.150921830068, 3.049150920001, -0.544915520042, 1.258517242732),
}
REFERENCE = "neohooke"


def body_terms(x: ArrayLike, fy: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """The model's features of one body, shape (5, ...): x, x nu, x nu^2, f y, f y nu (see the module doc)."""
    x, fy, nu = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x, fy, nu)))
    return np.stack([x, x * nu, x * nu**2, fy, fy * nu])


def _parts(a_over_R1, a_over_R2, nu1, nu2, E1, E2):
    x1, x2, nu1, nu2, E1, E2 = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (a_over_R1, a_over_R2, nu1, nu2, E1, E2)))
    c1 = (1.0 - nu1) * (1.0 + nu1) / E1
    c2 = (1.0 - nu2) * (1.0 + nu2) / E2
    with np.errstate(invalid="ignore", divide="ignore"):
        f1 = c1 / (c1 + c2)
    y = x1 + x2  # a/R* = a/R1 + a/R2
    return x1, x2, nu1, nu2, c1, c2, f1, y


def log_ratio_correction(a_over_R1: ArrayLike, a_over_R2: ArrayLike, nu1: ArrayLike, nu2: ArrayLike,
                         E1: ArrayLike, E2: ArrayLike, reference: str = REFERENCE) -> np.ndarray:
    """k1 - k2 = ln((S1/S2)_FE / (c1/c2)): the model's log-correction of the law's energy ratio (-)."""
    coef = np.asarray(COEFFICIENTS[reference])
    x1, x2, nu1, nu2, c1, c2, f1, y = _parts(a_over_R1, a_over_R2, nu1, nu2, E1, E2)
    k1 = np.tensordot(coef, body_terms(x1, f1 * y, nu1), axes=1)
    k2 = np.tensordot(coef, body_terms(x2, (1.0 - f1) * y, nu2), axes=1)
    return k1 - k2


def corrected_share(a_over_R1: ArrayLike, a_over_R2: ArrayLike, nu1: ArrayLike, nu2: ArrayLike,
                    E1: ArrayLike, E2: ArrayLike, reference: str = REFERENCE) -> np.ndarray:
    """Body 1's share (0..1) of a contact's normal energy, the law corrected by the fitted model.

    a_over_R1, a_over_R2 : contact radius over each body's radius, a = sqrt(R* delta) (0 for a plane);
    nu1, nu2 : Poisson's ratios; E1, E2 : Young's moduli (Pa; inf is rigid). reference : 'neohooke'
    (finite strain, the default) or 'small' (linear elastic bodies). Two rigid bodies give NaN.
    """
    x1, x2, nu1, nu2, c1, c2, f1, y = _parts(a_over_R1, a_over_R2, nu1, nu2, E1, E2)
    d = log_ratio_correction(x1, x2, nu1, nu2, E1, E2, reference)
    # c1 e^k1 / (c1 e^k1 + c2 e^k2) = c1 / (c1 + c2 e^-(k1 - k2))
    with np.errstate(invalid="ignore", divide="ignore"):
        return c1 / (c1 + c2 * np.exp(-d))


def expected_share_error(a_over_R1: ArrayLike, a_over_R2: ArrayLike, nu1: ArrayLike, nu2: ArrayLike,
                         E1: ArrayLike, E2: ArrayLike, reference: str = REFERENCE) -> np.ndarray:
    """Expected error of the law's share of body 1 (FE share minus law share; absolute, in share units).

    Same arguments as ``corrected_share``. E.g. -0.005 means the finite-element body 1 holds 0.5 % of the
    contact's energy less than the law gives it (and body 2 that much more).
    """
    x1, x2, nu1, nu2, c1, c2, f1, y = _parts(a_over_R1, a_over_R2, nu1, nu2, E1, E2)
    return corrected_share(x1, x2, nu1, nu2, E1, E2, reference) - f1


def contact_radius_ratios(delta: ArrayLike, r1: ArrayLike, r2: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """a/R1 and a/R2 of every contact (-), a = sqrt(R* delta) the Hertz contact radius, 1/R* = 1/R1 + 1/R2;
    a/R2 = 0 against a plane (R2 = inf) and both 0 without overlap."""
    r1, r2 = np.asarray(r1, dtype=np.float64), np.asarray(r2, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        R = 1.0 / (1.0 / r1 + 1.0 / r2)
        a = np.sqrt(R * np.maximum(np.asarray(delta, dtype=np.float64), 0.0))
        return a / r1, np.where(np.isinf(r2), 0.0, a / r2)


HERTZ_VALIDITY = 0.1
"""a/R beyond which a contact leaves the range where the half-space (Hertz) assumptions are usually trusted."""
