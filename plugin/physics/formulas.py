"""The pure formulas: one definition for numpy and for the compiled loops.

Every function here is written with operators and numpy ufuncs only, takes
float64 arrays or scalars and checks nothing, so the same function works on
whole arrays (numpy) and, compiled by numba (:mod:`demsplit.kernels`), on the
scalars of one contact. Both therefore perform the same IEEE operations in the
same order: the compiled results equal the numpy ones bit for bit. This module
is a leaf: it imports numpy only. SI units throughout (m, Pa, N, J).

Equation numbers refer to Feng & Gao, "On the strain energy distribution of
two elastic solids under smooth contact" (the paper), corrected as in
``docs/physics.md``.
"""

from __future__ import annotations

import numpy as np


def clamped_overlap(delta):
    """delta clamped to >= 0 (m): a separated pair stores no elastic energy (NaN stays NaN)."""
    return np.maximum(delta, 0.0)


def inverse_curvature_sum(R1, R2):
    """R* = 1/(1/R1 + 1/R2) (m), eq. (3), unchecked (R = inf is a plane)."""
    return 1.0 / (1.0 / R1 + 1.0 / R2)


def hertz_energy_formula(d, R_eff, E_eff):
    """Hertz elastic energy (8/15) E* sqrt(R* d) d^2 (J), eq. (13), for a clamped overlap d >= 0 (m)."""
    return (8.0 / 15.0) * E_eff * np.sqrt(R_eff * d) * d * d


def hertz_kt_formula(d, R_eff, G_eff):
    """Mindlin tangential stiffness 8 G* sqrt(R* d) (N/m) for a clamped overlap d >= 0 (m)."""
    return 8.0 * G_eff * np.sqrt(R_eff * d)


def squared_norm(x, y, z):
    """x^2 + y^2 + z^2, summed in that order."""
    return x * x + y * y + z * z


def spring_energy(k, s2):
    """k s^2 / 2 (J) of a spring of stiffness k (N/m) stretched by s (s2 = s^2, m^2)."""
    return 0.5 * k * s2


def body_energies(s_n, s_t, u_n, u_t):
    """Energy of body 1 and body 2 of a contact (J): u1 = s_n u_n + s_t u_t,
    u2 = (1 - s_n) u_n + (1 - s_t) u_t, with s_m the share of mode m to body 1."""
    return s_n * u_n + s_t * u_t, (1.0 - s_n) * u_n + (1.0 - s_t) * u_t


def contact_point_coordinate(x1, n, r1, depth1):
    """One coordinate of the contact point x1 + (r1 - depth1) n (m), eq. (31)."""
    return x1 + (r1 - depth1) * n


def minimum_image_components(dx, dy, dz, lengths, tilt, periodic):
    """Minimum image of difference vectors (dx, dy, dz) (m) in a box of edge
    ``lengths``, tilt ``xy xz yz`` and ``periodic`` axes, applying the tilt in the
    LAMMPS order (z, then y, then x)."""
    if periodic[2]:
        k = np.rint(dz / lengths[2])
        dz = dz - k * lengths[2]
        dy = dy - k * tilt[2]
        dx = dx - k * tilt[1]
    if periodic[1]:
        k = np.rint(dy / lengths[1])
        dy = dy - k * lengths[1]
        dx = dx - k * tilt[0]
    if periodic[0]:
        k = np.rint(dx / lengths[0])
        dx = dx - k * lengths[0]
    return dx, dy, dz
