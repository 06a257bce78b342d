//! Constitutive models, written for the updated-Lagrangian step.
//!
//! Each load step starts from the configuration at its beginning. A model is
//! given the incremental deformation gradient `dF = I + grad(du)` (gradient in
//! that configuration) and its history from the start of the step, and
//! returns the stress measure `P` that pairs with `dF` per unit reference
//! volume, so that the internal force of node `a` is `V0 P g_a` with `g_a`
//! the shape-function gradient in the step's start configuration, and the
//! consistent tangent `dP/d(dF)`.
//!
//! In 2D plane strain all tensors are the in-plane 2x2 blocks; the
//! out-of-plane stretch is one. A 2x2 matrix `M` flattens row-major,
//! `M[(i, j)] -> 2 i + j`, so the tangent is a 4x4 matrix
//! `A[(2i + I, 2j + J)] = dP_iI / d(dF)_jJ`.

mod drucker_prager;
mod hencky;
mod mohr_coulomb;
mod return_map;
mod small_strain;
mod three_dimensional;
mod von_mises;

use nalgebra::{Matrix2, Matrix4};

pub use drucker_prager::DruckerPrager;
use drucker_prager::drucker_prager;
use hencky::hencky;
pub use mohr_coulomb::MohrCoulomb;
use mohr_coulomb::mohr_coulomb;
pub use return_map::APEX_SEPARATION;
use small_strain::small_strain;
pub use three_dimensional::{History3, Response3, Tangent3};
pub use von_mises::VonMises;
use von_mises::von_mises;

/// Stress of a material point in the current configuration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CauchyStress {
    /// In-plane components `[xx, yy, xy]`.
    pub plane: [f64; 3],
    /// Out-of-plane normal stress `zz` (non-zero in plane strain).
    pub zz: f64,
}

/// What a model returns for a trial `dF`.
#[derive(Debug, Clone, Copy)]
pub struct Response {
    /// Stress paired with `dF` per unit reference volume (for Hencky:
    /// Kirchhoff stress times `dF^-T`).
    pub p: Matrix2<f64>,
    /// `dP / d(dF)`, flattened as described in the module docs.
    pub tangent: Matrix4<f64>,
    /// History to keep if the step converges.
    pub history: History,
    pub cauchy: CauchyStress,
    /// The return could not meet the model's flow rule: a trial past the
    /// apex of a frictional model whose dilation cannot take the volume
    /// change the apex asks (`psi = 0` with the point opening). The state
    /// is the apex's, and the point loop refuses it
    /// (`particles::admissible`).
    pub off_flow_rule: bool,
}

/// What a point carries from step to step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct History {
    /// Hencky and the plastic models: the in-plane elastic left Cauchy-Green tensor's
    /// excess over the identity, `b - I` (kept rather than `b`, whose entries would
    /// hold a small strain only to the round-off of one: `hencky::trial_excess`);
    /// linear elasticity: the small strain.
    pub tensor: Matrix2<f64>,
    /// The plastic models: `b`'s out-of-plane component less one, `b_zz - 1`
    /// (zero for the others, whose out-of-plane stretch stays one).
    pub zz: f64,
    /// Accumulated plastic strain `alpha` (zero for the elastic models).
    pub plastic_strain: f64,
}

impl History {
    /// An elastic model's history: `tensor` alone.
    pub fn elastic(tensor: Matrix2<f64>) -> Self {
        Self {
            tensor,
            zz: 0.0,
            plastic_strain: 0.0,
        }
    }
}

/// The constitutive models of the case format.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Material {
    Hencky(Elastic),
    LinearElastic(Elastic),
    VonMises(VonMises),
    DruckerPrager(DruckerPrager),
    MohrCoulomb(MohrCoulomb),
}

/// The stiffnesses over a run's materials that its stabilisation and line
/// search scale by: found once, as the materials do not change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StiffnessScales {
    /// The elastic constants of the material with the largest P-wave
    /// modulus `lambda + 2 mu` (the soft background's).
    pub stiffest: Option<Elastic>,
    /// The largest ratio of P-wave to shear modulus, `(lambda + 2 mu) /
    /// mu` (2 at nu = 0, 5001 at nu = 0.4999), at least 1: how much more a
    /// spurious volume change costs than a shear, which bounds how far a
    /// converging Newton step may raise the residual (`newton::Search`).
    pub p_wave_to_shear: f64,
}

impl StiffnessScales {
    pub fn of(materials: &[Material]) -> Self {
        let elastic = || materials.iter().map(Material::elastic);
        Self {
            stiffest: elastic()
                .max_by(|a, b| (a.lambda + 2.0 * a.mu).total_cmp(&(b.lambda + 2.0 * b.mu))),
            p_wave_to_shear: elastic()
                .map(|c| (c.lambda + 2.0 * c.mu) / c.mu)
                .fold(1.0, f64::max),
        }
    }
}

/// Isotropic elastic constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elastic {
    /// Lame's first parameter.
    pub lambda: f64,
    /// Shear modulus.
    pub mu: f64,
}

impl Elastic {
    pub fn from_young_poisson(e: f64, nu: f64) -> Self {
        Self {
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            mu: e / (2.0 * (1.0 + nu)),
        }
    }

    /// The bulk modulus `K = lambda + 2 mu / 3`.
    pub fn bulk(&self) -> f64 {
        self.lambda + 2.0 * self.mu / 3.0
    }

    /// Plane-strain stress of an in-plane strain (the out-of-plane strain is
    /// zero): `s = lambda tr(e) I + 2 mu e`, `s_zz = lambda tr(e)`.
    pub(crate) fn stress(&self, e: &Matrix2<f64>) -> (Matrix2<f64>, f64) {
        let tr = e.trace();
        (
            Matrix2::identity() * (self.lambda * tr) + e * (2.0 * self.mu),
            self.lambda * tr,
        )
    }
}

impl Material {
    /// The elastic constants (any model).
    pub fn elastic(&self) -> Elastic {
        match *self {
            Material::Hencky(c) | Material::LinearElastic(c) => c,
            Material::VonMises(m) => m.elastic,
            Material::DruckerPrager(m) => m.elastic,
            Material::MohrCoulomb(m) => m.elastic,
        }
    }

    /// Whether the model is elastic (no yield surface).
    pub fn is_elastic(&self) -> bool {
        matches!(self, Material::Hencky(_) | Material::LinearElastic(_))
    }

    /// Whether the tangent `dP/d(dF)` has major symmetry (then so has the
    /// stiffness it makes): for the elastic models and associated flow,
    /// not for a dilation angle other than the friction angle.
    pub fn symmetric_tangent(&self) -> bool {
        match self {
            Material::Hencky(_) | Material::LinearElastic(_) | Material::VonMises(_) => true,
            Material::DruckerPrager(m) => m.eta_flow == m.eta,
            Material::MohrCoulomb(m) => m.dilation == m.friction,
        }
    }

    /// The material with its strength divided by `factor` (strength
    /// reduction): a frictional model's `c`, `tan(phi)` and `tan(psi)`, von
    /// Mises's yield stress and hardening. The elastic constants stay, and
    /// the elastic models have no strength to reduce.
    pub fn with_strength_reduced(&self, factor: f64) -> Material {
        match *self {
            Material::Hencky(_) | Material::LinearElastic(_) => *self,
            Material::VonMises(m) => Material::VonMises(VonMises {
                yield_stress: m.yield_stress / factor,
                hardening: m.hardening / factor,
                ..m
            }),
            Material::DruckerPrager(m) => Material::DruckerPrager(m.reduced(factor)),
            Material::MohrCoulomb(m) => Material::MohrCoulomb(m.reduced(factor)),
        }
    }

    /// The history of an undeformed point that carries the Cauchy stress
    /// `sigma = [xx, yy, zz]` (principal axes x, y, z): the elastic strain
    /// that makes it, as the plastic models keep it (`b = exp(2 e)`, its
    /// out-of-plane part too). The elastic models keep no out-of-plane
    /// strain: theirs is the in-plane strain of `xx` and `yy`, and their
    /// `zz` follows from it.
    pub fn history_carrying(&self, sigma: [f64; 3]) -> History {
        let Elastic { lambda, mu } = self.elastic();
        let in_plane = || {
            // [xx, yy] = [[l + 2m, l], [l, l + 2m]] [exx, eyy]
            let det = 4.0 * mu * (lambda + mu);
            let p = lambda + 2.0 * mu;
            [
                (p * sigma[0] - lambda * sigma[1]) / det,
                (p * sigma[1] - lambda * sigma[0]) / det,
            ]
        };
        match self {
            Material::LinearElastic(_) => {
                let [exx, eyy] = in_plane();
                History::elastic(Matrix2::new(exx, 0.0, 0.0, eyy))
            }
            Material::Hencky(_) => {
                let [exx, eyy] = in_plane();
                History::elastic(Matrix2::new(
                    (2.0 * exx).exp_m1(),
                    0.0,
                    0.0,
                    (2.0 * eyy).exp_m1(),
                ))
            }
            Material::VonMises(_) | Material::DruckerPrager(_) | Material::MohrCoulomb(_) => {
                let mean_part = lambda / (3.0 * lambda + 2.0 * mu) * sigma.iter().sum::<f64>();
                let e = sigma.map(|t| (t - mean_part) / (2.0 * mu));
                History {
                    tensor: Matrix2::new((2.0 * e[0]).exp_m1(), 0.0, 0.0, (2.0 * e[1]).exp_m1()),
                    zz: (2.0 * e[2]).exp_m1(),
                    plastic_strain: 0.0,
                }
            }
        }
    }

    /// History of an undeformed, unstressed point.
    pub fn initial_history(&self) -> History {
        match self {
            Material::Hencky(_)
            | Material::VonMises(_)
            | Material::DruckerPrager(_)
            | Material::MohrCoulomb(_)
            | Material::LinearElastic(_) => History::elastic(Matrix2::zeros()),
        }
    }

    /// Trial response to the displacement gradient `grad_u` of the step
    /// (`dF = I + grad_u`) from `history`; `j_start` is the volume ratio at
    /// the start of the step (for the Cauchy stress). The gradient is passed
    /// rather than `dF` so that tiny strains are not lost to round-off in
    /// `dF - I`.
    pub fn respond(&self, history: &History, grad_u: &Matrix2<f64>, j_start: f64) -> Response {
        self.respond_wanting(history, grad_u, j_start, true)
    }

    /// [`Material::respond`] with its tangent left zero (the small-strain
    /// model's, a constant, excepted): what the point loop and a commit
    /// need, for the finite-strain models at about half the cost.
    pub fn respond_without_tangent(
        &self,
        history: &History,
        grad_u: &Matrix2<f64>,
        j_start: f64,
    ) -> Response {
        self.respond_wanting(history, grad_u, j_start, false)
    }

    fn respond_wanting(
        &self,
        history: &History,
        grad_u: &Matrix2<f64>,
        j_start: f64,
        want_tangent: bool,
    ) -> Response {
        match self {
            Material::Hencky(c) => hencky(c, &history.tensor, grad_u, j_start, want_tangent),
            Material::LinearElastic(c) => small_strain(c, &history.tensor, grad_u),
            Material::VonMises(m) => von_mises(m, history, grad_u, j_start, want_tangent),
            Material::DruckerPrager(m) => drucker_prager(m, history, grad_u, j_start, want_tangent),
            Material::MohrCoulomb(m) => mohr_coulomb(m, history, grad_u, j_start, want_tangent),
        }
    }
}

/// Checks a model's tangent against central differences of its `P` at
/// `df` (relative to the tangent's norm): `respond` is the model at a fixed
/// history.
#[cfg(test)]
pub(crate) fn assert_tangent_is_the_derivative(
    respond: impl Fn(&Matrix2<f64>) -> Response,
    df: &Matrix2<f64>,
    eps: f64,
    tolerance: f64,
    label: &str,
) {
    let tangent = respond(df).tangent;
    let scale = tangent.norm();
    for j in 0..2 {
        for jj in 0..2 {
            let mut dir = Matrix2::zeros();
            dir[(j, jj)] = eps;
            let fd = (respond(&(df + dir)).p - respond(&(df - dir)).p) / (2.0 * eps);
            for i in 0..2 {
                for ii in 0..2 {
                    let a = tangent[(2 * i + ii, 2 * j + jj)];
                    assert!(
                        (a - fd[(i, ii)]).abs() < tolerance * scale,
                        "{label}: dP{i}{ii}/dF{j}{jj} = {a}, finite difference {}",
                        fd[(i, ii)]
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every model, undeformed with the history that carries a stress,
    /// answers that stress: in full for the plastic models, in-plane for
    /// the elastic ones (their zz is plane strain's `lambda tr(e)`).
    #[test]
    fn a_history_carries_the_stress_it_was_made_for() {
        let elastic = Elastic::from_young_poisson(2e7, 0.3);
        let soil = MohrCoulomb {
            elastic,
            cohesion: 1e4,
            friction: 0.5,
            dilation: 0.0,
        };
        let sigma = [-5e4, -1e5, -6e4];
        for m in [
            Material::Hencky(elastic),
            Material::LinearElastic(elastic),
            Material::MohrCoulomb(soil),
        ] {
            let r = m.respond(&m.history_carrying(sigma), &Matrix2::zeros(), 1.0);
            let got = [r.cauchy.plane[0], r.cauchy.plane[1], r.cauchy.zz];
            let full = matches!(m, Material::MohrCoulomb(_));
            for k in 0..if full { 3 } else { 2 } {
                assert!((got[k] - sigma[k]).abs() < 1e-9 * 1e5, "{m:?}: {got:?}");
            }
            assert_eq!(r.cauchy.plane[2], 0.0);
        }
    }

    /// Strength reduction by `F` is the model of the reduced constants: `c /
    /// F`, `atan(tan(phi) / F)`, `atan(tan(psi) / F)` (Griffiths and Lane
    /// 1999, eq. 1-2), here with psi below phi and a factor below one too.
    #[test]
    fn a_reduced_strength_is_the_model_of_the_reduced_constants() {
        let c = Elastic::from_young_poisson(1.0e7, 0.3);
        let (phi, psi) = (30f64.to_radians(), 10f64.to_radians());
        let reduce = |angle: f64, f: f64| (angle.tan() / f).atan();
        for f in [1.6, 0.8] {
            let dp = DruckerPrager::plane_strain_match(c, 1.0e4, phi, psi);
            let Material::DruckerPrager(got) = Material::DruckerPrager(dp).with_strength_reduced(f)
            else {
                unreachable!()
            };
            let want =
                DruckerPrager::plane_strain_match(c, 1.0e4 / f, reduce(phi, f), reduce(psi, f));
            for (g, w) in [
                (got.eta, want.eta),
                (got.xi, want.xi),
                (got.eta_flow, want.eta_flow),
            ] {
                assert!((g - w).abs() < 1e-14, "{got:?} {want:?}");
            }
            assert_eq!(got.cohesion, want.cohesion);
            let mc = MohrCoulomb {
                elastic: c,
                cohesion: 1.0e4,
                friction: phi,
                dilation: psi,
            };
            let Material::MohrCoulomb(got) = Material::MohrCoulomb(mc).with_strength_reduced(f)
            else {
                unreachable!()
            };
            assert!((got.friction - reduce(phi, f)).abs() < 1e-15);
            assert!((got.dilation - reduce(psi, f)).abs() < 1e-15);
            assert_eq!((got.cohesion, got.elastic), (1.0e4 / f, c));
        }
    }

    fn materials() -> [Material; 2] {
        let c = Elastic::from_young_poisson(1.0e6, 0.3);
        [Material::Hencky(c), Material::LinearElastic(c)]
    }

    /// A stretched, sheared, rotated history and increment: nothing special.
    fn general_state(m: &Material) -> (History, Matrix2<f64>) {
        let f_n = Matrix2::new(1.1, 0.2, -0.05, 0.9);
        let history = match m {
            Material::LinearElastic(_) => Matrix2::new(0.01, 0.003, 0.003, -0.02),
            _ => f_n * f_n.transpose() - Matrix2::identity(),
        };
        (
            History::elastic(history),
            Matrix2::new(0.97, 0.11, -0.08, 1.04),
        )
    }

    #[test]
    fn tangent_equals_finite_difference_of_stress() {
        // Central differences have O(eps^2) truncation error; with eps = 1e-6
        // and stresses of order 1e5 Pa the round-off is ~1e5 * 1e-16 / 1e-6 =
        // 1e-5, so 1e-6 relative to the tangent's norm (~1e6) is a real check.
        for m in materials() {
            let (history, df) = general_state(&m);
            assert_tangent_is_the_derivative(
                |df| m.respond(&history, &(df - Matrix2::identity()), 1.0),
                &df,
                1e-6,
                1e-6,
                &format!("{m:?}"),
            );
        }
    }

    #[test]
    fn tangent_is_exact_when_eigenvalues_coincide() {
        // b = I (unstressed, its excess zero) is the degenerate case of the
        // log derivative.
        let m = materials()[0];
        let r = m.respond(&History::elastic(Matrix2::zeros()), &Matrix2::zeros(), 1.0);
        // At the reference state the Hencky tangent is the linear elastic one.
        let lin =
            materials()[1].respond(&History::elastic(Matrix2::zeros()), &Matrix2::zeros(), 1.0);
        assert!((r.tangent - lin.tangent).norm() < 1e-9 * lin.tangent.norm());
    }

    #[test]
    fn pure_rotation_gives_zero_stress() {
        // Hencky is objective: b = R R^T = I, so e = 0 and tau = 0 whatever the
        // angle (here 60 degrees, far from small rotations).
        let m = materials()[0];
        let (s, c) = (60f64).to_radians().sin_cos();
        let r = Matrix2::new(c, -s, s, c);
        let resp = m.respond(
            &History::elastic(Matrix2::zeros()),
            &(r - Matrix2::identity()),
            1.0,
        );
        assert!(resp.p.norm() < 1e-9, "{}", resp.p);
        assert!(resp.cauchy.plane.iter().all(|s| s.abs() < 1e-9));
    }

    /// At a strain of 1e-9 Hencky's stress is the linear one to nine
    /// digits (their difference is of the order of the strain). Formed
    /// from `b = dF dF^T`, whose entries hold the strain only to the
    /// round-off of one, it was off by some 1e-7.
    #[test]
    fn a_tiny_strain_keeps_its_precision() {
        let [hencky, linear] = materials();
        let grad_u = Matrix2::new(1.0e-9, 0.3e-9, -0.2e-9, -0.7e-9);
        let after_a_step = hencky.respond(&hencky.initial_history(), &grad_u, 1.0);
        for history in [hencky.initial_history(), after_a_step.history] {
            let h = hencky.respond(&history, &grad_u, 1.0).cauchy.plane;
            let reference = if history == hencky.initial_history() {
                linear.respond(&linear.initial_history(), &grad_u, 1.0)
            } else {
                linear.respond(
                    &linear
                        .respond(&linear.initial_history(), &grad_u, 1.0)
                        .history,
                    &grad_u,
                    1.0,
                )
            };
            let l = reference.cauchy.plane;
            let scale = l.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for k in 0..3 {
                assert!((h[k] - l[k]).abs() < 1e-8 * scale, "{h:?} {l:?}");
            }
        }
    }

    #[test]
    fn uniaxial_stretch_matches_hencky_closed_form() {
        // Plane strain, nu = 0 (lambda = 0, mu = E/2): stretch l in y gives
        // tau_yy = E ln(l) and Cauchy sigma_yy = E ln(l) / l.
        let e = 1.0e4;
        let m = Material::Hencky(Elastic::from_young_poisson(e, 0.0));
        let l = 0.6;
        let resp = m.respond(
            &History::elastic(Matrix2::zeros()),
            &Matrix2::new(0.0, 0.0, 0.0, l - 1.0),
            1.0,
        );
        let expected = e * l.ln() / l;
        assert!((resp.cauchy.plane[1] - expected).abs() < 1e-10 * expected.abs());
        assert!(resp.cauchy.plane[0].abs() < 1e-10 && resp.cauchy.zz.abs() < 1e-10);
    }

    /// Yielding under a turned, sheared increment after a stretch that
    /// yielded them: the elastic model and the associated flow rules keep
    /// the tangent symmetric to round-off; non-associated flow (psi = 5 deg
    /// against phi = 30 deg) makes it unsymmetric by far more. What
    /// `symmetric_tangent` says must match.
    /// One of each model, the plastic ones with associated and
    /// non-associated flow.
    fn every_model() -> [Material; 6] {
        let elastic = Elastic::from_young_poisson(20e6, 0.3);
        let (c, phi, psi) = (10e3, 30f64.to_radians(), 5f64.to_radians());
        [
            Material::Hencky(elastic),
            Material::VonMises(VonMises {
                elastic,
                yield_stress: 2.0 * c,
                hardening: 1e5,
            }),
            Material::DruckerPrager(DruckerPrager::plane_strain_match(elastic, c, phi, phi)),
            Material::DruckerPrager(DruckerPrager::plane_strain_match(elastic, c, phi, psi)),
            Material::MohrCoulomb(MohrCoulomb {
                elastic,
                cohesion: c,
                friction: phi,
                dilation: phi,
            }),
            Material::MohrCoulomb(MohrCoulomb {
                elastic,
                cohesion: c,
                friction: phi,
                dilation: psi,
            }),
        ]
    }

    #[test]
    fn only_non_associated_flow_makes_the_tangent_unsymmetric() {
        let models = every_model();
        let stretch = Matrix2::new(0.004, 0.0, 0.0, -0.004);
        let sheared = Matrix2::new(0.002, 0.0011, -0.0006, -0.0017);
        for m in models {
            let yielded = m.respond(&m.initial_history(), &stretch, 1.0).history;
            let r = m.respond(&yielded, &sheared, 1.0);
            let flowing = r.history.plastic_strain > yielded.plastic_strain;
            assert_eq!(flowing, !matches!(m, Material::Hencky(_)), "{m:?}");
            let asymmetry = (r.tangent - r.tangent.transpose()).norm() / r.tangent.norm();
            if m.symmetric_tangent() {
                assert!(asymmetry < 1e-10, "{m:?}: {asymmetry:e}");
            } else {
                assert!(asymmetry > 1e-3, "{m:?}: {asymmetry:e}");
            }
        }
    }

    /// The point loop and the commit ask for a response without its
    /// tangent: it must be the full response's stress, history and Cauchy
    /// stress to the bit (the internal force and the committed state do
    /// not change with what the assembly asks for), in elastic and plastic
    /// steps of every model.
    #[test]
    fn a_response_without_its_tangent_is_the_same_response() {
        let stretch = Matrix2::new(0.004, 0.0, 0.0, -0.004);
        let sheared = Matrix2::new(0.002, 0.0011, -0.0006, -0.0017);
        let small_strain = Material::LinearElastic(Elastic::from_young_poisson(1e6, 0.3));
        for m in every_model().into_iter().chain([small_strain]) {
            let yielded = m.respond(&m.initial_history(), &stretch, 1.0).history;
            for (history, grad_u) in [(m.initial_history(), stretch), (yielded, sheared)] {
                let full = m.respond(&history, &grad_u, 0.9);
                let part = m.respond_without_tangent(&history, &grad_u, 0.9);
                assert_eq!(full.p, part.p, "{m:?}");
                assert_eq!(full.history, part.history, "{m:?}");
                assert_eq!(full.cauchy, part.cauchy, "{m:?}");
            }
        }
    }
}
