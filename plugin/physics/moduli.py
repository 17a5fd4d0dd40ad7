"""Contact moduli from the two bodies' materials and radii: E*, G*, R*, m*.

Moduli enter through compliances c = (1 - nu^2)/E, so a rigid body (E = inf)
has c = 0 exactly; radii enter through curvatures k = 1/R, so a plane
(R = inf) has k = 0. Every function takes numpy arrays or scalars (broadcast
together), computes in float64 and returns float64. SI units (m, Pa, kg).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ContactError


def f64(x: ArrayLike) -> np.ndarray:
    """``x`` as a float64 array (no copy when it already is one)."""
    return np.asarray(x, dtype=np.float64)


def plane_strain_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """Normal compliance c = 1/E' = (1 - nu)(1 + nu)/E (1/Pa), eq. (1).

    ``(1 - nu)(1 + nu)`` instead of ``1 - nu**2`` keeps full relative
    precision near |nu| = 1. E = inf gives exactly 0 (a rigid body).
    """
    nu = f64(nu)
    return (1.0 - nu) * (1.0 + nu) / f64(E)


def mindlin_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """Tangential (Mindlin) compliance t = (2 - nu)/G = 2 (2 - nu)(1 + nu)/E (1/Pa).

    The uniform tangential surface displacement of a half-space under the
    full-stick Mindlin traction is (2 - nu) Q/(8 G a) (Johnson, sec. 7.2), so
    the tangential energy of each body is proportional to t. It is the same
    factor LIGGGHTS and YADE build G* from: 1/G* = t1 + t2.
    """
    nu = f64(nu)
    return 2.0 * (2.0 - nu) * (1.0 + nu) / f64(E)


def torsional_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """Torsional compliance 1/G = 2 (1 + nu)/E (1/Pa).

    A half-space twisted by a torsional traction on a circle of radius a
    rotates by an angle proportional to 1/G alone (Johnson, sec. 7.4: M = (16/3) G a^3 beta),
    so each body's share of a twisting spring's energy is proportional to 1/G.
    """
    return 2.0 * (1.0 + f64(nu)) / f64(E)


def paper_tangential_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """The paper's eq. (22) factor (1 - 2 nu)/G = 2 (1 - 2 nu)(1 + nu)/E (1/Pa).

    Kept for comparison only: (1 - 2 nu)/G is the normal-tangential coupling
    compliance (Dundurs' beta), not the tangential displacement factor; it
    would give zero tangential energy to a body with nu = 0.5.
    """
    nu = f64(nu)
    return 2.0 * (1.0 - 2.0 * nu) * (1.0 + nu) / f64(E)


def _inverse_sum(a: np.ndarray, b: np.ndarray, what: str) -> np.ndarray:
    total = a + b
    if np.any(total == 0):
        raise ContactError(
            f"two rigid bodies are in contact: the {what} is infinite and no elastic energy can be stored.",
            fix="give at least one of the two bodies a finite Young's modulus.",
        )
    return 1.0 / total


def effective_modulus(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Contact modulus E* = 1/(c1 + c2) (Pa), eq. (2)."""
    return _inverse_sum(plane_strain_compliance(E1, nu1), plane_strain_compliance(E2, nu2), "contact modulus E*")


def effective_shear_modulus(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Contact shear modulus G* = 1/(t1 + t2), t = (2 - nu)/G (Pa), as LIGGGHTS
    (``global_properties.cpp``) and YADE (``HertzMindlin.cpp``) build it."""
    return _inverse_sum(mindlin_compliance(E1, nu1), mindlin_compliance(E2, nu2), "contact shear modulus G*")


def effective_radius(R1: ArrayLike, R2: ArrayLike) -> np.ndarray:
    """Effective radius R* = 1/(1/R1 + 1/R2) (m), eq. (3).

    Computed from curvatures, so R2 = inf (a plane) gives R* = R1 exactly and
    radius ratios of 1e6 or 1e-6 lose nothing.
    """
    k = 1.0 / f64(R1) + 1.0 / f64(R2)
    if np.any(k <= 0):
        raise curvature_error()
    return 1.0 / k


def curvature_error() -> ContactError:
    """The error of a contact whose curvatures 1/R1 + 1/R2 do not add up to > 0."""
    return ContactError(
        "the sum of the two curvatures 1/R1 + 1/R2 must be > 0.",
        fix="check the radii: two planes cannot be in Hertz contact.",
    )


def reduced_mass(m1: ArrayLike, m2: ArrayLike) -> np.ndarray:
    """m* = m1 m2/(m1 + m2) (kg); m2 = inf (a wall) gives m1."""
    m1, m2 = f64(m1), f64(m2)
    return 1.0 / (1.0 / m1 + 1.0 / m2)
