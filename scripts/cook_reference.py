#!/usr/bin/env python3
"""Independent finite-element reference value for Cook's membrane (linear,
plane strain, nearly incompressible): the vertical displacement of the
top-right corner.

Problem (small-strain linear elasticity, no body force)
-------------------------------------------------------
* Cook, R. D. (1974), "Improved two-dimensional finite element",
  J. Struct. Div. ASCE 100(ST9), 1851-1863: the tapered panel with vertices
  (0,0), (48,44), (48,60), (0,44) (counter-clockwise), clamped on the left
  edge x = 0 (u = 0), loaded on the right edge x = 48, 44 <= y <= 60 by a
  uniform vertical (shear) traction t_y = F/16 per unit length (total F per
  unit thickness); the slanted top and bottom edges are traction-free.
* Nearly incompressible variant (default here): plane strain, E = 250,
  nu = 0.4999, F = 100 (t_y = 6.25), the form used in the literature on
  locking-free elements after Simo & Rifai (1990), "A class of mixed assumed
  strain methods and the method of incompatible modes", IJNME 29, 1595-1638
  (this parameter set was taken from the project brief, not re-checked
  against the papers).
* Outputs: u_y at the top-right corner C = (48, 60) (the quantity wanted),
  and u_y at the midpoint of the loaded edge (48, 52), the point several
  codes track (see the sanity check below).
* Options: --E, --nu, --F, --plane-stress (solved through the equivalent
  plane-strain constants E* = E(1+2nu)/(1+nu)^2, nu* = nu/(1+nu), which
  give the same 2D Lame constants), --element q2q1 (Taylor-Hood cross-check).

Formulation (perturbed Lagrangian / Herrmann mixed u-p)
--------------------------------------------------------
With mu = E/(2(1+nu)), kappa = E/(3(1-2nu)) (3D bulk modulus) and the 3D
deviator of the plane-strain strain (eps_zz = 0),
    Pi(u, p) = int mu dev(eps(u)):dev(eps(u)) + int p div u
               - int p^2 / (2 kappa) - int_{x=48} t.u ds,
so that  a(u,v) + (p, div v) = f(v)   and   (q, div u) - (q, p)/kappa = 0,
i.e. p = kappa div u is the mean stress; at the continuous level
2 mu dev(eps) + kappa tr(eps) I = 2 mu eps + lambda tr(eps) I (Hooke).
Default discrete pair: Q2/P1-discontinuous (Q9 biquadratic displacement,
pressure linear per element and discontinuous, the inf-sup stable
"Q2/P1disc" element; the pressure basis 1, x - xc, y - yc is taken in
PHYSICAL coordinates, the "unmapped" P1 that keeps the inf-sup condition and
optimal order on non-affine quadrilaterals, Boffi & Gastaldi 2002).  The
pressure is element-local, so the pressure equation is eliminated element by
element (static condensation, exact):
    p_e = kappa M_e^{-1} G_e u_e,   K_e = A_e + kappa G_e^T M_e^{-1} G_e,
with A_e = int 2 mu dev(eps):dev(eps), G_e = int psi div N, M_e = int psi psi.
The condensed matrix is symmetric positive definite and does not lock (it
penalises only the L2 projection of div u onto P1).  `--monolithic` solves
the full symmetric indefinite [[A, G^T], [G, -M/kappa]] system instead
(same answer to ~1e-9: a check of the condensation).  `--element q2q1`
solves the same u-p equations with the Taylor-Hood pair (Q9 displacement,
continuous bilinear pressure), an independent stable discretisation.

Discretisation
--------------
* Structured mesh: the bilinear map X(s,t) of the unit square onto the
  quadrilateral (x = 48 s, y = 44 s + 44 t - 28 s t) applied to an n x n
  grid; every element is the bilinear image of its own four corners, so the
  Q9 nodes are placed by the same map and the isoparametric Q9 geometry is
  exact.  Elements are trapezoids (non-affine).
* 3x3 Gauss quadrature on every element (A_e, G_e, M_e).
* Consistent nodal load on the straight right edge: t_y * h * (1/6, 4/6,
  1/6) per element edge (h = 16/n).
* Clamped dofs eliminated; SuperLU (scipy.sparse.linalg) direct solve.
* Convergence: f(h), f(h/2), f(h/4) give the observed order
  p = log2(|f(h)-f(h/2)| / |f(h/2)-f(h/4)|) and the Richardson value
  f(h/4) + (f(h/4)-f(h/2)) / (2^p - 1).  Singularities limit p:
  - the top-left corner (0,44), where the clamped edge meets the free top
    edge at 108.4 deg, has the Williams exponent lambda = 0.5437 at
    nu = 0.4999 (0.6244 at nu = 1/3 in plane strain, 0.6772 in plane
    stress; printed by the script): displacement
    functionals then converge like h^(2 lambda) = h^1.087 (pollution);
  - at the loaded corner (48,60) itself the shear traction meets the free
    top edge; the local solution contains r log r terms (Airy function
    r^2 theta), so the point value u_y(48,60) is ultimately only O(h).
  The corner values indeed show p = 1.09 -> 1.06 (nu = 0.4999) and
  p -> 1.02 (nu = 1/3), the mid-edge values p ~ 1.2 and 1.36 ~ 2 lambda.
  Printed besides the observed-order extrapolation: the previous triple's,
  and the last pair extrapolated with the fixed orders 1 and 2 lambda; the
  quoted +- is the largest deviation among them.

How to run
----------
    python3 scripts/cook_reference.py                  # E=250, nu=0.4999, F=100, n=8..128
    python3 scripts/cook_reference.py --max-n 256      # one more mesh (~45 s more)
    python3 scripts/cook_reference.py --element q2q1   # Taylor-Hood cross-check (~30 s)
    python3 scripts/cook_reference.py --E 1 --nu 0.3333333333333333 --F 1 --plane-stress
    python3 scripts/cook_reference.py --E 1 --nu 0.3333333333333333 --F 1   # plane strain

Dependencies: Python 3, numpy, scipy (tested with Python 3.11.7,
numpy 2.4.6, scipy 1.17.1).

Results printed by this script (2-core machine shared with a compile job)
-------------------------------------------------------------------------
Default run (Q2/P1disc, E = 250, nu = 0.4999, F = 100; 5.6 s wall, 0.75 GB):
    n  unknowns |     u_y(48,60)       diff      p   Richardson |     u_y(48,52)       diff      p   Richardson
    8       544 |   7.7129914881                                |   7.3838056641
   16      2112 |   7.7438251058  3.083e-02                     |   7.3944803561  1.067e-02
   32      8320 |   7.7582900169  1.446e-02  1.092    7.7710726 |   7.4002071371  5.727e-03  0.898    7.4068354
   64     33024 |   7.7650723552  6.782e-03  1.093    7.7710599 |   7.4027556565  2.549e-03  1.168    7.4047992
  128    131584 |   7.7682959870  3.224e-03  1.073    7.7712161 |   7.4038665539  1.111e-03  1.198    7.4047250
  (per-mesh times 0.01, 0.03, 0.14, 0.66, 4.2 s)
  u_y(48,60): observed order 7.771216, previous triple 7.771060, p = 1 ->
              7.771520, p = 2 lambda -> 7.771162: estimate 7.771216 +- 3.0e-04
  u_y(48,52): estimate 7.404725 +- 1.3e-04
With --max-n 256 (extra row; 37 s for that mesh, 44 s total, 3.1 GB):
  256    525312 |   7.7698445815  1.549e-03  1.058    7.7712763 |   7.4043578600  4.913e-04  1.177    7.4047474
  u_y(48,60): observed order 7.771276, previous triple 7.771216, p = 1 ->
              7.771393, p = 2 lambda -> 7.771221: estimate 7.771276 +- 1.2e-04
  u_y(48,52): estimate 7.404747 +- 4.7e-05
Taylor-Hood Q2/Q1 (--element q2q1, n = 8..128, 32 s): u_y(48,60) =
  7.7499108552, 7.7637958169, 7.7680199943, 7.7698053323, 7.7706192582,
  p = 1.72, 1.24, 1.13, Richardson 7.771301 (+- 1.9e-04); u_y(48,52) ->
  7.404751.  It converges from much closer but to the same limit.
=> Reference: u_y(48,60) = 7.7713 +- 0.0002, u_y(48,52) = 7.4047(5) +- 0.0001
   (E = 250, nu = 0.4999, F = 100, plane strain).  The values scale as F/E.

Sanity check, E = 1, nu = 1/3, F = 1 (n = 8..256, Q2/P1disc):
  plane stress: u_y(48,60) = 25.1894 +- 0.002 (p -> 1.02);
                u_y(48,52) = 23.96774 (p = 1.357, extrapolations agree to 4e-7).
  plane strain: u_y(48,60) = 22.6104 +- 0.001;  u_y(48,52) = 21.52457.
  The widely quoted 23.96 (23.97 in FinEtools, "converged free mid-edge
  displacement") is the PLANE-STRESS value at the MIDPOINT (48,52) of the
  loaded edge, not at the corner (25.19 in plane stress).  The plane-strain
  corner value agrees with published plane-strain results for E = 70 MPa,
  nu = 1/3, t = 6.25 kPa (solids4foam/Abaqus CPE4H, about 32.3 um): here
  22.6104 * 100 / 70 = 32.30.
"""

import argparse
import math
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import brentq

# ---------------------------------------------------------------- geometry
CORNERS = np.array([[0.0, 0.0], [48.0, 44.0], [48.0, 60.0], [0.0, 44.0]])
LOADED_EDGE_LENGTH = 16.0  # x = 48, 44 <= y <= 60


def bilinear_map(s, t):
    """Map (s, t) in [0,1]^2 onto Cook's quadrilateral."""
    P0, P1, P2, P3 = CORNERS
    x = ((1 - s) * (1 - t))[..., None] * P0 + (s * (1 - t))[..., None] * P1 \
        + (s * t)[..., None] * P2 + ((1 - s) * t)[..., None] * P3
    return x


# 1D quadratic Lagrange basis on [-1, 1] with nodes -1, 0, 1.
def lagrange1d(xi):
    return np.array([0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)])


def lagrange1d_deriv(xi):
    return np.array([xi - 0.5, -2.0 * xi, xi + 0.5])


GAUSS3_PTS = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
GAUSS3_WTS = np.array([5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])


def q9_reference():
    """Q9 values N[g, k] and derivatives dN[g, k, r] at the 3x3 Gauss points.

    Local node k = 3*b + a sits at (xi_a, eta_b), xi/eta in {-1, 0, 1}.
    """
    N, dN, W = [], [], []
    for eta, wy in zip(GAUSS3_PTS, GAUSS3_WTS):
        for xi, wx in zip(GAUSS3_PTS, GAUSS3_WTS):
            lx, ly = lagrange1d(xi), lagrange1d(eta)
            dx, dy = lagrange1d_deriv(xi), lagrange1d_deriv(eta)
            N.append(np.outer(ly, lx).ravel())
            dN.append(np.stack([np.outer(ly, dx).ravel(), np.outer(dy, lx).ravel()], axis=1))
            W.append(wx * wy)
    return np.array(N), np.array(dN), np.array(W)


def element_matrices(X, mu, pressure):
    """Element matrices A_e (nel x 18 x 18), G_e (nel x np x 18), M_e (nel x np x np).

    X: (nel, 9, 2) Q9 node coordinates; dofs 2k = u_x, 2k+1 = u_y of node k.
    pressure = "p1disc": psi = 1, (x - xc)/h, (y - yc)/h (unmapped, per element);
    pressure = "q1": psi = the 4 bilinear corner functions (continuous,
    Taylor-Hood), corners ordered (xi, eta) = (-1,-1), (1,-1), (-1,1), (1,1).
    """
    N, dNref, W = q9_reference()
    pts = [(xi, eta) for eta in GAUSS3_PTS for xi in GAUSS3_PTS]  # q9_reference order
    nel = X.shape[0]
    # Deviatoric plane-strain elasticity in Voigt form [exx, eyy, gxy]:
    # 2 mu dev(eps):dev(eps) = 2 mu eps:eps - (2 mu / 3) tr(eps)^2.
    Ddev = mu * np.array([[4.0 / 3.0, -2.0 / 3.0, 0.0],
                          [-2.0 / 3.0, 4.0 / 3.0, 0.0],
                          [0.0, 0.0, 1.0]])
    xc = X.mean(axis=1)                              # (nel, 2) node centroid
    d1, d2 = X[:, 8] - X[:, 0], X[:, 6] - X[:, 2]    # diagonals
    hs = np.sqrt(0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]))  # sqrt(area)
    npe = 3 if pressure == "p1disc" else 4
    A = np.zeros((nel, 18, 18))
    G = np.zeros((nel, npe, 18))
    M = np.zeros((nel, npe, npe))
    for g in range(len(W)):
        J = np.einsum("eki,kr->eir", X, dNref[g])    # dx_i / dxi_r
        detJ = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        assert np.all(detJ > 0.0)
        Jinv = np.empty_like(J)
        Jinv[:, 0, 0] = J[:, 1, 1] / detJ
        Jinv[:, 1, 1] = J[:, 0, 0] / detJ
        Jinv[:, 0, 1] = -J[:, 0, 1] / detJ
        Jinv[:, 1, 0] = -J[:, 1, 0] / detJ
        dNdx = np.einsum("kr,eri->eki", dNref[g], Jinv)  # (nel, 9, 2)
        B = np.zeros((nel, 3, 18))
        B[:, 0, 0::2] = dNdx[:, :, 0]
        B[:, 1, 1::2] = dNdx[:, :, 1]
        B[:, 2, 0::2] = dNdx[:, :, 1]
        B[:, 2, 1::2] = dNdx[:, :, 0]
        div = B[:, 0, :] + B[:, 1, :]                     # (nel, 18)
        if pressure == "p1disc":
            xg = np.einsum("k,eki->ei", N[g], X)          # physical Gauss point
            psi = np.stack([np.ones(nel), (xg[:, 0] - xc[:, 0]) / hs,
                            (xg[:, 1] - xc[:, 1]) / hs], axis=1)
        else:
            xi, eta = pts[g]
            q = 0.25 * np.array([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta),
                                 (1 - xi) * (1 + eta), (1 + xi) * (1 + eta)])
            psi = np.broadcast_to(q, (nel, 4))
        w = W[g] * detJ
        A += w[:, None, None] * np.einsum("eai,ab,ebj->eij", B, Ddev, B)
        G += w[:, None, None] * psi[:, :, None] * div[:, None, :]
        M += w[:, None, None] * psi[:, :, None] * psi[:, None, :]
    return A, G, M


def solve_mesh(n, E, nu, F, element="q2p1", monolithic=False):
    """u_y at (48, 60) and at (48, 52) on the n x n mesh, and the unknown count."""
    mu = E / (2.0 * (1.0 + nu))
    kappa = E / (3.0 * (1.0 - 2.0 * nu))
    nn = 2 * n + 1                      # Q9 nodes per grid line
    ndof = 2 * nn * nn
    s, t = np.meshgrid(np.linspace(0.0, 1.0, nn), np.linspace(0.0, 1.0, nn), indexing="xy")
    coords = bilinear_map(s.ravel(), t.ravel())   # node (i, j) -> index j*nn + i

    ei, ej = np.meshgrid(np.arange(n), np.arange(n), indexing="xy")
    ei, ej = ei.ravel(), ej.ravel()
    nel = n * n
    conn = np.empty((nel, 9), dtype=np.int64)
    for b in range(3):
        for a in range(3):
            conn[:, 3 * b + a] = (2 * ej + b) * nn + (2 * ei + a)
    edofs = np.empty((nel, 18), dtype=np.int64)
    edofs[:, 0::2] = 2 * conn
    edofs[:, 1::2] = 2 * conn + 1

    pressure = "p1disc" if element == "q2p1" else "q1"
    A_e, G_e, M_e = element_matrices(coords[conn], mu, pressure)

    # Consistent load on x = 48 (i = nn-1): t_y * h * (1/6, 4/6, 1/6) per edge.
    f = np.zeros(ndof)
    ty = F / LOADED_EDGE_LENGTH
    h = LOADED_EDGE_LENGTH / n
    right = np.arange(nn) * nn + (nn - 1)
    for e in range(n):
        f[2 * right[2 * e:2 * e + 3] + 1] += ty * h * np.array([1.0, 4.0, 1.0]) / 6.0
    assert abs(f.sum() - F) < 1e-12 * max(1.0, F)

    left = np.arange(nn) * nn
    fixed = np.concatenate([2 * left, 2 * left + 1])
    free = np.setdiff1d(np.arange(ndof), fixed)
    corner = (nn - 1) * nn + (nn - 1)   # (s, t) = (1, 1) -> (48, 60)
    mid = (nn // 2) * nn + (nn - 1)     # (s, t) = (1, 1/2) -> (48, 52)
    assert np.allclose(coords[corner], [48.0, 60.0])
    assert np.allclose(coords[mid], [48.0, 52.0])

    rows = np.repeat(edofs, 18, axis=1).ravel()
    cols = np.tile(edofs, (1, 18)).ravel()
    u = np.zeros(ndof)
    if element == "q2p1" and not monolithic:
        # Static condensation of the element pressures.
        K_e = A_e + kappa * np.einsum("eqi,eqj->eij", G_e, np.linalg.solve(M_e, G_e))
        K = sp.coo_matrix((K_e.ravel(), (rows, cols)), shape=(ndof, ndof)).tocsc()
        Kff = K[free][:, free].tocsc()
        # SPD: symmetric ordering, no pivoting (threshold pivoting on the
        # kappa/mu ~ 5e3 penalty rows would destroy the ordering's sparsity).
        lu = spla.splu(Kff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options=dict(SymmetricMode=True))
        u[free] = lu.solve(f[free])
        nunk = len(free)
    else:
        # Full symmetric indefinite system [[A, G^T], [G, -M/kappa]].
        if element == "q2p1":
            npd = 3 * nel
            pdofs = ndof + 3 * np.arange(nel)[:, None] + np.arange(3)[None, :]
        else:
            npd = (n + 1) ** 2
            pconn = np.stack([ej * (n + 1) + ei, ej * (n + 1) + ei + 1,
                              (ej + 1) * (n + 1) + ei, (ej + 1) * (n + 1) + ei + 1], axis=1)
            pdofs = ndof + pconn
        m = pdofs.shape[1]
        r = [rows, np.repeat(pdofs, 18, axis=1).ravel(), np.repeat(edofs, m, axis=1).ravel(),
             np.repeat(pdofs, m, axis=1).ravel()]
        c = [cols, np.tile(edofs, (1, m)).ravel(), np.tile(pdofs, (1, 18)).ravel(),
             np.tile(pdofs, (1, m)).ravel()]
        v = [A_e.ravel(), G_e.ravel(), np.transpose(G_e, (0, 2, 1)).ravel(),
             (-M_e / kappa).ravel()]
        ntot = ndof + npd
        K = sp.coo_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))),
                          shape=(ntot, ntot)).tocsc()
        keep = np.concatenate([free, np.arange(ndof, ntot)])
        rhs = np.concatenate([f, np.zeros(npd)])
        x = np.zeros(ntot)
        # SuperLU with COLAMD ordering and partial pivoting (slower: ~30 s at n = 128).
        x[keep] = spla.spsolve(K[keep][:, keep].tocsc(), rhs[keep], permc_spec="COLAMD")
        u = x[:ndof]
        nunk = len(keep)
    return u[2 * corner + 1], u[2 * mid + 1], nunk


def corner_exponent(alpha, nu):
    """Smallest real Williams exponent lambda in (0, 1] of a clamped-free
    wedge of interior angle alpha (plane strain, Kolosov kappa = 3 - 4 nu):
        kappa sin^2(lambda alpha) + lambda^2 sin^2(alpha) = (1 + kappa)^2 / 4,
    displacements ~ r^lambda.  (For alpha = pi it gives the classical
    1/2 + i ln(kappa)/(2 pi) of a bonded edge.)  None if no real root."""
    kappa = 3.0 - 4.0 * nu
    D = lambda l: kappa * math.sin(l * alpha) ** 2 + (l * math.sin(alpha)) ** 2 \
        - (1.0 + kappa) ** 2 / 4.0
    grid = np.linspace(1e-3, 1.0, 1000)
    for a, b in zip(grid, grid[1:]):
        if D(a) * D(b) <= 0.0:
            return brentq(D, a, b, xtol=1e-14)
    return None


def richardson(f):
    """Observed orders and Richardson extrapolations for a sequence with h halving."""
    out = []
    for k in range(2, len(f)):
        d1, d2 = f[k - 1] - f[k - 2], f[k] - f[k - 1]
        if d2 == 0.0 or d1 == 0.0:
            out.append((float("nan"), f[k], 0.0))
            continue
        p = math.log2(abs(d1) / abs(d2))
        corr = d2 / (2.0 ** p - 1.0)
        out.append((p, f[k] + corr, abs(corr)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--E", type=float, default=250.0, help="Young's modulus (default 250)")
    ap.add_argument("--nu", type=float, default=0.4999, help="Poisson's ratio (default 0.4999)")
    ap.add_argument("--F", type=float, default=100.0,
                    help="total shear load on the right edge (default 100, t_y = F/16)")
    ap.add_argument("--plane-stress", action="store_true",
                    help="plane stress (via equivalent plane-strain constants)")
    ap.add_argument("--min-n", type=int, default=8)
    ap.add_argument("--max-n", type=int, default=128,
                    help="finest mesh (default 128); meshes double from --min-n")
    ap.add_argument("--element", choices=["q2p1", "q2q1"], default="q2p1",
                    help="q2p1: Q2/P1disc (default); q2q1: Taylor-Hood Q2/Q1 (cross-check)")
    ap.add_argument("--monolithic", action="store_true",
                    help="Q2/P1disc: solve the full u-p system instead of condensing p")
    args = ap.parse_args()

    E, nu = args.E, args.nu
    if args.plane_stress:
        E, nu = E * (1.0 + 2.0 * nu) / (1.0 + nu) ** 2, nu / (1.0 + nu)
    print(f"Cook's membrane, {'plane stress' if args.plane_stress else 'plane strain'}, "
          f"E = {args.E:g}, nu = {args.nu:.10g}, F = {args.F:g} (t_y = {args.F / 16:g}); "
          + ("Taylor-Hood Q2/Q1, monolithic u-p" if args.element == "q2q1" else
             f"Q2/P1disc, {'monolithic u-p' if args.monolithic else 'condensed p'}"))
    if args.plane_stress:
        print(f"  (solved as plane strain with E* = {E:.10g}, nu* = {nu:.10g})")

    ns = []
    n = args.min_n
    while n <= args.max_n:
        ns.append(n)
        n *= 2

    t0 = time.time()
    vals = {"corner": [], "mid": []}
    print(f"{'n':>5} {'unknowns':>9} | {'u_y(48,60)':>14} {'diff':>10} {'p':>6} {'Richardson':>12} "
          f"| {'u_y(48,52)':>14} {'diff':>10} {'p':>6} {'Richardson':>12} | {'time[s]':>7}")
    for k, n in enumerate(ns):
        t = time.time()
        uc, um, nunk = solve_mesh(n, E, nu, args.F, args.element, args.monolithic)
        line = f"{n:>5} {nunk:>9}"
        for key, v in (("corner", uc), ("mid", um)):
            f = vals[key]
            f.append(v)
            line += f" | {v:>14.10f}"
            line += f" {v - f[-2]:>10.3e}" if k >= 1 else f" {'':>10}"
            if k >= 2:
                p, fx, _ = richardson(f)[-1]
                line += f" {p:>6.3f} {fx:>12.7f}"
            else:
                line += f" {'':>6} {'':>12}"
        print(line + f" | {time.time() - t:>7.2f}", flush=True)

    # Leading corner singularity: the clamped-free corner (0, 44), interior
    # angle 90 + atan(16/48) deg.  A displacement functional then converges
    # like h^(2 lambda) (pollution from the corner), so 2 lambda is the
    # expected asymptotic order; the bottom-left corner (0, 0) is milder.
    # At the loaded corner (48, 60) itself the shear traction on x = 48 meets
    # the free top edge; the local field there contains r log r terms
    # (Airy function r^2 theta), which limits the point value there to O(h).
    lam_tl = corner_exponent(math.pi / 2 + math.atan(16.0 / 48.0), nu)
    lam_bl = corner_exponent(math.pi / 2 - math.atan(44.0 / 48.0), nu)
    fmt = lambda l: "none in (0,1]" if l is None else f"{l:.4f}"
    print(f"\nWilliams exponents (clamped-free): top-left corner lambda = {fmt(lam_tl)}, "
          f"bottom-left lambda = {fmt(lam_bl)}")
    orders = {"corner": [1.0], "mid": []}
    if lam_tl is not None:
        orders["corner"].append(2.0 * lam_tl)
        orders["mid"].append(2.0 * lam_tl)
    for key, label in (("corner", "u_y(48,60)"), ("mid", "u_y(48,52)")):
        f = vals[key]
        rich = richardson(f)
        if not rich:
            continue
        p, fx, err = rich[-1]
        print(f"{label}: Richardson (observed order) from n = {ns[-3]}, {ns[-2]}, {ns[-1]}: "
              f"p = {p:.3f} -> {fx:.6f} (correction {err:.1e})")
        cands = [fx]
        if len(rich) >= 2:
            print(f"    previous triple: p = {rich[-2][0]:.3f} -> {rich[-2][1]:.6f}")
            cands.append(rich[-2][1])
        for pt in orders[key]:
            ft = f[-1] + (f[-1] - f[-2]) / (2.0 ** pt - 1.0)
            print(f"    fixed order p = {pt:.3f} from n = {ns[-2]}, {ns[-1]} -> {ft:.6f}")
            cands.append(ft)
        if len(cands) >= 2:
            unc = max(abs(c - fx) for c in cands)
            print(f"  estimate {label} = {fx:.6f} +- {unc:.1e} (largest deviation of the "
                  f"other extrapolations)")
    print(f"total run time {time.time() - t0:.1f} s")


if __name__ == "__main__":
    main()
