"""The thick sphere under internal follower pressure at finite strain: the
1D radial reference for crates/mpm/tests/verification/sphere3d.rs.

A hollow sphere (radii a < b in the reference configuration) of the
solver's Hencky material (Kirchhoff stress tau = lambda tr(e) I + 2 mu e,
e the logarithmic strain, Cauchy sigma = tau / J) under a pressure p on its
current inner surface, free outside. With r = phi(R), the principal
stretches are lambda_r = phi'(R) and lambda_t = phi / R; equilibrium in the
current configuration, d sigma_r / dr + 2 (sigma_r - sigma_t) / r = 0,
becomes in R

    d sigma_r / dR = -2 lambda_r (sigma_r - sigma_t) / phi,

an ODE for (phi, lambda_r): lambda_t' = (lambda_r - lambda_t) / R, and
lambda_r' from the chain rule through sigma_r(lambda_r, lambda_t). It is
shot from R = a, where sigma_r = -p fixes lambda_r for a trial phi(a), to
R = b, and phi(a) found so that sigma_r(b) = 0 (Brent). The integrator
(scipy's DOP853 at rtol 1e-12) and the root (xtol 1e-14) are far tighter
than the comparisons need; halving the tolerances changes no printed digit.

Prints u(a), u(b) and sigma_r, sigma_t at sample radii; with --small, the
same against Lame's solution at a small pressure (a check of the script).

    python3 scripts/sphere_radial.py [--p P] [--E E] [--nu NU] [--a A] [--b B]
"""
import argparse
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


def stresses(lr, lt, lam, mu):
    """Cauchy (sigma_r, sigma_t) of the Hencky material at stretches lr, lt."""
    er, et = math.log(lr), math.log(lt)
    tr = er + 2 * et
    j = lr * lt * lt
    return (lam * tr + 2 * mu * er) / j, (lam * tr + 2 * mu * et) / j


def solve(p, E, nu, a, b):
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))

    def d_sr(lr, lt, h=1e-7):
        return [
            (stresses(lr * (1 + h), lt, lam, mu)[0] - stresses(lr * (1 - h), lt, lam, mu)[0]) / (2 * h * lr),
            (stresses(lr, lt * (1 + h), lam, mu)[0] - stresses(lr, lt * (1 - h), lam, mu)[0]) / (2 * h * lt),
        ]

    def rhs(R, y):
        phi, lr = y
        lt = phi / R
        sr, st = stresses(lr, lt, lam, mu)
        dr, dt = d_sr(lr, lt)
        target = -2 * lr * (sr - st) / phi
        dlt = (lr - lt) / R
        return [lr, (target - dt * dlt) / dr]

    def radial_stretch_at_a(phi_a):
        lt = phi_a / a
        return brentq(lambda lr: stresses(lr, lt, lam, mu)[0] + p, 1e-3, 10.0, xtol=1e-15)

    def shoot(phi_a, dense=False):
        y0 = [phi_a, radial_stretch_at_a(phi_a)]
        sol = solve_ivp(rhs, (a, b), y0, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=dense)
        return sol

    def miss(phi_a):
        y = shoot(phi_a).y[:, -1]
        return stresses(y[1], y[0] / b, lam, mu)[0]

    phi_a = brentq(miss, a * 0.9, a * 1.6, xtol=1e-14)
    sol = shoot(phi_a, dense=True)
    return sol, lam, mu


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--p", type=float, default=1e5)
    ap.add_argument("--E", type=float, default=1e6)
    ap.add_argument("--nu", type=float, default=0.3)
    ap.add_argument("--a", type=float, default=0.5)
    ap.add_argument("--b", type=float, default=1.0)
    ap.add_argument("--small", action="store_true")
    args = ap.parse_args()
    p = 1e-3 * args.E if args.small else args.p
    sol, lam, mu = solve(p, args.E, args.nu, args.a, args.b)
    a, b = args.a, args.b
    phi = lambda R: sol.sol(R)[0]
    print(f"p = {p:g}, E = {args.E:g}, nu = {args.nu}, a = {a}, b = {b}")
    print(f"u(a) = {phi(a) - a:.10e}")
    print(f"u(b) = {phi(b) - b:.10e}")
    for R in np.linspace(a, b, 11):
        lr = sol.sol(R)[1]
        sr, st = stresses(lr, phi(R) / R, lam, mu)
        print(f"R = {R:.3f}: u = {phi(R) - R:.8e}, sigma_r = {sr:.6e}, sigma_t = {st:.6e}")
    if args.small:
        nu, E = args.nu, args.E
        u = lambda r: p * a**3 * r / (E * (b**3 - a**3)) * ((1 - 2 * nu) + (1 + nu) * b**3 / (2 * r**3))
        print(f"Lame: u(a) = {u(a):.10e}, u(b) = {u(b):.10e}")


if __name__ == "__main__":
    main()
