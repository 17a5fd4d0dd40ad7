"""Compiled per-contact loops: the hot paths of :mod:`demsplit.physics.partition` and the LIGGGHTS join.

Numpy evaluates an expression one operation at a time over whole arrays, so
the per-contact work (gather both bodies, the law, the split, the contact
point, the sums per body) made some 40 passes over millions of contacts.
Here each stage is one loop over the contacts, compiled by numba
(:func:`demsplit.runtime.jit.kernel`: cached, GIL released, numpy error model).

No second copy of the physics: the loops call the formulas of
:mod:`demsplit.physics.formulas` (``hertz_energy_formula``,
``hertz_kt_formula``, ``spring_energy``, ``contact_point_coordinate``, ...),
compiled here from those very functions. This module imports only those
formulas and the compiled-function decorator: nothing above it.
The public array API evaluates the same functions on arrays, so the two give
the same IEEE operations in the same order; ``tests/test_kernels.py`` checks
the compiled paths against the numpy formulation (bit for bit, except |v|^2,
which the loops sum in order x, y, z where ``np.einsum`` may pair the terms
differently: one ulp). Checks that raise (unknown ids, unknown walls or types,
curvatures) are reported by the loops as the index of the first bad contact
(-1: none), and the caller raises the usual error.

Per-contact values come as ``(values, code)``: with a non-empty ``code``
contact i has ``values[code[i]]`` (a small table per pair of material types,
``code = type1 * n_types + type2``); with an empty ``code``, ``values`` holds
one value per contact, or a single value for all of them (length 1).

Energies of the modes (:mod:`demsplit.physics.modes`) come as one array of
shape (modes, contacts), row m the energy of mode m, and the shares as
``(values, code)`` with one row of values per mode, or a single row that every
mode shares. The loops add the modes of a contact in mode order.

Outputs are allocated by numpy and filled by the loops (the public functions
here are thin wrappers around the compiled ``_...`` loops): numpy asks the
kernel for transparent huge pages on large arrays, numba's allocator does not,
and the 4 KiB page faults of fresh numba arrays dominate a loop
(``docs/performance.md``, "Standing decisions").

This module imports numba: import it lazily, inside the functions that use it
(``import demsplit`` must work in YADE's Python, without numba).
"""

from __future__ import annotations

import numpy as np

from .physics import formulas
from .runtime import threads
from .runtime.jit import kernel

_clamped_overlap = kernel(formulas.clamped_overlap)
_inverse_curvature_sum = kernel(formulas.inverse_curvature_sum)
_hertz_energy = kernel(formulas.hertz_energy_formula)
_hertz_kt = kernel(formulas.hertz_kt_formula)
_squared_norm = kernel(formulas.squared_norm)
_spring_energy = kernel(formulas.spring_energy)
_contact_point_coordinate = kernel(formulas.contact_point_coordinate)
_minimum_image = kernel(formulas.minimum_image_components)


NO_CODE = np.empty(0, np.int64)
"""The ``code`` of values given per contact (or one for all)."""


@kernel
def _stride(values):
    """Step through per-contact ``values`` given without code: 0 for one value for all."""
    return 0 if values.shape[0] == 1 else 1


# Loops select values inline, ``values[code[i]] if coded else values[i * stride]``:
# a helper function taking the arrays would not be inlined and would pay numba's
# reference counting of both arrays on every call, which costs more than the loop's work. For the same
# reason the formulas called per contact get scalars and tuples, never arrays.


def contact_rows(row_of_id, id1, id2, wall):
    """Particle rows of both bodies of every contact from a dense id -> row table
    (-1: no particle), in the table's integer type. For a wall contact rows2 is
    -1 - wall (< 0). Returns (rows1, rows2, first contact naming an unknown id or -1);
    pieces of the contacts on every core."""
    rows1 = np.empty(len(id1), row_of_id.dtype)
    rows2 = np.empty(len(id1), row_of_id.dtype)

    def piece(lo: int, hi: int) -> int:
        return _offset(_contact_rows(row_of_id, id1[lo:hi], id2[lo:hi], wall[lo:hi], rows1[lo:hi], rows2[lo:hi]), lo)

    return rows1, rows2, _first_found(threads.map_ranges(piece, len(id1)))


def _offset(found: int, lo: int) -> int:
    """A piece's first contact found (-1: none) as a contact of the whole range, the piece starting at ``lo``."""
    return found if found < 0 else lo + found


def _first_found(found: list[int]) -> int:
    """The first contact found by the pieces, in order (-1: none)."""
    return next((f for f in found if f >= 0), -1)


@kernel
def _contact_rows(row_of_id, id1, id2, wall, rows1, rows2):
    n = id1.shape[0]
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
    return bad


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


def hertz_history_energies(delta, r1, r2, E_eff, G_eff, code, shearx, sheary, shearz, with_shear):
    """LIGGGHTS ``model hertz`` (+ ``tangential history``) energies of every contact (J):
    u_n = (8/15) E* sqrt(R* d) d^2 and, with shear, u_t = kt |shear|^2 / 2 with
    kt = 8 G* sqrt(R* d) where delta > 0 (0 elsewhere); R* = 1/(1/r1 + 1/r2),
    d = max(delta, 0). E_eff, G_eff: values for ``code`` (module docstring).
    Returns (u_n, u_t, first contact with 1/r1 + 1/r2 <= 0 or -1); pieces of the contacts on every core."""
    n = len(delta)
    u_n = np.empty(n)
    u_t = np.empty(n)
    per_contact = len(code) == 0  # E_eff, G_eff: one value per contact (cut with them) or one for all

    def moduli(values, lo: int, hi: int):
        return values[lo:hi] if per_contact and len(values) > 1 else values

    def piece(lo: int, hi: int) -> int:
        return _offset(
            _hertz_history_energies(
                delta[lo:hi],
                r1[lo:hi],
                r2[lo:hi],
                moduli(E_eff, lo, hi),
                moduli(G_eff, lo, hi),
                code[lo:hi],
                shearx[lo:hi],
                sheary[lo:hi],
                shearz[lo:hi],
                with_shear,
                u_n[lo:hi],
                u_t[lo:hi],
            ),
            lo,
        )

    return u_n, u_t, _first_found(threads.map_ranges(piece, n))


@kernel
def _hertz_history_energies(delta, r1, r2, E_eff, G_eff, code, shearx, sheary, shearz, with_shear, u_n, u_t):
    n = delta.shape[0]
    coded, se, sg = code.shape[0] > 0, _stride(E_eff), _stride(G_eff)
    bad = -1
    for i in range(n):
        R = _inverse_curvature_sum(r1[i], r2[i])
        if (R < 0.0 or R == np.inf) and bad < 0:  # 1/R* <= 0
            bad = i
        d = _clamped_overlap(delta[i])
        u_n[i] = _hertz_energy(d, R, E_eff[code[i]] if coded else E_eff[i * se])
        if with_shear and delta[i] > 0.0:
            u_t[i] = _spring_energy(
                _hertz_kt(d, R, G_eff[code[i]] if coded else G_eff[i * sg]),
                _squared_norm(shearx[i], sheary[i], shearz[i]),
            )
        else:
            u_t[i] = 0.0
    return bad


def split_contacts(share_values, share_code, u, delta, x1, y1, z1, nx, ny, nz, r1):
    """Per contact: the share of body 1 of every mode (``share_values`` of shape (modes or 1, K),
    ``share_code``: module docstring), u1 = sum_m s_m u_m, u2 = sum_m (1 - s_m) u_m (``u``: shape
    (modes, n), J), depth1 = s_0 delta (the normal mode's share) and the contact point
    x1 + (r1 - depth1) n, shape (3, n), pieces of the contacts on every core.
    Returns (shares (modes, n), u1, u2, depth1, cp)."""
    n = len(delta)
    shares = np.empty((u.shape[0], n))
    out = [np.empty(n) for _ in range(3)]
    cp = np.empty((3, n))
    per_contact = share_values.shape[1] > 1 and len(share_code) == 0

    def piece(lo: int, hi: int) -> None:
        values = share_values[:, lo:hi] if per_contact else share_values
        _split_contacts(
            values,
            share_code[lo:hi],
            tuple(u[:, lo:hi]),
            delta[lo:hi],
            x1[lo:hi],
            y1[lo:hi],
            z1[lo:hi],
            nx[lo:hi],
            ny[lo:hi],
            nz[lo:hi],
            r1[lo:hi],
            tuple(shares[:, lo:hi]),
            *(o[lo:hi] for o in out),
            cp[:, lo:hi],
        )

    threads.map_ranges(piece, n)
    return (shares, *out, cp)


# The energies and shares of the modes go into the loops as tuples of 1-D arrays (rows of the (modes, n)
# arrays, no copy): numba compiles one loop per number of modes, whose inner loop over the modes it unrolls.
# With the (modes, n) arrays themselves the per-body sums took three times as long.


@kernel
def _split_contacts(share_values, share_code, u, delta, x1, y1, z1, nx, ny, nz, r1, shares, u1, u2, depth1, cp):
    n = delta.shape[0]
    coded = share_code.shape[0] > 0
    per_mode = share_values.shape[0] > 1
    per_contact = share_values.shape[1] > 1
    for i in range(n):
        # the share's column: inline, as a helper taking the arrays would pay their reference counts per call
        col = share_code[i] if coded else (i if per_contact else 0)
        a = share_values[0, col]
        shares[0][i] = a
        b1 = a * u[0][i]
        b2 = (1.0 - a) * u[0][i]
        for m in range(1, len(u)):
            s = share_values[m if per_mode else 0, col]
            shares[m][i] = s
            b1 = b1 + s * u[m][i]
            b2 = b2 + (1.0 - s) * u[m][i]
        u1[i] = b1
        u2[i] = b2
        d1 = a * delta[i]
        depth1[i] = d1
        cp[0, i] = _contact_point_coordinate(x1[i], nx[i], r1[i], d1)
        cp[1, i] = _contact_point_coordinate(y1[i], ny[i], r1[i], d1)
        cp[2, i] = _contact_point_coordinate(z1[i], nz[i], r1[i], d1)


def body_sums(rows1, rows2, shares, u, n_particles, n_walls):
    """Sums per particle and per wall (rows2 = -1 - wall) of the energy of every mode each body
    stores (body 1: s u; body 2: u - s u; ``shares`` and ``u`` of shape (modes, n)) and of its contacts.

    Body-1 and body-2 terms are summed separately, each in contact order, and added
    at the end: the order of ``np.bincount(rows1, w1) + np.bincount(rows2, w2)``,
    so the sums are those of the numpy formulation bit for bit.
    Returns (particle energies (modes, n_particles), n_contacts, wall energies (modes, n_walls), n_contacts)."""
    modes = u.shape[0]
    # one row per particle: body-1 sums of every mode, body-2 sums, the count: one cache line per visit
    acc = np.zeros((n_particles, 2 * modes + 1))
    walls = np.zeros((modes, n_walls))
    w_count = np.zeros(n_walls, np.int64)
    _body_sums(rows1, rows2, tuple(shares), tuple(u), acc, walls, w_count)
    particles = np.empty((modes, n_particles))
    for m in range(modes):
        np.add(acc[:, m], acc[:, modes + m], out=particles[m])
    return particles, acc[:, 2 * modes].astype(np.int64), walls, w_count


@kernel
def _body_sums(rows1, rows2, shares, u, acc, walls, w_count):
    n = rows1.shape[0]
    modes = len(u)
    count = 2 * modes
    for i in range(n):
        r = rows1[i]
        r2 = rows2[i]
        if r2 >= 0:
            for m in range(modes):
                b1 = shares[m][i] * u[m][i]
                acc[r, m] += b1
                acc[r2, modes + m] += u[m][i] - b1
            acc[r2, count] += 1.0
        else:
            w = -1 - r2
            for m in range(modes):
                b1 = shares[m][i] * u[m][i]
                acc[r, m] += b1
                walls[m, w] += u[m][i] - b1
            w_count[w] += 1
        acc[r, count] += 1.0  # counts below 2^53 are exact in a double


def particle_sums(rows1, rows2, share_values, u, n_particles):
    """Energy of every particle under one share per contact for every mode (``share_values`` of
    shape (1, n) or (1, 1)): u1 = sum_m s u_m on body 1, sum_m u_m - u1 on body 2 of particle
    pairs (rows2 >= 0); sums in the order of :func:`body_sums`."""
    acc = np.zeros((n_particles, 2))  # body-1 and body-2 sums of a particle side by side
    _particle_sums(rows1, rows2, share_values, tuple(u), acc)
    return acc[:, 0] + acc[:, 1]


@kernel
def _particle_sums(rows1, rows2, share_values, u, acc):
    n = rows1.shape[0]
    per_contact = share_values.shape[1] > 1
    for i in range(n):
        s = share_values[0, i if per_contact else 0]
        b1 = s * u[0][i]
        total = u[0][i]
        for m in range(1, len(u)):
            b1 = b1 + s * u[m][i]
            total = total + u[m][i]
        acc[rows1[i], 0] += b1
        r2 = rows2[i]
        if r2 >= 0:
            acc[r2, 1] += total - b1


def signed_particle_sums(rows1, rows2, e, u, n_particles):
    """Per particle, the sum of e u over the contacts where it is body 1 minus the sum over the particle
    pairs (rows2 >= 0) where it is body 2 (the units of u): the expected error of each particle's normal
    energy from the share errors e. Each sum in contact order, then their difference: bit for bit
    ``np.bincount(rows1, e u) - np.bincount(rows2[pair], (e u)[pair])``, without those arrays."""
    acc = np.zeros((n_particles, 2))
    _signed_sums(rows1, rows2, e, u, acc)
    return acc[:, 0] - acc[:, 1]


@kernel
def _signed_sums(rows1, rows2, e, u, acc):
    for i in range(rows1.shape[0]):
        d = e[i] * u[i]
        acc[rows1[i], 0] += d
        r2 = rows2[i]
        if r2 >= 0:
            acc[r2, 1] += d


@kernel
def max_wall(rows2):
    """Largest wall index of the contacts, from rows2 = -1 - wall (-1: no wall contact)."""
    m = -1
    for i in range(rows2.shape[0]):
        if -1 - rows2[i] > m:
            m = -1 - rows2[i]
    return m


def repeated_pair(rows1, rows2, n_particles):
    """Contacts ``(first, repeat)`` of the earliest-repeated particle pair (rows, in
    either order), or ``(i, i)`` for a particle paired with itself, whichever
    repeat comes first; (-1, -1) when every contact is a distinct pair. O(n):
    contacts are bucketed by their lower row (a counting sort keeping contact
    order) and each bucket, a particle's few neighbours, is searched directly."""
    return _repeated_pair(rows1, rows2, np.zeros(n_particles + 1, np.int64), np.empty(len(rows1), np.int64))


@kernel
def _repeated_pair(rows1, rows2, start, members):
    n = rows1.shape[0]
    n_particles = start.shape[0] - 1
    for i in range(n):
        start[min(rows1[i], rows2[i]) + 1] += 1
    for r in range(n_particles):
        start[r + 1] += start[r]
    fill = start[:-1].copy()
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


def pair_geometry(rows1, rows2, xyzr, h, lengths, tilt, periodic, with_cp):
    """The join of a particle-pair contact list with the particles (rows), one pass
    (``xyzr``: each particle's centre and radius in one row, one cache line to fetch):
    d = x2 - x1 (minimum image along ``periodic`` axes), dist = |d|, the unit
    normal n = d/dist (d where dist = 0), body 1's centre and both radii, the
    overlap from positions r1 + r2 - dist, the larger printed step of the two
    centres (when ``h`` is given, else an empty array) and, ``with_cp``,
    LIGGGHTS' radius-weighted contact point x1 + r1/(r1 + r2) d, shape (3, n)
    (``contactPoint`` of ``compute pair/gran/local``), pieces of the list on every core.
    Returns (nx, ny, nz, x1, y1, z1, r1, r2, gap, hmax, cp)."""
    n = len(rows1)
    out = [np.empty(n) for _ in range(9)]
    hmax = np.empty(n if len(h) else 0)
    cp = np.empty((3, n if with_cp else 0))

    def piece(lo: int, hi: int) -> None:
        _pair_geometry(
            rows1[lo:hi],
            rows2[lo:hi],
            xyzr,
            h,
            lengths,
            tilt,
            periodic,
            *(o[lo:hi] for o in out),
            hmax[lo:hi],
            cp[:, lo:hi],
        )

    threads.map_ranges(piece, n)
    return (*out, hmax, cp)


@kernel
def _pair_geometry(rows1, rows2, xyzr, h, lengths, tilt, periodic, nx, ny, nz, x1, y1, z1, r1, r2, gap, hmax, cp):
    n = rows1.shape[0]
    with_h = hmax.shape[0] > 0
    with_cp = cp.shape[1] > 0
    box = (lengths[0], lengths[1], lengths[2])  # tuples, not arrays, into the per-contact call
    skew = (tilt[0], tilt[1], tilt[2])
    for i in range(n):
        a = rows1[i]
        b = rows2[i]
        xa, ya, za, ra = xyzr[a, 0], xyzr[a, 1], xyzr[a, 2], xyzr[a, 3]
        rb = xyzr[b, 3]
        dx, dy, dz = _minimum_image(xyzr[b, 0] - xa, xyzr[b, 1] - ya, xyzr[b, 2] - za, box, skew, periodic)
        dist = np.sqrt(_squared_norm(dx, dy, dz))
        s = dist if dist > 0 else 1.0
        nx[i] = dx / s
        ny[i] = dy / s
        nz[i] = dz / s
        x1[i] = xa
        y1[i] = ya
        z1[i] = za
        r1[i] = ra
        r2[i] = rb
        gap[i] = ra + rb - dist
        if with_h:
            hmax[i] = max(h[a], h[b])
        if with_cp:
            w = ra / (ra + rb)
            cp[0, i] = xa + w * dx
            cp[1, i] = ya + w * dy
            cp[2, i] = za + w * dz
