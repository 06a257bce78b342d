#!/usr/bin/env python3
"""Tip displacements of the elastica: a clamped Euler-Bernoulli beam under a
dead vertical end load P, for k = P L^2 / EI.

The tabulated values (Mattiasson 1981, "Numerical results from large
deflection beam and frame problems analysed by means of elliptic
integrals", IJNME 17, Table 1) come from elliptic integrals; this script
recomputes them independently by shooting on the beam's equilibrium

    theta''(s) = -k cos(theta(s)),  theta(0) = 0,  theta'(1) = 0,

over the arc length s in [0, 1] (lengths in units of L), with the tip at
x(1) = int cos(theta), y(1) = int sin(theta). Printed: k, the horizontal
shortening u/L = 1 - x(1) and the deflection v/L = y(1), to 5 digits,
which agree with Mattiasson's table for k = 1, 2, 5, 10 (e.g. 0.55500 and
0.81061 at k = 10).

    python3 scripts/elastica_reference.py [k ...]
"""

import sys

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


def tip(k):
    """(u/L, v/L) of the clamped elastica with end load k = P L^2 / EI."""

    def end(m):
        rhs = lambda s, y: [y[1], -k * np.cos(y[0]), np.cos(y[0]), np.sin(y[0])]
        # theta, theta', x, y; theta grows downwards (the load's direction).
        sol = solve_ivp(rhs, [0.0, 1.0], [0.0, m, 0.0, 0.0], rtol=1e-12, atol=1e-13)
        return sol.y[:, -1]

    # theta'(0) = m, the root curvature, is found where theta'(1) = 0; the
    # first sign change from small m is the stable (first-mode) solution.
    moments = np.linspace(1e-3, 1.5 * k + 1.0, 400)
    ends = [end(m)[1] for m in moments]
    for a, b, fa, fb in zip(moments, moments[1:], ends, ends[1:]):
        if fa * fb < 0.0:
            m = brentq(lambda m: end(m)[1], a, b, xtol=1e-14)
            y = end(m)
            return 1.0 - y[2], y[3]
    raise ValueError(f"no root curvature found for k = {k}")


if __name__ == "__main__":
    for k in [float(a) for a in sys.argv[1:]] or [1.0, 2.0, 5.0, 10.0]:
        u, v = tip(k)
        print(f"k = {k:g}: u/L = {u:.5f}, v/L = {v:.5f}")
