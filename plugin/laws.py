"""Contact laws: elastic force and energy of one contact, vectorised.

Every function takes numpy arrays or scalars (broadcast together), computes in
float64 (float32 input is upcast first) and returns float64. SI units: m, Pa,
N, J. Equation numbers refer to Feng & Gao, "On the strain energy distribution
of two elastic solids under smooth contact" (the paper), corrected as in
``docs/physics.md``.

Numerics (``docs/physics.md``):

* moduli enter through compliances c = (1 - nu^2)/E, so a rigid body
  (E = inf) has c = 0 exactly;
* radii enter through curvatures k = 1/R, so a plane (R = inf) has k = 0;
* overlaps delta <= 0 are clamped to 0 before any fractional power, so force
  and energy are 0 (never NaN) for separated bodies;
* energies use the delta forms (``(8/15) E* sqrt(R* delta) delta^2``), never
  the high-power force forms that overflow.

One definition for numpy and for compiled loops: the formulas the per-contact
loops need (:func:`clamped_overlap`, :func:`inverse_curvature_sum`,
:func:`hertz_energy_formula`, :func:`hertz_kt_formula`, :func:`squared_norm`,
:func:`spring_energy`) are written with operators and numpy ufuncs only, so the
same function works on float64 arrays and, compiled by numba, on the scalars of
one contact (:mod:`demsplit.kernels` compiles these very functions; it has no
copy of them). The public functions below convert their inputs (``_f64``),
check them and call those formulas, so array and compiled results are the same
IEEE operations in the same order: bit for bit equal.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .errors import ContactError


def _f64(x: ArrayLike) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def clamped_overlap(delta):
    """delta clamped to >= 0 (m): a separated pair stores no elastic energy (NaN stays NaN).
    Formula on float64 arrays or scalars, compiled by :mod:`demsplit.kernels`."""
    return np.maximum(delta, 0.0)


def _overlap(delta: ArrayLike) -> np.ndarray:
    return clamped_overlap(_f64(delta))


def inverse_curvature_sum(R1, R2):
    """R* = 1/(1/R1 + 1/R2) (m), unchecked: formula on float64 arrays or scalars."""
    return 1.0 / (1.0 / R1 + 1.0 / R2)


def hertz_energy_formula(d, R_eff, E_eff):
    """(8/15) E* sqrt(R* d) d^2 (J) for a clamped overlap d >= 0: formula on float64 arrays or scalars."""
    return (8.0 / 15.0) * E_eff * np.sqrt(R_eff * d) * d * d


def hertz_kt_formula(d, R_eff, G_eff):
    """8 G* sqrt(R* d) (N/m) for a clamped overlap d >= 0: formula on float64 arrays or scalars."""
    return 8.0 * G_eff * np.sqrt(R_eff * d)


def squared_norm(x, y, z):
    """x^2 + y^2 + z^2, summed in that order: formula on float64 arrays or scalars."""
    return x * x + y * y + z * z


def spring_energy(k, s2):
    """k s^2 / 2 (J) of a spring of stiffness k (N/m) stretched by s (s2 = s^2, m^2)."""
    return 0.5 * k * s2


def _squared_norms(v: np.ndarray) -> np.ndarray:
    """|v|^2 of vectors (shape (n, 3)) or v^2 of magnitudes (shape (n,))."""
    return squared_norm(v[..., 0], v[..., 1], v[..., 2]) if v.ndim == 2 else v * v


def plane_strain_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """Normal compliance c = 1/E' = (1 - nu)(1 + nu)/E (1/Pa), eq. (1).

    ``(1 - nu)(1 + nu)`` instead of ``1 - nu**2`` keeps full relative
    precision near |nu| = 1. E = inf gives exactly 0 (a rigid body).
    """
    nu = _f64(nu)
    return (1.0 - nu) * (1.0 + nu) / _f64(E)


def mindlin_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """Tangential (Mindlin) compliance t = (2 - nu)/G = 2 (2 - nu)(1 + nu)/E (1/Pa).

    The uniform tangential surface displacement of a half-space under the
    full-stick Mindlin traction is (2 - nu) Q/(8 G a) (Johnson, sec. 7.2), so
    the tangential energy of each body is proportional to t. It is the same
    factor LIGGGHTS and YADE build G* from: 1/G* = t1 + t2.
    """
    nu = _f64(nu)
    return 2.0 * (2.0 - nu) * (1.0 + nu) / _f64(E)


def paper_tangential_compliance(E: ArrayLike, nu: ArrayLike) -> np.ndarray:
    """The paper's eq. (22) factor (1 - 2 nu)/G = 2 (1 - 2 nu)(1 + nu)/E (1/Pa).

    Kept for comparison only: (1 - 2 nu)/G is the normal-tangential coupling
    compliance (Dundurs' beta), not the tangential displacement factor; it
    would give zero tangential energy to a body with nu = 0.5.
    """
    nu = _f64(nu)
    return 2.0 * (1.0 - 2.0 * nu) * (1.0 + nu) / _f64(E)


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
    return _inverse_sum(plane_strain_compliance(E1, nu1), plane_strain_compliance(E2, nu2),
                        "contact modulus E*")


def effective_shear_modulus(E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Contact shear modulus G* = 1/(t1 + t2), t = (2 - nu)/G (Pa), as LIGGGHTS
    (``global_properties.cpp``) and YADE (``HertzMindlin.cpp``) build it."""
    return _inverse_sum(mindlin_compliance(E1, nu1), mindlin_compliance(E2, nu2),
                        "contact shear modulus G*")


def effective_radius(R1: ArrayLike, R2: ArrayLike) -> np.ndarray:
    """Effective radius R* = 1/(1/R1 + 1/R2) (m), eq. (3).

    Computed from curvatures, so R2 = inf (a plane) gives R* = R1 exactly and
    radius ratios of 1e6 or 1e-6 lose nothing.
    """
    k = 1.0 / _f64(R1) + 1.0 / _f64(R2)
    if np.any(k <= 0):
        raise curvature_error()
    return 1.0 / k


def curvature_error() -> ContactError:
    """The error of a contact whose curvatures 1/R1 + 1/R2 do not add up to > 0."""
    return ContactError("the sum of the two curvatures 1/R1 + 1/R2 must be > 0.",
                        fix="check the radii: two planes cannot be in Hertz contact.")


def hertz_force_from_moduli(delta: ArrayLike, R_eff: ArrayLike, E_eff: ArrayLike) -> np.ndarray:
    """Hertz normal force P = (4/3) E* sqrt(R* delta) delta (N), eq. (12)."""
    d = _overlap(delta)
    return (4.0 / 3.0) * _f64(E_eff) * np.sqrt(_f64(R_eff) * d) * d


def hertz_energy_from_moduli(delta: ArrayLike, R_eff: ArrayLike, E_eff: ArrayLike) -> np.ndarray:
    """Hertz elastic energy S = (8/15) E* sqrt(R* delta) delta^2 = (2/5) P delta (J), eq. (13)."""
    return hertz_energy_formula(_overlap(delta), _f64(R_eff), _f64(E_eff))


def hertz_force(delta: ArrayLike, R1: ArrayLike, R2: ArrayLike,
                E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Hertz normal force P = (4/3) E* sqrt(R*) delta^(3/2) (N), eqs. (2), (3), (12).

    R2 = inf for a plane; E = inf for a rigid body.
    """
    return hertz_force_from_moduli(delta, effective_radius(R1, R2), effective_modulus(E1, nu1, E2, nu2))


def hertz_energy(delta: ArrayLike, R1: ArrayLike, R2: ArrayLike,
                 E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike) -> np.ndarray:
    """Hertz elastic energy S = (8/15) E* sqrt(R*) delta^(5/2) (J), eq. (13)."""
    return hertz_energy_from_moduli(delta, effective_radius(R1, R2), effective_modulus(E1, nu1, E2, nu2))


def hertz_energy_from_kno(delta: ArrayLike, kno: ArrayLike) -> np.ndarray:
    """Hertz energy from YADE's stored stiffness: S = (2/5) kno delta^(5/2) (J),
    with F = kno delta^(3/2) and kno = (4/3) E* sqrt(R*) (N/m^1.5)."""
    d = _overlap(delta)
    return 0.4 * _f64(kno) * np.sqrt(d) * d * d


def hooke_energy(delta: ArrayLike, kn: ArrayLike) -> np.ndarray:
    """Linear spring energy S = kn delta^2 / 2 (J), the power law with n = 1."""
    d = _overlap(delta)
    return 0.5 * _f64(kn) * d * d


def power_law_energy(delta: ArrayLike, k: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Energy of a power-law contact F = k delta^n: S = k delta^(n+1)/(n+1) (J), eq. (25).

    n > 0; n = 1 is a linear spring, n = 3/2 with k = (4/3) E* sqrt(R*) is Hertz.
    """
    n = _f64(n)
    if np.any(n <= 0):
        raise ContactError(f"the power-law exponent n must be > 0, got {np.min(n)!r}.")
    d = _overlap(delta)
    return _f64(k) * d ** (n + 1.0) / (n + 1.0)


def tangential_spring_energy(ft: ArrayLike, kt: ArrayLike) -> np.ndarray:
    """Tangential elastic energy S_t = |F_t|^2 / (2 kt) (J).

    ``ft`` is the elastic tangential force: a magnitude (shape (n,)) or vectors
    (shape (n, 3)). Where kt = 0 (YADE sets ks = 0 on a contact that has
    separated) the energy is 0.
    """
    ft2 = _squared_norms(_f64(ft))
    kt = _f64(kt)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(kt > 0, 0.5 * ft2 / np.where(kt > 0, kt, 1.0), 0.0)


def shear_spring_energy(shear: ArrayLike, kt: ArrayLike) -> np.ndarray:
    """Tangential energy from a spring displacement: S_t = kt |shear|^2 / 2 (J).

    LIGGGHTS ``tangential history`` stores ``shear`` (m) with
    F_t,el = -kt shear; this is the same energy as
    :func:`tangential_spring_energy` of that force.
    """
    return spring_energy(_f64(kt), _squared_norms(_f64(shear)))


def liggghts_hertz_kt(delta: ArrayLike, R_eff: ArrayLike, G_eff: ArrayLike) -> np.ndarray:
    """LIGGGHTS ``model hertz`` tangential stiffness kt = 8 G* sqrt(R* delta) (N/m)
    (``normal_model_hertz.h``)."""
    return hertz_kt_formula(_overlap(delta), _f64(R_eff), _f64(G_eff))


def liggghts_hooke_kn(R_eff: ArrayLike, E_eff: ArrayLike, m_eff: ArrayLike, v_char: float) -> np.ndarray:
    """LIGGGHTS ``model hooke`` normal stiffness (N/m) (``normal_model_hooke.h``):

    kn = (16/15) sqrt(R*) E* (15 m* V^2 / (16 sqrt(R*) E*))^(1/5),

    with m* = m1 m2/(m1 + m2) (m* = m1 on a wall) and V the
    ``characteristicVelocity``.
    """
    sqR = np.sqrt(_f64(R_eff))
    E_eff = _f64(E_eff)
    return (16.0 / 15.0) * sqR * E_eff * (15.0 * _f64(m_eff) * v_char**2 / (16.0 * sqR * E_eff)) ** 0.2


def reduced_mass(m1: ArrayLike, m2: ArrayLike) -> np.ndarray:
    """m* = m1 m2/(m1 + m2) (kg); m2 = inf (a wall) gives m1."""
    m1, m2 = _f64(m1), _f64(m2)
    return 1.0 / (1.0 / m1 + 1.0 / m2)
