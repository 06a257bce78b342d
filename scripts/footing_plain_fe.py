#!/usr/bin/env python3
"""A plain finite-element footing on the grids mpm uses: what a textbook
displacement discretisation gives for the bearing factors at the same cell
sizes, outside mpm's code.

Problem (small strain, plane strain, rigid strip footing, half model)
--------------------------------------------------------------------
* Soil [0, W] x [0, H] (default 5 m x 3 m, as `mpm example footing`), the
  footing's half-width b = 0.5 m (B = 1 m) on the top surface y = H from the
  axis x = 0.
* Rollers on x = 0 and x = W, the base fixed.
* The footing pushed down by a prescribed displacement of the top nodes with
  x <= b, in equal steps; `--rough` also holds them horizontally.
* Soil: Drucker-Prager matched to Mohr-Coulomb in plane strain,
  alpha = tan(phi) / sqrt(9 + 12 tan^2 phi), k = 3 c / sqrt(9 + 12 tan^2 phi),
  in `sqrt(J2) + alpha I1 <= k`, associated. With associated flow this cone
  has the same plane-strain collapse loads as Mohr-Coulomb (Chen 1975, Limit
  analysis and soil plasticity, section 2.8); with phi = 0 it is von Mises
  with k = c.
* Self-weight gamma with a geostatic start (sigma_v = -gamma (H - y),
  sigma_h = K0 sigma_v), or weightless with `--gamma 0`.

Method
------
* Bilinear quadrilaterals (Q4) of side h, the footing's edge and the surface
  on element boundaries; 2x2 Gauss points; `--bbar` (default) replaces each
  Gauss point's volumetric strain by its element's mean (Hughes 1980).
* The return map is the cone's closed form (and the apex); Newton's tangent
  is its finite difference (four extra returns a Gauss point), plus 1e-6 of
  the elastic moduli so that points at a cohesionless apex leave no null
  rows; the residual is the exact one, so the answer does not depend on it.
* Output: the footing's mean pressure at every step, as 2 q / (gamma B)
  (N_gamma) or q / c (weightless).

Usage
-----
    python3 scripts/footing_plain_fe.py --h 0.0625 --phi 30 --smooth
    python3 scripts/footing_plain_fe.py --h 0.0625 --phi 0 --c 1e4 --gamma 0 \
        --nu 0.49 --E 1e8 --push 0.004 --steps 80 --rough

Measured (docs/guide.md, "The bearing factors against a plain finite-element
mesh"): the rows of that table, each under a minute at h = B/16.
"""

import argparse
import math
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def run(h, rough, bbar, E, nu, phi, c, gamma, k0, W, H, b, push, steps, tol, maxit):
    nx, ny = round(W / h), round(H / h)
    X = np.array([[i * h, j * h] for j in range(ny + 1) for i in range(nx + 1)])

    def nid(i, j):
        return j * (nx + 1) + i

    conn = np.array([[nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1)]
                     for j in range(ny) for i in range(nx)])
    ne, ndof = len(conn), 2 * len(X)
    g = 1 / math.sqrt(3)
    gauss = [(-g, -g), (g, -g), (g, g), (-g, g)]
    # Strain rows xx, yy, zz, xy (engineering); the elements are equal squares.
    Bs = []
    for xi, eta in gauss:
        dN = 0.25 * np.array([[-(1 - eta), 1 - eta, 1 + eta, -(1 + eta)],
                              [-(1 - xi), -(1 + xi), 1 + xi, 1 - xi]]) * (2 / h)
        B = np.zeros((4, 8))
        B[0, 0::2], B[1, 1::2] = dN[0], dN[1]
        B[3, 0::2], B[3, 1::2] = dN[1], dN[0]
        Bs.append(B)
    Bs = np.array(Bs)
    if bbar:
        m = np.array([1.0, 1.0, 1.0, 0.0])
        div = Bs[:, 0, :] + Bs[:, 1, :]
        mean = div.mean(axis=0)
        Bs = np.array([B - np.outer(m, div[q] - mean) / 3 for q, B in enumerate(Bs)])
    w = h * h / 4
    K, G = E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu))
    lam = K - 2 * G / 3
    D = np.zeros((4, 4))
    D[:3, :3] = lam
    D[0, 0] = D[1, 1] = D[2, 2] = lam + 2 * G
    D[3, 3] = G
    t = math.tan(math.radians(phi))
    alpha, k = t / math.sqrt(9 + 12 * t * t), 3 * c / math.sqrt(9 + 12 * t * t)

    def returned(s):
        p = s[..., :3].sum(axis=-1) / 3
        dev = s.copy()
        dev[..., :3] -= p[..., None]
        sq = np.sqrt(0.5 * (dev[..., :3] ** 2).sum(axis=-1) + dev[..., 3] ** 2)
        f = sq + 3 * alpha * p - k
        dg = np.where(f > 0, f / (G + 9 * K * alpha * alpha), 0.0)
        cone = (f > 0) & (sq - G * dg > 0)
        apex = (f > 0) & ~cone
        scale = np.where(cone, (sq - G * dg) / np.where(sq > 0, sq, 1.0), 1.0)
        out = dev * scale[..., None]
        out[..., :3] += np.where(cone, p - 3 * K * alpha * dg, p)[..., None]
        if alpha > 0:
            out[apex] = 0.0
            out[apex, :3] = k / (3 * alpha)
        return out

    depth = np.array([[H - (X[conn[e]].mean(axis=0)[1] + h / 2 * gauss[q][1]) for q in range(4)]
                      for e in range(ne)])
    sig = np.zeros((ne, 4, 4))
    sig[..., 1] = -gamma * depth
    sig[..., 0] = sig[..., 2] = k0 * sig[..., 1]
    edofs = np.zeros((ne, 8), dtype=int)
    edofs[:, 0::2], edofs[:, 1::2] = 2 * conn, 2 * conn + 1
    fext = np.zeros(ndof)
    np.add.at(fext, 2 * conn + 1, -gamma * w)
    footing = [nid(i, ny) for i in range(nx + 1) if i * h <= b + 1e-9]
    held = {}
    for j in range(ny + 1):
        held[2 * nid(0, j)] = held[2 * nid(nx, j)] = 0.0
    for i in range(nx + 1):
        held[2 * nid(i, 0)] = held[2 * nid(i, 0) + 1] = 0.0
    u = np.zeros(ndof)
    rows, cols = np.repeat(edofs, 8, axis=1).ravel(), np.tile(edofs, (1, 8)).ravel()
    scale = gamma * H if gamma > 0 else c
    eps = 1e-7 * max(1.0, scale) / E
    force_scale = gamma * W * H if gamma > 0 else c * W

    def stresses(du):
        trial = sig + np.einsum('qij,ej->eqi', Bs, du[edofs]) @ D.T
        return returned(trial), trial

    def internal(s):
        f = np.zeros(ndof)
        np.add.at(f, edofs, np.einsum('qij,eqi->ej', Bs, s) * w)
        return f

    curve = []
    for step in range(1, steps + 1):
        fixed = dict(held)
        for n in footing:
            fixed[2 * n + 1] = -push * step / steps
            if rough:
                fixed[2 * n] = 0.0
        dofs = np.array(sorted(fixed))
        free = np.setdiff1d(np.arange(ndof), dofs)
        du = np.zeros(ndof)
        du[dofs] = np.array([fixed[d] for d in dofs]) - u[dofs]
        for _ in range(maxit):
            s, trial = stresses(du)
            r = fext - internal(s)
            if np.linalg.norm(r[free]) / force_scale < tol:
                break
            tangent = np.zeros((ne, 4, 4, 4))
            for a in range(4):
                tangent[..., :, a] = (returned(trial + eps * D[:, a]) - s) / eps
            tangent += 1e-6 * D
            ke = np.einsum('qia,eqij,qjb->eab', Bs, tangent, Bs) * w
            Km = sp.csr_matrix((ke.ravel(), (rows, cols)), shape=(ndof, ndof))
            du[free] += spla.spsolve(Km[free][:, free].tocsc(), r[free])
        else:
            print(f'step {step}: Newton did not converge')
            break
        u += du
        sig[:] = s
        force = -(internal(s) - fext)[[2 * n + 1 for n in footing]].sum()
        q = force / b
        curve.append((push * step / steps / (2 * b), 2 * q / (gamma * 2 * b) if gamma > 0 else q / c))
    return curve


def main():
    a = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    a.add_argument('--h', type=float, default=0.125)
    rough = a.add_mutually_exclusive_group()
    rough.add_argument('--rough', dest='rough', action='store_true', default=True)
    rough.add_argument('--smooth', dest='rough', action='store_false')
    a.add_argument('--full', dest='bbar', action='store_false', help='no B-bar')
    a.add_argument('--E', type=float, default=1e9)
    a.add_argument('--nu', type=float, default=0.3)
    a.add_argument('--phi', type=float, default=30.0)
    a.add_argument('--c', type=float, default=0.0)
    a.add_argument('--gamma', type=float, default=20e3)
    a.add_argument('--k0', type=float, default=0.5)
    a.add_argument('--push', type=float, default=0.005, help='m')
    a.add_argument('--steps', type=int, default=20)
    a.add_argument('--tol', type=float, default=1e-9)
    a.add_argument('--maxit', type=int, default=100)
    v = a.parse_args()
    start = time.time()
    curve = run(v.h, v.rough, v.bbar, v.E, v.nu, v.phi, v.c, v.gamma, v.k0, 5.0, 3.0, 0.5,
                v.push, v.steps, v.tol, v.maxit)
    for settlement, factor in curve:
        print(f'{settlement:.5f} B  {factor:.3f}')
    print(f'{time.time() - start:.0f} s')


if __name__ == '__main__':
    main()
