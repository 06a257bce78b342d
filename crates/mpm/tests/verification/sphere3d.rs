//! A thick hollow sphere (a = 0.5 m < R < b = 1 m, E = 1 MPa, nu = 0.3,
//! weightless) under a follower pressure `p` on its inner surface, carried
//! by the bicubic B-spline surface through its points
//! (`boundary::surface_loading`); symmetry by rollers on the grid planes
//! x, y, z = 0 through its centre, GIMP, 2 points a cell each way on the
//! sphere's own lattice (shells, bands, sectors).
//!
//! References:
//! - small strain (`linear_elastic`, p = 100 Pa, p / E = 1e-4): Lame's
//!   thick sphere (Timoshenko & Goodier, Theory of Elasticity, 3rd ed.,
//!   section 141): `sigma_rr = A (1 - b^3 / r^3)`, `sigma_tt = A (1 + b^3 /
//!   (2 r^3))`, `u = A r / E ((1 - 2 nu) + (1 + nu) b^3 / (2 r^3))`, `A =
//!   p a^3 / (b^3 - a^3)`;
//! - finite strain (Hencky, p = 100 kPa: the inner radius grows 9.5%): the
//!   radial solution of `scripts/sphere_radial.py` (the equilibrium ODE in
//!   the reference radius, shot from the loaded surface at rtol 1e-12),
//!   ported below as [`Radial`] (RK4) and checked against the script's
//!   u(a) = 4.7375740786e-2 m, u(b) = 1.9262853763e-2 m.
//!
//! u(a) and u(b) are read from the surfaces themselves: the mean radius of
//! the inner and outer faces' data points less the reference radius. The
//! stresses are each point's radial and hoop Cauchy stress, against the
//! reference at its reference radius, as root mean squares over the
//! points, relative to p.
//!
//! Measured (h = 0.2, 0.1, 0.05 m; 3,674, 29,307 and 234,670 points):
//!
//! | | h (m) | u(a) | u(b) | sigma_rr rms / p | sigma_tt rms / p |
//! |---|---|---|---|---|---|
//! | small strain | 0.2 | -0.694% | +0.015% | 0.0527 | 0.0380 |
//! | | 0.1 | -0.398% | +0.060% | 0.0285 | 0.0186 |
//! | | 0.05 | -0.082% | +0.030% | 0.0146 | 0.0101 |
//! | finite strain | 0.2 | -0.941% | -0.212% | 0.0563 | 0.0397 |
//! | | 0.1 | +0.014% | +0.062% | 0.0301 | 0.0200 |
//! | | 0.05 | +0.152% | +0.135% | 0.0139 | 0.0101 |
//!
//! The stresses converge at first order (0.89, 0.97 and 1.03, 0.88 at
//! small strain): each point's stress against the exact one at its place,
//! GIMP's error at the surfaces, where the points' domains meet cells the
//! material only partly fills. The surface's displacements are read
//! through the outer points' deformation gradients (a data point rides its
//! point at `x_p + F_p d`), which carry that first-order error half a
//! spacing out: u(a) -0.69%, -0.40%, -0.08%. The points' own displacements
//! fitted by Lame's form `A r + B / r^2` give u(a) within 0.04% at every h
//! (the surface-free check of the load: the pressure's resultant on each
//! octant is right). At finite strain the surface's u(a) and u(b) settle
//! within 0.15% from h = 0.1 m on. The finer rows are `sphere3d_table`
//! (ignored: 35 s and 130 s) and, for the finite case at 0.05 m, the CLI
//! (10 steps of 35-90 s, read from the stored surfaces and points).

use mpm::boundary::face_patches::carried_position;
use mpm::case::solid::SolidCase;
use mpm::{NoObserver, Simulation};

const A: f64 = 0.5;
const B: f64 = 1.0;
const E: f64 = 1e6;
const NU: f64 = 0.3;

/// The sphere on cells of `h` under `p`, in `steps` steps.
fn sphere(h: f64, model: &str, p: f64, steps: u32) -> Simulation<3> {
    let case = serde_json::json!({
        "version": 1,
        "analysis": { "type": "3d", "load_steps": steps },
        "grid": { "cell_size": h, "origin": [0.0, 0.0, 0.0] },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "spherical_shell": { "center": [0.0, 0.0, 0.0], "inner_radius": A, "outer_radius": B } },
            "points": { "per_cell": 2 },
            "material": { "model": model, "youngs_modulus": E, "poisson_ratio": NU, "density": 0.0 }
        }],
        "loads": { "surface": [{ "on": { "sphere": { "center": [0.0, 0.0, 0.0], "radius": A } }, "pressure": p }] },
        "supports": [
            { "on": { "x": 0.0 }, "fix": "x" },
            { "on": { "y": 0.0 }, "fix": "y" },
            { "on": { "z": 0.0 }, "fix": "z" }
        ]
    });
    let case = SolidCase::from_json(&case.to_string()).expect("a valid case");
    let mut sim = Simulation::from_solid_case(&case).expect("a case that builds");
    sim.run(&mut NoObserver).expect("the sphere finishes");
    sim
}

fn norm(x: [f64; 3]) -> f64 {
    (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
}

/// u(a) and u(b): the mean current radius of the data points of the inner
/// and the outer surface, less its reference radius.
fn surface_displacements(sim: &Simulation<3>) -> (f64, f64) {
    let points = &sim.points;
    let (mut sum, mut count) = ([0.0; 2], [0usize; 2]);
    for face in &sim.faces {
        for c in &face.data {
            let r = points.reference[c.point];
            let reference = norm(std::array::from_fn(|d| r[d] + c.offset[d]));
            let k = usize::from((reference - B).abs() < 1e-9);
            assert!(k == 1 || (reference - A).abs() < 1e-9);
            sum[k] += norm(carried_position(points, c));
            count[k] += 1;
        }
    }
    (sum[0] / count[0] as f64 - A, sum[1] / count[1] as f64 - B)
}

/// The root mean squares, relative to `p`, of the points' radial and hoop
/// stress less `exact(R)` at their reference radius `R`.
fn stress_errors(sim: &Simulation<3>, p: f64, exact: impl Fn(f64) -> (f64, f64)) -> (f64, f64) {
    let points = &sim.points;
    let n = points.len();
    let (mut err_r, mut err_t) = (0.0, 0.0);
    for k in 0..n {
        let x = points.position[k];
        let radial: [f64; 3] = x.map(|v| v / norm(x));
        let s = points.stress[k];
        let srr: f64 = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| radial[i] * s[(i, j)] * radial[j])
                    .sum::<f64>()
            })
            .sum();
        let stt = (s[(0, 0)] + s[(1, 1)] + s[(2, 2)] - srr) / 2.0;
        let (er, et) = exact(norm(points.reference[k]));
        err_r += (srr - er).powi(2);
        err_t += (stt - et).powi(2);
    }
    ((err_r / n as f64).sqrt() / p, (err_t / n as f64).sqrt() / p)
}

/// Lame's `(sigma_rr, sigma_tt)` and `u` at `r` under `p`.
fn lame(r: f64, p: f64) -> ((f64, f64), f64) {
    let c = p * A.powi(3) / (B.powi(3) - A.powi(3));
    let b3 = (B / r).powi(3);
    let u = c * r / E * ((1.0 - 2.0 * NU) + (1.0 + NU) * b3 / 2.0);
    ((c * (1.0 - b3), c * (1.0 + b3 / 2.0)), u)
}

/// The finite-strain radial solution of `scripts/sphere_radial.py`:
/// `(R, phi, lambda_r)` on 4000 RK4 steps from a to b, shot by the secant
/// method on phi(a).
struct Radial {
    samples: Vec<(f64, f64, f64)>,
    lame_lambda: f64,
    mu: f64,
}

impl Radial {
    /// Cauchy `(sigma_r, sigma_t)` at stretches `lr`, `lt`.
    fn stresses(&self, lr: f64, lt: f64) -> (f64, f64) {
        let (er, et) = (lr.ln(), lt.ln());
        let tr = er + 2.0 * et;
        let j = lr * lt * lt;
        (
            (self.lame_lambda * tr + 2.0 * self.mu * er) / j,
            (self.lame_lambda * tr + 2.0 * self.mu * et) / j,
        )
    }

    fn new(p: f64) -> Self {
        let mut out = Radial {
            samples: Vec::new(),
            lame_lambda: E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)),
            mu: E / (2.0 * (1.0 + NU)),
        };
        let shoot = |out: &Radial, phi_a: f64| -> Vec<(f64, f64, f64)> {
            // sigma_r(lr, phi_a / a) = -p by Newton on lr.
            let lt = phi_a / A;
            let mut lr = 1.0;
            for _ in 0..50 {
                let h = 1e-7;
                let f = out.stresses(lr, lt).0 + p;
                let df = (out.stresses(lr + h, lt).0 - out.stresses(lr - h, lt).0) / (2.0 * h);
                lr -= f / df;
            }
            let rhs = |r: f64, phi: f64, lr: f64| -> (f64, f64) {
                let lt = phi / r;
                let (sr, st) = out.stresses(lr, lt);
                let h = 1e-7;
                let d_lr = (out.stresses(lr + h, lt).0 - out.stresses(lr - h, lt).0) / (2.0 * h);
                let d_lt = (out.stresses(lr, lt + h).0 - out.stresses(lr, lt - h).0) / (2.0 * h);
                let target = -2.0 * lr * (sr - st) / phi;
                (lr, (target - d_lt * (lr - lt) / r) / d_lr)
            };
            let steps = 4000;
            let dr = (B - A) / steps as f64;
            let mut y = (phi_a, lr);
            let mut samples = vec![(A, y.0, y.1)];
            for k in 0..steps {
                let r = A + k as f64 * dr;
                let k1 = rhs(r, y.0, y.1);
                let k2 = rhs(r + dr / 2.0, y.0 + dr / 2.0 * k1.0, y.1 + dr / 2.0 * k1.1);
                let k3 = rhs(r + dr / 2.0, y.0 + dr / 2.0 * k2.0, y.1 + dr / 2.0 * k2.1);
                let k4 = rhs(r + dr, y.0 + dr * k3.0, y.1 + dr * k3.1);
                y.0 += dr / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
                y.1 += dr / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
                samples.push((r + dr, y.0, y.1));
            }
            samples
        };
        let miss = |out: &Radial, phi_a: f64| {
            let &(r, phi, lr) = shoot(out, phi_a).last().expect("samples");
            out.stresses(lr, phi / r).0
        };
        let (mut x0, mut x1) = (A * 1.05, A * 1.1);
        let (mut f0, mut f1) = (miss(&out, x0), miss(&out, x1));
        for _ in 0..50 {
            if f1 == f0 {
                break;
            }
            let x2 = x1 - f1 * (x1 - x0) / (f1 - f0);
            (x0, f0) = (x1, f1);
            x1 = x2;
            f1 = miss(&out, x1);
        }
        out.samples = shoot(&out, x1);
        out
    }

    /// `(phi, lambda_r)` at reference radius `r`, by linear interpolation
    /// between the RK4 samples (1.25e-4 m apart).
    fn at(&self, r: f64) -> (f64, f64) {
        let step = (B - A) / (self.samples.len() - 1) as f64;
        let k = (((r - A) / step).floor() as usize).min(self.samples.len() - 2);
        let (r0, phi0, l0) = self.samples[k];
        let (_, phi1, l1) = self.samples[k + 1];
        let w = (r - r0) / step;
        (phi0 + w * (phi1 - phi0), l0 + w * (l1 - l0))
    }

    fn stress(&self, r: f64) -> (f64, f64) {
        let (phi, lr) = self.at(r);
        self.stresses(lr, phi / r)
    }
}

#[test]
fn the_radial_reference_is_the_scripts() {
    let radial = Radial::new(1e5);
    let (ua, ub) = (radial.at(A).0 - A, radial.at(B).0 - B);
    assert!((ua / 4.7375740786e-2 - 1.0).abs() < 1e-8, "{ua:e}");
    assert!((ub / 1.9262853763e-2 - 1.0).abs() < 1e-8, "{ub:e}");
    // And it is Lame's at a small pressure, to the strain's order.
    let small = Radial::new(100.0);
    let ua = small.at(A).0 - A;
    assert!((ua / lame(A, 100.0).1 - 1.0).abs() < 2e-4, "{ua:e}");
}

#[test]
fn a_thick_sphere_under_internal_pressure_at_small_strain() {
    let p = 100.0;
    let mut errors = Vec::new();
    for h in [0.2, 0.1] {
        let sim = sphere(h, "linear_elastic", p, 1);
        let (ua, ub) = surface_displacements(&sim);
        let (er, et) = stress_errors(&sim, p, |r| lame(r, p).0);
        let (ea, eb) = (ua / lame(A, p).1 - 1.0, ub / lame(B, p).1 - 1.0);
        eprintln!(
            "h = {h}: u(a) {:+.3}%, u(b) {:+.3}%, sigma_rr rms {er:.4}, sigma_tt rms {et:.4}",
            100.0 * ea,
            100.0 * eb
        );
        errors.push([ea, eb, er, et]);
    }
    // First order, with a margin on the measured ratios (0.57, 0.54, 0.49).
    let [coarse, fine] = [errors[0], errors[1]];
    assert!(
        coarse[0].abs() < 0.01 && fine[0].abs() < 0.7 * coarse[0].abs(),
        "u(a): {errors:?}"
    );
    assert!(
        coarse[1].abs() < 2e-3 && fine[1].abs() < 2e-3,
        "u(b): {errors:?}"
    );
    assert!(
        coarse[2] < 0.06 && fine[2] < 0.6 * coarse[2],
        "sigma_rr: {errors:?}"
    );
    assert!(
        coarse[3] < 0.045 && fine[3] < 0.6 * coarse[3],
        "sigma_tt: {errors:?}"
    );
}

#[test]
fn a_thick_sphere_under_internal_pressure_at_finite_strain() {
    let p = 1e5;
    let radial = Radial::new(p);
    let sim = sphere(0.2, "hencky", p, 10);
    let (ua, ub) = surface_displacements(&sim);
    let (er, et) = stress_errors(&sim, p, |r| radial.stress(r));
    let (ea, eb) = (
        ua / (radial.at(A).0 - A) - 1.0,
        ub / (radial.at(B).0 - B) - 1.0,
    );
    eprintln!(
        "finite: u(a) {:+.3}%, u(b) {:+.3}%, sigma_rr rms {er:.4}, sigma_tt rms {et:.4}",
        100.0 * ea,
        100.0 * eb
    );
    // The measured -0.94%, -0.21%, 0.056, 0.040 with a fifth again.
    assert!(
        ea.abs() < 0.012 && eb.abs() < 0.003,
        "u(a) {ea:e}, u(b) {eb:e}"
    );
    assert!(er < 0.068 && et < 0.048, "sigma_rr {er}, sigma_tt {et}");
}

/// The table's finer rows (a few minutes): `cargo test --test verification
/// sphere3d_table -- --ignored --nocapture`.
#[test]
#[ignore]
fn sphere3d_table() {
    let p = 100.0;
    let sim = sphere(0.05, "linear_elastic", p, 1);
    let (ua, ub) = surface_displacements(&sim);
    let (er, et) = stress_errors(&sim, p, |r| lame(r, p).0);
    eprintln!(
        "small, h = 0.05: u(a) {:+.3}%, u(b) {:+.3}%, sigma_rr rms {er:.4}, sigma_tt rms {et:.4}",
        100.0 * (ua / lame(A, p).1 - 1.0),
        100.0 * (ub / lame(B, p).1 - 1.0)
    );
    let p = 1e5;
    let radial = Radial::new(p);
    let sim = sphere(0.1, "hencky", p, 10);
    let (ua, ub) = surface_displacements(&sim);
    let (er, et) = stress_errors(&sim, p, |r| radial.stress(r));
    eprintln!(
        "finite, h = 0.1: u(a) {:+.3}%, u(b) {:+.3}%, sigma_rr rms {er:.4}, sigma_tt rms {et:.4}",
        100.0 * (ua / (radial.at(A).0 - A) - 1.0),
        100.0 * (ub / (radial.at(B).0 - B) - 1.0)
    );
}
