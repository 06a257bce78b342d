//! J2 (von Mises) plasticity at finite strain with linear isotropic
//! hardening: Simo (1992), "Algorithms for static and dynamic multiplicative
//! plasticity that preserve the classical return mapping schemes of the
//! infinitesimal theory", CMAME 99; de Souza Neto, Peric & Owen (2008),
//! "Computational Methods for Plasticity", ch. 14.
//!
//! The elastic predictor is the trial elastic left Cauchy-Green tensor
//! `b_tr = dF b_n dF^T` (plane strain: its out-of-plane component carried
//! from the step's start, `dF_zz = 1`). In its principal directions the
//! logarithmic strains `e_i = ln(l_i) / 2` (three of them) give the
//! Kirchhoff stress `tau = kappa tr(e) 1 + 2 mu dev(e)`, and the return to
//! the yield surface `q = sigma_y + H alpha` (`q = sqrt(3/2) |s|`) is the
//! radial return of the small-strain theory in those strains
//! (`return_map`):
//!
//! `dgamma = (q_tr - sigma_y - H alpha_n) / (3 mu + H)`,
//! `s = (1 - 3 mu dgamma / q_tr) s_tr`, `alpha = alpha_n + dgamma`,
//!
//! and the exponential map writes the plastic flow back into
//! `b = sum exp(2 e_i) n_i n_i^T`. The algorithmic tangent in those strains
//! is `kappa 1 (x) 1 + 2 mu theta I_dev - 6 mu^2 (1 / (3 mu + H) -
//! dgamma / q_tr) N (x) N` with `theta = 1 - 3 mu dgamma / q_tr` and `N`
//! the unit trial deviator; it is chained to `dP / d(dF)` as the Hencky
//! model's (`hencky::piola_and_tangent`).

use nalgebra::Matrix2;

use super::return_map::{InvariantModuli, Moduli, Predictor, Returned, Trial, respond};
use super::{Elastic, History, Response};

/// The model's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VonMises {
    pub elastic: Elastic,
    /// Initial uniaxial yield stress `sigma_y` (Pa).
    pub yield_stress: f64,
    /// Linear isotropic hardening modulus `H` (Pa): `sigma_y + H alpha`.
    pub hardening: f64,
}

/// The trial response to `dF = I + grad_u` from `state` (`tensor`: in-plane
/// `b - I`, `zz`: `b_zz - 1`, `plastic_strain`: `alpha`), with the state to keep if the step
/// converges. `j_start` is the volume ratio at the step's start.
pub(super) fn von_mises(
    m: &VonMises,
    state: &History,
    grad_u: &Matrix2<f64>,
    j_start: f64,
    want_tangent: bool,
) -> Response {
    let df = &(Matrix2::identity() + grad_u);
    let trial = Trial::new(state, grad_u);
    let returned = von_mises_return(m, state.plastic_strain, trial.strains);
    respond(state, df, j_start, &trial, &returned, want_tangent)
}

/// The return of the trial's principal logarithmic `strains` from the
/// accumulated plastic strain `alpha_n`, in any dimension.
pub(super) fn von_mises_return(m: &VonMises, alpha_n: f64, strains: [f64; 3]) -> Returned {
    let Elastic { mu, .. } = m.elastic;
    let kappa = m.elastic.bulk();
    let Predictor {
        volumetric,
        deviator,
        unit,
        norm,
    } = Predictor::new(strains, mu);
    let q_trial = (1.5f64).sqrt() * norm;
    let yield_now = m.yield_stress + m.hardening * alpha_n;
    let mut moduli = InvariantModuli::elastic(kappa, mu);
    let dgamma = if q_trial > yield_now * (1.0 + 1e-12) {
        let dgamma = (q_trial - yield_now) / (3.0 * mu + m.hardening);
        let theta = 1.0 - 3.0 * mu * dgamma / q_trial;
        moduli.identity = 2.0 * mu * theta;
        moduli.trace = kappa - 2.0 * mu * theta / 3.0;
        moduli.nn = -6.0 * mu * mu * (1.0 / (3.0 * mu + m.hardening) - dgamma / q_trial);
        dgamma
    } else {
        0.0
    };
    // The deviator scaled back by theta = 1 - 3 mu dgamma / q_tr.
    let theta = moduli.identity / (2.0 * mu);
    let elastic_strains = [0, 1, 2].map(|i| volumetric / 3.0 + theta * deviator[i]);
    let tau = [0, 1, 2].map(|i| kappa * volumetric + 2.0 * mu * theta * deviator[i]);
    Returned {
        tau,
        elastic_strains,
        plastic_increment: dgamma,
        unit,
        moduli: Moduli::Invariant(moduli),
        off_flow_rule: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> VonMises {
        VonMises {
            elastic: Elastic::from_young_poisson(200e9, 0.3),
            yield_stress: 250e6,
            hardening: 0.0,
        }
    }

    /// Plane-strain isochoric stretch `diag(l, 1/l)` from the virgin state:
    /// the trial strains are `(ln l, -ln l, 0)`, deviatoric, so
    /// `q_tr = 2 sqrt(3) mu ln l`. Past yield the deviator is scaled back
    /// to `q = sigma_y + H alpha` with `alpha = (q_tr - sigma_y) / (3 mu +
    /// H)`: `tau_xx - tau_yy = (2 / sqrt(3)) q`, `tau_zz = (tau_xx +
    /// tau_yy) / 2 = 0`. Perfectly plastic, `tau_xx - tau_yy = 2 k` with
    /// `k = sigma_y / sqrt(3)`, the plane-strain shear strength.
    #[test]
    fn an_isochoric_stretch_past_yield_returns_to_the_surface() {
        for hardening in [0.0, 10e9] {
            let m = VonMises {
                hardening,
                ..steel()
            };
            let mu = m.elastic.mu;
            let l: f64 = 1.01;
            let df = Matrix2::new(l, 0.0, 0.0, 1.0 / l);
            let r = von_mises(
                &m,
                &History::elastic(Matrix2::zeros()),
                &(df - Matrix2::identity()),
                1.0,
                true,
            );
            let next = r.history;
            let q_trial = 2.0 * 3f64.sqrt() * mu * l.ln();
            let alpha = (q_trial - m.yield_stress) / (3.0 * mu + hardening);
            let q = m.yield_stress + hardening * alpha;
            let [sxx, syy, sxy] = r.cauchy.plane; // J = 1: Cauchy = Kirchhoff
            assert!(
                ((sxx - syy) - 2.0 / 3f64.sqrt() * q).abs() < 1e-6 * q,
                "{sxx} {syy}"
            );
            assert!((sxx + syy).abs() < 1e-6 * q && sxy.abs() < 1e-6 * q);
            assert!(r.cauchy.zz.abs() < 1e-6 * q);
            assert!(
                (next.plastic_strain - alpha).abs() < 1e-12,
                "{} {alpha}",
                next.plastic_strain
            );
            // The returned state is on the surface: q from the stresses.
            let s = [sxx, syy, r.cauchy.zz];
            let mean = s.iter().sum::<f64>() / 3.0;
            let q_now = (1.5 * s.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt();
            assert!((q_now - q).abs() < 1e-6 * q);
        }
    }

    /// The same stretch in ten steps, each from the state the last one
    /// kept: on this proportional path the return in logarithmic strains
    /// is exact, so the end state is the one-step state. Then a small
    /// release is elastic: the deviator falls by `2 mu` times the strain
    /// taken back and `alpha` stays.
    #[test]
    fn steps_add_up_and_unloading_is_elastic() {
        let m = VonMises {
            hardening: 10e9,
            ..steel()
        };
        let total: f64 = 1.01;
        let one = von_mises(
            &m,
            &History::elastic(Matrix2::zeros()),
            &(Matrix2::new(total, 0.0, 0.0, 1.0 / total) - Matrix2::identity()),
            1.0,
            true,
        );
        let mut state = History::elastic(Matrix2::zeros());
        let step = total.powf(0.1);
        let df = Matrix2::new(step, 0.0, 0.0, 1.0 / step);
        let mut last = None;
        for _ in 0..10 {
            let r = von_mises(&m, &state, &(df - Matrix2::identity()), 1.0, true);
            state = r.history;
            last = Some(r);
        }
        let r = last.expect("ten steps");
        for k in 0..3 {
            assert!((r.cauchy.plane[k] - one.cauchy.plane[k]).abs() < 1e-6 * m.yield_stress);
        }
        assert!((state.plastic_strain - one.history.plastic_strain).abs() < 1e-12);
        let back: f64 = 1.0001;
        let release = Matrix2::new(1.0 / back, 0.0, 0.0, back);
        let u = von_mises(&m, &state, &(release - Matrix2::identity()), 1.0, true);
        assert_eq!(u.history.plastic_strain, state.plastic_strain);
        let drop =
            (r.cauchy.plane[0] - r.cauchy.plane[1]) - (u.cauchy.plane[0] - u.cauchy.plane[1]);
        let expected = 2.0 * m.elastic.mu * 2.0 * back.ln();
        assert!(
            (drop - expected).abs() < 1e-6 * expected,
            "{drop} {expected}"
        );
    }

    /// The tangent against central differences of `P`, in plastic flow
    /// (with and without hardening, from a yielded history with a turned,
    /// sheared increment) and in the elastic range.
    #[test]
    fn the_tangent_is_the_derivative_of_the_return_map() {
        for (hardening, plastic) in [(0.0, true), (10e9, true), (0.0, false)] {
            let m = VonMises {
                hardening,
                ..steel()
            };
            // A yielded history (the isochoric stretch of the test above)
            // stretched further with some shear and volume change; or a
            // strain of 2e-4 from the virgin state, well inside the surface.
            let yielded = von_mises(
                &m,
                &History::elastic(Matrix2::zeros()),
                &(Matrix2::new(1.01, 0.0, 0.0, 1.0 / 1.01) - Matrix2::identity()),
                1.0,
                true,
            )
            .history;
            let (state, df) = if plastic {
                (yielded, Matrix2::new(1.004, 0.0012, -0.0007, 0.9975))
            } else {
                (
                    History::elastic(Matrix2::zeros()),
                    Matrix2::new(1.0002, 0.0001, -0.0001, 0.9999),
                )
            };
            let r = von_mises(&m, &state, &(df - Matrix2::identity()), 1.0, true);
            assert_eq!(
                r.history.plastic_strain > state.plastic_strain,
                plastic,
                "the case is what it says"
            );
            crate::material::assert_tangent_is_the_derivative(
                |df| von_mises(&m, &state, &(df - Matrix2::identity()), 1.0, true),
                &df,
                1e-8,
                1e-6,
                &format!("H {hardening}"),
            );
        }
    }
}
