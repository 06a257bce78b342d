#!/usr/bin/env python3
"""The 3D elastic cantilever under self-weight by finite elements, as the
reference of `crates/mpm/tests/verification/cantilever3d.rs`.

A 10 m x 2 m x 2 m beam (x along its length, z up), E = 1e8 Pa, nu = 0.3,
rho = 1 kg/m3, g = 10 m/s2 in -z, clamped at x = 0 (every displacement
zero on that face). Small-strain linear elasticity: the deflection is
3.8e-5 of the length, so the finite-strain Hencky model mpm solves
differs from it by about that fraction (its strains are of order 1e-5).

Triquadratic hexahedra (scikit-fem's ElementHex2, 27 nodes, 4th-order
Gauss rule) on n x n/5 x n/5 meshes, n = 10, 20, 40 (70,227 DOFs on the
finest; SuperLU runs out of memory at 80); the two
functionals, each a volume mean of the vertical displacement u_z:

- over the whole beam (the work of gravity over rho g V: the compliance);
- over its last fifth, 8 m < x < 10 m.

They converge as h^p; the script prints p from the last three meshes and
the Richardson extrapolation from the last two. Needs numpy, scipy and
scikit-fem (`pip install scikit-fem`).
"""

import numpy as np
from skfem import Basis, ElementHex2, ElementVector, Functional, LinearForm, MeshHex, asm, condense, solve
from skfem.models.elasticity import lame_parameters, linear_elasticity

L, W, H = 10.0, 2.0, 2.0
E, NU, RHO, G = 1.0e8, 0.3, 1.0, 10.0


def solve_beam(n):
    """(mean u_z over the beam, mean u_z over x > 8 m) on an n x n/5 x n/5 mesh."""
    m = MeshHex.init_tensor(np.linspace(0, L, n + 1), np.linspace(0, W, n // 5 + 1), np.linspace(0, H, n // 5 + 1))
    basis = Basis(m, ElementVector(ElementHex2()), intorder=4)
    stiffness = asm(linear_elasticity(*lame_parameters(E, NU)), basis)

    @LinearForm
    def weight(v, w):
        return -RHO * G * v[2]

    load = asm(weight, basis)
    clamped = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
    u = solve(*condense(stiffness, load, D=clamped))
    uh = basis.interpolate(u)

    @Functional
    def uz(w):
        return w["u"][2]

    @Functional
    def uz_tip(w):
        return w["u"][2] * (w.x[0] > 8.0)

    whole = uz.assemble(basis, u=uh) / (L * W * H)
    tip = uz_tip.assemble(basis, u=uh) / (2.0 * W * H)
    return whole, tip


def main():
    sizes = [10, 20, 40]
    values = []
    for n in sizes:
        whole, tip = solve_beam(n)
        values.append((whole, tip))
        print(f"n = {n:3d} (h = {L / n:.4f} m): mean u_z {whole:.10e} m, mean u_z over x > 8 m {tip:.10e} m", flush=True)
    for k, name in enumerate(["mean u_z", "mean u_z over x > 8 m"]):
        a, b, c = (v[k] for v in values[-3:])
        p = np.log(abs((a - b) / (b - c))) / np.log(2.0)
        extrapolated = c + (c - b) / (2.0**p - 1.0)
        print(f"{name}: order {p:.2f}, Richardson {extrapolated:.10e} m (last mesh off by {abs(c / extrapolated - 1):.1e})")


if __name__ == "__main__":
    main()
