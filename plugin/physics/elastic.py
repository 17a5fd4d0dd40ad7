"""Elastic force and energy of Hertz contacts and springs, vectorised.

The energy formulas several contact laws share (Hertz, the linear and the
power-law spring, the tangential spring). Every function takes numpy arrays or
scalars (broadcast together), computes in float64 and returns float64.
Overlaps delta <= 0 are clamped to 0 before any fractional power, so force and
energy are 0 (never NaN) for separated bodies; energies use the delta forms
(``(8/15) E* sqrt(R* delta) delta^2``), never the high-power force forms that
overflow. Equation numbers: Feng & Gao (``docs/physics.md``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ContactError
from .formulas import clamped_overlap, hertz_energy_formula, spring_energy, squared_norm
from .moduli import effective_modulus, effective_radius, f64


def overlap(delta: ArrayLike) -> np.ndarray:
    """The overlap as float64, clamped to >= 0 (m)."""
    return clamped_overlap(f64(delta))


def squared_norms(v: np.ndarray) -> np.ndarray:
    """|v|^2 of vectors (shape (n, 3)) or v^2 of magnitudes (shape (n,))."""
    return squared_norm(v[..., 0], v[..., 1], v[..., 2]) if v.ndim == 2 else v * v


def hertz_force_from_moduli(delta: ArrayLike, R_eff: ArrayLike, E_eff: ArrayLike) -> np.ndarray:
    """Hertz normal force P = (4/3) E* sqrt(R* delta) delta (N), eq. (12)."""
    d = overlap(delta)
    return (4.0 / 3.0) * f64(E_eff) * np.sqrt(f64(R_eff) * d) * d


def hertz_energy_from_moduli(delta: ArrayLike, R_eff: ArrayLike, E_eff: ArrayLike) -> np.ndarray:
    """Hertz elastic energy S = (8/15) E* sqrt(R* delta) delta^2 = (2/5) P delta (J), eq. (13)."""
    return hertz_energy_formula(overlap(delta), f64(R_eff), f64(E_eff))


def hertz_force(
    delta: ArrayLike, R1: ArrayLike, R2: ArrayLike, E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike
) -> np.ndarray:
    """Hertz normal force P = (4/3) E* sqrt(R*) delta^(3/2) (N), eqs. (2), (3), (12).

    R2 = inf for a plane; E = inf for a rigid body.
    """
    return hertz_force_from_moduli(delta, effective_radius(R1, R2), effective_modulus(E1, nu1, E2, nu2))


def hertz_energy(
    delta: ArrayLike, R1: ArrayLike, R2: ArrayLike, E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike, nu2: ArrayLike
) -> np.ndarray:
    """Hertz elastic energy S = (8/15) E* sqrt(R*) delta^(5/2) (J), eq. (13)."""
    return hertz_energy_from_moduli(delta, effective_radius(R1, R2), effective_modulus(E1, nu1, E2, nu2))


def hooke_energy(delta: ArrayLike, kn: ArrayLike) -> np.ndarray:
    """Linear spring energy S = kn delta^2 / 2 (J), the power law with n = 1."""
    d = overlap(delta)
    return 0.5 * f64(kn) * d * d


def power_law_energy(delta: ArrayLike, k: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Energy of a power-law contact F = k delta^n: S = k delta^(n+1)/(n+1) (J), eq. (25).

    n > 0; n = 1 is a linear spring, n = 3/2 with k = (4/3) E* sqrt(R*) is Hertz.
    """
    n = f64(n)
    if np.any(n <= 0):
        raise ContactError(f"the power-law exponent n must be > 0, got {np.min(n)!r}.")
    d = overlap(delta)
    return f64(k) * d ** (n + 1.0) / (n + 1.0)


def tangential_spring_energy(ft: ArrayLike, kt: ArrayLike) -> np.ndarray:
    """Tangential elastic energy S_t = |F_t|^2 / (2 kt) (J).

    ``ft`` is the elastic tangential force (N): a magnitude (shape (n,)) or
    vectors (shape (n, 3)). Where kt = 0 (YADE sets ks = 0 on a contact that
    has separated) the energy is 0.
    """
    ft2 = squared_norms(f64(ft))
    kt = f64(kt)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(kt > 0, 0.5 * ft2 / np.where(kt > 0, kt, 1.0), 0.0)


def shear_spring_energy(shear: ArrayLike, kt: ArrayLike) -> np.ndarray:
    """Tangential energy from a spring displacement: S_t = kt |shear|^2 / 2 (J).

    LIGGGHTS ``tangential history`` stores ``shear`` (m) with
    F_t,el = -kt shear; this is the same energy as
    :func:`tangential_spring_energy` of that force.
    """
    return spring_energy(f64(kt), squared_norms(f64(shear)))


def history_spring_energy(delta: ArrayLike, shear: ArrayLike, kt: ArrayLike) -> np.ndarray:
    """Energy kt |shear|^2 / 2 (J) of a tangential spring with memory (LIGGGHTS ``tangential history``)
    on contacts in overlap (delta > 0), 0 elsewhere; ``shear`` has shape (n, 3) (m)."""
    return np.where(f64(delta) > 0, shear_spring_energy(shear, kt), 0.0)


def stored_shear_energy(delta: ArrayLike, ft: ArrayLike, ks: ArrayLike) -> np.ndarray:
    """Energy |F_t|^2 / (2 ks) (J) of an incremental shear spring whose force F_t (N, shape (n, 3)) and
    stiffness ks (N/m) the simulator stored (YADE), on contacts in overlap (delta > 0), 0 elsewhere."""
    return np.where(f64(delta) > 0, tangential_spring_energy(ft, ks), 0.0)
