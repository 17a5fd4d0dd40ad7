"""Axisymmetric finite-element model of a frictionless two-body contact: the open reference for the split.

Two bodies meet at the origin of the r-z plane, on the symmetry axis r = 0:

* body 1, a sphere of radius R1 (m), centre (0, R1), lies above z = 0;
* body 2, a sphere of radius R2 centre (0, -R2), or a flat block (``R2 = inf``, radius and depth ``L``), below.

Each sphere is modelled as the quarter disk between its pole and its equatorial plane (the paper's set-up,
Feng & Gao section 5.1: the equator is a symmetry plane of a sphere squeezed at both poles). Body 1's equator is
moved down by the overlap delta (u_z = -delta, u_r free); body 2's equator (or the block's base) has u_z = 0. The
axis has u_r = 0. The contact is frictionless, enforced by a penalty on the gap integrated at Gauss points of
body 1's facets against body 2's current (deformed) P2 surface; the potential
``Pi_c = 2 pi * int (eps/2) <-g>^2 r dS`` (J) is conservative, so the work of the reaction equals the
stored energy U1 + U2 + Pi_c.

Materials (SI units: Pa, m, N, J):

``small``
    linear elasticity, W = lambda/2 (tr eps)^2 + mu eps:eps, eps = sym(grad u) with eps_tt = u_r/r (hoop).
    The contact gap is still evaluated in the current positions x = X + u.
``neohooke``
    compressible neo-Hookean, W = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2, F_tt = 1 + u_r/r; first
    Piola stress P = mu (F - F^-T) + lambda ln J F^-T.

lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)). Elements: P2 triangles (scikit-fem), meshes built
by newest-vertex bisection of a coarse disk (scikit-fem's own adaptive refinement, no gmsh), graded from
element size ``h_c`` on the contact patch with growth ``grading`` per unit distance, boundary nodes snapped
onto the circle.

Energies are per whole body of revolution (the 2 pi is included): U_i = 2 pi * int W r dr dz (J). The contact
force P (N) is the reaction on body 1's equator. Hertz (Johnson 1985, eq. 4.22-4.23, the law demsplit uses):
1/E* = c1 + c2 with c_i = (1 - nu_i^2)/E_i, 1/R* = 1/R1 + 1/R2, a = sqrt(R* delta), P = 4/3 E* a delta,
S = 2/5 P delta, S_i = c_i/(c1 + c2) S.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu
from scipy.spatial import Delaunay
from skfem import Basis, BilinearForm, ElementTriP2, ElementVector, Functional, LinearForm, MeshTri, asm

TWO_PI = 2.0 * math.pi
DEBUG = False
STALL_TOL = 1e-4  # a stalled Newton is accepted below this out-of-balance force / Hertz force


# --------------------------------------------------------------------------------------------------- Hertz


def hertz(delta: float, R1: float, R2: float, E1: float, nu1: float, E2: float, nu2: float) -> dict:
    """Hertz contact of two spheres (R2 = inf for a plane) at overlap ``delta`` (m).

    Returns a (m), P (N) = 4/3 E* a delta, S (J) = 2/5 P delta and the law's share of body 1,
    f1 = c1/(c1 + c2) with c_i = (1 - nu_i^2)/E_i (E = inf is rigid, c = 0).
    """
    c1 = (1 - nu1**2) / E1
    c2 = (1 - nu2**2) / E2
    Estar = 1.0 / (c1 + c2)
    Rstar = 1.0 / (1.0 / R1 + 1.0 / R2)
    a = math.sqrt(Rstar * delta)
    P = 4.0 / 3.0 * Estar * a * delta
    return {"a": a, "P": P, "S": 0.4 * P * delta, "f1": c1 / (c1 + c2), "Estar": Estar, "Rstar": Rstar}


def delta_for(a_over_R1: float, R1: float, R2: float) -> float:
    """Overlap (m) at which the Hertz contact radius is a = a_over_R1 * R1: delta = a^2 / R*."""
    Rstar = 1.0 / (1.0 / R1 + 1.0 / R2)
    return (a_over_R1 * R1) ** 2 / Rstar


# ---------------------------------------------------------------------------------------------------- mesh


def _snap(m: MeshTri, kind: str, R: float, C: float) -> MeshTri:
    """Move boundary nodes of the curved surface back onto the ellipse (r/R)^2 + ((s - C)/C)^2 = 1."""
    if kind != "sphere":
        return m
    p = m.p.copy()
    ends = m.facets[:, m.boundary_facets()]
    pe = p[:, ends]
    axis = np.all(pe[0] == 0.0, axis=0)
    equator = np.all(pe[1] == C, axis=0)
    nodes = np.unique(ends[:, ~axis & ~equator])
    t = np.hypot(p[0, nodes] / R, (p[1, nodes] - C) / C)
    p[0, nodes] = p[0, nodes] / t
    p[1, nodes] = C + (p[1, nodes] - C) / t
    return MeshTri(p, m.t)


def body_mesh(
    kind: str, R: float, h_c: float, grading: float, patch: float, h_max: float, C: float | None = None
) -> MeshTri:
    """Graded triangle mesh of one body in pole-local coordinates (r, s): s (m) is the depth below the pole.

    ``kind`` 'sphere': the quarter disk r >= 0, s <= R of the sphere of radius R centred at (0, R); with
    ``C`` the quarter ellipse of the spheroid of horizontal semi-axis R and vertical semi-axis C, centre (0, C)
    (pole radius of curvature R^2/C).
    ``kind`` 'block': the square [0, R] x [0, R] (R is then the block's radius and depth L).
    Element edges are at most ``h_c + grading * d`` (m), d the distance to the contact patch
    {0 <= r <= patch, s = 0}, and at most ``h_max``.
    """
    C = R if C is None else C
    if kind == "sphere":
        ang = np.linspace(0.0, np.pi / 2, 9)
        inner = np.linspace(0.0, np.pi / 2, 4)
        pts = np.vstack(
            [
                [0.0, C],
                np.c_[R * np.sin(ang), C - C * np.cos(ang)],
                np.c_[0.55 * R * np.sin(inner), C - 0.55 * C * np.cos(inner)],
            ]
        )
    elif kind == "block":
        x = np.linspace(0.0, R, 5)
        pts = np.array([[xi, yi] for xi in x for yi in x])
    else:
        raise ValueError(kind)
    # exact axis (r = 0) and equator (s = C) coordinates: the boundary tests below compare with ==
    pts[np.abs(pts[:, 0]) < 1e-9 * R, 0] = 0.0
    pts[np.abs(pts[:, 1] - C) < 1e-9 * C, 1] = C
    tri = Delaunay(pts).simplices
    m = MeshTri(pts.T, tri.T)
    m = _snap(m.refined(), kind, R, C)
    for _ in range(200):
        pc = m.p[:, m.t]
        cent = pc.mean(axis=1)
        edge = np.linalg.norm(pc - np.roll(pc, 1, axis=1), axis=0).max(axis=0)
        d = np.hypot(np.maximum(cent[0] - patch, 0.0), cent[1])
        mark = np.nonzero(edge > np.minimum(h_c + grading * d, h_max))[0]
        if len(mark) == 0:
            break
        m = _snap(m.refined(mark), kind, R, C)
    return m


# --------------------------------------------------------------------------------------------- materials


def lame(E: float, nu: float) -> tuple[float, float]:
    """Lame constants (Pa): lambda = E nu/((1+nu)(1-2nu)), mu = E/(2(1+nu))."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def _grad3(u, r):
    """3x3 displacement gradient of an axisymmetric field (components r, z, theta); u a DiscreteField."""
    g = u.grad
    z = np.zeros_like(g[0, 0])
    return np.array([[g[0, 0], g[0, 1], z], [g[1, 0], g[1, 1], z], [z, z, u[0] / r]])


def _inv_det(F):
    """Inverse and determinant of 3x3 fields whose theta row/column is diagonal."""
    a, b, c, d, t = F[0, 0], F[0, 1], F[1, 0], F[1, 1], F[2, 2]
    det2 = a * d - b * c
    z = np.zeros_like(a)
    inv = np.array([[d / det2, -b / det2, z], [-c / det2, a / det2, z], [z, z, 1.0 / t]])
    return inv, det2 * t


def _log_J(G):
    """ln J = ln det(I + G) without the round-off of det - 1 (log1p of J - 1 expanded in G's entries): a stiff
    body's strains are ~1e-7 and its energy would otherwise be round-off."""
    a, b, c, d, t = G[0, 0], G[0, 1], G[1, 0], G[1, 1], G[2, 2]
    return np.log1p((a + d + a * d - b * c) * (1.0 + t) + t)


def _stress(G, model, lam, mu):
    """First Piola(-Kirchhoff) stress (Pa) for displacement gradient G (the Cauchy stress for 'small')."""
    if model == "small":
        return lam * np.einsum("ii...", G) * np.eye(3)[:, :, None, None] + mu * (G + G.transpose(1, 0, 2, 3))
    F = G + np.eye(3)[:, :, None, None]
    Fi, J = _inv_det(F)
    FiT = Fi.transpose(1, 0, 2, 3)
    # F - F^-T = G + G^T F^-T (F^-T - I = -G^T F^-T): no difference of two numbers near 1
    return mu * (G + np.einsum("ji...,jk...->ik...", G, FiT)) + lam * _log_J(G) * FiT


def _dstress(G, dG, model, lam, mu):
    """Directional derivative of the stress, dP = A : dG (Pa)."""
    if model == "small":
        return _stress(dG, "small", lam, mu)
    F = G + np.eye(3)[:, :, None, None]
    Fi, J = _inv_det(F)
    FiT = Fi.transpose(1, 0, 2, 3)
    trFidG = np.einsum("ij...,ji...", Fi, dG)
    FiT_dGT_FiT = np.einsum("ij...,kj...,kl...->il...", FiT, dG, FiT)
    return mu * dG + (mu - lam * _log_J(G)) * FiT_dGT_FiT + lam * trFidG * FiT


def _density(G, model, lam, mu):
    """Strain energy density W (J/m^3) of the reference volume."""
    if model == "small":
        eps = 0.5 * (G + G.transpose(1, 0, 2, 3))
        tr = np.einsum("ii...", eps)
        return 0.5 * lam * tr**2 + mu * np.einsum("ij...,ij...", eps, eps)
    # tr C - 3 = 2 tr G + G:G, written so that a stiff body's tiny strains keep their digits
    lnJ = _log_J(G)
    trC3 = 2.0 * np.einsum("ii...", G) + np.einsum("ij...,ij...", G, G)
    return 0.5 * mu * (trC3 - 2.0 * lnJ) + 0.5 * lam * lnJ**2


# ------------------------------------------------------------------------------------------------ bodies


@dataclass
class Body:
    """One body: mesh in global (r, z), P2 vector basis, material, boundary dofs, contact-surface facets."""

    mesh: MeshTri
    basis: Basis
    model: str
    lam: float
    mu: float
    axis_dofs: np.ndarray
    base_dofs: np.ndarray
    surf: np.ndarray  # (3, 2, nf) dofs of the surface facets near the contact, [end a, end b, mid] x [r, z]
    surf_X: np.ndarray  # (3, 2, nf) their reference positions
    offset: int = 0
    K_small: object = field(default=None, repr=False)
    base_r_dofs: np.ndarray | None = field(default=None, repr=False)  # u_r of the base (fixed if clamped)

    @property
    def ndofs(self) -> int:
        return self.basis.N

    def residual(self, u, tangent: bool = True):
        """Internal force vector (N/rad: without 2 pi) and tangent stiffness (None if not ``tangent``) at u (m)."""
        lam, mu, model = self.lam, self.mu, self.model

        if model == "small":
            if self.K_small is None:

                @BilinearForm
                def a(du, v, w):
                    r = w.x[0]
                    return np.einsum("ij...,ij...", _stress(_grad3(du, r), "small", lam, mu), _grad3(v, r)) * r

                self.K_small = asm(a, self.basis).tocsr()
            return self.K_small @ u, self.K_small

        prev = self.basis.interpolate(u)

        @LinearForm
        def f(v, w):
            r = w.x[0]
            return np.einsum("ij...,ij...", _stress(_grad3(w.prev, r), model, lam, mu), _grad3(v, r)) * r

        @BilinearForm
        def k(du, v, w):
            r = w.x[0]
            G = _grad3(w.prev, r)
            return np.einsum("ij...,ij...", _dstress(G, _grad3(du, r), model, lam, mu), _grad3(v, r)) * r

        if not tangent:
            return asm(f, self.basis, prev=prev), None
        return asm(f, self.basis, prev=prev), asm(k, self.basis, prev=prev).tocsr()

    def energy(self, u) -> float:
        """Stored strain energy U = 2 pi int W r dr dz (J) of the whole body of revolution."""
        lam, mu, model = self.lam, self.mu, self.model

        @Functional
        def e(w):
            r = w.x[0]
            return _density(_grad3(w.prev, r), model, lam, mu) * r

        return TWO_PI * e.assemble(self.basis, prev=self.basis.interpolate(u))


def make_body(
    which: int,
    kind: str,
    R: float,
    E: float,
    nu: float,
    model: str,
    h_c: float,
    grading: float,
    patch: float,
    surf_reach: float,
    C: float | None = None,
) -> Body:
    """Body 1 (above z = 0) or 2 (below) with its mesh, basis and the facets of its surface within r <= surf_reach.

    ``C``: vertical semi-axis of a spheroid (horizontal semi-axis R); None for a sphere."""
    C = R if C is None else C
    h_max = min(R, C) / 6.0 if kind == "sphere" else R / 4.0
    m = body_mesh(kind, R, h_c, grading, patch, h_max, C)
    p = m.p.copy()
    t = m.t.copy()
    if which == 2:
        p[1] = -p[1]
        t = t[[0, 2, 1]]
    m = MeshTri(p, t)
    basis = Basis(m, ElementVector(ElementTriP2()), intorder=4)
    base_z = C if which == 1 else -C
    axis = basis.get_dofs(lambda x: x[0] == 0.0).all("u^1")
    base = basis.get_dofs(lambda x: x[1] == base_z).all("u^2")
    # contact surface facets: boundary facets (not on the axis, not the base) with r <= surf_reach, near z = 0
    bf = m.boundary_facets()
    ends = m.facets[:, bf]
    pe = m.p[:, ends]
    onaxis = np.all(pe[0] == 0.0, axis=0)
    onbase = np.all(pe[1] == base_z, axis=0)
    onside = np.all(pe[0] == R, axis=0) if kind == "block" else np.zeros_like(onaxis)
    near = np.all(pe[0] <= surf_reach, axis=0) & np.all(np.abs(pe[1]) < 0.5 * C, axis=0)
    sel = bf[~onaxis & ~onbase & ~onside & near]
    ends = m.facets[:, sel]
    # order ends so that r increases from a to b, sort facets by r
    swap = m.p[0, ends[0]] > m.p[0, ends[1]]
    ends[:, swap] = ends[::-1, swap]
    order = np.argsort(m.p[0, ends[0]])
    ends, sel = ends[:, order], sel[order]
    nd, fd = basis.nodal_dofs, basis.facet_dofs
    surf = np.array([[nd[0, ends[0]], nd[1, ends[0]]], [nd[0, ends[1]], nd[1, ends[1]]], [fd[0, sel], fd[1, sel]]])
    Xa, Xb = m.p[:, ends[0]], m.p[:, ends[1]]
    surf_X = np.array([Xa, Xb, 0.5 * (Xa + Xb)])
    lam, mu = lame(E, nu)
    base_r = basis.get_dofs(lambda x: x[1] == base_z).all("u^1")
    return Body(m, basis, model, lam, mu, axis, base, surf, surf_X, base_r_dofs=base_r)


# ----------------------------------------------------------------------------------------------- contact


def _N(xi):
    """Quadratic facet shape functions at xi in [0, 1]: end a, end b, midside."""
    return np.array([(1 - xi) * (1 - 2 * xi), xi * (2 * xi - 1), 4 * xi * (1 - xi)])


def _dN(xi):
    return np.array([4 * xi - 3, 4 * xi - 1, 4 - 8 * xi])


GAUSS_XI, GAUSS_W = np.polynomial.legendre.leggauss(6)
GAUSS_XI = 0.5 * (GAUSS_XI + 1.0)
GAUSS_W = 0.5 * GAUSS_W


def contact(b1: Body, b2: Body, U: np.ndarray, eps: float, rigid_plane: bool = False, gap: str = "current"):
    """Penalty contact of body 1's surface Gauss points against body 2's current P2 surface.

    Returns (force vector f_c (N/rad), tangent K_c, penalty energy Pi_c (J), contact force P_c (N)), where
    Pi_c = 2 pi * sum_q eps/2 <-g_q>^2 r_q |dX/dxi| w_q, g the signed normal gap (m, < 0 is penetration),
    and f_c = dPi_c/dU / (2 pi). With ``rigid_plane`` body 2 is the rigid plane z = 0.
    K_c omits the curvature terms (of order eps * g), which leaves the solution exact.
    ``gap`` 'current': the gap along body 2's normal in the current positions (the default); 'reference':
    the linearized (classical small-deformation) gap g = (Z1 + u1z) - (Z2 + u2z) between the two surfaces at
    the same reference radius, vertical; radial displacements do not enter it.
    """
    n = len(U)
    s_dofs = b1.surf + b1.offset  # (3, 2, nf)
    xs_nodes = b1.surf_X + U[s_dofs]  # (3, 2, nf)
    if gap == "reference":
        xs_nodes[:, 0] = b1.surf_X[:, 0]
    elif gap != "current":
        raise ValueError(gap)
    Ns = _N(GAUSS_XI)  # (3, nq)
    xs = np.einsum("kcf,kq->cfq", xs_nodes, Ns)  # (2, nf, nq)
    Xs = np.einsum("kcf,kq->cfq", b1.surf_X, Ns)
    L0 = np.linalg.norm(b1.surf_X[1] - b1.surf_X[0], axis=0)  # (nf,)
    wq = Xs[0] * L0[:, None] * GAUSS_W[None, :]  # r dS weight, (nf, nq)
    xs = xs.reshape(2, -1)
    wq = wq.reshape(-1)
    nf = s_dofs.shape[2]
    sdof = np.broadcast_to(s_dofs[:, :, :, None], (3, 2, nf, len(GAUSS_XI))).reshape(3, 2, -1)
    sN = np.broadcast_to(Ns[:, None, :], (3, nf, len(GAUSS_XI))).reshape(3, -1)

    if rigid_plane:
        nvec = np.array([[0.0], [1.0]]) * np.ones((1, xs.shape[1]))
        g = xs[1]
        mdof = None
        mN = None
    else:
        m_dofs = b2.surf + b2.offset
        xm_nodes = b2.surf_X + U[m_dofs]  # (3, 2, nm)
        if gap == "reference":
            xm_nodes[:, 0] = b2.surf_X[:, 0]
        ra = xm_nodes[0, 0]
        rb = xm_nodes[1, 0]
        j = np.clip(np.searchsorted(rb, xs[0]), 0, len(rb) - 1)
        xi = np.clip((xs[0] - ra[j]) / (rb[j] - ra[j]), 0.0, 1.0)
        d2 = np.array([4.0, 4.0, -8.0])
        for sweep in range(3 if gap == "current" else 0):
            for _ in range(4):  # closest point on the quadratic facet j (Newton on (x_m - x_s) . x_m' = 0)
                N, dN = _N(xi), _dN(xi)
                xm = np.einsum("kcq,kq->cq", xm_nodes[:, :, j], N)
                t = np.einsum("kcq,kq->cq", xm_nodes[:, :, j], dN)
                dd = np.einsum("kcq,k->cq", xm_nodes[:, :, j], d2)
                res = ((xm - xs) * t).sum(0)
                jac = (t * t).sum(0) + ((xm - xs) * dd).sum(0)
                xi = xi - res / jac
            if sweep == 2:
                break
            lo = (xi < 0.0) & (j > 0)
            hi = (xi > 1.0) & (j < len(rb) - 1)
            j = np.where(lo, j - 1, np.where(hi, j + 1, j))
            xi = np.where(lo, 1.0, np.where(hi, 0.0, np.clip(xi, 0.0, 1.0)))
        xi = np.clip(xi, 0.0, 1.0)
        N, dN = _N(xi), _dN(xi)
        xm = np.einsum("kcq,kq->cq", xm_nodes[:, :, j], N)
        t = np.einsum("kcq,kq->cq", xm_nodes[:, :, j], dN)
        t = t / np.linalg.norm(t, axis=0)
        nvec = np.array([-t[1], t[0]])  # outward normal of body 2's upper surface (points up)
        if gap == "reference":  # reference facets are straight: xi is exact; the gap is vertical
            nvec = np.array([[0.0], [1.0]]) * np.ones((1, xs.shape[1]))
        g = ((xs - xm) * nvec).sum(0)
        mdof = m_dofs[:, :, j]  # (3, 2, nq)
        mN = N

    pen = np.maximum(-g, 0.0)
    act = pen > 0
    Pi = TWO_PI * 0.5 * eps * np.sum(pen**2 * wq)
    lam_q = eps * pen * wq  # per-radian normal force at each point (N/rad)
    # dPi/dx_s = -eps <-g> n ; dPi/dx_m = +eps <-g> N n
    rows, vals = [], []
    for k in range(3):
        for c in range(2):
            rows.append(sdof[k, c])
            vals.append(sN[k] * nvec[c])
            if mdof is not None:
                rows.append(mdof[k, c])
                vals.append(-mN[k] * nvec[c])
    rows = np.array(rows)[:, act]  # (ncomb, nact)
    vals = np.array(vals)[:, act]
    fc = np.zeros(n)
    np.add.at(fc, rows.ravel(), (-lam_q[act][None, :] * vals).ravel())
    wa = eps * wq[act]
    I = np.broadcast_to(rows[:, None, :], (rows.shape[0], rows.shape[0], rows.shape[1])).ravel()
    J = np.broadcast_to(rows[None, :, :], (rows.shape[0], rows.shape[0], rows.shape[1])).ravel()
    V = (vals[:, None, :] * vals[None, :, :] * wa[None, None, :]).ravel()
    Kc = sp.coo_matrix((V, (I, J)), shape=(n, n)).tocsr()
    Pz = TWO_PI * np.sum(lam_q * nvec[1])
    return fc, Kc, Pi, Pz


# ---------------------------------------------------------------------------------------------------- solve


@dataclass
class Result:
    """Outcome of one loading: per step overlap delta (m), force P (N), energies U1, U2, Pi_c (J)."""

    delta: np.ndarray
    P: np.ndarray
    U1: np.ndarray
    U2: np.ndarray
    Pi: np.ndarray
    work: float  # int P d(delta) (J), Simpson in s = sqrt(delta)
    converged: bool
    newton_its: int
    residual: float  # largest final out-of-balance force over the steps, relative to the Hertz force
    seconds: float
    ndofs: int
    nelements: int
    params: dict


def solve(
    R1: float,
    R2: float,
    E1: float,
    nu1: float,
    E2: float,
    nu2: float,
    delta: float,
    model: str = "small",
    refine: float = 1.0,
    steps: int = 8,
    kappa: float = 100.0,
    block: float | None = None,
    tol: float = 1e-8,
    maxit: int = 40,
    C1: float | None = None,
    C2: float | None = None,
    gap: str = "current",
    base: str = "slide",
) -> Result:
    """Load two bodies to overlap ``delta`` (m) in ``steps`` steps uniform in sqrt(delta).

    C1, C2 (m): vertical semi-axes of spheroids whose horizontal semi-axes are R1, R2 (None: spheres); Hertz
    then uses the pole radii of curvature R_i^2/C_i.

    R2 = inf: body 2 is a flat block of radius and depth ``block`` (m, default 20 R1); E2 = inf: a rigid plane.
    Mesh: h_c = a / (12 refine) on the patch r <= 1.3 a (a the Hertz contact radius at ``delta``), grading
    0.35 / refine. Penalty eps = kappa E* / h_c (Pa/m). Newton with a linear predictor; converged when the
    out-of-balance force is below ``tol`` times the Hertz force (or, below 1e-5 times it, when the Newton
    correction is below 1e-10 delta: the round-off floor of stiff bodies). ``model`` 'neohooke' first follows
    the small-strain path and starts each step from it.

    ``gap`` 'current' (default) or 'reference' (the linearized gap of classical small-deformation contact: see
    ``contact``); with ``model`` 'small' and ``gap`` 'reference' the problem is geometrically linear.
    ``base`` 'slide' (default): the bases (each sphere's equator, the block's bottom) are symmetry planes,
    u_r free; 'clamped': u_r = 0 there too.
    """
    t0 = time.perf_counter()
    rho1 = R1 if C1 is None else R1**2 / C1
    rho2 = R2 if C2 is None or not math.isfinite(R2) else R2**2 / C2
    H = hertz(delta, rho1, rho2, E1, nu1, E2, nu2)
    a = H["a"]
    h_c = a / (12.0 * refine)
    grading = 0.35 / refine
    patch = 1.3 * a
    reach = 2.5 * a
    rigid = math.isinf(E2)
    b1 = make_body(1, "sphere", R1, E1, nu1, model, h_c, grading, patch, reach, C1)
    if rigid:
        b2 = None
        nd = b1.ndofs
    else:
        kind2 = "sphere" if math.isfinite(R2) else "block"
        L2 = R2 if math.isfinite(R2) else (block or 20.0 * R1)
        b2 = make_body(
            2, kind2, L2, E2, nu2, model, h_c, grading, patch, reach * 1.5, C2 if kind2 == "sphere" else None
        )
        b2.offset = b1.ndofs
        nd = b1.ndofs + b2.ndofs
    eps = kappa * H["Estar"] / h_c

    top = b1.base_dofs
    fixed = [b1.axis_dofs, top]
    if b2 is not None:
        fixed += [b2.axis_dofs + b2.offset, b2.base_dofs + b2.offset]
    if base == "clamped":  # the bases' u_r fixed too (not a symmetry plane)
        fixed += [b.base_r_dofs + b.offset for b in (b1, b2) if b is not None]
    elif base != "slide":
        raise ValueError(base)
    fixed = np.unique(np.concatenate(fixed))
    free = np.setdiff1d(np.arange(nd), fixed)

    bodies = [b for b in (b1, b2) if b is not None]

    def assemble(U, model, tangent=True):
        fs, Ks = [], []
        for b in bodies:
            b.model = model
            f, K = b.residual(U[b.offset : b.offset + b.ndofs], tangent)
            fs.append(f)
            Ks.append(K)
        f = np.concatenate(fs)
        fc, Kc, Pi, Pz = contact(b1, b2, U, eps, rigid_plane=rigid, gap=gap)
        if not tangent:
            return f + fc, None, Pi, Pz, f
        K = sp.block_diag(Ks, format="csr") if len(Ks) > 1 else Ks[0]
        return f + fc, (K + Kc).tocsr(), Pi, Pz, f

    def slope(U, du, t, model):
        """phi'(t) = R(U + t du) . du, phi the total potential along the Newton direction (nan: inverted)."""
        Ut = U.copy()
        Ut[free] += t * du
        with np.errstate(invalid="ignore", divide="ignore"):
            R = assemble(Ut, model, tangent=False)[0][free]
        return float(R @ du) if np.all(np.isfinite(R)) else math.nan

    def newton(U, d, model):
        """Equilibrium at overlap d from the guess U; returns (U, converged, iterations, Pi, f_int)."""
        U = U.copy()
        U[top] = -d
        Pref = hertz(d, rho1, rho2, E1, nu1, E2, nu2)["P"] / TWO_PI
        R, K, Pi, Pz, fint = assemble(U, model)
        res = np.linalg.norm(R[free])
        hist = []
        for it in range(1, maxit + 1):
            hist.append(res / Pref)
            if DEBUG:
                print(model, d, it, res / Pref)
            if res < tol * Pref:
                return U, True, it, Pi, fint, res / Pref
            if len(hist) > 8 and hist[-1] < STALL_TOL and min(hist[-4:]) > 0.5 * min(hist[:-4]):
                # stalled below STALL_TOL: a Gauss point flipping in and out of contact (a 2-cycle)
                return U, True, it, Pi, fint, res / Pref
            du = splu(K[free][:, free].tocsc()).solve(-R[free])
            if res < 1e-5 * Pref and np.max(np.abs(du)) < 1e-10 * d:
                return U, True, it, Pi, fint, res / Pref  # at the round-off floor (stiff bodies: E ratio 1000)
            # line search on the total potential (the contact's active set makes plain Newton cycle):
            # accept t = 1 if the potential still decreases there, else the root of phi'(t) (Illinois)
            s0 = float(R[free] @ du)
            t1 = 1.0
            s1 = slope(U, du, t1, model)
            while not np.isfinite(s1) and t1 > 1e-3:  # an inverted element: shorter step
                t1 *= 0.5
                s1 = slope(U, du, t1, model)
            t = t1
            if s0 < 0 < s1:
                t0_, sa, tb, sb, side = 0.0, s0, t1, s1, 0
                for _ in range(8):
                    t = (t0_ * sb - tb * sa) / (sb - sa)
                    st = slope(U, du, t, model)
                    if not np.isfinite(st) or abs(st) < 1e-3 * abs(s0):
                        break
                    if st > 0:
                        tb, sb = t, st
                        if side == -1:
                            sa *= 0.5
                        side = -1
                    else:
                        t0_, sa = t, st
                        if side == 1:
                            sb *= 0.5
                        side = 1
            U = U.copy()
            U[free] += t * du
            R, K, Pi, Pz, fint = assemble(U, model)
            res = np.linalg.norm(R[free])
        return U, False, maxit, Pi, fint, res / Pref

    s_grid = np.linspace(0.0, math.sqrt(delta), steps + 1)
    deltas = s_grid**2
    out = {k: [0.0] for k in ("P", "U1", "U2", "Pi")}
    converged = True
    its = 0
    worst = 0.0
    # the small-strain path first (constant bulk stiffness: cheap); a finite-strain step starts from the
    # small-strain solution at the same overlap plus the previous step's finite-strain correction
    U = np.zeros(nd)
    Uprev = None
    Us = []
    for k in range(1, steps + 1):
        if Uprev is not None:
            guess = U + (U - Uprev) * (deltas[k] - deltas[k - 1]) / (deltas[k - 1] - deltas[k - 2])
        else:
            guess = U.copy()
            guess[b1.basis.get_dofs().all("u^2")] = -deltas[k]  # rigid shift of body 1 onto the contact
        Uprev = U
        U, ok, n_it, Pi, fint, rr = newton(guess, deltas[k], "small")
        worst = max(worst, rr)
        its += n_it
        converged &= ok
        Us.append((U, Pi, fint))
    corr = np.zeros(nd)
    for k in range(1, steps + 1):
        U, Pi, fint = Us[k - 1]
        if model != "small":
            if k == 1:
                converged = True
            if k == 1:
                worst = 0.0
            Un, ok, n_it, Pi, fint, rr = newton(U + corr, deltas[k], model)
            worst = max(worst, rr)
            its += n_it
            converged &= ok
            corr = Un - U
            U = Un
        for b in bodies:
            b.model = model
        out["P"].append(TWO_PI * np.sum(fint[top]))
        out["U1"].append(b1.energy(U[: b1.ndofs]))
        out["U2"].append(b2.energy(U[b1.ndofs :]) if b2 is not None else 0.0)
        out["Pi"].append(Pi)
    arr = {k: np.array(v) for k, v in out.items()}
    # work of the reaction: int P d(delta) = int 2 s P(s^2) ds, Simpson (steps even) on the uniform s grid
    g = 2.0 * s_grid * np.abs(arr["P"])
    from scipy.integrate import simpson

    work = float(simpson(g, x=s_grid))
    nel = b1.mesh.nelements + (b2.mesh.nelements if b2 is not None else 0)
    return Result(
        deltas,
        np.abs(arr["P"]),
        arr["U1"],
        arr["U2"],
        arr["Pi"],
        work,
        converged,
        its,
        worst,
        time.perf_counter() - t0,
        nd,
        nel,
        dict(
            R1=rho1,
            R2=rho2,
            E1=E1,
            nu1=nu1,
            E2=E2,
            nu2=nu2,
            delta=delta,
            model=model,
            refine=refine,
            steps=steps,
            kappa=kappa,
            C1=C1,
            C2=C2,
            gap=gap,
            base=base,
        ),
    )


def summary(res: Result) -> dict:
    """Final-step numbers of a run: FE force/energy against Hertz, shares, the work check."""
    p = res.params
    H = hertz(p["delta"], p["R1"], p["R2"], p["E1"], p["nu1"], p["E2"], p["nu2"])
    U1, U2, Pi = res.U1[-1], res.U2[-1], res.Pi[-1]
    share = U1 / (U1 + U2)
    return {
        **p,
        "a_over_R1": H["a"] / p["R1"],
        "P_fe": res.P[-1],
        "P_hertz": H["P"],
        "e_P": res.P[-1] / H["P"] - 1.0,
        "U1": U1,
        "U2": U2,
        "Pi_c": Pi,
        "S_hertz": H["S"],
        "e_S": (U1 + U2 + Pi) / H["S"] - 1.0,
        "work": res.work,
        "e_work": res.work / (U1 + U2 + Pi) - 1.0,
        "share_fe": share,
        "share_law": H["f1"],
        "share_err": share - H["f1"],
        "ratio_fe": U1 / U2 if U2 > 0 else math.inf,
        "ratio_law": H["f1"] / (1 - H["f1"]) if H["f1"] < 1 else math.inf,
        "converged": res.converged,
        "newton_its": res.newton_its,
        "residual": res.residual,
        "seconds": res.seconds,
        "ndofs": res.ndofs,
        "nelements": res.nelements,
    }
