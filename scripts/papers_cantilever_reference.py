#!/usr/bin/env python3
"""Independent finite-element reference values for the paper's (large-deformation)
cantilever: Hencky elasticity under a follower pressure.

Problem (finite-strain, plane-strain elasticity; the MPM solver's definition)
-----------------------------------------------------------------------------
* Bing, Cortis, Charlton, Coombs & Augarde (2017)'s cantilever as
  `mpm example cantilever` builds it: domain [0, 10] x [0, 2] m (reference),
  plane strain, no body force.
* Material "Hencky": E = 1e6 Pa, nu = 0.25 (Lame lambda, mu from them).
  F the 2x2 deformation gradient (F_zz = 1), b = F F^T, e = ln(b)/2 by
  eigen-decomposition (e_zz = 0), Kirchhoff stress
  tau = lambda tr(e) I + 2 mu e (in-plane part), first Piola P = tau F^-T
  (Cauchy tau / det F).
* Follower pressure p = 1500 Pa on the top edge (reference y = 2): the force
  on a piece da of the *current* edge is -p n da, n the current outward
  normal.  Applied in 5 equal load steps.
* Supports: u_x = 0 on x = 0 (rollers), u_y = 0 at the single point (0, 1).
* Outputs: tip u_x(10, 1) and u_y(10, 1); the left-edge mean
  mean = (1/2) int_0^2 u_y(0, y) dy (exact for the element's quadratic
  trace); the relative deflection u_y(10, 1) - mean.

Method
------
* Total Lagrangian, biquadratic 9-node Lagrange (Q9) elements on uniform
  n x n/5 meshes of square elements, h = 10/n (n a multiple of 10, so (0, 1)
  and (10, 1) are nodes); 3x3 Gauss quadrature; all Gauss points of all
  elements evaluated at once with numpy.
* Residual R(u) = f_int(u) - lam f_ext(u), f_int = sum int B^T vec(P) dV.
  The material tangent dP/dF is differentiated exactly (derivative of the
  matrix logarithm in b's eigenbasis, divided differences
  (ln l1 - ln l2)/(l1 - l2) with a series for l1 ~ l2).  b - I and ln b are
  evaluated as H + H^T + H H^T and log1p (H = F - I), so small strains keep
  full relative precision (needed for the small-load check below).
* Follower pressure: on a quadratic top edge with current nodes x_a,
  n da = (-x'_y, x'_x) ds, so f_a = -p int N_a (-x'_y, x'_x) ds = p G x:
  linear in the current positions, its load stiffness p G is constant and
  non-symmetric (3-point Gauss is exact).  Newton's matrix is
  K_mat - lam p G, assembled into a fixed CSC pattern (one bincount per
  iteration) and solved by scipy.sparse.linalg.spsolve (SuperLU).
* Newton in each step to |R| <= 1e-10 |lam f_ext| (free dofs), or until the
  last correction max|du| <= 1e-10 max|u| (the residual's round-off floor
  grows about 3x per halving of h and reaches ~1.7e-10 at n = 320).
  Convergence is quadratic (residuals e.g. 3.7, 2.2e-1, 3.5e-3, 4.2e-7,
  2.0e-10 in the last step at n = 320).
* Orders and Richardson extrapolation as in scripts/cantilever_reference.py:
  p = log2(|f(h)-f(h/2)| / |f(h/2)-f(h/4)|), f(h/4) + (f(h/4)-f(h/2))/(2^p-1).
  When the last orders are not > 0.5 the script prints the span of the
  meshes' values instead of an extrapolation.

How to run
----------
    pip install numpy scipy
    python3 scripts/papers_cantilever_reference.py                  # n = 20 .. 320
    python3 scripts/papers_cantilever_reference.py --check          # tangent vs finite differences
    python3 scripts/papers_cantilever_reference.py --steps-check 80 # 5 vs 20 load steps
    python3 scripts/papers_cantilever_reference.py --max-n 160 --scale 1e-6  # small load
    python3 scripts/papers_cantilever_reference.py --clamped        # diagnostic, no point support

Dependencies: Python 3, numpy, scipy (tested with Python 3.11.7,
numpy 2.4.6, scipy 1.17.1).  n = 640 is not run: n = 320 alone takes about
2 min (30 Newton iterations of a 165k-dof LU); n = 640 would take
roughly 20-30 min, and at n = 320 the node just above the pin has already
been pulled down to the pin's height (see below).

Results printed by this script (default --max-n 320, 2-core machine shared
with a build, total run time about 155 s)
---------------------------------------------------------------------------
    n    m         h     dofs       u_x(10,1)       u_y(10,1)   mean u_y(0,.)      rel. defl.  Newton its/step   |e|pin |e|rest  min J  time[s]
   20    4  0.500000      728   -0.4227082323   -2.7825897567   -0.0228337787   -2.7597559780  5,5,5,5,5         0.0714  0.1039  0.932      0.2
   40    8  0.250000     2736   -0.4227146804   -2.7881085689   -0.0282835735   -2.7598249954  5,5,5,5,5         0.1375  0.1085  0.920      0.8
   80   16  0.125000    10592   -0.4226927787   -2.7935748655   -0.0338217356   -2.7597531298  5,5,5,5,5         0.2712  0.1107  0.848      4.5
  160   32  0.062500    41664   -0.4226680195   -2.7994828844   -0.0398065214   -2.7596763630  5,5,5,5,5         0.5413  0.1401  0.738     17.4
  320   64  0.031250   165248   -0.4226205051   -2.8108125777   -0.0512454873   -2.7595670904  6,6,6,6,6         1.1585  0.3479  0.641    130.3
(|e|pin: largest |principal log strain| at the Gauss points of the two
elements touching the pin; |e|rest: elsewhere; min J: smallest det F.)

Successive differences (coarse -> fine) and observed orders:
  u_x(10,1)    -6.4e-6, +2.19e-5, +2.48e-5, +4.75e-5   p = -1.76, -0.18, -0.94
  rel. defl.   -6.9e-5, +7.19e-5, +7.68e-5, +1.09e-4   p = -0.06, -0.10, -0.51
  u_y(10,1)    -5.52e-3, -5.47e-3, -5.91e-3, -1.13e-2 (the linear problem:
               -5.5e-3 per halving, the log(1/h) of the point support)
  NO convergence: the changes grow with refinement.

Why: the point support.  The pin carries the whole vertical load
(about 15 kN/m) at one node.  In linear elasticity that is a log singularity
with strains ~ 1/r, harmless for the relative deflection (the small-strain
script converges at order 4).  Here the strain at the pin doubles with each
halving of h (|e|pin = 0.07, 0.14, 0.27, 0.54, 1.16): the finite-strain core
around the pin is never resolved, and at n = 320 the node above the pin has
been pulled down to y = 1.0000 (u_y = -0.015635 for a node spacing of
0.015625).  The core's far field changes every output at the 1e-4 level:
tip u_x, the tip's thickness change, and u_y(10,1) relative to the corners
(0,0), (0,2) or to the mean over |y - 1| >= 0.5 drift the same way, so it is
not only the left-edge mean.  The code itself converges: with the left edge
clamped instead (--clamped, no point support; corner singularities only)
every output converges at p = 1.4, as in the small-strain clamped case:
    n:           20            40            80            160           320
    u_x(10,1)  -0.4153929463 -0.4159164934 -0.4161039418 -0.4161753035 -0.4162025981
    u_y(10,1)  -2.7338404023 -2.7358480410 -2.7365553559 -2.7368198546 -2.7369194091
    p (u_x) 1.48, 1.39, 1.39 -> -0.4162195 +- 1.7e-5;
    p (u_y) 1.51, 1.42, 1.41 -> -2.7369795 +- 6e-5.

Reference values for the pinned case, then, are mesh-dependent at the 1e-4
level, without an extrapolation:
    tip u_x(10,1)         -0.42267 +- 1e-4   (meshes n = 40..320 span
                          -0.422715 .. -0.422621)
    relative deflection   -2.7597 +- 3e-4    (meshes n = 40..320 span
                          -2.759825 .. -2.759567)
The drift grows with refinement, so a comparison with the MPM solver (whose
pin is spread over its support) is meaningful to about 1e-4 relative, not
better.

Checks
------
* Load steps (--steps-check): 5 and 20 steps give the same state to round
  off: n = 40 differences <= 4.4e-16, n = 80 <= 1.8e-15 (u_x, u_y, mean,
  relative deflection); 4 Newton iterations per step with 20 steps.
* Small load (--scale): p scaled down, outputs scaled back up.  With
  p = 1.5e-3 Pa (scale 1e-6) at n = 160 the relative deflection is
  -2.7660657737 against the small-strain script's -2.7660657366 on the same
  mesh (3.7e-8 absolute, 1.3e-8 relative; Richardson -2.76606580 vs
  -2.76606576).  u_x(10,1) is 0.0023433330 against 0.00234375: -1.78e-4
  relative, and that is physics, not error: the beam's second-order
  shortening -(1/2) int w'^2 dx (about -5e-13 m at that load, i.e. -2e-4 of
  u_x) scales like p^2 while u_x scales like p.  The difference is linear
  in the scale: -1.78e-5 at 1e-7, -1.8e-6 at 1e-8, -1.78e-7 at 1e-9 (where
  u_x = 0.0023437496 and the relative deflection at n = 160 is
  -2.7660657378, 1.2e-9 from the small-strain value on the same mesh).  The small-strain MPM
  test quotes a 5e-6 follower-load effect at 1.5 mPa; its material is the
  linear one, so the shortening above does not appear there.
* Tangent (--check), 10 x 2 mesh, a bent, sheared and randomly perturbed
  state at 0.7 of the load; central differences with step eps:
        material: eps 1e-04  |FD - K v| / |K v| = 6.38e-07
        material: eps 1e-05  |FD - K v| / |K v| = 6.38e-09
        material: eps 1e-06  |FD - K v| / |K v| = 8.21e-11
   follower load: eps 1e-04  |FD - K v| / |K v| = 2.42e-12
   follower load: eps 1e-05  |FD - K v| / |K v| = 2.22e-11
  (material error ~ eps^2, the follower force is linear in u so only
  round-off); the assembled free-free matrix equals the direct sum; the
  material tangent is symmetric to 1.4e-16 (Hencky is hyperelastic); Newton
  on that mesh converges quadratically (1, 15, 5.1e-2, 1.2e-3, 8.2e-9,
  1.5e-12 in the first step).
"""

import argparse
import math
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

# ---------------------------------------------------------------- parameters
LX, LY = 10.0, 2.0
E, NU = 1.0e6, 0.25
LAM = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU))
MU = E / (2.0 * (1.0 + NU))
PRESSURE = 1500.0  # follower pressure on the (reference) top edge y = LY

# Small-strain values (scripts/cantilever_reference.py) for the small-load check.
SMALL_STRAIN = {"u_x(10,1)": 0.00234375, "rel. defl.": -2.76606576}

# The Q9 element's 1D basis, Gauss rule and Richardson extrapolation are
# the small-strain script's (scripts/ is on the path when run as a script).
from cantilever_reference import (  # noqa: E402
    GAUSS3_PTS,
    GAUSS3_WTS,
    lagrange1d,
    lagrange1d_deriv,
    print_differences,
)


# ---------------------------------------------------------------- material
def hencky(H):
    """Hencky material at a stack of displacement gradients H = F - I (N, 2, 2).

    b = F F^T = sum_a l_a n_a n_a^T, e = ln(b)/2, tau = LAM tr(e) I + 2 MU e,
    P = tau F^-T.  Returns P (N, 2, 2) and the exact tangent
    A (N, 4, 4), A[:, 2i+I, 2j+J] = dP_iI / dF_jJ, differentiated as in
    crates/mpm/src/material/hencky.rs but written independently:
    db = dF F^T + F dF^T, de = L[db]/2 with L the derivative of the matrix
    logarithm (in the eigenbasis of b: L'_ab = db'_ab * (ln l_a - ln l_b) /
    (l_a - l_b), 1/l_a on the diagonal), dtau = LAM tr(de) I + 2 MU de,
    dP = dtau F^-T - tau F^-T dF^T F^-T.
    The eigenvalues are taken of b - I = H + H^T + H H^T and the logarithm as
    log1p, so that small strains keep their relative precision (computing
    ln(l) from l = 1 + O(1e-9) would leave only 7 digits; the small-load
    check needs more).
    """
    N = H.shape[0]
    F = H + np.eye(2)
    bm = H + np.swapaxes(H, 1, 2) + np.einsum("nij,nkj->nik", H, H)   # b - I
    a, d, c = bm[:, 0, 0], bm[:, 1, 1], 0.5 * (bm[:, 0, 1] + bm[:, 1, 0])
    mean = 0.5 * (a + d)
    rad = np.sqrt(0.25 * (a - d) ** 2 + c * c)
    theta = 0.5 * np.arctan2(2.0 * c, a - d)
    co, s = np.cos(theta), np.sin(theta)
    mu1, mu2 = mean + rad, mean - rad        # eigenvalues of b - I
    l1, l2 = 1.0 + mu1, 1.0 + mu2
    ln1, ln2 = np.log1p(mu1), np.log1p(mu2)
    detF = F[:, 0, 0] * F[:, 1, 1] - F[:, 0, 1] * F[:, 1, 0]
    Q = np.empty((N, 2, 2))         # columns: eigenvectors n1, n2
    Q[:, 0, 0], Q[:, 1, 0] = co, s
    Q[:, 0, 1], Q[:, 1, 1] = -s, co
    Lh = np.zeros((N, 2, 2))
    Lh[:, 0, 0], Lh[:, 1, 1] = 0.5 * ln1, 0.5 * ln2
    e = Q @ Lh @ np.swapaxes(Q, 1, 2)
    eye = np.eye(2)
    tau = LAM * (e[:, 0, 0] + e[:, 1, 1])[:, None, None] * eye + 2.0 * MU * e
    Finv = np.empty_like(F)
    Finv[:, 0, 0], Finv[:, 1, 1] = F[:, 1, 1] / detF, F[:, 0, 0] / detF
    Finv[:, 0, 1], Finv[:, 1, 0] = -F[:, 0, 1] / detF, -F[:, 1, 0] / detF
    FinvT = np.swapaxes(Finv, 1, 2)
    P = tau @ FinvT

    # divided difference of the logarithm, (ln l1 - ln l2) / (l1 - l2)
    dl = 2.0 * rad                           # l1 - l2
    r = dl / l2
    with np.errstate(divide="ignore", invalid="ignore"):
        g12 = np.where(r > 1e-4, np.log1p(r) / np.where(dl > 0, dl, 1.0),
                       (1.0 - r / 2.0 + r * r / 3.0 - r ** 3 / 4.0 + r ** 4 / 5.0) / l2)
    G = np.empty((N, 2, 2))
    G[:, 0, 0], G[:, 1, 1] = 1.0 / l1, 1.0 / l2
    G[:, 0, 1] = G[:, 1, 0] = g12
    QT = np.swapaxes(Q, 1, 2)
    tauFiT = tau @ FinvT
    A = np.empty((N, 4, 4))
    for j in range(2):
        for J in range(2):
            Ed = np.zeros((2, 2))
            Ed[j, J] = 1.0
            db = Ed @ np.swapaxes(F, 1, 2) + F @ Ed.T
            de = 0.5 * (Q @ ((QT @ db @ Q) * G) @ QT)
            dtau = LAM * (de[:, 0, 0] + de[:, 1, 1])[:, None, None] * eye + 2.0 * MU * de
            dP = dtau @ FinvT - tauFiT @ Ed.T @ FinvT
            A[:, :, 2 * j + J] = dP.reshape(N, 4)
    return P, A


# ---------------------------------------------------------------- mesh
class Mesh:
    """Uniform n x n/5 Q9 mesh of [0, LX] x [0, LY] with the supports and the
    follower-pressure operator; assembles the residual and tangent."""

    def _q9_grid(self, n, m, h):
        """The uniform n x m grid of square Q9 elements of side h from the
        origin: node numbering, reference coordinates, element dofs and the
        Gauss-point data (shared by every element)."""
        nxn, nyn = 2 * n + 1, 2 * m + 1
        self.nxn, self.nyn = nxn, nyn
        self.ndof = ndof = 2 * nxn * nyn

        def node(i, j):
            return j * nxn + i
        self.node = node
        # reference coordinates, dof order (x0, y0, x1, y1, ...)
        ii, jj = np.meshgrid(np.arange(nxn), np.arange(nyn), indexing="xy")
        X = np.empty(ndof)
        X[0::2] = (ii.ravel() * h / 2.0)
        X[1::2] = (jj.ravel() * h / 2.0)
        self.X = X

        ei, ej = np.meshgrid(np.arange(n), np.arange(m), indexing="xy")
        ei, ej = ei.ravel(), ej.ravel()
        self.ne = ne = n * m
        conn = np.empty((ne, 9), dtype=np.int64)
        for b in range(3):
            for a in range(3):
                conn[:, 3 * b + a] = node(2 * ei + a, 2 * ej + b)
        edofs = np.empty((ne, 18), dtype=np.int64)
        edofs[:, 0::2] = 2 * conn
        edofs[:, 1::2] = 2 * conn + 1
        self.edofs = edofs

        # Gauss-point data (identical square elements): dN/dX (9 gp, 9 nodes, 2),
        # the matrices B_g (9, 4, 18) with vec(F - I)_(2i+I) = B_g u_e, and w*detJ.
        jac = h / 2.0
        dN = np.zeros((9, 9, 2))
        wdet = np.zeros(9)
        for qb, (eta, wy) in enumerate(zip(GAUSS3_PTS, GAUSS3_WTS)):
            for qa, (xi, wx) in enumerate(zip(GAUSS3_PTS, GAUSS3_WTS)):
                g = 3 * qb + qa
                Nx, Ny = lagrange1d(xi), lagrange1d(eta)
                dNx, dNy = lagrange1d_deriv(xi) / jac, lagrange1d_deriv(eta) / jac
                for b in range(3):
                    for a in range(3):
                        dN[g, 3 * b + a, 0] = dNx[a] * Ny[b]
                        dN[g, 3 * b + a, 1] = Nx[a] * dNy[b]
                wdet[g] = wx * wy * jac * jac
        B = np.zeros((9, 4, 18))
        for i in range(2):
            for I in range(2):
                B[:, 2 * i + I, i::2] = dN[:, :, I]
        self.dN = dN
        self.B = B
        self.Bw = (B * wdet[:, None, None]).reshape(36, 18)  # stacked (g, p) rows
        return node

    def __init__(self, n, pressure=PRESSURE, clamped=False):
        assert n % 10 == 0, "n must be a multiple of 10 so that (0,1), (10,1) are nodes"
        self.n, self.m = n, n // 5
        m = self.m
        self.h = h = LX / n
        assert abs(LY / m - h) < 1e-14
        self.pressure = pressure
        node = self._q9_grid(n, m, h)
        nxn, nyn, ndof, edofs = self.nxn, self.nyn, self.ndof, self.edofs

        # Follower pressure.  On a top edge with current nodes x_a (a = 0,1,2),
        # x(s) = sum N_a(s) x_a, s in [-1, 1]; n da = (-x'_y, x'_x) ds (outward,
        # the body lies to the right of the left-to-right tangent), so
        #   f_a = -p int N_a (-x'_y, x'_x) ds,  i.e.  f = p G x,
        # G[(a,x),(b,y)] = M_ab, G[(a,y),(b,x)] = -M_ab, M_ab = int N_a N_b' ds
        # (3-point Gauss, exact: cubic integrand).  f is linear in the current
        # positions x = X + u, so its load stiffness d f/du = p G is constant.
        M = np.zeros((3, 3))
        for s, ws in zip(GAUSS3_PTS, GAUSS3_WTS):
            M += ws * np.outer(lagrange1d(s), lagrange1d_deriv(s))
        top = np.array([[node(2 * e + a, nyn - 1) for a in range(3)] for e in range(n)])
        grow, gcol, gval = [], [], []
        for a in range(3):
            for b in range(3):
                grow.append(2 * top[:, a]); gcol.append(2 * top[:, b] + 1)
                gval.append(np.full(n, M[a, b]))
                grow.append(2 * top[:, a] + 1); gcol.append(2 * top[:, b])
                gval.append(np.full(n, -M[a, b]))
        grow, gcol, gval = (np.concatenate(v) for v in (grow, gcol, gval))
        self.G = sp.coo_matrix((gval, (grow, gcol)), shape=(ndof, ndof)).tocsr()

        # supports: u_x = 0 on x = 0, u_y = 0 at (0, 1)
        self.left_nodes = np.array([node(0, j) for j in range(nyn)])
        self.tip = node(nxn - 1, nyn // 2)   # (10, 1)
        self.pin = node(0, nyn // 2)         # (0, 1)
        fixed = np.unique(np.concatenate([2 * self.left_nodes, [2 * self.pin + 1]]
                                         + ([2 * self.left_nodes + 1] if clamped else [])))
        free = np.setdiff1d(np.arange(ndof), fixed)
        self.free = free
        fmap = -np.ones(ndof, dtype=np.int64)
        fmap[free] = np.arange(free.size)
        self.nfree = nf = free.size

        # exact weights for the left-edge mean of u_y (Simpson per element edge)
        w_left = np.zeros(nyn)
        for e in range(m):
            w_left[2 * e:2 * e + 3] += h * np.array([1.0, 4.0, 1.0]) / 6.0
        assert abs(w_left.sum() - LY) < 1e-12
        self.w_left = w_left

        # Sparsity pattern of the free-free tangent (element blocks + pressure
        # operator), computed once; each assembly is then one bincount.
        er = fmap[np.repeat(edofs, 18, axis=1).ravel()]
        ec = fmap[np.tile(edofs, (1, 18)).ravel()]
        Gc = self.G.tocoo()
        gr, gc = fmap[Gc.row], fmap[Gc.col]
        rows = np.concatenate([er, gr])
        cols = np.concatenate([ec, gc])
        keep = (rows >= 0) & (cols >= 0)
        self.n_el_entries = er.size
        self.keep = keep
        keys = cols[keep] * nf + rows[keep]       # column-major: CSC order
        ukeys, inv = np.unique(keys, return_inverse=True)
        self.inv = inv
        self.nnz = ukeys.size
        self.indices = (ukeys % nf).astype(np.int32)
        self.indptr = np.searchsorted(ukeys // nf, np.arange(nf + 1)).astype(np.int32)
        del er, ec, rows, cols, keys, ukeys
        self.Gvals = Gc.data

    # ---------------------------------------------------------- assembly
    def internal(self, u, tangent=True, chunk=4096):
        """Internal force (ndof) and element tangent values (ne*324) at u."""
        fint = np.zeros(self.ndof)
        kvals = np.empty((self.ne, 18, 18)) if tangent else None
        BwT = self.Bw.T
        for s in range(0, self.ne, chunk):
            ed = self.edofs[s:s + chunk]
            ue = u[ed].reshape(-1, 9, 2)
            Hg = np.einsum("eai,gaI->egiI", ue, self.dN)   # F - I
            ne = Hg.shape[0]
            P, A = hencky(Hg.reshape(-1, 2, 2))
            fe = P.reshape(ne, 36) @ self.Bw
            fint += np.bincount(ed.ravel(), weights=fe.ravel(), minlength=self.ndof)
            if tangent:
                AB = np.matmul(A.reshape(ne, 9, 4, 4), self.B).reshape(ne, 36, 18)
                kvals[s:s + ne] = np.matmul(BwT, AB)
        return fint, kvals

    def external(self, u):
        """Follower-pressure force at full load, p G (X + u)."""
        return self.pressure * (self.G @ (self.X + u))

    def tangent_matrix(self, kvals, lam):
        """Free-free tangent K_mat - lam p G as CSC."""
        vals = np.concatenate([kvals.ravel(), -lam * self.pressure * self.Gvals])[self.keep]
        data = np.bincount(self.inv, weights=vals, minlength=self.nnz)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.nfree, self.nfree))

    def residual(self, u, lam):
        fint, _ = self.internal(u, tangent=False)
        return fint - lam * self.external(u)

    # ---------------------------------------------------------- outputs
    def strain_report(self, u):
        """Largest |principal log strain| over the Gauss points of the two
        elements touching the pin, over all other elements, and the smallest
        det F anywhere."""
        ue = u[self.edofs].reshape(-1, 9, 2)
        F = np.einsum("eai,gaI->egiI", ue, self.dN) + np.eye(2)
        lam = np.linalg.eigvalsh(F @ np.swapaxes(F, -1, -2))
        emax = np.abs(0.5 * np.log(lam)).max(axis=(1, 2))
        pin_el = np.array([(self.m // 2 - 1) * self.n, (self.m // 2) * self.n])
        rest = np.ones(self.ne, bool)
        rest[pin_el] = False
        return emax[pin_el].max(), emax[rest].max(), np.linalg.det(F).min()

    def outputs(self, u):
        left_uy = u[2 * self.left_nodes + 1]
        mean = (self.w_left @ left_uy) / LY
        ux, uy = u[2 * self.tip], u[2 * self.tip + 1]
        return {"u_x(10,1)": ux, "u_y(10,1)": uy, "mean u_y(0,.)": mean,
                "rel. defl.": uy - mean}


# ---------------------------------------------------------------- Newton
def solve(mesh, steps, tol=1e-10, dtol=1e-10, maxit=30, u0=None, verbose=False):
    """Load in `steps` equal increments, full Newton in each.  Converged when
    |R_free| <= tol |lam f_ext,free|, or when the last correction was
    max|du| <= dtol max|u| (the residual's round-off floor grows with mesh
    refinement, about 3x per halving of h; Newton being quadratic, the error
    left after a correction of relative size 1e-10 is far below it).  Returns
    u and the iteration counts (linear solves) per step."""
    u = np.zeros(mesh.ndof) if u0 is None else u0.copy()
    free = mesh.free
    iters = []
    for k in range(1, steps + 1):
        lam = k / steps
        dmax = np.inf
        for it in range(maxit + 1):
            fint, kvals = mesh.internal(u)
            fext = lam * mesh.external(u)
            R = (fint - fext)[free]
            rel = np.linalg.norm(R) / np.linalg.norm(fext[free])
            if verbose:
                print(f"    step {k} it {it}: relative residual {rel:.3e},"
                      f" last max|du|/max|u| {dmax:.2e}", flush=True)
            if rel <= tol or dmax <= dtol:
                break
            if it == maxit:
                raise RuntimeError(f"Newton did not converge (step {k}, residual {rel:.2e})")
            K = mesh.tangent_matrix(kvals, lam)
            du = spla.spsolve(K, -R, permc_spec="MMD_AT_PLUS_A")
            u[free] += du
            dmax = np.abs(du).max() / np.abs(u).max()
        iters.append(it)
    return u, iters


def tangent_check(n=10):
    """Central finite differences of the residual against the tangent at a
    strongly deformed (non-equilibrium) state, for the material part and the
    follower-load part separately."""
    mesh = Mesh(n)
    rng = np.random.default_rng(1)
    X, Y = mesh.X[0::2], mesh.X[1::2]
    # a bent and sheared state (rotations up to ~0.5 rad) plus noise
    u = np.zeros(mesh.ndof)
    u[0::2] = -0.02 * X * (Y - 1.0) - 0.01 * X
    u[1::2] = -0.02 * X ** 2 + 0.05 * np.sin(Y)
    u += 0.01 * rng.standard_normal(mesh.ndof)
    lam = 0.7
    fint, kvals = mesh.internal(u)
    Kfull = sp.coo_matrix((kvals.ravel(), (np.repeat(mesh.edofs, 18, axis=1).ravel(),
                                           np.tile(mesh.edofs, (1, 18)).ravel())),
                          shape=(mesh.ndof, mesh.ndof)).tocsr()
    Kp = -lam * mesh.pressure * mesh.G
    v = rng.standard_normal(mesh.ndof)
    print(f"tangent check on the {n} x {n // 5} mesh (finite differences of the residual,"
          f" central, step eps * v):")
    for name, f, K in [("material", lambda w: mesh.internal(w, tangent=False)[0], Kfull),
                       ("follower load", lambda w: -lam * mesh.external(w), Kp)]:
        Kv = K @ v
        for eps in [1e-4, 1e-5, 1e-6, 1e-7]:
            fd = (f(u + eps * v) - f(u - eps * v)) / (2 * eps)
            print(f"  {name:>14}: eps {eps:.0e}  |FD - K v| / |K v| = "
                  f"{np.linalg.norm(fd - Kv) / np.linalg.norm(Kv):.2e}")
    # the free-free assembled matrix against the element tangent + load part
    Kff = mesh.tangent_matrix(kvals, lam)
    ref = (Kfull + Kp)[mesh.free][:, mesh.free]
    print(f"  assembled free-free tangent vs direct sum: max diff "
          f"{abs(Kff - ref).max():.1e} (max entry {abs(ref).max():.1e})")
    # symmetry of the material tangent (hyperelastic -> symmetric)
    print(f"  material tangent asymmetry |K - K^T|max / |K|max = "
          f"{abs(Kfull - Kfull.T).max() / abs(Kfull).max():.1e}")
    # one Newton solve from zero to check quadratic convergence
    print("  Newton on this mesh (full load, 5 steps):")
    solve(mesh, 5, tol=1e-11, verbose=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--max-n", type=int, default=320,
                    help="largest number of elements along the beam (default 320)")
    ap.add_argument("--min-n", type=int, default=20,
                    help="coarsest mesh (default 20); meshes double up to --max-n")
    ap.add_argument("--steps", type=int, default=5, help="load steps (default 5)")
    ap.add_argument("--tol", type=float, default=1e-10,
                    help="Newton tolerance on |R| / |f_ext| (default 1e-10)")
    ap.add_argument("--scale", type=float, default=1.0,
                    help="multiply the pressure by this; outputs are divided by it "
                         "(--scale 1e-6: the small-load check)")
    ap.add_argument("--check", action="store_true",
                    help="finite-difference check of the tangent, then exit")
    ap.add_argument("--steps-check", type=int, default=0, metavar="N",
                    help="solve the N x N/5 mesh with 5 and with 20 load steps, then exit")
    ap.add_argument("--clamped", action="store_true",
                    help="diagnostic: u_y = 0 on the whole left edge as well (no point support)")
    ap.add_argument("--verbose", action="store_true", help="print Newton residuals")
    args = ap.parse_args()

    if args.check:
        tangent_check()
        return
    if args.steps_check:
        mesh = Mesh(args.steps_check, PRESSURE * args.scale)
        res = {}
        for st in (5, 20):
            t = time.time()
            u, it = solve(mesh, st, tol=args.tol)
            res[st] = mesh.outputs(u)
            print(f"n = {args.steps_check}, {st:>2} steps: "
                  + ", ".join(f"{k} {v / args.scale:.12f}" for k, v in res[st].items())
                  + f"; iterations {it}; {time.time() - t:.1f} s", flush=True)
        print("differences (20 steps - 5 steps): "
              + ", ".join(f"{k} {(res[20][k] - res[5][k]) / args.scale:.2e}" for k in res[5]))
        return

    ns = []
    n = args.min_n
    while n <= args.max_n:
        ns.append(n)
        n *= 2

    t0 = time.time()
    results = []
    keys = None
    print(f"pressure {PRESSURE * args.scale:g} Pa (outputs divided by {args.scale:g}),"
          f" {args.steps} load steps, Newton tolerance {args.tol:g}"
          + (", CLAMPED left edge (diagnostic)" if args.clamped else ""))
    print(f"{'n':>5} {'m':>4} {'h':>9} {'dofs':>8} "
          f"{'u_x(10,1)':>15} {'u_y(10,1)':>15} {'mean u_y(0,.)':>15} {'rel. defl.':>15}"
          f"  {'Newton its/step':<16} {'|e|pin':>7} {'|e|rest':>7} {'min J':>6} {'time[s]':>8}")
    for n in ns:
        t = time.time()
        mesh = Mesh(n, PRESSURE * args.scale, clamped=args.clamped)
        u, its = solve(mesh, args.steps, tol=args.tol, verbose=args.verbose)
        r = {k: v / args.scale for k, v in mesh.outputs(u).items()}
        epin, erest, jmin = mesh.strain_report(u)
        keys = list(r)
        results.append(r)
        print(f"{n:>5} {n // 5:>4} {LX / n:>9.6f} {mesh.nfree:>8} "
              + " ".join(f"{r[k]:>15.10f}" for k in keys)
              + f"  {','.join(map(str, its)):<16} {epin:>7.4f} {erest:>7.4f} {jmin:>6.3f}"
              + f" {time.time() - t:>8.1f}", flush=True)
        del mesh, u

    print()
    for key in keys:
        f = [r[key] for r in results]
        print(f"{key}")
        rich = print_differences(ns, f)
        if key in ("u_x(10,1)", "rel. defl.") and rich:
            p, fx, err = rich[-1]
            spread = abs(rich[-1][1] - rich[-2][1]) if len(rich) >= 2 else float("nan")
            orders = [q[0] for q in rich[-2:]]
            biggest = max(abs(f[k] - f[k - 1]) for k in range(1, len(f)))
            if biggest <= 1e-8 * abs(f[-1]):
                line = (f"  mesh-independent: {f[-1]:.10f} (changes <= {biggest:.1e},"
                        f" round-off)")
            elif all(q > 0.5 for q in orders):
                line = (f"  extrapolated {fx:.8f} +- {max(err, spread):.1e}"
                        f" (correction {err:.1e}, spread vs previous triple {spread:.1e})")
            else:
                tail = f[1:] if len(f) > 3 else f
                lo, hi = min(tail), max(tail)
                line = (f"  NO asymptotic convergence (last orders "
                        + ", ".join(f"{q:.2f}" for q in orders)
                        + f"): finest {f[-1]:.8f}; meshes n >= {ns[len(f) - len(tail)]}"
                        f" span [{lo:.8f}, {hi:.8f}] (width {hi - lo:.1e})")
            if args.scale != 1.0:
                ref = SMALL_STRAIN[key]
                line += f"; small-strain {ref}; finest mesh rel. diff {(f[-1] - ref) / abs(ref):+.2e}"
            print(line)
        print()
    print(f"total run time {time.time() - t0:.1f} s")


if __name__ == "__main__":
    main()
