"""The force and torque a LIGGGHTS contact applies in one step, and the springs a wall fix's stored force gives back.

LIGGGHTS 3.8.0 evaluates a contact in ``post_force``, between the two half steps of the Verlet integration of
``fix nve/sphere`` (``fix_nve_sphere.cpp:157-181``: v += dt/2 f/m and omega += dt/2 tau/I, I = 0.4 m r^2, before
and after the force). So the force of a step used the velocities

    v_h = v - (dt/2) f/m,   omega_h = omega - (dt/2) tau/(0.4 m r^2)

of the dumped (end-of-step) v, omega, f, tau; a frame written at the setup of a ``run`` has no half step between
them (the force used the dumped velocities) and updates no history (``fix_wall_gran.cpp:740``: ``shearupdate``
is 0 then).

At a contact of unit normal e_n (from body 2 to body 1; from the wall to the particle), distance r between the
centres (the centre and the wall surface), lever arms c = r_k - delta/2 (0 for a wall) and relative velocity v
(``surface_model_default.h:150-203``):

    v_n = v . e_n,   w_r = (c_1 omega_1 + c_2 omega_2)/r,   v_tr = v - v_n e_n - w_r x (r e_n);

the normal force is the normal model's elastic force less its damping, F_n = f - gamma_n v_n; the tangential
history spring F_el = -k_t shear (``tangential_model_history.h:147-228``) is capped by Coulomb's mu |F_n|:

    |F_el| > mu |F_n|:  F_t = F_el mu |F_n|/|F_el|  (no damping; with shearupdate the history is rescaled to it),
    else:               F_t = F_el - gamma_t v_tr;

its torque on body k is -c_k e_n x F_t (``:229-262``). Rolling friction ``epsd2`` (``rolling_model_epsd2.h:98-224``)
adds the spring torque M = M_hist + k_r w_t dt (w_t: omega_1 - omega_2, or w_r on a wall, less its part along
e_n), capped at mu_r |F_n| R*, stored only with shearupdate, applied as -M on body 1 and +M on body 2.

A wall fix with ``store_force yes`` keeps the force F it applied to each particle (``fix_wall_gran_base.h:205-206,
345-350``). Split into F_n = F . e_n and F_t, it gives the spring back: mid-run a capped contact's history was
rescaled to F_t itself; an uncapped one's spring is F_t + gamma_t v_tr; at a setup frame a capped contact's history
was not rescaled, and only its direction is known.
"""

from __future__ import annotations

import numpy as np

NVE_SPHERE_INERTIA = 0.4
"""I/(m r^2) of a sphere as ``fix nve/sphere`` integrates it."""
CLOSURE_ULPS = 64.0
"""A particle's force (torque) balance closes to this many eps times the sum of the magnitudes of its terms, plus
the printed precision (:func:`closure_tolerance`): the rounding of the sums LIGGGHTS accumulates and of their
recomputation."""
CAP_RTOL = 1e-9
"""How close |F_t| (|M|) must be to the Coulomb (rolling) cap for the contact to count as sliding at it: an uncapped
contact lands that close only by accident."""


def magnitude(a: np.ndarray) -> np.ndarray:
    """|a| of every row of an (n, 3) array."""
    return np.sqrt(np.einsum("ij,ij->i", a, a))


def half_step_velocities(
    v: np.ndarray,
    omega: np.ndarray,
    force: np.ndarray,
    torque: np.ndarray,
    mass: np.ndarray,
    radius: np.ndarray,
    dt: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The velocities (m/s, rad/s; (n, 3)) a step's force used, from the dumped end-of-step ones and the dumped force
    (N) and torque (N m): v - (dt/2) f/m, omega - (dt/2) tau/(0.4 m r^2) (module docstring)."""
    dtf = 0.5 * dt
    dtfm = dtf / mass
    dtirotate = dtf / NVE_SPHERE_INERTIA / (radius * radius * mass)
    return v - dtfm[:, None] * force, omega - dtirotate[:, None] * torque


def contact_velocity(v: np.ndarray, en: np.ndarray, w_r: np.ndarray, dist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """v_n (m/s) and v_tr (m/s, (n, 3)) of a relative velocity ``v`` at a contact of normal ``en``, centre distance
    ``dist`` (m) and rotational term ``w_r`` = (c_1 omega_1 + c_2 omega_2)/r (rad/s): v_n = v . e_n,
    v_tr = v - v_n e_n - w_r x (r e_n)."""
    vn = np.einsum("ij,ij->i", v, en)
    return vn, v - vn[:, None] * en - np.cross(w_r, en * dist[:, None])


def tangential_part(w: np.ndarray, en: np.ndarray) -> np.ndarray:
    """``w`` less its part along e_n, w - (w . e_n) e_n."""
    return w - np.einsum("ij,ij->i", w, en)[:, None] * en


def coulomb_rescaled(vec: np.ndarray, cap: np.ndarray) -> np.ndarray:
    """``vec`` rescaled to ``cap`` where its magnitude exceeds it (the Coulomb and the rolling cap)."""
    mag = magnitude(vec)
    return vec * np.where(mag > cap, cap / np.where(mag > 0, mag, 1.0), 1.0)[:, None]


def at_cap(vec: np.ndarray, cap: np.ndarray, setup: bool) -> np.ndarray:
    """Whether a spring (or rolling torque) ``vec`` as the history holds it after the step sat at its cap in the
    step: at a setup step (no update) where it exceeds it; mid-run where it reaches it to CAP_RTOL (a capped history
    was rescaled to the cap)."""
    mag = magnitude(vec)
    return mag > cap if setup else mag >= cap * (1.0 - CAP_RTOL)


def onto_cap(vec: np.ndarray, cap: np.ndarray) -> np.ndarray:
    """``vec`` rescaled to the magnitude ``cap`` (a zero vector stays zero)."""
    mag = magnitude(vec)
    return vec * (cap / np.where(mag > 0, mag, 1.0))[:, None]


def applied_tangential_force(
    spring: np.ndarray, cap: np.ndarray, gamma_t: np.ndarray, vtr: np.ndarray, setup: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The tangential force (N, (n, 3)) a contact applied in the step and whether it sat at the Coulomb cap
    mu |F_n| (N), from its spring F_el = -k_t shear as the history holds it after the step (:func:`at_cap`): a
    capped one applied F_el rescaled to the cap (mid-run its history was rescaled to it: the rescaling only removes
    the rounding, or a copy's difference on the other side of a periodic boundary), an uncapped one adds the damping
    -gamma_t v_tr (module docstring)."""
    capped = at_cap(spring, cap, setup)
    return np.where(capped[:, None], onto_cap(spring, cap), spring - gamma_t[:, None] * vtr), capped


def tangential_spring(
    force: np.ndarray, cap: np.ndarray, gamma_t: np.ndarray, vtr: np.ndarray, slack: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The spring F_el = -k_t shear (N, (n, 3)) behind an applied tangential force ``force`` (N), and whether the
    contact sat at the cap mu |F_n| (``cap``, N), |F_t| within CAP_RTOL cap + ``slack`` of it: then F_el is F_t
    itself (mid-run, module docstring), else F_t + gamma_t v_tr."""
    capped = np.abs(magnitude(force) - cap) <= CAP_RTOL * cap + slack
    return np.where(capped[:, None], force, force + gamma_t[:, None] * vtr), capped


def rolling_increment(w: np.ndarray, en: np.ndarray, kr: np.ndarray, dt: float) -> np.ndarray:
    """The step's rolling spring increment k_r w_t dt (N m, (n, 3)) of ``epsd2``: w_t is the relative rotational
    velocity ``w`` (rad/s) less its part along e_n, k_r (N m/rad)."""
    return tangential_part(w, en) * (dt * kr)[:, None]


def applied_rolling_torque(history: np.ndarray, increment: np.ndarray, cap: np.ndarray, setup: bool) -> np.ndarray:
    """The rolling spring torque M (N m, (n, 3)) an ``epsd2`` contact applied in the step, from its history after
    the step: mid-run the history holds it (on the cap mu_r |F_n| R* (N m) where it reached it,
    :func:`at_cap`); at a setup step (no update) it is cap(M_hist + k_r w_t dt)."""
    if setup:
        return coulomb_rescaled(history + increment, cap)
    return np.where(at_cap(history, cap, False)[:, None], onto_cap(history, cap), history)


def contact_torque(lever: np.ndarray, en: np.ndarray, ft: np.ndarray) -> np.ndarray:
    """The torque (N m, (n, 3)) of a tangential force ``ft`` on a body of lever arm c (m): -c e_n x F_t."""
    return -lever[:, None] * np.cross(en, ft)


def closure_tolerance(scale: np.ndarray, print_rtol: float) -> np.ndarray:
    """How far a balance may miss: (CLOSURE_ULPS eps + 4 p) times ``scale``, the sum of the magnitudes of its terms,
    with p the relative rounding of one printed value (0 for %.17g, which round-trips; 5e-6 for %g's 6 digits)."""
    return (CLOSURE_ULPS * np.finfo(np.float64).eps + 4.0 * print_rtol) * scale
