//! The constitutive models in three dimensions: the same models and return
//! maps as in plane strain ([`super::return_map`] and the model files),
//! with the kinematics of a full 3x3 `dF`.
//!
//! The trial elastic left Cauchy-Green tensor `b = dF b_n dF^T` is kept as
//! `b - I` ([`trial_excess`]), decomposed by its three eigenvalues, and
//! the model returns its three principal logarithmic strains exactly as in
//! plane strain (where the third is the out-of-plane one). `P = tau dF^-T`
//! and its tangent follow as in `hencky::piola_and_tangent`, over nine
//! directions of `dF`: `A[(3i + I, 3j + J)] = dP_iI / d(dF)_jJ`. The spins
//! of the principal directions of Mohr-Coulomb's moduli act on all three
//! pairs of directions.
//!
//! A plane-strain state (`dF` with `dF_zz = 1` and no out-of-plane shear)
//! gives the plane-strain response to round-off (the tests below), which
//! is what makes a slab one cell thick between rollers a plane-strain body.

use nalgebra::{Matrix3, SMatrix, SymmetricEigen, Vector3};

use super::return_map::{Moduli, Returned};
use super::{Elastic, Material};
use crate::material::drucker_prager::drucker_prager_return;
use crate::material::mohr_coulomb::mohr_coulomb_return;
use crate::material::von_mises::von_mises_return;

/// `dP / d(dF)`, flattened as in the module docs.
pub type Tangent3 = SMatrix<f64, 9, 9>;

/// What a point carries from step to step in 3D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct History3 {
    /// The finite-strain models: the elastic left Cauchy-Green tensor's
    /// excess over the identity, `b - I`; linear elasticity: the small
    /// strain.
    pub tensor: Matrix3<f64>,
    /// Accumulated plastic strain `alpha` (zero for the elastic models).
    pub plastic_strain: f64,
}

impl History3 {
    /// An undeformed, unstressed point's.
    pub fn virgin() -> Self {
        Self {
            tensor: Matrix3::zeros(),
            plastic_strain: 0.0,
        }
    }
}

/// What a model returns for a trial `dF` in 3D.
#[derive(Debug, Clone, Copy)]
pub struct Response3 {
    /// Stress paired with `dF` per unit reference volume.
    pub p: Matrix3<f64>,
    pub tangent: Tangent3,
    /// History to keep if the step converges.
    pub history: History3,
    /// Cauchy stress, symmetric.
    pub cauchy: Matrix3<f64>,
    /// As [`super::Response::off_flow_rule`].
    pub off_flow_rule: bool,
}

impl Material {
    /// The trial response to the displacement gradient `grad_u` of the step
    /// (`dF = I + grad_u`) from `history`, in 3D; `j_start` is the volume
    /// ratio at the step's start. As [`Material::respond`].
    pub fn respond_3d(&self, history: &History3, grad_u: &Matrix3<f64>, j_start: f64) -> Response3 {
        let df = Matrix3::identity() + grad_u;
        if let Material::LinearElastic(c) = self {
            return small_strain(c, &history.tensor, grad_u);
        }
        let excess = trial_excess(&history.tensor, grad_u);
        let eig = Spectral::of_excess(&excess);
        let strains = eig.log_strains();
        let alpha = history.plastic_strain;
        let returned = match self {
            Material::LinearElastic(_) => unreachable!("answered above"),
            Material::Hencky(c) => elastic_return(c, strains),
            Material::VonMises(m) => von_mises_return(m, alpha, strains),
            Material::DruckerPrager(m) => drucker_prager_return(m, strains),
            Material::MohrCoulomb(m) => mohr_coulomb_return(m, strains),
        };
        respond(history, &df, j_start, &eig, strains, &returned)
    }
}

/// Hencky's elastic "return": `tau = kappa tr(e) 1 + 2 mu dev(e)`.
fn elastic_return(c: &Elastic, strains: [f64; 3]) -> Returned {
    let trace: f64 = strains.iter().sum();
    Returned {
        tau: strains.map(|e| c.lambda * trace + 2.0 * c.mu * e),
        elastic_strains: strains,
        plastic_increment: 0.0,
        unit: [0.0; 3],
        moduli: Moduli::Invariant(super::return_map::InvariantModuli::elastic(c.bulk(), c.mu)),
        off_flow_rule: false,
    }
}

/// Geometrically linear elasticity: `eps = eps_n + sym(grad_u)`, `P = sigma`.
fn small_strain(c: &Elastic, eps_n: &Matrix3<f64>, h: &Matrix3<f64>) -> Response3 {
    let eps = eps_n + (h + h.transpose()) * 0.5;
    let sigma = Matrix3::identity() * (c.lambda * eps.trace()) + eps * (2.0 * c.mu);
    let delta = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
    let tangent = Tangent3::from_fn(|r, col| {
        let (i, ii, j, jj) = (r / 3, r % 3, col / 3, col % 3);
        c.lambda * delta(i, ii) * delta(j, jj)
            + c.mu * (delta(i, j) * delta(ii, jj) + delta(i, jj) * delta(ii, j))
    });
    Response3 {
        p: sigma,
        tangent,
        history: History3 {
            tensor: eps,
            plastic_strain: 0.0,
        },
        cauchy: sigma,
        off_flow_rule: false,
    }
}

/// `b - I` of the trial `b = dF b_n dF^T`, from `b_n - I` and `grad_u`, as
/// `hencky::trial_excess` in 2D.
fn trial_excess(b_n_excess: &Matrix3<f64>, grad_u: &Matrix3<f64>) -> Matrix3<f64> {
    let df = Matrix3::identity() + grad_u;
    grad_u + grad_u.transpose() + grad_u * grad_u.transpose() + df * b_n_excess * df.transpose()
}

/// The spectral decomposition of `b = sum_a l_a n_a n_a^T` given by `b - I`.
struct Spectral {
    /// `l_a - 1`.
    excess: [f64; 3],
    vectors: [Vector3<f64>; 3],
}

impl Spectral {
    fn of_excess(excess: &Matrix3<f64>) -> Self {
        let symmetric = (excess + excess.transpose()) * 0.5;
        let eig = SymmetricEigen::new(symmetric);
        Self {
            excess: [0, 1, 2].map(|a| eig.eigenvalues[a]),
            vectors: [0, 1, 2].map(|a| eig.eigenvectors.column(a).into_owned()),
        }
    }

    /// `ln(l_a) / 2`.
    fn log_strains(&self) -> [f64; 3] {
        self.excess.map(|x| 0.5 * x.ln_1p())
    }

    /// `sum_a v_a n_a n_a^T`.
    fn compose(&self, v: [f64; 3]) -> Matrix3<f64> {
        (0..3)
            .map(|a| self.vectors[a] * self.vectors[a].transpose() * v[a])
            .sum()
    }

    /// `f_aa = 1/l_a`, `f_ab = (ln l_a - ln l_b)/(l_a - l_b)` (its series
    /// where they nearly coincide), as in 2D.
    fn log_derivative_weights(&self) -> [[f64; 3]; 3] {
        let l = self.excess.map(|x| 1.0 + x);
        std::array::from_fn(|a| {
            std::array::from_fn(|b| {
                let gap = self.excess[a] - self.excess[b];
                if a == b {
                    1.0 / l[a]
                } else if gap.abs() > 1e-8 * l[a].abs() {
                    (self.excess[a].ln_1p() - self.excess[b].ln_1p()) / gap
                } else {
                    let m = 0.5 * (l[a] + l[b]);
                    1.0 / m + gap * gap / (12.0 * m * m * m)
                }
            })
        })
    }

    /// The derivative of `ln(b)` along a symmetric `db`.
    fn log_derivative(&self, f: &[[f64; 3]; 3], db: &Matrix3<f64>) -> Matrix3<f64> {
        let mut out = Matrix3::zeros();
        for a in 0..3 {
            for b in 0..3 {
                let (na, nb) = (&self.vectors[a], &self.vectors[b]);
                out += na * nb.transpose() * (f[a][b] * na.dot(&(db * nb)));
            }
        }
        out
    }
}

/// `P`, its tangent, the history to keep and the Cauchy stress of a
/// returned trial state, as `return_map::respond` in 2D.
fn respond(
    state: &History3,
    df: &Matrix3<f64>,
    j_start: f64,
    eig: &Spectral,
    strains: [f64; 3],
    ret: &Returned,
) -> Response3 {
    let tau = eig.compose(ret.tau);
    let history = History3 {
        tensor: eig.compose(ret.elastic_strains.map(|e| (2.0 * e).exp_m1())),
        plastic_strain: state.plastic_strain + ret.plastic_increment,
    };
    let unit = eig.compose(ret.unit);
    // The spins of the principal directions, pair by pair.
    let spin = |a: usize, b: usize| match ret.moduli {
        Moduli::Principal(d) => {
            let gap = strains[a] - strains[b];
            if gap.abs() > 1e-9 {
                (ret.tau[a] - ret.tau[b]) / gap
            } else {
                d[a][a] - d[a][b]
            }
        }
        Moduli::Invariant(_) => 0.0,
    };
    let spins = [[0, 1], [0, 2], [1, 2]].map(|[a, b]| (a, b, spin(a, b)));
    let dtau = |de: &Matrix3<f64>| -> Matrix3<f64> {
        match ret.moduli {
            Moduli::Invariant(m) => {
                let tr = de.trace();
                let n_de = (unit.transpose() * de).trace();
                de * m.identity
                    + Matrix3::identity() * (m.trace * tr + m.tr_n * n_de)
                    + unit * (m.nn * n_de + m.n_tr * tr)
            }
            Moduli::Principal(d) => {
                let n = &eig.vectors;
                let de_p = [0, 1, 2].map(|a| n[a].dot(&(de * n[a])));
                let mut out: Matrix3<f64> = (0..3)
                    .map(|a| {
                        n[a] * n[a].transpose()
                            * (d[a][0] * de_p[0] + d[a][1] * de_p[1] + d[a][2] * de_p[2])
                    })
                    .sum();
                for &(a, b, w) in &spins {
                    let shear = n[a].dot(&(de * n[b]));
                    out += (n[a] * n[b].transpose() + n[b] * n[a].transpose()) * (w * shear);
                }
                out
            }
        }
    };
    let df_inv_t = df
        .try_inverse()
        .map(|m| m.transpose())
        .unwrap_or_else(|| Matrix3::from_element(f64::NAN));
    let b_n = Matrix3::identity() + state.tensor;
    let weights = eig.log_derivative_weights();
    let mut tangent = Tangent3::zeros();
    for j in 0..3 {
        for jj in 0..3 {
            let mut dir = Matrix3::zeros();
            dir[(j, jj)] = 1.0;
            let db = dir * b_n * df.transpose() + df * b_n * dir.transpose();
            let de = eig.log_derivative(&weights, &db) * 0.5;
            let dp = dtau(&de) * df_inv_t - tau * df_inv_t * dir.transpose() * df_inv_t;
            for i in 0..3 {
                for ii in 0..3 {
                    tangent[(3 * i + ii, 3 * j + jj)] = dp[(i, ii)];
                }
            }
        }
    }
    let j = j_start * df.determinant();
    Response3 {
        p: tau * df_inv_t,
        tangent,
        history,
        cauchy: tau / j,
        off_flow_rule: ret.off_flow_rule,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{DruckerPrager, History, MohrCoulomb, VonMises};
    use nalgebra::Matrix2;

    fn models() -> Vec<(&'static str, Material)> {
        let elastic = Elastic::from_young_poisson(1e7, 0.3);
        let degrees = f64::to_radians;
        vec![
            ("hencky", Material::Hencky(elastic)),
            ("linear", Material::LinearElastic(elastic)),
            (
                "von Mises",
                Material::VonMises(VonMises {
                    elastic,
                    yield_stress: 2e4,
                    hardening: 1e5,
                }),
            ),
            (
                "Drucker-Prager",
                Material::DruckerPrager(DruckerPrager::plane_strain_match(
                    elastic,
                    5e3,
                    degrees(30.0),
                    degrees(10.0),
                )),
            ),
            (
                "Mohr-Coulomb",
                Material::MohrCoulomb(MohrCoulomb {
                    elastic,
                    cohesion: 5e3,
                    friction: degrees(30.0),
                    dilation: degrees(10.0),
                }),
            ),
        ]
    }

    /// A 2D history as the 3D one it stands for: `b - I` with `b_zz - 1`.
    fn lifted(h: &History) -> History3 {
        let mut tensor = Matrix3::zeros();
        tensor.fixed_view_mut::<2, 2>(0, 0).copy_from(&h.tensor);
        tensor[(2, 2)] = h.zz;
        History3 {
            tensor,
            plastic_strain: h.plastic_strain,
        }
    }

    fn lift(m: &Matrix2<f64>) -> Matrix3<f64> {
        let mut out = Matrix3::zeros();
        out.fixed_view_mut::<2, 2>(0, 0).copy_from(m);
        out
    }

    /// Plane strain is the 3D models' `dF_zz = 1` case: from a history of
    /// two earlier steps (elastic and past yield), each model's 3D response
    /// to an in-plane `grad_u` is its plane-strain one, `P`, the Cauchy
    /// stress (with `zz`), the history and the in-plane block of the
    /// tangent, to round-off (the two eigen-solvers differ in their last
    /// bits). `P_zz` is the out-of-plane Kirchhoff stress, `J sigma_zz` (the
    /// small-strain model's `sigma_zz`), and
    /// the out-of-plane shears are zero.
    #[test]
    fn an_in_plane_deformation_gives_the_plane_strain_response() {
        let steps = [
            Matrix2::new(2e-4, 1e-4, -5e-5, -3e-4),
            Matrix2::new(-4e-3, 2.5e-3, 1e-3, 1.5e-3),
            Matrix2::new(-1.2e-2, 4e-3, -2e-3, 6e-3),
        ];
        for (name, model) in models() {
            let mut plane = model.initial_history();
            for (k, grad_u) in steps.iter().enumerate() {
                let r2 = model.respond(&plane, grad_u, 1.0);
                let r3 = model.respond_3d(&lifted(&plane), &lift(grad_u), 1.0);
                let scale = r2.p.norm().max(1.0);
                let tscale = r2.tangent.norm();
                for i in 0..3 {
                    for ii in 0..3 {
                        let expected = match (i, ii) {
                            (2, 2) if name == "linear" => r2.cauchy.zz,
                            (2, 2) => r2.cauchy.zz * (Matrix2::identity() + grad_u).determinant(),
                            (0..2, 0..2) => r2.p[(i, ii)],
                            _ => 0.0,
                        };
                        let got = r3.p[(i, ii)];
                        assert!(
                            (got - expected).abs() < 1e-9 * scale,
                            "{name} step {k}: P{i}{ii} {got} vs {expected}"
                        );
                    }
                }
                let sigma = [
                    r3.cauchy[(0, 0)],
                    r3.cauchy[(1, 1)],
                    r3.cauchy[(0, 1)],
                    r3.cauchy[(2, 2)],
                ];
                let expected = [
                    r2.cauchy.plane[0],
                    r2.cauchy.plane[1],
                    r2.cauchy.plane[2],
                    r2.cauchy.zz,
                ];
                for (g, e) in sigma.iter().zip(expected) {
                    assert!(
                        (g - e).abs() < 1e-9 * scale,
                        "{name} step {k}: {sigma:?} vs {expected:?}"
                    );
                }
                let history = lifted(&r2.history);
                assert!(
                    (r3.history.tensor - history.tensor).norm() < 1e-12,
                    "{name} step {k}: history"
                );
                assert!((r3.history.plastic_strain - history.plastic_strain).abs() < 1e-12);
                for i in 0..2 {
                    for ii in 0..2 {
                        for j in 0..2 {
                            for jj in 0..2 {
                                let a = r2.tangent[(2 * i + ii, 2 * j + jj)];
                                let b = r3.tangent[(3 * i + ii, 3 * j + jj)];
                                assert!(
                                    (a - b).abs() < 1e-8 * tscale,
                                    "{name} step {k}: A {a} vs {b}"
                                );
                            }
                        }
                    }
                }
                plane = r2.history;
            }
            if !model.is_elastic() {
                assert!(plane.plastic_strain > 0.0, "{name} flowed");
            }
        }
    }

    /// The 3D tangent is the derivative of `P`, for every model, about a
    /// general 3D deformation from a history past yield: central
    /// differences on all nine directions.
    #[test]
    fn the_tangent_is_the_derivative_of_the_stress() {
        let first = Matrix3::new(-6e-3, 1e-3, 2e-3, 5e-4, 3e-3, -1e-3, 1.5e-3, -2e-3, -4e-3);
        let grad_u = Matrix3::new(-3e-3, 2e-3, -1e-3, 1e-3, 2e-3, 1.5e-3, -5e-4, 1e-3, -5e-3);
        for (name, model) in models() {
            let history = model.respond_3d(&History3::virgin(), &first, 1.0).history;
            let r = model.respond_3d(&history, &grad_u, 1.0);
            if !model.is_elastic() {
                assert!(
                    r.history.plastic_strain > history.plastic_strain,
                    "{name} flows"
                );
            }
            let scale = r.tangent.norm();
            let eps = 1e-7;
            for col in 0..9 {
                let mut dir = Matrix3::zeros();
                dir[(col / 3, col % 3)] = eps;
                let plus = model.respond_3d(&history, &(grad_u + dir), 1.0).p;
                let minus = model.respond_3d(&history, &(grad_u - dir), 1.0).p;
                let fd = (plus - minus) / (2.0 * eps);
                for row in 0..9 {
                    let a = r.tangent[(row, col)];
                    let b = fd[(row / 3, row % 3)];
                    assert!(
                        (a - b).abs() < 1e-6 * scale,
                        "{name}: A[{row}, {col}] = {a}, difference {b}"
                    );
                }
            }
        }
    }

    /// Triaxial compression of a homogeneous sample, in Kirchhoff
    /// stresses (compression positive): confined isotropically to `p`,
    /// then shortened axially 2% in 200 steps with the lateral stress held
    /// at `p` (each step's lateral stretch found by Newton). The axial
    /// stress ends at the analytic strength, at two confinements:
    /// - von Mises, perfectly plastic: `sigma_1 = p + sigma_y`;
    /// - Mohr-Coulomb (phi = 30, psi = 0 and 30 degrees): `sigma_1 = p N +
    ///   2 c sqrt(N)`, `N = (1 + sin phi) / (1 - sin phi)`;
    /// - Drucker-Prager (`sqrt(J2) + eta m = xi c`, `m` the mean stress,
    ///   tension positive): `sigma_1 = (xi c + p (1/sqrt 3 + 2 eta / 3)) /
    ///   (1/sqrt 3 - eta / 3)`.
    ///
    /// The return maps are exact on the yield surface, so the tolerance is
    /// the lateral Newton's (1e-9 of the stress).
    #[test]
    fn triaxial_compression_ends_at_the_analytic_strength() {
        let elastic = Elastic::from_young_poisson(1e8, 0.3);
        let c = 1e4;
        let phi = 30f64.to_radians();
        let n = (1.0 + phi.sin()) / (1.0 - phi.sin());
        let dp = DruckerPrager::plane_strain_match(elastic, c, phi, phi);
        let cases = [
            Material::VonMises(VonMises {
                elastic,
                yield_stress: 5e4,
                hardening: 0.0,
            }),
            Material::MohrCoulomb(MohrCoulomb {
                elastic,
                cohesion: c,
                friction: phi,
                dilation: 0.0,
            }),
            Material::MohrCoulomb(MohrCoulomb {
                elastic,
                cohesion: c,
                friction: phi,
                dilation: phi,
            }),
            Material::DruckerPrager(dp),
        ];
        for p in [1e5, 4e5] {
            for model in cases {
                let strength = match model {
                    Material::VonMises(m) => p + m.yield_stress,
                    Material::MohrCoulomb(_) => p * n + 2.0 * c * n.sqrt(),
                    Material::DruckerPrager(m) => {
                        let r3 = 3f64.sqrt().recip();
                        (m.xi * c + p * (r3 + 2.0 * m.eta / 3.0)) / (r3 - m.eta / 3.0)
                    }
                    _ => unreachable!(),
                };
                // Kirchhoff stress of the step (dF diagonal: lateral, axial).
                let tau = |h: &History3, lateral: f64, axial: f64| {
                    let grad_u = Matrix3::from_diagonal(&Vector3::new(lateral, lateral, axial));
                    let r = model.respond_3d(h, &grad_u, 1.0);
                    (
                        r.cauchy * (Matrix3::identity() + grad_u).determinant(),
                        r.history,
                    )
                };
                // The lateral strain of a step that holds the lateral stress at -p.
                let lateral = |h: &History3, axial: f64, guess: f64| {
                    let mut x = guess;
                    for _ in 0..50 {
                        let f = tau(h, x, axial).0[(0, 0)] + p;
                        if f.abs() < 1e-10 * p {
                            return x;
                        }
                        let d = 1e-9;
                        let slope = (tau(h, x + d, axial).0[(0, 0)]
                            - tau(h, x - d, axial).0[(0, 0)])
                            / (2.0 * d);
                        x -= f / slope;
                    }
                    panic!("{model:?}: the lateral stress was not held at {p}");
                };
                // Isotropic confinement: an elastic volume change.
                let k = elastic.bulk();
                let e = (-p / (3.0 * k)).exp_m1();
                let mut history = tau(&History3::virgin(), e, e).1;
                let mut x = 0.0;
                let mut axial_stress = 0.0;
                for _ in 0..200 {
                    let axial = -1e-4;
                    x = lateral(&history, axial, x);
                    let (t, next) = tau(&history, x, axial);
                    axial_stress = -t[(2, 2)];
                    history = next;
                }
                assert!(
                    (axial_stress - strength).abs() < 1e-9 * strength,
                    "{model:?} at p = {p}: {axial_stress} against {strength}"
                );
                assert!(history.plastic_strain > 0.0);
            }
        }
    }
}
