"""The hysteretic linear spring LIGGGHTS' ``hooke/hysteresis`` and ``luding`` models share (Walton-Braun/Luding).

Loading follows k1 delta; unloading and reloading follow a steeper line of
slope k2 through the point of largest overlap delta_max, with k2 growing from
k1 to k2Max as delta_max approaches delta_lim = k2Max/(k2Max - k1) phiF 2 R*
(beyond it k2 = k2Max and the line passes through k1 delta_lim); the force
never goes below the adhesive branch -kc delta (``normal_model_hooke_hysteresis.h``,
``normal_model_luding.h``):

    f = min(k1 delta, max(k2 (delta - delta_max) + k1 delta_max, -kc delta)).

The elastic energy is what the contact gives back unloading along its current
k2 line to zero force, u_n = f^2/(2 k2), whose derivative along that line is f
itself. delta_max is the contact's history as LIGGGHTS wrote it (after its
update at the output step), so the energy needs no trajectory.

The force gives delta_max back: below delta_lim the unloading line through delta_max is
f = k1 delta + a delta_max (delta - delta_max), a = (k2Max - k1)/delta_lim, whose root delta_max >= delta is
(delta + sqrt(delta^2 - 4 (f - k1 delta)/a))/2 (delta_max = delta on the loading line); the adhesive branch
f = -kc delta sets delta_max to that same root (``normal_model_hooke_hysteresis.h:170-190``).
"""

from __future__ import annotations

import numpy as np

from ..elastic import overlap
from ..moduli import effective_radius
from .base import ContactRows

DELTA_MAX = "delta_max"
"""Contact column of the largest overlap so far (m), the normal model's first history value."""


def hysteretic_force(
    delta: np.ndarray, delta_max: np.ndarray, k1: np.ndarray, k2max: np.ndarray, kc: np.ndarray, delta_lim: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Elastic normal force f (N) and unloading stiffness k2 (N/m) of the hysteretic spring
    (module docstring); 0 force without overlap."""
    d = overlap(delta)
    dmax = np.maximum(delta_max, d)
    big = dmax >= delta_lim
    with np.errstate(invalid="ignore", divide="ignore"):
        k2 = np.where(big, k2max, k1 + (k2max - k1) * dmax / delta_lim)
    anchor = np.where(big, delta_lim, dmax)
    line = k2 * (d - anchor) + k1 * anchor
    f = np.where(big, np.maximum(line, -kc * d), np.minimum(k1 * d, np.maximum(line, -kc * d)))
    return np.where(d > 0, f, 0.0), k2


def unloading_energy(f: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """Energy released unloading along the k2 line to zero force, f^2/(2 k2) (J)."""
    return np.divide(f * f, 2.0 * k2, out=np.zeros_like(f), where=k2 > 0)


def delta_max_of_force(
    f: np.ndarray, delta: np.ndarray, k1: np.ndarray, k2max: np.ndarray, delta_lim: np.ndarray
) -> np.ndarray:
    """The largest overlap delta_max (m) of a contact at overlap ``delta`` (m) whose elastic force is ``f`` (N)
    (module docstring): (delta + sqrt(delta^2 - 4 (f - k1 delta)/a))/2 with a = (k2Max - k1)/delta_lim, delta
    itself where f >= k1 delta. Beyond delta_lim the unloading line no longer depends on delta_max: a force that no
    delta_max gives is found by comparing :func:`hysteretic_force` of the result with f."""
    d = overlap(delta)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (k2max - k1) / delta_lim
        disc = d * d - 4.0 * (f - k1 * d) / slope
    return np.where(f >= k1 * d, d, 0.5 * (d + np.sqrt(np.maximum(disc, d * d))))


def hysteresis_parameters(
    rows: ContactRows, k1: np.ndarray, k2max_over_k1, kc_over_k1, plasticity_depth
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """k2Max, kc (N/m) and delta_lim = k2Max/(k2Max - k1) phiF 2 R* (m) of every row, from the loading stiffness
    ``k1`` and the per-type-pair ratios k2Max/k1, kc/k1 and the plasticity depth phiF."""
    k2max = k1 * rows.type_pair(k2max_over_k1)
    kc = k1 * rows.type_pair(kc_over_k1)
    with np.errstate(divide="ignore", invalid="ignore"):
        lim = k2max / (k2max - k1) * rows.type_pair(plasticity_depth) * 2.0 * effective_radius(rows.r1, rows.r2)
    return k2max, kc, lim


def hysteresis_of(
    rows: ContactRows, k1: np.ndarray, k2max_over_k1, kc_over_k1, plasticity_depth
) -> tuple[np.ndarray, np.ndarray]:
    """Force f (N) and unloading stiffness k2 (N/m) of every row, from the loading stiffness ``k1`` and the
    per-type-pair ratios k2Max/k1, kc/k1 and the plasticity depth phiF (:func:`hysteresis_parameters`)."""
    k2max, kc, lim = hysteresis_parameters(rows, k1, k2max_over_k1, kc_over_k1, plasticity_depth)
    return hysteretic_force(rows.delta, rows.column(DELTA_MAX), k1, k2max, kc, lim)
