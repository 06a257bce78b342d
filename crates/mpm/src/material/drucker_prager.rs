//! Drucker-Prager plasticity at finite strain, perfectly plastic, with a
//! dilation angle of its own: de Souza Neto, Peric & Owen (2008),
//! "Computational Methods for Plasticity", sections 8.3.3 (return to the
//! cone and to its apex) and 14 (finite strain), in the framework of
//! `return_map`.
//!
//! Yield and flow, with `p = tr(tau) / 3` (tension positive) and
//! `J = sqrt(J2(s))`:
//!
//! `Phi = J + eta p - xi c`,   `G = J + eta_flow p`.
//!
//! The cone is matched to Mohr-Coulomb in plane strain (de Souza Neto et
//! al., eq. 8.89): `eta = 3 tan(phi) / sqrt(9 + 12 tan^2 phi)`,
//! `xi = 3 / sqrt(9 + 12 tan^2 phi)`, and `eta_flow` the same of the
//! dilation angle `psi`. With associated flow (`psi = phi`) a state in
//! plane-strain plastic flow (no out-of-plane plastic strain) then meets
//! Mohr-Coulomb's criterion with `c` and `phi` in the plane, so plane-strain
//! collapse loads are Mohr-Coulomb's; at `phi = 0` the cone is the cylinder
//! `J = c`, von Mises with `sigma_y = sqrt(3) c`.
//!
//! The return in the trial logarithmic strains (`K` bulk, `G` shear
//! modulus): to the cone,
//! `dgamma = Phi_tr / (G + K eta eta_flow)`,
//! `s = (1 - G dgamma / J_tr) s_tr`, `p = p_tr - K eta_flow dgamma`;
//! when that would leave `J < 0`, to the apex `p = xi c / eta`, `s = 0`.
//! The accumulated plastic strain is the equivalent
//! `sqrt(2/3 |de_p|^2)` summed over steps, as von Mises' `alpha`.

use nalgebra::Matrix2;

use super::return_map::{
    InvariantModuli, Moduli, Predictor, Returned, Trial, off_apex_flow_rule, respond,
};
use super::{Elastic, History, Response};

/// The model's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DruckerPrager {
    pub elastic: Elastic,
    /// Cohesion `c` (Pa).
    pub cohesion: f64,
    /// `eta` of the yield function, from the friction angle.
    pub eta: f64,
    /// `xi` of the yield function, from the friction angle.
    pub xi: f64,
    /// `eta` of the flow potential, from the dilation angle.
    pub eta_flow: f64,
}

impl DruckerPrager {
    /// The plane-strain match to Mohr-Coulomb's `c`, friction angle `phi`
    /// and dilation angle `psi` (radians).
    pub fn plane_strain_match(elastic: Elastic, cohesion: f64, phi: f64, psi: f64) -> Self {
        Self::matched_to_tangents(elastic, cohesion, phi.tan(), psi.tan())
    }

    /// The match to `c`, `tan(phi)` and `tan(psi)`: `eta = 3 t / sqrt(9 +
    /// 12 t^2)` and `xi = 3 / sqrt(9 + 12 t^2)`, so that `t = eta / xi`.
    fn matched_to_tangents(elastic: Elastic, cohesion: f64, tan_phi: f64, tan_psi: f64) -> Self {
        let matched = |t: f64| {
            let root = (9.0 + 12.0 * t * t).sqrt();
            (3.0 * t / root, 3.0 / root)
        };
        let (eta, xi) = matched(tan_phi);
        Self {
            elastic,
            cohesion,
            eta,
            xi,
            eta_flow: matched(tan_psi).0,
        }
    }

    /// The match with `c`, `tan(phi)` and `tan(psi)` divided by `factor`
    /// (strength reduction). `tan(psi)` comes back from `eta_flow` as
    /// `3 eta_flow / sqrt(9 - 12 eta_flow^2)`.
    pub fn reduced(&self, factor: f64) -> Self {
        let tan_phi = self.eta / self.xi;
        let e = self.eta_flow;
        let tan_psi = 3.0 * e / (9.0 - 12.0 * e * e).sqrt();
        Self::matched_to_tangents(
            self.elastic,
            self.cohesion / factor,
            tan_phi / factor,
            tan_psi / factor,
        )
    }
}

/// The trial response to `dF = I + grad_u` from `state`, with the state to keep if the
/// step converges; as `von_mises`.
pub(super) fn drucker_prager(
    m: &DruckerPrager,
    state: &History,
    grad_u: &Matrix2<f64>,
    j_start: f64,
    want_tangent: bool,
) -> Response {
    let df = &(Matrix2::identity() + grad_u);
    let trial = Trial::new(state, grad_u);
    let returned = drucker_prager_return(m, trial.strains);
    respond(state, df, j_start, &trial, &returned, want_tangent)
}

/// The return of the trial's principal logarithmic `strains`, in any
/// dimension (perfectly plastic: the accumulated plastic strain is only
/// reported).
pub(super) fn drucker_prager_return(m: &DruckerPrager, strains: [f64; 3]) -> Returned {
    let Elastic { mu, .. } = m.elastic;
    let bulk = m.elastic.bulk();
    let Predictor {
        volumetric,
        deviator,
        unit,
        norm,
    } = Predictor::new(strains, mu);
    let j_trial = norm / 2f64.sqrt();
    let p_trial = bulk * volumetric;
    let strength = m.xi * m.cohesion;
    let phi_trial = j_trial + m.eta * p_trial - strength;
    let scale = strength + m.eta * p_trial.abs() + j_trial;
    let elastic = Returned {
        tau: deviator.map(|e| p_trial + 2.0 * mu * e),
        elastic_strains: strains,
        plastic_increment: 0.0,
        unit,
        moduli: Moduli::Invariant(InvariantModuli::elastic(bulk, mu)),
        off_flow_rule: false,
    };
    if phi_trial <= 1e-12 * scale {
        elastic
    } else {
        let a = mu + bulk * m.eta * m.eta_flow;
        let dgamma = phi_trial / a;
        if j_trial - mu * dgamma >= 0.0 {
            to_cone(m, &elastic, volumetric, deviator, j_trial, dgamma)
        } else {
            to_apex(m, &elastic, volumetric, norm)
        }
    }
}

/// The return to the cone's smooth part by `dgamma`.
fn to_cone(
    m: &DruckerPrager,
    elastic: &Returned,
    volumetric: f64,
    deviator: [f64; 3],
    j_trial: f64,
    dgamma: f64,
) -> Returned {
    let Elastic { mu, .. } = m.elastic;
    let bulk = m.elastic.bulk();
    let theta = 1.0 - mu * dgamma / j_trial;
    let p = bulk * (volumetric - m.eta_flow * dgamma);
    let a = mu + bulk * m.eta * m.eta_flow;
    // dgamma = (sqrt(2) G N:de + eta K tr(de)) / a; J_tr and p_tr move
    // with the trial strain, theta with J_tr and dgamma.
    let root2 = 2f64.sqrt();
    Returned {
        tau: deviator.map(|e| p + 2.0 * mu * theta * e),
        elastic_strains: deviator.map(|e| p / (3.0 * bulk) + theta * e),
        plastic_increment: (2.0f64 / 3.0).sqrt()
            * dgamma
            * (0.5 + m.eta_flow * m.eta_flow / 3.0).sqrt(),
        unit: elastic.unit,
        moduli: Moduli::Invariant(InvariantModuli {
            identity: 2.0 * mu * theta,
            trace: bulk - 2.0 * mu * theta / 3.0 - bulk * bulk * m.eta * m.eta_flow / a,
            nn: 2.0 * mu * mu * (dgamma / j_trial - 1.0 / a),
            n_tr: -root2 * mu * m.eta * bulk / a,
            tr_n: -root2 * mu * bulk * m.eta_flow / a,
        }),
        off_flow_rule: false,
    }
}

/// The return to the apex `p = xi c / eta`: the whole trial deviator and
/// the volume change past the apex's are plastic, and the stress no longer
/// moves with the strain (perfect plasticity). The flow rule takes that
/// volume change only with dilation ([`off_apex_flow_rule`]; the cone's
/// flow vectors at the apex make `sqrt(2) eta_g` of volume per unit
/// deviatoric plastic strain, and more as their deviators cancel).
fn to_apex(m: &DruckerPrager, elastic: &Returned, volumetric: f64, deviator_norm: f64) -> Returned {
    let Elastic { mu, .. } = m.elastic;
    let bulk = m.elastic.bulk();
    let p = m.xi * m.cohesion / m.eta;
    let plastic_volume = volumetric - p / bulk;
    let plastic_deviator = deviator_norm / (2.0 * mu);
    Returned {
        tau: [p; 3],
        elastic_strains: [p / (3.0 * bulk); 3],
        plastic_increment: (2.0f64 / 3.0).sqrt()
            * (plastic_deviator.powi(2) + plastic_volume.powi(2) / 3.0).sqrt(),
        unit: elastic.unit,
        moduli: Moduli::Invariant(InvariantModuli::default()),
        off_flow_rule: off_apex_flow_rule(
            plastic_volume,
            2f64.sqrt() * m.eta_flow * plastic_deviator,
            m.eta_flow > 0.0,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::VonMises;
    use crate::material::von_mises::von_mises;

    /// A stiff clay-like soil: E = 20 MPa, nu = 0.3, c = 10 kPa.
    fn soil(phi_degrees: f64, psi_degrees: f64) -> DruckerPrager {
        DruckerPrager::plane_strain_match(
            Elastic::from_young_poisson(20e6, 0.3),
            10e3,
            phi_degrees.to_radians(),
            psi_degrees.to_radians(),
        )
    }

    fn virgin() -> History {
        History::elastic(Matrix2::zeros())
    }

    /// `(J, p)` of a Cauchy stress (Kirchhoff when `J = 1`).
    fn invariants(r: &Response) -> (f64, f64) {
        let [xx, yy, xy] = r.cauchy.plane;
        let zz = r.cauchy.zz;
        let p = (xx + yy + zz) / 3.0;
        let j2 = 0.5 * ((xx - p).powi(2) + (yy - p).powi(2) + (zz - p).powi(2)) + xy * xy;
        (j2.sqrt(), p)
    }

    /// Plane-strain isochoric stretch `diag(l, 1/l)` from the virgin state,
    /// solved by hand: `p_tr = 0`, `J_tr = 2 G ln(l)`, so
    /// `dgamma = (J_tr - xi c) / (G + K eta eta_flow)`, `J = J_tr - G
    /// dgamma`, `p = -K eta_flow dgamma`. The state is on the cone, and a
    /// small release from it is elastic.
    #[test]
    fn a_stretch_past_yield_returns_to_the_cone_as_solved_by_hand() {
        for (phi, psi) in [(20.0, 20.0), (30.0, 0.0), (0.0, 0.0)] {
            let m = soil(phi, psi);
            let Elastic { mu, .. } = m.elastic;
            let bulk = m.elastic.bulk();
            let l: f64 = 1.002;
            let r = drucker_prager(
                &m,
                &virgin(),
                &(Matrix2::new(l, 0.0, 0.0, 1.0 / l) - Matrix2::identity()),
                1.0,
                true,
            );
            let j_trial = 2.0 * mu * l.ln();
            let dgamma = (j_trial - m.xi * m.cohesion) / (mu + bulk * m.eta * m.eta_flow);
            assert!(dgamma > 0.0, "the stretch yields");
            let (j, p) = invariants(&r);
            let tol = 1e-9 * m.cohesion;
            assert!(
                (j - (j_trial - mu * dgamma)).abs() < tol,
                "phi {phi}: J {j}"
            );
            assert!(
                (p + bulk * m.eta_flow * dgamma).abs() < tol,
                "phi {phi}: p {p}"
            );
            assert!(
                (j + m.eta * p - m.xi * m.cohesion).abs() < tol,
                "on the cone"
            );
            let release = Matrix2::new(0.9999, 0.0, 0.0, 1.0 / 0.9999);
            let u = drucker_prager(&m, &r.history, &(release - Matrix2::identity()), 1.0, true);
            assert_eq!(u.history.plastic_strain, r.history.plastic_strain);
            let (j_after, p_after) = invariants(&u);
            assert!(
                j_after + m.eta * p_after < m.xi * m.cohesion,
                "inside after release"
            );
        }
    }

    /// With no friction the cone is von Mises' cylinder with
    /// `sigma_y = sqrt(3) c`: the same response to the same step.
    #[test]
    fn without_friction_it_is_von_mises() {
        let m = soil(0.0, 0.0);
        let vm = VonMises {
            elastic: m.elastic,
            yield_stress: 3f64.sqrt() * m.cohesion,
            hardening: 0.0,
        };
        let df = Matrix2::new(1.003, 0.001, -0.0004, 0.998);
        let a = drucker_prager(&m, &virgin(), &(df - Matrix2::identity()), 1.0, true);
        let b = von_mises(&vm, &virgin(), &(df - Matrix2::identity()), 1.0, true);
        assert!(a.history.plastic_strain > 0.0);
        assert!((a.p - b.p).norm() < 1e-9 * m.cohesion);
        assert!((a.tangent - b.tangent).norm() < 1e-9 * b.tangent.norm());
        assert!((a.history.plastic_strain - b.history.plastic_strain).abs() < 1e-12);
    }

    /// The plane-strain match, checked against Mohr-Coulomb itself: in
    /// associated flow with no out-of-plane plastic strain, the in-plane
    /// principal stresses meet `(s1 - s2) / 2 = c cos(phi) - (s1 + s2) / 2
    /// sin(phi)`. The trial's out-of-plane strain is found (by bisection)
    /// for which the return leaves the out-of-plane strain elastic.
    #[test]
    fn in_plane_strain_flow_the_cone_is_mohr_coulomb() {
        for phi in [10.0f64, 20.0, 35.0] {
            let m = soil(phi, phi);
            let df = Matrix2::new(0.99, 0.0, 0.0, 1.0 / 0.99);
            let zz_plastic = |e_zz: f64| {
                let state = History {
                    zz: (2.0 * e_zz).exp_m1(),
                    ..virgin()
                };
                let r = drucker_prager(&m, &state, &(df - Matrix2::identity()), 1.0, true);
                (e_zz - 0.5 * r.history.zz.ln_1p(), r)
            };
            let (mut lo, mut hi) = (-0.008, 0.005);
            assert!(
                zz_plastic(lo).0 * zz_plastic(hi).0 < 0.0,
                "phi {phi}: the bracket holds the root"
            );
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if zz_plastic(mid).0 * zz_plastic(lo).0 > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let (_, r) = zz_plastic(0.5 * (lo + hi));
            assert!(r.history.plastic_strain > 0.0, "phi {phi}: plastic flow");
            // Kirchhoff stress: Cauchy times J = det(dF).
            let [xx, yy, xy] = r.cauchy.plane.map(|s| s * df.determinant());
            let radius = (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
            let centre = 0.5 * (xx + yy);
            let (s, c) = phi.to_radians().sin_cos();
            let mohr_coulomb = m.cohesion * c - centre * s;
            assert!(
                (radius - mohr_coulomb).abs() < 1e-6 * m.cohesion,
                "phi {phi}: radius {radius}, Mohr-Coulomb {mohr_coulomb}"
            );
        }
    }

    /// Past the apex without dilation the cone's flow keeps the volume, so
    /// an expansion to the apex is off the flow rule; with dilation it is
    /// not (the test above).
    #[test]
    fn without_dilation_an_expansion_to_the_apex_is_off_the_flow_rule() {
        let expand = Matrix2::new(1.01, 0.0, 0.0, 1.008);
        for (psi, off) in [(0.0, true), (1.0, false), (20.0, false)] {
            let r = drucker_prager(&soil(20.0, psi), &virgin(), &expand, 1.0, true);
            assert_eq!(r.off_flow_rule, off, "psi {psi}");
        }
    }

    /// Stretched equally both ways far past the apex's tension: the stress
    /// is the apex's `xi c / eta` all round.
    #[test]
    fn an_expansion_past_the_apex_returns_to_it() {
        let m = soil(20.0, 20.0);
        let r = drucker_prager(
            &m,
            &virgin(),
            &(Matrix2::new(1.01, 0.0, 0.0, 1.01) - Matrix2::identity()),
            1.0,
            true,
        );
        let apex = m.xi * m.cohesion / m.eta;
        // Cauchy = Kirchhoff / J.
        let j = 1.01f64 * 1.01;
        for s in [r.cauchy.plane[0], r.cauchy.plane[1], r.cauchy.zz] {
            assert!((s * j - apex).abs() < 1e-9 * apex, "{s} vs {apex}");
        }
        assert!(r.cauchy.plane[2].abs() < 1e-9 * apex);
    }

    /// The tangent against central differences of `P`: on the cone
    /// (associated and not, from a yielded history, with a turned, sheared
    /// increment), at the apex, and in the elastic range.
    #[test]
    fn the_tangent_is_the_derivative_of_the_return_map() {
        let sheared = Matrix2::new(1.002, 0.0011, -0.0006, 0.9983);
        let cases = [
            ("cone, associated", soil(20.0, 20.0), sheared),
            ("cone, non-associated", soil(30.0, 5.0), sheared),
            (
                "apex",
                soil(20.0, 20.0),
                Matrix2::new(1.01, 0.002, 0.001, 1.012),
            ),
            (
                "elastic",
                soil(20.0, 20.0),
                Matrix2::new(1.00001, 0.0, 0.0, 0.99999),
            ),
        ];
        for (name, m, df) in cases {
            // A yielded history: the stretch of the test above.
            let state = drucker_prager(
                &m,
                &virgin(),
                &(Matrix2::new(1.002, 0.0, 0.0, 1.0 / 1.002) - Matrix2::identity()),
                1.0,
                true,
            )
            .history;
            let state = if name == "elastic" { virgin() } else { state };
            let plastic = drucker_prager(&m, &state, &(df - Matrix2::identity()), 1.0, true)
                .history
                .plastic_strain
                > state.plastic_strain;
            assert_eq!(
                plastic,
                name != "elastic",
                "{name}: the case is what it says"
            );
            crate::material::assert_tangent_is_the_derivative(
                |df| drucker_prager(&m, &state, &(df - Matrix2::identity()), 1.0, true),
                &df,
                1e-9,
                1e-6,
                name,
            );
        }
    }
}
