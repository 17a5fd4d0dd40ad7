"""Compiled per-contact loops: the hot paths of :mod:`demsplit.partition` and the LIGGGHTS join.

Numpy evaluates an expression one operation at a time over whole arrays, so
the per-contact work (gather both bodies, the law, the split, the contact
point, the sums per body) made some 40 passes over millions of contacts.
Here each stage is one loop over the contacts, compiled by numba
(:func:`demsplit.jit.kernel`: cached, GIL released, numpy error model).

No second copy of the physics: the loops call the formulas of
:mod:`demsplit.laws` and :mod:`demsplit.partition` (``hertz_energy_formula``,
``hertz_kt_formula``, ``spring_energy``, ``body_energies``,
``contact_point_coordinate``, ...), compiled here from those very functions.
The public array API evaluates the same functions on arrays, so the two give
the same IEEE operations in the same order; ``tests/test_kernels.py`` checks
the compiled paths against the numpy formulation. Checks that raise (unknown
ids, rigid pairs, curvatures) are reported by the loops as the index of the
first bad contact (-1: none), and the caller raises the usual error.

Per-contact values come as ``(values, code)``: with a non-empty ``code``
contact i has ``values[code[i]]`` (a small table per pair of material types,
``code = type1 * n_types + type2``); with an empty ``code``, ``values`` holds
one value per contact, or a single value for all of them (length 1).

This module imports numba: import it lazily, inside the functions that use it
(``import demsplit`` must work in YADE's Python, without numba).
"""

from __future__ import annotations

import numpy as np

from . import laws
from .frame import minimum_image_components
from .partition import body_energies, contact_point_coordinate
from .jit import kernel

_clamped_overlap = kernel(laws.clamped_overlap)
_inverse_curvature_sum = kernel(laws.inverse_curvature_sum)
_hertz_energy = kernel(laws.hertz_energy_formula)
_hertz_kt = kernel(laws.hertz_kt_formula)
_squared_norm = kernel(laws.squared_norm)
_spring_energy = kernel(laws.spring_energy)
_body_energies = kernel(body_energies)
_contact_point_coordinate = kernel(contact_point_coordinate)
_minimum_image = kernel(minimum_image_components)


NO_CODE = np.empty(0, np.int64)
"""The ``code`` of values given per contact (or one for all)."""


@kernel
def _stride(values):
    """Step through per-contact ``values`` given without code: 0 for one value for all."""
    return 0 if values.shape[0] == 1 else 1

# Loops select values inline, ``values[code[i]] if coded else values[i * stride]``:
# a helper function taking the arrays would not be inlined and would pay numba's
# reference counting of both arrays on every call (10x slower).


@kernel
def contact_rows(row_of_id, id1, id2, wall):
    """Particle rows of both bodies of every contact from a dense id -> row table
    (-1: no particle), in the table's integer type. For a wall contact rows2 is
    -1 - wall (< 0). Returns (rows1, rows2, first contact naming an unknown id or -1)."""
    n = id1.shape[0]
    rows1 = np.empty(n, row_of_id.dtype)
    rows2 = np.empty(n, row_of_id.dtype)
    bad = -1
    m = row_of_id.shape[0]
    for i in range(n):
        a = id1[i]
        r = row_of_id[a] if 0 <= a < m else -1
        rows1[i] = r
        w = wall[i]
        if w >= 0:
            rows2[i] = -1 - w
        else:
            b = id2[i]
            r2 = row_of_id[b] if 0 <= b < m else -1
            rows2[i] = r2
            if r2 < 0:
                r = -1
        if r < 0 and bad < 0:
            bad = i
    return rows1, rows2, bad


@kernel
def contact_types(rows1, rows2, ptype, wall_types, n_types, code):
    """Pair code type1 * n_types + type2 of every contact into ``code`` (body 1: a
    particle; body 2: a particle, or for rows2 = -1 - wall that wall's type), and
    which codes are present. Returns (present, first contact naming a wall beyond
    ``wall_types`` or -1, first contact with a type outside 0..n_types-1 or -1)."""
    n = rows1.shape[0]
    present = np.zeros(n_types * n_types, np.bool_)
    bad_wall = -1
    bad_type = -1
    for i in range(n):
        t1 = np.int64(ptype[rows1[i]])
        r2 = rows2[i]
        if r2 >= 0:
            t2 = np.int64(ptype[r2])
        elif -1 - r2 < wall_types.shape[0]:
            t2 = wall_types[-1 - r2]
        else:
            t2 = np.int64(-1)
            if bad_wall < 0:
                bad_wall = i
        if 0 <= t1 < n_types and 0 <= t2 < n_types:
            c = t1 * n_types + t2
            code[i] = c
            present[c] = True
        else:
            code[i] = 0
            if bad_type < 0:
                bad_type = i
    return present, bad_wall, bad_type


@kernel
def hertz_history_energies(delta, r1, r2, E_eff, G_eff, code, shearx, sheary, shearz, with_shear):
    """LIGGGHTS ``model hertz`` (+ ``tangential history``) energies of every contact (J):
    u_n = (8/15) E* sqrt(R* d) d^2 and, with shear, u_t = kt |shear|^2 / 2 with
    kt = 8 G* sqrt(R* d) where delta > 0 (0 elsewhere); R* = 1/(1/r1 + 1/r2),
    d = max(delta, 0). E_eff, G_eff: values for ``code`` (module docstring).
    Returns (u_n, u_t, first contact with 1/r1 + 1/r2 <= 0 or -1)."""
    n = delta.shape[0]
    u_n = np.empty(n)
    u_t = np.zeros(n)
    coded, se, sg = code.shape[0] > 0, _stride(E_eff), _stride(G_eff)
    bad = -1
    for i in range(n):
        R = _inverse_curvature_sum(r1[i], r2[i])
        if (R < 0.0 or R == np.inf) and bad < 0:  # 1/R* <= 0
            bad = i
        d = _clamped_overlap(delta[i])
        u_n[i] = _hertz_energy(d, R, E_eff[code[i]] if coded else E_eff[i * se])
        if with_shear and delta[i] > 0.0:
            u_t[i] = _spring_energy(_hertz_kt(d, R, G_eff[code[i]] if coded else G_eff[i * sg]),
                                    _squared_norm(shearx[i], sheary[i], shearz[i]))
    return u_n, u_t, bad


@kernel
def split_contacts(sn_values, sn_code, st_values, st_code, u_n, u_t, delta, x1, y1, z1, nx, ny, nz, r1):
    """Per contact: the shares s_n, s_t (from values and codes, module docstring),
    u1, u2 (:func:`~demsplit.partition.body_energies`), depth1 = s_n delta and
    the contact point x1 + (r1 - depth1) n, as an array of shape (3, n)."""
    n = delta.shape[0]
    s_n = np.empty(n)
    s_t = np.empty(n)
    u1 = np.empty(n)
    u2 = np.empty(n)
    depth1 = np.empty(n)
    cp = np.empty((3, n))
    n_coded, t_coded = sn_code.shape[0] > 0, st_code.shape[0] > 0
    sn, st = _stride(sn_values), _stride(st_values)
    for i in range(n):
        a = sn_values[sn_code[i]] if n_coded else sn_values[i * sn]
        b = st_values[st_code[i]] if t_coded else st_values[i * st]
        s_n[i] = a
        s_t[i] = b
        u1[i], u2[i] = _body_energies(a, b, u_n[i], u_t[i])
        d1 = a * delta[i]
        depth1[i] = d1
        cp[0, i] = _contact_point_coordinate(x1[i], nx[i], r1[i], d1)
        cp[1, i] = _contact_point_coordinate(y1[i], ny[i], r1[i], d1)
        cp[2, i] = _contact_point_coordinate(z1[i], nz[i], r1[i], d1)
    return s_n, s_t, u1, u2, depth1, cp


@kernel
def body_sums(rows1, rows2, s_n, s_t, u_n, u_t, n_particles, n_walls):
    """Sums per particle and per wall (rows2 = -1 - wall) of the normal and tangential
    energy each body stores (body 1: s u; body 2: u - s u) and of its contacts.

    Body-1 and body-2 terms are summed separately, each in contact order, and added
    at the end: the order of ``np.bincount(rows1, w1) + np.bincount(rows2, w2)``,
    so the sums are those of the numpy formulation bit for bit.
    Returns (particle u_n, u_t, n_contacts, wall u_n, u_t, n_contacts)."""
    n = rows1.shape[0]
    sn, st = _stride(s_n), _stride(s_t)
    p_un = np.zeros(n_particles)
    p_ut = np.zeros(n_particles)
    q_un = np.zeros(n_particles)
    q_ut = np.zeros(n_particles)
    p_count = np.zeros(n_particles, np.int64)
    w_un = np.zeros(n_walls)
    w_ut = np.zeros(n_walls)
    w_count = np.zeros(n_walls, np.int64)
    for i in range(n):
        un1 = s_n[i * sn] * u_n[i]
        ut1 = s_t[i * st] * u_t[i]
        r = rows1[i]
        p_un[r] += un1
        p_ut[r] += ut1
        p_count[r] += 1
        r2 = rows2[i]
        if r2 >= 0:
            q_un[r2] += u_n[i] - un1
            q_ut[r2] += u_t[i] - ut1
            p_count[r2] += 1
        else:
            w = -1 - r2
            w_un[w] += u_n[i] - un1
            w_ut[w] += u_t[i] - ut1
            w_count[w] += 1
    for r in range(n_particles):
        p_un[r] += q_un[r]
        p_ut[r] += q_ut[r]
    return p_un, p_ut, p_count, w_un, w_ut, w_count


@kernel
def particle_sums(rows1, rows2, s_n, s_t, u_n, u_t, n_particles):
    """Energy of every particle under shares s_n, s_t (per contact or one value):
    u1 = s_n u_n + s_t u_t on body 1, u_n + u_t - u1 on body 2 of particle pairs
    (rows2 >= 0); sums in the order of :func:`body_sums`."""
    n = rows1.shape[0]
    sn, st = _stride(s_n), _stride(s_t)
    p1 = np.zeros(n_particles)
    p2 = np.zeros(n_particles)
    for i in range(n):
        u1 = _body_energies(s_n[i * sn], s_t[i * st], u_n[i], u_t[i])[0]
        p1[rows1[i]] += u1
        r2 = rows2[i]
        if r2 >= 0:
            p2[r2] += u_n[i] + u_t[i] - u1
    for r in range(n_particles):
        p1[r] += p2[r]
    return p1


@kernel
def max_wall(rows2):
    """Largest wall index of the contacts, from rows2 = -1 - wall (-1: no wall contact)."""
    m = -1
    for i in range(rows2.shape[0]):
        if -1 - rows2[i] > m:
            m = -1 - rows2[i]
    return m


@kernel
def repeated_pair(rows1, rows2, n_particles):
    """Contacts ``(first, repeat)`` of the earliest-repeated particle pair (rows, in
    either order), or ``(i, i)`` for a particle paired with itself, whichever
    repeat comes first; (-1, -1) when every contact is a distinct pair. O(n):
    contacts are bucketed by their lower row (a counting sort keeping contact
    order) and each bucket, a particle's few neighbours, is searched directly."""
    n = rows1.shape[0]
    start = np.zeros(n_particles + 1, np.int64)
    for i in range(n):
        start[min(rows1[i], rows2[i]) + 1] += 1
    for r in range(n_particles):
        start[r + 1] += start[r]
    fill = start[:-1].copy()
    members = np.empty(n, np.int64)
    for i in range(n):
        a = min(rows1[i], rows2[i])
        members[fill[a]] = i
        fill[a] += 1
    first, repeat = -1, -1
    for i in range(n):
        if rows1[i] == rows2[i]:
            first, repeat = i, i
            break
    for r in range(n_particles):
        for k in range(start[r] + 1, start[r + 1]):
            j = members[k]
            if repeat >= 0 and j >= repeat:
                continue
            b = max(rows1[j], rows2[j])
            for m in range(start[r], k):
                e = members[m]
                if max(rows1[e], rows2[e]) == b:
                    first, repeat = e, j
                    break
    return first, repeat


@kernel
def pair_geometry(rows1, rows2, x, y, z, radius, h, lengths, tilt, periodic, with_cp):
    """The join of a particle-pair contact list with the particles (rows), one pass:
    d = x2 - x1 (minimum image along ``periodic`` axes), dist = |d|, the unit
    normal n = d/dist (d where dist = 0), body 1's centre and both radii, the
    overlap from positions r1 + r2 - dist, the larger printed step of the two
    centres (when ``h`` is given, else an empty array) and, ``with_cp``,
    LIGGGHTS' radius-weighted contact point x1 + r1/(r1 + r2) d, shape (3, n)
    (``contactPoint`` of ``compute pair/gran/local``).
    Returns (nx, ny, nz, x1, y1, z1, r1, r2, gap, hmax, cp)."""
    n = rows1.shape[0]
    nx = np.empty(n)
    ny = np.empty(n)
    nz = np.empty(n)
    x1 = np.empty(n)
    y1 = np.empty(n)
    z1 = np.empty(n)
    r1 = np.empty(n)
    r2 = np.empty(n)
    gap = np.empty(n)
    with_h = h.shape[0] > 0
    hmax = np.empty(n if with_h else 0)
    cp = np.empty((3, n if with_cp else 0))
    for i in range(n):
        a = rows1[i]
        b = rows2[i]
        dx, dy, dz = _minimum_image(x[b] - x[a], y[b] - y[a], z[b] - z[a], lengths, tilt, periodic)
        dist = np.sqrt(_squared_norm(dx, dy, dz))
        s = dist if dist > 0 else 1.0
        nx[i] = dx / s
        ny[i] = dy / s
        nz[i] = dz / s
        x1[i] = x[a]
        y1[i] = y[a]
        z1[i] = z[a]
        ra = radius[a]
        rb = radius[b]
        r1[i] = ra
        r2[i] = rb
        gap[i] = ra + rb - dist
        if with_h:
            hmax[i] = max(h[a], h[b])
        if with_cp:
            w = ra / (ra + rb)
            cp[0, i] = x[a] + w * dx
            cp[1, i] = y[a] + w * dy
            cp[2, i] = z[a] + w * dz
    return nx, ny, nz, x1, y1, z1, r1, r2, gap, hmax, cp
