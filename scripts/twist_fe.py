#!/usr/bin/env python3
"""The twisted square Hencky bar by finite elements, as the reference torque
of the material point method's twisting test.

Problem (SI units)
------------------
* Bar 0 <= x <= L = 10 m, 0 <= y, z <= a = 1 m; no body force; the four
  lateral faces traction free.
* Hencky hyperelasticity: E = 1e6 Pa, nu = 0.3, Kirchhoff stress
  tau = lambda tr(eps) I + 2 mu eps with eps = ln(b) / 2, b = F F^T, and
  first Piola-Kirchhoff stress P = tau F^-T.
* Every displacement component prescribed on both end faces: zero at x = 0;
  at x = L the face turned rigidly by theta about the x-axis through
  (y, z) = (0.5, 0.5), with u_x = 0 (so the ends can neither warp nor move
  axially).
* theta from 0 to 90 degrees in 10 equal steps of 9 degrees.

Method
------
* Triquadratic hexahedra (scikit-fem's ElementHex2, 27 nodes, 27-point
  Gauss rule, intorder 4) on cubic n x n x 10n meshes, n = 1, 2, 4, 8
  (139,587 DOFs on the finest); `python3 twist_fe.py 1 2 4` runs only some.
* Total Lagrangian Newton. Each step starts from the previous step's
  solution with the new end rotation imposed: every cross-section of the
  deformed bar is turned about the axis by the step's 9 degrees times x / L
  (so the end x = L gets exactly the new rotation, x = 0 none, and the
  Newton corrections vanish on both ends). Converged when the out-of-balance
  force on the free DOFs is below 1e-10 of the reaction forces on the
  prescribed ones (Euclidean norms); the script prints that ratio before
  every correction, so that the quadratic convergence shows.
* H = grad u, P and the tangent dP/dF are numpy arrays over all quadrature
  points. ln(b) is log1p of the eigenvalues (numpy's eigh) of
  b - I = H + H^T + H H^T, so that tiny strains keep their digits; dP/dF is
  the central difference of P over the 9 components of F (step 1e-6),
  symmetrised (the exact one is, the material being hyperelastic). The
  internal force int P : grad v is a scikit-fem LinearForm reading P through
  its `w` argument; the tangent matrix int grad v : dP/dF : grad du is
  assembled element by element with numpy (a scikit-fem BilinearForm reading
  dP/dF gives the same matrix about 30 times slower). `check` compares the
  two on the n = 1 mesh, compares the tangent at F = I with scikit-fem's
  linear elasticity, compares K du with a central difference of the internal
  force at a random state, and compares T / theta at theta = 1e-6 rad with
  the linear problem's.
* Linear systems: a sparse LU (SuperLU) of the tangent at the first Newton
  iteration of each step; the later iterations solve with the current
  tangent by conjugate gradients preconditioned by that LU, to a relative
  tolerance of 1e-4 times the Newton residual ratio (which keeps Newton
  quadratic).
* The small-strain linear problem with u_y = -theta (z - 0.5),
  u_z = theta (y - 0.5) at x = L is solved on the same meshes.

Printed
-------
* Per load step: the residual history and the torque about the x-axis at
  x = L, T = sum over its DOFs of (y + u_y - 0.5) R_z - (z + u_z - 0.5) R_y
  with R the internal force vector there (the reaction; the moment in the
  deformed configuration); the same at x = 0 (should be -T); T / theta;
  the axial reaction at x = L (sum of R_x there).
* Per mesh: the linear T / theta and the wall time.
* Then, for T at 90 degrees, T / theta at 9 degrees and the linear T / theta:
  the order p from the last three meshes and the Richardson extrapolation
  from the last two (with p, and with p = 2), and Saint-Venant's
  beta G a^4 / L, beta = 1/3 - (64 / pi^5) sum_{n odd} tanh(n pi / 2) / n^5
  (free warping, so below the clamped bar's value).

The ends
--------
The stiffness is Saint-Venant's interior plus the two clamped ends, which
converge differently: the interior as about h^3.7, the ends, where the
clamped faces meet the free ones, more slowly (order 1.6 to 2 on these
meshes), so that the order seen on the 10 m bar (about 3.4, the interior
dominating) overstates how fast it converges. `python3 twist_fe.py --ends
4 8 12` separates the two for the linear problem: with the ends far apart,
theta / T = (length - 2 delta) / GJ, and linear solutions on bars 2 m and
4 m long on the same meshes give the rigidity GJ (against Saint-Venant's
beta G a^4) and delta per mesh; it prints T / theta of the 10 m bar from
Saint-Venant's GJ and delta extrapolated (orders observed, 2 and 1).

Needs numpy, scipy and scikit-fem (`pip install scikit-fem`). On two cores
the default run takes about 12 minutes and 6 GB (n = 8: 11 minutes);
`--ends 4 8 12` takes about 6 minutes and 12 GB (n = 12, 4 m).
"""

import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import brentq
from skfem import Basis, BilinearForm, ElementHex2, ElementVector, LinearForm, MeshHex, asm
from skfem.models.elasticity import linear_elasticity

L, SIDE = 10.0, 1.0
E, NU = 1.0e6, 0.3
LAMBDA = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU))
MU = E / (2.0 * (1.0 + NU))
STEPS, FINAL_ANGLE = 10, np.pi / 2.0
TOLERANCE = 1.0e-10
MAX_NEWTON = 15
FD_STEP = 1.0e-6
CG_FORCING = 1.0e-4
CG_MAX = 200


# --- the material ----------------------------------------------------------


def hencky_piola(H):
    """First Piola-Kirchhoff stress of Hencky's model for the displacement
    gradient H = F - I, shape (..., 3, 3). ln(b) is log1p of the eigenvalues
    of b - I = H + H^T + H H^T, accurate however small the strain."""
    Ht = np.swapaxes(H, -1, -2)
    stretch2_minus_1, axes = np.linalg.eigh(H + Ht + H @ Ht)
    eps = (axes * (0.5 * np.log1p(stretch2_minus_1))[..., None, :]) @ np.swapaxes(axes, -1, -2)
    trace = np.trace(eps, axis1=-2, axis2=-1)
    tau = 2.0 * MU * eps + LAMBDA * trace[..., None, None] * np.eye(3)
    return tau @ np.swapaxes(np.linalg.inv(np.eye(3) + H), -1, -2)


def hencky_tangent(H):
    """dP_ij / dF_kl by central differences, shape (..., 3, 3, 3, 3), symmetrised."""
    A = np.zeros(H.shape[:-2] + (3, 3, 3, 3))
    for k in range(3):
        for l in range(3):
            dH = np.zeros((3, 3))
            dH[k, l] = FD_STEP
            A[..., k, l] = (hencky_piola(H + dH) - hencky_piola(H - dH)) / (2.0 * FD_STEP)
    return 0.5 * (A + np.einsum("...ijkl->...klij", A))


def linear_moduli():
    """The small-strain elasticity tensor C_ijkl, shape (3, 3, 3, 3)."""
    I = np.eye(3)
    return LAMBDA * np.einsum("ij,kl->ijkl", I, I) + MU * (np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I))


# --- the discretisation ----------------------------------------------------


@LinearForm
def internal_force_form(v, w):
    return np.einsum("ij...,ij...->...", w["P"], v.grad)


@BilinearForm
def tangent_form(du, v, w):
    return np.einsum("ijkl...,kl...,ij...->...", w["A"], du.grad, v.grad)


class Bar:
    """A bar of the given length (L unless told) meshed by cubes of side 1/n,
    with its basis and DOF sets."""

    def __init__(self, n, length=L):
        self.length = length
        along = round(length * n / SIDE)
        self.mesh = MeshHex.init_tensor(np.linspace(0.0, length, along + 1), np.linspace(0.0, SIDE, n + 1), np.linspace(0.0, SIDE, n + 1))
        self.basis = Basis(self.mesh, ElementVector(ElementHex2()), intorder=4)
        self.ndofs = self.basis.N
        # The components' DOFs, node by node in the same order.
        self.xdofs, self.ydofs, self.zdofs = self.basis.split_indices()
        self.nodes = self.basis.doflocs[:, self.xdofs]
        assert np.allclose(self.nodes, self.basis.doflocs[:, self.ydofs]) and np.allclose(self.nodes, self.basis.doflocs[:, self.zdofs])
        self.left = np.isclose(self.nodes[0], 0.0)
        self.right = np.isclose(self.nodes[0], length)
        ends = self.left | self.right
        self.fixed = np.sort(np.concatenate([self.xdofs[ends], self.ydofs[ends], self.zdofs[ends]]))
        self.free = np.setdiff1d(np.arange(self.ndofs), self.fixed)
        # Gradients of the 81 basis functions at the quadrature points,
        # G[q, e, 3 i + j, a] = d(phi_a)_i / dx_j, and the weights dx[q, e].
        nelems, npoints = self.basis.dx.shape
        grads = np.stack([phi[0].grad.reshape(9, nelems, npoints) for phi in self.basis.basis], axis=-1)
        self.G = np.ascontiguousarray(grads.transpose(2, 1, 0, 3))
        self.dx = np.ascontiguousarray(self.basis.dx.T)

    def end_displacement(self, theta):
        """Values of the prescribed DOFs (ordered as self.fixed) for an end rotation theta."""
        u = np.zeros(self.ndofs)
        y, z = self.nodes[1, self.right] - 0.5, self.nodes[2, self.right] - 0.5
        u[self.ydofs[self.right]] = (np.cos(theta) - 1.0) * y - np.sin(theta) * z
        u[self.zdofs[self.right]] = np.sin(theta) * y + (np.cos(theta) - 1.0) * z
        return u[self.fixed]

    def linear_end_displacement(self, theta):
        """The prescribed DOFs for the small-rotation (linear) problem."""
        u = np.zeros(self.ndofs)
        u[self.ydofs[self.right]] = -theta * (self.nodes[2, self.right] - 0.5)
        u[self.zdofs[self.right]] = theta * (self.nodes[1, self.right] - 0.5)
        return u[self.fixed]

    def displacement_gradient(self, u):
        """H = F - I at the quadrature points, shape (nelems, npoints, 3, 3)."""
        return self.basis.interpolate(u).grad.transpose(2, 3, 0, 1)

    def internal_force(self, P):
        """The vector int P : grad v for P of shape (nelems, npoints, 3, 3)."""
        return asm(internal_force_form, self.basis, P=P.transpose(2, 3, 0, 1))

    def tangent(self, A):
        """The matrix int grad v : A : grad du, A of shape (nelems, npoints, 3, 3, 3, 3) or (3, 3, 3, 3)."""
        nelems = self.dx.shape[1]
        A = np.broadcast_to(A, (nelems, self.dx.shape[0], 3, 3, 3, 3))
        moduli = A.reshape(nelems, -1, 9, 9).transpose(1, 0, 2, 3)
        local = np.zeros((nelems, 81, 81))
        for q in range(self.dx.shape[0]):
            weighted = moduli[q] * self.dx[q][:, None, None]
            local += np.swapaxes(self.G[q], 1, 2) @ (weighted @ self.G[q])
        dofs = self.basis.element_dofs.T
        rows = np.broadcast_to(dofs[:, :, None], local.shape)
        cols = np.broadcast_to(dofs[:, None, :], local.shape)
        return sp.coo_matrix((local.ravel(), (rows.ravel(), cols.ravel())), shape=(self.ndofs, self.ndofs)).tocsr()

    def end_loads(self, u, R, end):
        """(moment about the bar's axis, axial force) of the nodal forces R on one end face."""
        uy, uz = u[self.ydofs[end]], u[self.zdofs[end]]
        Rx, Ry, Rz = R[self.xdofs[end]], R[self.ydofs[end]], R[self.zdofs[end]]
        y = self.nodes[1, end] + uy - 0.5
        z = self.nodes[2, end] + uz - 0.5
        return np.sum(y * Rz - z * Ry), np.sum(Rx)


# --- the solvers -----------------------------------------------------------


class LinearSolver:
    """Conjugate gradients preconditioned by the sparse LU of an earlier matrix."""

    def __init__(self):
        self.lu = None
        self.factorisations = 0
        self.iterations = 0

    def solve(self, K, rhs, rtol, refactorise):
        if refactorise:
            self.lu = None
            self.lu = spla.splu(K.tocsc())
            self.factorisations += 1
        preconditioner = spla.LinearOperator(K.shape, self.lu.solve)
        iterations = [0]

        def count(_):
            iterations[0] += 1

        x, info = spla.cg(K, rhs, rtol=rtol, atol=0.0, M=preconditioner, maxiter=CG_MAX, callback=count)
        if info != 0:
            raise RuntimeError(f"CG did not converge in {CG_MAX} iterations")
        self.iterations += iterations[0]
        return x


def solve_linear(bar, solver):
    """T / theta of the small-strain problem (solved for theta = 1)."""
    K = bar.tangent(linear_moduli())
    u = np.zeros(bar.ndofs)
    u[bar.fixed] = bar.linear_end_displacement(1.0)
    rhs = -K[bar.free][:, bar.fixed] @ u[bar.fixed]
    u[bar.free] = solver.solve(K[bar.free][:, bar.free], rhs, 1.0e-12, True)
    return bar.end_loads(np.zeros(bar.ndofs), K @ u, bar.right)[0]


def turn_sections(bar, u, angle):
    """Turn every cross-section of the deformed bar about the axis by angle x / length."""
    phi = angle * bar.nodes[0] / bar.length
    y = bar.nodes[1] + u[bar.ydofs] - 0.5
    z = bar.nodes[2] + u[bar.zdofs] - 0.5
    u[bar.ydofs] = 0.5 + np.cos(phi) * y - np.sin(phi) * z - bar.nodes[1]
    u[bar.zdofs] = 0.5 + np.sin(phi) * y + np.cos(phi) * z - bar.nodes[2]


def newton_step(bar, u, theta, solver):
    """Equilibrium at end rotation theta, from u (which must satisfy the end
    conditions; updated in place); returns the internal forces and the
    residual history."""
    history = []
    for iteration in range(MAX_NEWTON):
        H = bar.displacement_gradient(u)
        R = bar.internal_force(hencky_piola(H))
        ratio = np.linalg.norm(R[bar.free]) / np.linalg.norm(R[bar.fixed])
        history.append(ratio)
        if ratio < TOLERANCE:
            return R, history
        K = bar.tangent(hencky_tangent(H))
        rtol = CG_FORCING * min(ratio, 1.0)
        u[bar.free] += solver.solve(K[bar.free][:, bar.free], -R[bar.free], rtol, iteration == 0)
    raise RuntimeError(f"Newton did not converge at theta = {np.degrees(theta):.1f} deg: {history}")


def twist(n):
    """Run the load steps and the linear problem on the n x n x 10n mesh."""
    start = time.time()
    bar = Bar(n)
    solver = LinearSolver()
    linear = solve_linear(bar, solver)
    print(f"n = {n} ({bar.ndofs} DOFs): linear T/theta {linear:.8e} N m", flush=True)
    u = np.zeros(bar.ndofs)
    torques = []
    for step in range(1, STEPS + 1):
        theta = FINAL_ANGLE * step / STEPS
        turn_sections(bar, u, FINAL_ANGLE / STEPS)
        u[bar.fixed] = bar.end_displacement(theta)
        R, history = newton_step(bar, u, theta, solver)
        torque, axial = bar.end_loads(u, R, bar.right)
        torque_left = bar.end_loads(u, R, bar.left)[0]
        torques.append(torque)
        residuals = " ".join(f"{r:.1e}" for r in history)
        print(
            f"  {np.degrees(theta):4.0f} deg: T {torque:.8e}, at x = 0 {torque_left:.8e}, T/theta {torque / theta:.8e} N m, "
            f"axial {axial:.6e} N; residuals {residuals}",
            flush=True,
        )
    print(f"  {solver.factorisations} LU factorisations, {solver.iterations} CG iterations, wall time {time.time() - start:.1f} s", flush=True)
    return torques[-1], torques[0] / (FINAL_ANGLE / STEPS), linear


# --- checks and the report -------------------------------------------------


def check():
    """The assembly and the tangent on the n = 1 mesh (10 elements)."""
    bar = Bar(1)
    K_linear = asm(linear_elasticity(LAMBDA, MU), bar.basis)
    K_identity = bar.tangent(hencky_tangent(np.zeros(bar.dx.T.shape + (3, 3))))
    print(f"check: tangent at F = I vs linear elasticity, max difference / max entry {abs(K_identity - K_linear).max() / abs(K_linear).max():.1e}")
    rng = np.random.default_rng(1)
    u = 0.05 * rng.standard_normal(bar.ndofs)
    A = hencky_tangent(bar.displacement_gradient(u))
    K = bar.tangent(A)
    K_form = asm(tangent_form, bar.basis, A=A.transpose(2, 3, 4, 5, 0, 1))
    print(f"check: numpy assembly vs scikit-fem BilinearForm, max difference / max entry {abs(K - K_form).max() / abs(K_form).max():.1e}")
    du = rng.standard_normal(bar.ndofs)
    h = 1.0e-6
    difference = (bar.internal_force(hencky_piola(bar.displacement_gradient(u + h * du))) - bar.internal_force(hencky_piola(bar.displacement_gradient(u - h * du)))) / (2.0 * h)
    print(f"check: K du vs difference of the internal force, relative {np.linalg.norm(K @ du - difference) / np.linalg.norm(difference):.1e}")
    theta = 1.0e-6
    u = np.zeros(bar.ndofs)
    turn_sections(bar, u, theta)
    u[bar.fixed] = bar.end_displacement(theta)
    R, _ = newton_step(bar, u, theta, LinearSolver())
    small = bar.end_loads(np.zeros(bar.ndofs), R, bar.right)[0] / theta
    linear = solve_linear(bar, LinearSolver())
    print(f"check: T/theta at theta = 1e-6 rad {small:.8e}, linear {linear:.8e}, relative {abs(small / linear - 1):.1e}", flush=True)


def saint_venant():
    """Saint-Venant's beta of the square section, the torsional rigidity being beta G a^4."""
    n = np.arange(1, 200, 2)
    return 1.0 / 3.0 - 64.0 / np.pi**5 * np.sum(np.tanh(n * np.pi / 2.0) / n**5)


def observed_order(sizes, values):
    """The order p of the last three values, from
    (a - b) / (b - c) = (r1^p - 1) r2^p / (r2^p - 1), r1 and r2 the ratios of
    the mesh sizes (both 2 for halved meshes, where this is 2^p)."""
    (n1, n2, n3), (a, b, c) = sizes[-3:], values[-3:]
    r1, r2 = n2 / n1, n3 / n2
    return brentq(lambda p: (a - b) / (b - c) - (r1**p - 1.0) * r2**p / (r2**p - 1.0), 0.1, 10.0)


def richardson(sizes, values, p):
    """The last two values extrapolated with order p."""
    return values[-1] + (values[-1] - values[-2]) / ((sizes[-1] / sizes[-2]) ** p - 1.0)


def extrapolate(name, sizes, values):
    """Print the order and the Richardson extrapolations of one quantity."""
    text = ", ".join(f"n = {n}: {v:.8e}" for n, v in zip(sizes, values))
    print(f"{name}: {text}")
    if len(values) >= 3:
        p = observed_order(sizes, values)
        extrapolated = richardson(sizes, values, p)
        print(f"  order {p:.2f}, Richardson {extrapolated:.8e} (last mesh off by {abs(values[-1] / extrapolated - 1):.1e}); Richardson (order 2) {richardson(sizes, values, 2.0):.8e}")
    elif len(values) == 2:
        print(f"  Richardson (order 2) {richardson(sizes, values, 2.0):.8e}")


def end_effect(sizes):
    """The linear problem split into the bar's interior and its ends.

    With the ends far apart, the compliance is theta / T = (length - 2 delta) / GJ:
    GJ the torsional rigidity of the cross-section (Saint-Venant's beta G a^4
    in the limit) and delta the length that each clamped end takes off. Bars
    of 2 m and 4 m on the same meshes give GJ and delta per mesh; then T / theta
    of the 10 m bar from Saint-Venant's GJ and delta extrapolated."""
    exact = saint_venant() * MU * SIDE**4
    deltas = []
    for n in sizes:
        start = time.time()
        short, long = (solve_linear(Bar(n, length), LinearSolver()) for length in (2.0, 4.0))
        rigidity = 2.0 / (1.0 / long - 1.0 / short)
        delta = 1.0 - rigidity / (2.0 * short)
        deltas.append(delta)
        print(f"n = {n}: T/theta {short:.8e} (2 m), {long:.8e} (4 m); GJ {rigidity:.8e} (Saint-Venant + {rigidity - exact:.3e}), delta {delta:.8f} m; wall time {time.time() - start:.1f} s", flush=True)
    print(f"Saint-Venant GJ {exact:.8e} N m2; T/theta of the {L:g} m bar with delta of the last mesh {exact / (L - 2.0 * deltas[-1]):.8e} N m")
    if len(sizes) >= 3:
        p = observed_order(sizes, deltas)
        for order in (p, 2.0, 1.0):
            delta = richardson(sizes, deltas, order)
            print(f"  delta extrapolated with order {order:.2f}: {delta:.8f} m, T/theta {exact / (L - 2.0 * delta):.8e} N m")


def main():
    args = sys.argv[1:]
    if args[:1] == ["--ends"]:
        end_effect([int(arg) for arg in args[1:]] or [2, 4, 8])
        return
    sizes = [int(arg) for arg in args] or [1, 2, 4, 8]
    check()
    results = [twist(n) for n in sizes]
    for k, name in enumerate(["T at 90 deg [N m]", "T/theta at 9 deg [N m]", "linear T/theta [N m]"]):
        extrapolate(name, sizes, [r[k] for r in results])
    beta = saint_venant()
    print(f"Saint-Venant: beta {beta:.6f}, beta G a^4 / L {beta * MU * SIDE**4 / L:.8e} N m")


if __name__ == "__main__":
    main()
