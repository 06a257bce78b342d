#!/usr/bin/env python3
"""Independent finite-element reference for the quarter plate with a hole
(the built-in case `plate-with-hole`, scripts/plate_with_hole_template.json).

Problem (small-strain linear elasticity, PLANE STRAIN, no body force)
---------------------------------------------------------------------
* Region: 0 <= x <= W, 0 <= y <= W minus the disc r < a (W = 10 m, a = 1 m);
  the full plate is 20 m x 20 m with a 2 m central hole (d/D = 0.1).
* E = 1e6 Pa, nu = 0.3.
* Load: uniform dead traction t = (s, 0), s = 1000 Pa, on x = W (10000 N per
  unit thickness on the quarter); y = W and the hole are traction free.
* Supports (symmetry): u_x = 0 on x = 0, u_y = 0 on y = 0.

NOTE on the hoop stress at the top of the hole: the load is along x, so at
(0, a) the hoop (tangential) direction is x and the hoop stress is SIGMA_XX
(Kirsch: 3 s).  sigma_yy(0, a) is the radial stress there and is zero
(traction-free hole).  Likewise the stress that concentrates along the net
section x = 0 is sigma_xx.  Both sigma_xx and sigma_yy are printed.

Method
------
* Biquadratic 9-node (Q9) quadrilaterals, 3x3 Gauss quadrature, consistent
  edge loads (3-point Gauss on the edges), scipy.sparse direct solve.
* Structured mesh of two blocks split along the diagonal y = x:
    block 1: arc theta in [0, 45 deg]  ->  right edge x = W,
    block 2: arc theta in [45, 90 deg] ->  top edge   y = W,
  x(p, s) = (1 - s) A(p) + s B(p) with A on the arc and B on the straight
  edge (rays from the arc point to the edge point); uniform in p (angle).
  Nested refinement levels L = 0..3 (every element halved each level):
    family A (main): 12*2^L elements along each 45-degree arc; along the rays
      element boundaries at the fractions s of y = 1, 1.05, 1.1, 1.25, 1.5, 2,
      3.2, 5.5, 10 on x = 0, each interval split into 2^L (graded toward the
      hole, first element 0.05 m/2^L), so that every table point (theta = 45,
      60, 75, 90 on the hole, y = 1.05 ... 2 on x = 0) is a node;
    family B (cross-check): n = 8*2^L elements both ways, s_k = g(k/n),
      g(t) = expm1(beta t)/expm1(beta), beta = 4 (smooth geometric grading).
* Geometry: default "exact" = every element is the image of its parameter box
  under the analytic block map (blending map), so the hole is represented
  EXACTLY; the displacement is Q9 in the element's parameter coordinates
  (conforming: neighbours share the edge parametrisation).  Cross-check:
  "iso" = classical isoparametric Q9 with the nodes (incl. the hole mid-side
  nodes) placed exactly on the arc (the arc between nodes is then a parabola).
* Stress recovery: the element stress D B u evaluated at the wanted point in
  the element containing it ((0, a) is the corner of a single element; at
  theta = 45 deg, a node of two elements, the two element values are averaged
  and their jump is printed).
* Richardson extrapolation over the last three levels: observed order
  p = log2((f_h - f_h/2)/(f_h/2 - f_h/4)), extrapolated
  f_h/4 + (f_h/4 - f_h/2)/(2^p - 1), error estimate |extrapolated - finest|;
  if p is outside [1, 5] (not asymptotic) the finest value is kept and the
  error estimate is the last change |f_h/4 - f_h/2|.

Checks
------
* Sum of the x reactions on x = 0 = -10000 N (to round-off).
* Lame thick cylinder (annulus 1 <= r <= 2, internal pressure p, quarter with
  symmetry; same element code, curved mesh) against the exact plane-strain
  solution: errors in u_r(1), sigma_tt(1), sigma_rr(1) and observed orders.
* Kirsch problem: the same plate-with-hole mesh with Kirsch's exact
  infinite-plate tractions applied on x = W and y = W; the FE solution must
  converge to Kirsch's field (sigma_xx(0, 1) -> 3 s, displacements).
* Finite length: the quarter strip 0 <= x <= L, 0 <= y <= W (an extra block
  for W <= x <= L) for L = 10, 20, 40, 80, i.e. how far the 20 x 20 plate is
  from the infinite strip of the Howland / Peterson and Heywood formulas.

Run:  python3 scripts/plate_with_hole_reference.py [--levels 4] [--no-checks]
      (about 25 s on 2 cores with the default 4 levels)
"""

import argparse
import math
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

E, NU = 1.0e6, 0.3
A_HOLE, W = 1.0, 10.0
S = 1000.0
BETA = 4.0

LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
MU = E / (2 * (1 + NU))
DMAT = np.array([[LAM + 2 * MU, LAM, 0.0], [LAM, LAM + 2 * MU, 0.0], [0.0, 0.0, MU]])

GP1 = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
GW1 = np.array([5.0, 8.0, 5.0]) / 9.0


# ----------------------------------------------------------------------------
# Q9 shape functions, local node (i, j) -> index 3 j + i, xi_i, eta_j in {-1,0,1}
# ----------------------------------------------------------------------------
def lag1(t):
    t = np.asarray(t, float)
    L = np.stack([0.5 * t * (t - 1), 1 - t * t, 0.5 * t * (t + 1)], -1)
    dL = np.stack([t - 0.5, -2 * t, t + 0.5], -1)
    return L, dL


def q9(xi, eta):
    Lx, dLx = lag1(xi)
    Ly, dLy = lag1(eta)
    N = (Ly[..., :, None] * Lx[..., None, :]).reshape(Lx.shape[:-1] + (9,))
    Nxi = (Ly[..., :, None] * dLx[..., None, :]).reshape(N.shape)
    Neta = (dLy[..., :, None] * Lx[..., None, :]).reshape(N.shape)
    return N, Nxi, Neta


# ----------------------------------------------------------------------------
# Blocks: map F(p, q) -> (x, y) with derivatives, element boundaries in p, q
# ----------------------------------------------------------------------------
class Block:
    def __init__(self, F, pb, qb):
        self.F = F  # F(p, q) -> (x, y, xp, yp, xq, yq)
        self.pb = np.asarray(pb, float)  # element boundaries in p
        self.qb = np.asarray(qb, float)

    @staticmethod
    def nodes1d(b):
        out = np.empty(2 * len(b) - 1)
        out[0::2] = b
        out[1::2] = 0.5 * (b[:-1] + b[1:])
        return out


def ray_map(Afun, Bfun):
    """x = (1 - q) A(p) + q B(p); Afun/Bfun return (x, y, dx/dp, dy/dp)."""

    def F(p, q):
        ax, ay, axp, ayp = Afun(p)
        bx, by, bxp, byp = Bfun(p)
        x = (1 - q) * ax + q * bx
        y = (1 - q) * ay + q * by
        return x, y, (1 - q) * axp + q * bxp, (1 - q) * ayp + q * byp, bx - ax, by - ay

    return F


def arc(r, th0, th1):
    d = th1 - th0

    def f(p):
        th = th0 + d * p
        c, s = np.cos(th), np.sin(th)
        return r * c, r * s, -r * s * d, r * c * d

    return f


def line(P0, P1):
    def f(p):
        p = np.asarray(p, float)
        return (P0[0] + (P1[0] - P0[0]) * p, P0[1] + (P1[1] - P0[1]) * p,
                np.full_like(p, P1[0] - P0[0]), np.full_like(p, P1[1] - P0[1]))

    return f


def graded(n, beta=BETA):
    t = np.arange(n + 1) / n
    return np.expm1(beta * t) / math.expm1(beta) if beta else t


# ----------------------------------------------------------------------------
# Mesh assembly from blocks
# ----------------------------------------------------------------------------
class Mesh:
    def __init__(self, blocks, geom="exact"):
        self.blocks, self.geom = blocks, geom
        coords, conn, einfo = [], [], []
        self.block_node = []  # per block: global node ids on its (2np+1)x(2nq+1) grid
        key2id = {}
        X = []
        for b, blk in enumerate(blocks):
            pn, qn = Block.nodes1d(blk.pb), Block.nodes1d(blk.qb)
            P, Q = np.meshgrid(pn, qn)  # [iq, ip]
            x, y = blk.F(P, Q)[:2]
            ids = np.empty(P.shape, int)
            for idx in np.ndindex(P.shape):
                k = (round(float(x[idx]) * 1e8), round(float(y[idx]) * 1e8))
                if k not in key2id:
                    key2id[k] = len(X)
                    X.append((float(x[idx]), float(y[idx])))
                ids[idx] = key2id[k]
            self.block_node.append(ids)
            npe, nqe = len(blk.pb) - 1, len(blk.qb) - 1
            for jq in range(nqe):
                for ip in range(npe):
                    conn.append(ids[2 * jq:2 * jq + 3, 2 * ip:2 * ip + 3].reshape(9))
                    einfo.append((b, blk.pb[ip], blk.pb[ip + 1], blk.qb[jq], blk.qb[jq + 1]))
        self.X = np.array(X)
        self.conn = np.array(conn)
        self.einfo = einfo
        self.eblock = np.array([e[0] for e in einfo])
        self.ebox = np.array([e[1:] for e in einfo])
        self.eoff = np.concatenate([[0], np.cumsum([(len(b.pb) - 1) * (len(b.qb) - 1) for b in blocks])])
        self.nn = len(self.X)
        self.ndof = 2 * self.nn

    # geometry at local points (xi, eta) for elements `els` (arrays broadcast)
    def geometry(self, els, xi, eta):
        N, Nxi, Neta = q9(xi, eta)
        if self.geom == "iso":
            xe = self.X[self.conn[els]]  # (ne, 9, 2)
            x = np.einsum("...a,...ad->...d", N, xe)
            xxi = np.einsum("...a,...ad->...d", Nxi, xe)
            xeta = np.einsum("...a,...ad->...d", Neta, xe)
            return N, Nxi, Neta, x[..., 0], x[..., 1], xxi[..., 0], xxi[..., 1], xeta[..., 0], xeta[..., 1]
        els = np.asarray(els)
        box = self.ebox[els]
        p0, p1, q0, q1 = box[..., 0], box[..., 1], box[..., 2], box[..., 3]
        p = p0 + 0.5 * (1 + xi) * (p1 - p0)
        q = q0 + 0.5 * (1 + eta) * (q1 - q0)
        x = np.empty(np.broadcast(p, q).shape)
        y, xp, yp, xq, yq = (np.empty_like(x) for _ in range(5))
        eb = self.eblock[els]
        for b, blk in enumerate(self.blocks):
            m = np.broadcast_to(eb == b, x.shape)
            if not m.any():
                continue
            pb, qb = np.broadcast_to(p, x.shape)[m], np.broadcast_to(q, x.shape)[m]
            r = blk.F(pb, qb)
            for arr, v in zip((x, y, xp, yp, xq, yq), r):
                arr[m] = v
        dp = 0.5 * (p1 - p0)
        dq = 0.5 * (q1 - q0)
        return N, Nxi, Neta, x, y, xp * dp, yp * dp, xq * dq, yq * dq

    def bmat(self, els, xi, eta):
        N, Nxi, Neta, x, y, xxi, yxi, xeta, yeta = self.geometry(els, xi, eta)
        det = xxi * yeta - xeta * yxi
        Nx = (yeta[..., None] * Nxi - yxi[..., None] * Neta) / det[..., None]
        Ny = (-xeta[..., None] * Nxi + xxi[..., None] * Neta) / det[..., None]
        sh = Nx.shape[:-1]
        B = np.zeros(sh + (3, 18))
        B[..., 0, 0::2] = Nx
        B[..., 1, 1::2] = Ny
        B[..., 2, 0::2] = Ny
        B[..., 2, 1::2] = Nx
        return B, det, x, y

    def stiffness(self):
        ne = len(self.conn)
        els = np.arange(ne)
        Ke = np.zeros((ne, 18, 18))
        for gi, wi in zip(GP1, GW1):
            for gj, wj in zip(GP1, GW1):
                B, det, _, _ = self.bmat(els, np.full(ne, gi), np.full(ne, gj))
                DB = np.einsum("ij,ejk->eik", DMAT, B)
                Ke += np.einsum("eji,ejk->eik", B, DB) * (np.abs(det) * wi * wj)[:, None, None]
        dofs = np.empty((ne, 18), int)
        dofs[:, 0::2] = 2 * self.conn
        dofs[:, 1::2] = 2 * self.conn + 1
        r = np.repeat(dofs, 18, axis=1).ravel()
        c = np.tile(dofs, (1, 18)).ravel()
        return sp.csr_matrix((Ke.ravel(), (r, c)), shape=(self.ndof, self.ndof))

    def edge_elements(self, b, side):
        """Elements of block b along a side ('p0','p1','q0','q1') and the local
        coordinate fixed on that side."""
        blk = self.blocks[b]
        npe, nqe = len(blk.pb) - 1, len(blk.qb) - 1
        grid = np.arange(npe * nqe).reshape(nqe, npe) + self.eoff[b]
        if side == "q0":
            return grid[0, :], "eta", -1.0
        if side == "q1":
            return grid[-1, :], "eta", 1.0
        if side == "p0":
            return grid[:, 0], "xi", -1.0
        return grid[:, -1], "xi", 1.0

    def edge_load(self, f, b, side, tfun):
        els, which, val = self.edge_elements(b, side)
        for g, w in zip(GP1, GW1):
            ne = len(els)
            if which == "eta":
                xi, eta = np.full(ne, g), np.full(ne, val)
            else:
                xi, eta = np.full(ne, val), np.full(ne, g)
            N, Nxi, Neta, x, y, xxi, yxi, xeta, yeta = self.geometry(els, xi, eta)
            ds = np.hypot(xxi, yxi) if which == "eta" else np.hypot(xeta, yeta)
            tx, ty = tfun(x, y)
            wN = N * (w * ds)[:, None]
            np.add.at(f, 2 * self.conn[els], wN * tx[:, None])
            np.add.at(f, 2 * self.conn[els] + 1, wN * ty[:, None])

    def solve(self, f, fixed):
        K = self.stiffness()
        free = np.setdiff1d(np.arange(self.ndof), fixed)
        u = np.zeros(self.ndof)
        Kff = K[free][:, free].tocsc()
        u[free] = spla.splu(Kff, permc_spec="MMD_AT_PLUS_A").solve(f[free])
        R = K @ u - f
        return u, R

    def locate(self, b, p, q):
        blk = self.blocks[b]
        npe = len(blk.pb) - 1
        ip = min(max(np.searchsorted(blk.pb, p, side="right") - 1, 0), npe - 1)
        jq = min(max(np.searchsorted(blk.qb, q, side="right") - 1, 0), len(blk.qb) - 2)
        xi = 2 * (p - blk.pb[ip]) / (blk.pb[ip + 1] - blk.pb[ip]) - 1
        eta = 2 * (q - blk.qb[jq]) / (blk.qb[jq + 1] - blk.qb[jq]) - 1
        return self.eoff[b] + jq * npe + ip, xi, eta

    def stress_at(self, u, e, xi, eta):
        B, det, x, y = self.bmat(np.array([e]), np.array([xi]), np.array([eta]))
        dofs = np.empty(18, int)
        dofs[0::2] = 2 * self.conn[e]
        dofs[1::2] = 2 * self.conn[e] + 1
        return DMAT @ (B[0] @ u[dofs]), (x[0], y[0])

    def stress_param(self, u, b, p, q):
        return self.stress_at(u, *self.locate(b, p, q))[0]

    def stress_all(self, u, b, p, q, tol=1e-12):
        """Stress at block-parameter point (p, q) from every element of block b
        whose closed parameter box contains it (1, 2 or 4 elements)."""
        blk = self.blocks[b]
        npe = len(blk.pb) - 1
        ips = [i for i in range(npe) if blk.pb[i] - tol <= p <= blk.pb[i + 1] + tol]
        jqs = [j for j in range(len(blk.qb) - 1) if blk.qb[j] - tol <= q <= blk.qb[j + 1] + tol]
        out = []
        for j in jqs:
            for i in ips:
                xi = 2 * (p - blk.pb[i]) / (blk.pb[i + 1] - blk.pb[i]) - 1
                eta = 2 * (q - blk.qb[j]) / (blk.qb[j + 1] - blk.qb[j]) - 1
                out.append(self.stress_at(u, self.eoff[b] + j * npe + i, xi, eta)[0])
        return out

    def node_at(self, x, y):
        d = np.hypot(self.X[:, 0] - x, self.X[:, 1] - y)
        i = int(np.argmin(d))
        assert d[i] < 1e-9, (x, y, d[i])
        return i


def hoop(sig, th):
    c, s = math.cos(th), math.sin(th)
    return sig[0] * s * s + sig[1] * c * c - 2 * sig[2] * s * c


# ----------------------------------------------------------------------------
# Exact solutions
# ----------------------------------------------------------------------------
def kirsch_stress(x, y, s=S, a=A_HOLE):
    r2 = x * x + y * y
    th = np.arctan2(y, x)
    q2, q4 = a * a / r2, a ** 4 / r2 ** 2
    c2, c4, s2, s4 = np.cos(2 * th), np.cos(4 * th), np.sin(2 * th), np.sin(4 * th)
    sxx = s * (1 - q2 * (1.5 * c2 + c4) + 1.5 * q4 * c4)
    syy = s * (-q2 * (0.5 * c2 - c4) - 1.5 * q4 * c4)
    sxy = s * (-q2 * (0.5 * s2 + s4) + 1.5 * q4 * s4)
    return sxx, syy, sxy


def kirsch_disp(x, y, s=S, a=A_HOLE):
    kap = 3 - 4 * NU  # plane strain
    r = math.hypot(x, y)
    th = math.atan2(y, x)
    f = s * a / (8 * MU)
    ux = f * (r / a * (kap + 1) * math.cos(th) + 2 * a / r * ((1 + kap) * math.cos(th) + math.cos(3 * th))
              - 2 * (a / r) ** 3 * math.cos(3 * th))
    uy = f * (r / a * (kap - 3) * math.sin(th) + 2 * a / r * ((1 - kap) * math.sin(th) + math.sin(3 * th))
              - 2 * (a / r) ** 3 * math.sin(3 * th))
    return ux, uy


def kirsch_tt(r, th, s=S, a=A_HOLE):
    return s / 2 * (1 + a * a / r ** 2) - s / 2 * (1 + 3 * a ** 4 / r ** 4) * math.cos(2 * th)


def kirsch_rr_90(r, s=S, a=A_HOLE):  # sigma_yy on x = 0 (radial stress at theta = 90 deg)
    return 1.5 * s * (a * a / r ** 2 - a ** 4 / r ** 4)


# ----------------------------------------------------------------------------
# Richardson
# ----------------------------------------------------------------------------
def richardson(vals):
    """vals on meshes n, 2n, 4n, ...; returns list of (order, extrapolated) per triplet."""
    out = []
    for f1, f2, f3 in zip(vals, vals[1:], vals[2:]):  # -> (order, value, error estimate)
        d1, d2 = f1 - f2, f2 - f3
        if abs(d2) < 1e-13 * max(1.0, abs(f3)) or d1 / d2 <= 0:
            out.append((float("nan"), f3, abs(d2)))
            continue
        p = math.log2(d1 / d2)
        if 1.0 <= p <= 5.0:
            ext = f3 + (f3 - f2) / (2 ** p - 1)
            out.append((p, ext, abs(ext - f3)))
        else:  # not in the asymptotic range: no extrapolation, error ~ last change
            out.append((p, f3, abs(d2)))
    return out


def fmt(v):
    return f"{v:.8g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.6e}"


def print_table(title, ns, rows, exact=None):
    """rows: list of (name, values over ns, reference or None)."""
    print(f"\n{title}")
    hdr = f"{'quantity':<22}" + "".join(f"{str(n):>15}" for n in ns) + f"{'orders':>18}{'extrapolated':>16}{'est.err':>11}"
    if any(r[2] is not None for r in rows):
        hdr += f"{'reference':>14}"
    print(hdr)
    res = {}
    for name, vals, ref in rows:
        rr = richardson(vals)
        orders = " ".join("--" if math.isnan(p) else f"{p:.2f}" for p, _, _ in rr)
        ext, err = rr[-1][1], rr[-1][2]
        line = f"{name:<22}" + "".join(f"{fmt(v):>15}" for v in vals) + f"{orders:>18}{fmt(ext):>16}{err:>11.2e}"
        if ref is not None:
            line += f"{fmt(ref):>14}"
        print(line)
        res[name] = (ext, err, rr)
    return res


# ----------------------------------------------------------------------------
# Plate with hole: mesh families
# ----------------------------------------------------------------------------
# Family A (main): element boundaries along x = 0 (and, proportionally, along
# every ray) at y = Y_BREAKS, each interval split uniformly into 2^level, so
# that every table point on x = 0 is a node at every level; NC0 * 2^level
# uniform elements along each 45-degree arc (NC0 = 12, a multiple of 3 so that
# theta = 60 and 75 degrees are nodes).  Family B (cross-check): n = 8 * 2^level
# elements in both directions, smooth geometric grading g(k/n) (see above).
Y_BREAKS = [1.0, 1.05, 1.1, 1.25, 1.5, 2.0, 3.2, 5.5, 10.0]
NC0 = 12
Y_TABLE = (1.05, 1.1, 1.25, 1.5, 2.0)
TH_TABLE = (90, 75, 60, 45)


def family(name, level):
    if name == "A":
        k = 2 ** level
        sb = [(y - A_HOLE) / (W - A_HOLE) for y in Y_BREAKS]
        qb = np.concatenate([np.linspace(s0, s1, k + 1)[:-1] for s0, s1 in zip(sb, sb[1:])] + [[1.0]])
        return np.arange(NC0 * k + 1) / (NC0 * k), qb
    n = 8 * 2 ** level
    return np.arange(n + 1) / n, graded(n)


def plate_blocks(pb, qb, L=W):
    b1 = Block(ray_map(arc(A_HOLE, 0.0, math.pi / 4), line((W, 0.0), (W, W))), pb, qb)
    b2 = Block(ray_map(arc(A_HOLE, math.pi / 4, math.pi / 2), line((W, W), (0.0, W))), pb, qb)
    blocks = [b1, b2]
    if L > W:
        # extension W <= x <= L: p along y (matches block 1's p grid on x = W),
        # q along x, m elements growing geometrically away from x = W
        m = max(2, round((L - W) / (8 * W) * (len(pb) - 1)))
        blocks.append(Block(ray_map(line((W, 0.0), (W, W)), line((L, 0.0), (L, W))), pb, graded(m, 2.0)))
    return blocks


def solve_plate(fam, level, geom="exact", L=W, kirsch=False):
    m = Mesh(plate_blocks(*family(fam, level), L=L), geom)
    f = np.zeros(m.ndof)
    right = (2, "q1") if L > W else (0, "q1")
    if kirsch:
        m.edge_load(f, *right, lambda x, y: (kirsch_stress(x, y)[0], kirsch_stress(x, y)[2]))
        m.edge_load(f, 1, "q1", lambda x, y: (kirsch_stress(x, y)[2], kirsch_stress(x, y)[1]))
    else:
        m.edge_load(f, *right, lambda x, y: (np.full_like(x, S), np.zeros_like(x)))
    fx = np.where(np.abs(m.X[:, 0]) < 1e-9)[0]
    fy = np.where(np.abs(m.X[:, 1]) < 1e-9)[0]
    u, R = m.solve(f, np.concatenate([2 * fx, 2 * fy + 1]))
    return m, u, R, fx


def plate_outputs(m, u, R, fx):
    """Point values; at a node shared by several elements the element values
    are averaged and the largest deviation from the mean is kept ('jump')."""
    out, jumps = {}, {}
    sig = m.stress_all(u, 1, 1.0, 0.0)  # (0, 1): corner of a single element
    assert len(sig) == 1
    out["sxx(0,1)=hoop"], out["syy(0,1) (->0)"], out["sxy(0,1) (->0)"] = sig[0]
    for deg in TH_TABLE:
        th = math.radians(deg)
        sl = m.stress_all(u, 1, (deg - 45) / 45.0, 0.0)
        if deg == 45:
            sl += m.stress_all(u, 0, 1.0, 0.0)
        h = [hoop(s_, th) for s_ in sl]
        out[f"hoop r=1 t={deg}"] = float(np.mean(h))
        jumps[f"hoop t={deg}"] = max(abs(v - np.mean(h)) for v in h)
    for yv in Y_TABLE:
        sl = np.array(m.stress_all(u, 1, 1.0, (yv - A_HOLE) / (W - A_HOLE)))
        out[f"sxx(0,{yv})"], out[f"syy(0,{yv})"] = sl[:, 0].mean(), sl[:, 1].mean()
        jumps[f"sxx y={yv}"] = np.abs(sl[:, 0] - sl[:, 0].mean()).max()
    for name, (x, y), c in (("uy(0,1)", (0, 1), 1), ("ux(1,0)", (1, 0), 0), ("ux(10,10)", (W, W), 0),
                            ("uy(10,10)", (W, W), 1), ("ux(10,0)", (W, 0), 0)):
        out[name] = u[2 * m.node_at(x, y) + c]
    out["max nodal jump"] = max(jumps.values())
    out["sum Rx on x=0"] = R[2 * fx].sum()
    return out


def kirsch_refs():
    refs = {"sxx(0,1)=hoop": 3 * S, "syy(0,1) (->0)": 0.0, "sxy(0,1) (->0)": 0.0}
    for deg in TH_TABLE:
        refs[f"hoop r=1 t={deg}"] = kirsch_tt(1.0, math.radians(deg))
    for yv in Y_TABLE:
        refs[f"sxx(0,{yv})"] = kirsch_tt(yv, math.pi / 2)
        refs[f"syy(0,{yv})"] = kirsch_rr_90(yv)
    return refs


def error_table(title, levels, rows):
    print(f"\n{title}")
    print(f"{'quantity':<18}{'exact':>14}" + "".join(f"{'err L' + str(l):>12}" for l in levels) + "   orders")
    for k, vals, ref in rows:
        errs = [v - ref for v in vals]
        ords = [math.log2(abs(e1 / e2)) if e2 != 0 else float("nan") for e1, e2 in zip(errs, errs[1:])]
        print(f"{k:<18}{fmt(ref):>14}" + "".join(f"{e:>12.2e}" for e in errs) + "   "
              + " ".join(f"{o:.2f}" for o in ords))


def lame_check():
    p_in, a, b = 1000.0, 1.0, 2.0
    Ac, Bc = p_in * a * a / (b * b - a * a), p_in * a * a * b * b / (b * b - a * a)
    refs = {"u_r(1)": (1 + NU) / E * ((1 - 2 * NU) * Ac * a + Bc / a),
            "u_r(2)": (1 + NU) / E * ((1 - 2 * NU) * Ac * b + Bc / b),
            "s_tt(1,45deg)": Ac + Bc / a ** 2, "s_rr(1,45deg)": Ac - Bc / a ** 2,
            "s_tt(2,0deg)": Ac + Bc / b ** 2}
    ns = [2, 4, 8, 16, 32]
    for geom in ("exact", "iso"):
        rows = {k: [] for k in refs}
        for n in ns:
            pb = np.arange(n + 1) / n
            m = Mesh([Block(ray_map(arc(a, 0, math.pi / 2), arc(b, 0, math.pi / 2)), pb, pb)], geom)
            f = np.zeros(m.ndof)
            m.edge_load(f, 0, "q0", lambda x, y: (p_in * x / np.hypot(x, y), p_in * y / np.hypot(x, y)))
            fx = np.where(np.abs(m.X[:, 0]) < 1e-9)[0]
            fy = np.where(np.abs(m.X[:, 1]) < 1e-9)[0]
            u, R = m.solve(f, np.concatenate([2 * fx, 2 * fy + 1]))
            rows["u_r(1)"].append(u[2 * m.node_at(a, 0)])
            rows["u_r(2)"].append(u[2 * m.node_at(b, 0)])
            th = math.pi / 4
            sg = np.mean(m.stress_all(u, 0, 0.5, 0.0), axis=0)
            c, s = math.cos(th), math.sin(th)
            rows["s_tt(1,45deg)"].append(hoop(sg, th))
            rows["s_rr(1,45deg)"].append(sg[0] * c * c + sg[1] * s * s + 2 * sg[2] * s * c)
            rows["s_tt(2,0deg)"].append(m.stress_all(u, 0, 0.0, 1.0)[0][1])
        error_table(f"LAME CHECK ({geom} geometry): annulus 1<=r<=2, p = {p_in}, quarter, n x n uniform Q9, "
                    f"level L = n = {ns}", ns, [(k, v, refs[k]) for k, v in rows.items()])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, default=4, help="number of refinement levels (4: 0..3)")
    ap.add_argument("--no-checks", action="store_true")
    args = ap.parse_args()
    t0 = time.time()
    levels = list(range(args.levels))
    refs = kirsch_refs()

    if not args.no_checks:
        lame_check()
        outs = [plate_outputs(*solve_plate("A", l, kirsch=True)) for l in levels]
        kd = {"uy(0,1)": kirsch_disp(0, 1)[1], "ux(1,0)": kirsch_disp(1, 0)[0],
              "ux(10,10)": kirsch_disp(W, W)[0], "uy(10,10)": kirsch_disp(W, W)[1], "ux(10,0)": kirsch_disp(W, 0)[0]}
        rows = [(k, [o[k] for o in outs], {**refs, **kd}[k]) for k in list(refs) + list(kd)]
        error_table("KIRSCH CHECK: mesh family A, exact Kirsch tractions on x = 10 and y = 10 (FE must -> Kirsch)",
                    levels, rows)
        print(f"  [{time.time() - t0:.1f} s]")

    # ---------------- main problem ----------------
    res = {}
    for fam, geom in (("A", "exact"), ("A", "iso"), ("B", "exact")):
        outs = []
        for l in levels:
            m, u, R, fx = solve_plate(fam, l, geom)
            outs.append(plate_outputs(m, u, R, fx))
            if fam == "A" and geom == "exact":
                print(f"  family A level {l}: {len(m.conn)} Q9 elements ({m.blocks[0].pb.size - 1} arc x "
                      f"{m.blocks[0].qb.size - 1} radial per block), {m.ndof} dofs, "
                      f"sum Rx(x=0) = {outs[-1]['sum Rx on x=0']:.10f} N  [{time.time() - t0:.1f} s]")
        res[(fam, geom)] = outs
        print(f"  family {fam}, {geom} geometry done [{time.time() - t0:.1f} s]")
    outs = res[("A", "exact")]
    keys = [k for k in outs[0] if k not in ("sum Rx on x=0", "max nodal jump")]
    main_res = print_table("PLATE WITH HOLE, family A, exact geometry; 'reference' = Kirsch infinite plate",
                           [f"L{l}" for l in levels], [(k, [o[k] for o in outs], refs.get(k)) for k in keys])
    print("  largest jump between element values at shared table nodes (hoop 45/60/75, sxx on x=0), per level: "
          + ", ".join(f"{o['max nodal jump']:.3g}" for o in outs) + " Pa")
    ck = ["sxx(0,1)=hoop", "hoop r=1 t=75", "hoop r=1 t=45", "sxx(0,1.5)", "uy(0,1)", "ux(1,0)", "ux(10,10)",
          "uy(10,10)", "ux(10,0)"]
    for fam, geom, what in (("A", "iso", "isoparametric Q9 (hole = parabolas through arc nodes), family A"),
                            ("B", "exact", "family B (n x n per block, n = 8*2^L, smooth geometric grading; "
                                           "table points not nodes)")):
        o2 = res[(fam, geom)]
        r2 = print_table(f"Cross-check: {what}", [f"L{l}" for l in levels], [(k, [o[k] for o in o2], None) for k in ck])
        print("  extrapolated difference from the main result: " + ", ".join(
            f"{k}: {r2[k][0] - main_res[k][0]:.2e}" for k in ck))

    K, dK = main_res["sxx(0,1)=hoop"][0] / S, main_res["sxx(0,1)=hoop"][1] / S
    r = 0.1
    ktn_p = 3.00 - 3.13 * r + 3.66 * r ** 2 - 1.53 * r ** 3
    ktn_h = 2 + (1 - r) ** 3

    # ---------------- finite length ----------------
    def k_of(fam, l, L):
        m, u, R, fx = solve_plate(fam, l, L=L)
        return m.stress_all(u, 1, 1.0, 0.0)[0][0] / S

    ks = [k_of("A", l, 40.0) for l in levels]
    rs = print_table("LONG STRIP (quarter 0<=x<=40, 0<=y<=10; full 80 x 20): K = sigma_xx(0,1)/s",
                     [f"L{l}" for l in levels], [("K strip", ks, None)])
    Ks, dKs = rs["K strip"][0], rs["K strip"][1]
    kl = {10.0: outs[-1]["sxx(0,1)=hoop"] / S, 40.0: ks[-1]}
    for Lq in (20.0, 80.0):
        kl[Lq] = k_of("A", levels[-1], Lq)
    print(f"  level-{levels[-1]} K for quarter length L = " + ", ".join(f"{Lq:g}: {kl[Lq]:.6f}" for Lq in sorted(kl)))

    print(f"\nSTRESS CONCENTRATION (gross, s = 1000): 20 x 20 plate K = {K:.5f} +- {dK:.1e};"
          f" long strip K = {Ks:.5f} +- {dKs:.1e}; plate - strip = {K - Ks:+.4f} ({(K - Ks) / Ks * 100:+.2f} %)")
    print(f"  net (x (1-d/D)): plate K_tn = {K * (1 - r):.5f}, strip K_tn = {Ks * (1 - r):.5f}")
    for name, ktn in (("Peterson/Howland", ktn_p), ("Heywood", ktn_h)):
        ktg = ktn / (1 - r)
        print(f"  {name:<17} K_tn = {ktn:.5f}, K_tg = {ktg:.5f}: plate/formula - 1 = {(K / ktg - 1) * 100:+.2f} %,"
              f" strip/formula - 1 = {(Ks / ktg - 1) * 100:+.2f} %")
    print(f"\ntotal time {time.time() - t0:.1f} s")


if __name__ == "__main__":
    main()
