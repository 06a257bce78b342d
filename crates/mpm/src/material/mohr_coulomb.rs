//! Mohr-Coulomb plasticity at finite strain, perfectly plastic, with a
//! dilation angle of its own, returned in principal stress space: de Souza
//! Neto, Peric & Owen (2008), "Computational Methods for Plasticity",
//! section 8.2 (boxes 8.4 to 8.7), in the framework of `return_map`.
//!
//! With the principal Kirchhoff stresses ordered `s1 >= s2 >= s3` (tension
//! positive; the out-of-plane one among them), the yield function of the
//! main plane and its flow vector are
//!
//! `Phi = (s1 - s3) + (s1 + s3) sin(phi) - 2 c cos(phi)`,
//! `n = (1 + sin(psi), 0, -(1 - sin(psi)))`.
//!
//! The trial state goes back along `D n` (`D` the elastic moduli in
//! principal strains) to the main plane; if that breaks the ordering it
//! goes to the edge it overshot: where the main plane meets the plane of
//! `(s1, s2)` (`s2 = s3`) or of `(s2, s3)` (`s1 = s2`), with two
//! multipliers; if one of those is negative or the ordering still breaks,
//! to the apex `s = c cot(phi)` (none without friction: Tresca). The
//! algorithmic moduli in principal strains are `D - D n_g A^-1 n_f^T D`
//! over the active planes (`A_ij = n_f,i . D n_g,j`), zero at the apex;
//! the tangent adds the spin of the principal directions
//! ([`super::return_map::Moduli`]).

use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector3};

use super::return_map::{Moduli, Returned, Trial, off_apex_flow_rule, respond};
use super::{Elastic, History, Response};

/// The model's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MohrCoulomb {
    pub elastic: Elastic,
    /// Cohesion `c` (Pa).
    pub cohesion: f64,
    /// Friction angle `phi` (radians).
    pub friction: f64,
    /// Dilation angle `psi` (radians).
    pub dilation: f64,
}

/// A plane of the yield surface: the major and minor principal stresses it
/// joins (indices into the ordered stresses).
#[derive(Clone, Copy)]
struct Plane(usize, usize);

impl MohrCoulomb {
    /// The model with `c`, `tan(phi)` and `tan(psi)` divided by `factor`
    /// (strength reduction).
    pub fn reduced(&self, factor: f64) -> Self {
        Self {
            elastic: self.elastic,
            cohesion: self.cohesion / factor,
            friction: (self.friction.tan() / factor).atan(),
            dilation: (self.dilation.tan() / factor).atan(),
        }
    }

    fn plane_vector(&self, plane: Plane, angle: f64) -> Vector3<f64> {
        let mut n = Vector3::zeros();
        n[plane.0] = 1.0 + angle.sin();
        n[plane.1] = -(1.0 - angle.sin());
        n
    }

    fn yield_value(&self, s: &Vector3<f64>, plane: Plane) -> f64 {
        let (a, b) = (s[plane.0], s[plane.1]);
        (a - b) + (a + b) * self.friction.sin() - 2.0 * self.cohesion * self.friction.cos()
    }

    /// The elastic moduli in principal strains: `lambda 1 1^T + 2 mu I`.
    fn moduli(&self) -> Matrix3<f64> {
        let Elastic { lambda, mu } = self.elastic;
        Matrix3::from_element(lambda) + Matrix3::identity() * (2.0 * mu)
    }

    /// The return to the active `planes` from the ordered trial stresses:
    /// the stresses, the multipliers, and the algorithmic moduli; `None` if
    /// the system is singular.
    fn return_to<const K: usize>(&self, s: &Vector3<f64>, planes: [Plane; K]) -> Option<Return<K>> {
        let d = self.moduli();
        let flow = planes.map(|p| d * self.plane_vector(p, self.dilation));
        let normal = planes.map(|p| d * self.plane_vector(p, self.friction));
        let a = SMatrix::<f64, K, K>::from_fn(|i, j| {
            self.plane_vector(planes[i], self.friction).dot(&flow[j])
        });
        let rhs = SVector::<f64, K>::from_fn(|i, _| self.yield_value(s, planes[i]));
        let a_inv = a.try_inverse()?;
        let gammas = a_inv * rhs;
        let mut stress = *s;
        let mut ep = d;
        for i in 0..K {
            stress -= flow[i] * gammas[i];
            for j in 0..K {
                ep -= flow[i] * normal[j].transpose() * a_inv[(i, j)];
            }
        }
        Some(Return {
            stress,
            multipliers: gammas.into(),
            moduli: ep,
        })
    }
}

/// A return to `K` planes.
struct Return<const K: usize> {
    stress: Vector3<f64>,
    multipliers: [f64; K],
    moduli: Matrix3<f64>,
}

impl<const K: usize> Return<K> {
    /// Ordered to within `tol`, with no negative multiplier.
    fn valid(&self, tol: f64) -> bool {
        ordered(&self.stress, tol) && self.multipliers.iter().all(|&g| g >= -tol)
    }
}

/// Whether `s` is ordered `s1 >= s2 >= s3` to within `tol`.
fn ordered(s: &Vector3<f64>, tol: f64) -> bool {
    s[0] >= s[1] - tol && s[1] >= s[2] - tol
}

/// The trial response to `dF = I + grad_u` from `state`, with the state to keep if the
/// step converges; as `von_mises`.
pub(super) fn mohr_coulomb(
    m: &MohrCoulomb,
    state: &History,
    grad_u: &Matrix2<f64>,
    j_start: f64,
    want_tangent: bool,
) -> Response {
    let df = &(Matrix2::identity() + grad_u);
    let trial = Trial::new(state, grad_u);
    let returned = mohr_coulomb_return(m, trial.strains);
    respond(state, df, j_start, &trial, &returned, want_tangent)
}

/// The return of the trial's principal logarithmic `strains`, in any
/// dimension.
pub(super) fn mohr_coulomb_return(m: &MohrCoulomb, strains: [f64; 3]) -> Returned {
    let Elastic { lambda, mu } = m.elastic;
    let e = Vector3::from(strains);
    let d = m.moduli();
    let tau_trial = d * e;
    // Order the principal stresses, largest first.
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| tau_trial[b].total_cmp(&tau_trial[a]));
    let s = Vector3::from_fn(|i, _| tau_trial[order[i]]);
    let scale = m.cohesion + s.abs().max();
    let tol = 1e-12 * scale;
    let main = Plane(0, 2);
    let mut at_apex = false;
    let elastic = m.yield_value(&s, main) <= tol;
    let (stress, ep) = if elastic {
        (s, d)
    } else {
        let on_plane = m.return_to(&s, [main]);
        // The edge the main plane's return overshot towards: s2 past s1
        // (s1 = s2, with the plane of (s2, s3)) or s3 past s2 (s2 = s3,
        // with the plane of (s1, s2)).
        let overshot_major = on_plane.as_ref().is_some_and(|r| r.stress[1] > r.stress[0]);
        let edge = if overshot_major {
            Plane(1, 2)
        } else {
            Plane(0, 1)
        };
        match on_plane {
            Some(r) if r.valid(tol) => (r.stress, r.moduli),
            _ => match m.return_to(&s, [main, edge]) {
                Some(r) if r.valid(tol) || m.friction == 0.0 => (r.stress, r.moduli),
                // Tresca's edges always hold; with friction, the apex.
                _ => {
                    at_apex = true;
                    (
                        Vector3::from_element(m.cohesion / m.friction.tan()),
                        Matrix3::zeros(),
                    )
                }
            },
        }
    };
    // Back to the trial's principal directions.
    let mut tau = [0.0; 3];
    let mut moduli = [[0.0; 3]; 3];
    for i in 0..3 {
        tau[order[i]] = stress[i];
        for j in 0..3 {
            moduli[order[i]][order[j]] = ep[(i, j)];
        }
    }
    // An elastic trial keeps its strains as they are: recovered from the
    // stresses, they would differ by round-off, and read as plastic flow.
    let mean_part = lambda / (3.0 * lambda + 2.0 * mu) * tau.iter().sum::<f64>();
    let elastic_strains = if elastic {
        strains
    } else {
        tau.map(|t| (t - mean_part) / (2.0 * mu))
    };
    let plastic_strains: [f64; 3] = std::array::from_fn(|i| strains[i] - elastic_strains[i]);
    let plastic = plastic_strains.iter().map(|e| e * e).sum::<f64>().sqrt();
    // At the apex the flow vectors of the six planes make `sin(psi)` of
    // volume per unit principal range each (`2 sin(psi)` against `2`),
    // and more as they cancel ([`off_apex_flow_rule`]).
    let off_flow_rule = at_apex && {
        let volume = plastic_strains.iter().sum::<f64>();
        let range = plastic_strains.iter().copied().fold(f64::MIN, f64::max)
            - plastic_strains.iter().copied().fold(f64::MAX, f64::min);
        off_apex_flow_rule(volume, m.dilation.sin() * range, m.dilation > 0.0)
    };
    Returned {
        tau,
        elastic_strains,
        plastic_increment: (2.0f64 / 3.0).sqrt() * plastic,
        unit: [0.0; 3],
        moduli: Moduli::Principal(moduli),
        off_flow_rule,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E = 20 MPa, nu = 0.3, c = 10 kPa.
    fn soil(phi_degrees: f64, psi_degrees: f64) -> MohrCoulomb {
        MohrCoulomb {
            elastic: Elastic::from_young_poisson(20e6, 0.3),
            cohesion: 10e3,
            friction: phi_degrees.to_radians(),
            dilation: psi_degrees.to_radians(),
        }
    }

    /// The trial of principal logarithmic strains `e` (x, y, zz) from the
    /// virgin state, and the `dF` that makes it: `b_zz` carries the
    /// out-of-plane one.
    fn trial(e: [f64; 3]) -> (History, Matrix2<f64>) {
        let state = History {
            tensor: Matrix2::zeros(),
            zz: (2.0 * e[2]).exp_m1(),
            plastic_strain: 0.0,
        };
        (state, Matrix2::new(e[0].exp(), 0.0, 0.0, e[1].exp()))
    }

    /// Principal Kirchhoff stresses (x, y, zz) of an axis-aligned response.
    fn principal(r: &Response, df: &Matrix2<f64>) -> Vector3<f64> {
        let j = df.determinant();
        Vector3::new(r.cauchy.plane[0], r.cauchy.plane[1], r.cauchy.zz) * j
    }

    /// Plane-strain isochoric stretch `diag(l, 1/l)` past yield, without
    /// dilation, solved by hand: the trial `2 mu (a, -a, 0)`, `a = ln l`,
    /// goes back along `D (1, 0, -1) = 2 mu (1, 0, -1)`, so `s_zz = 0`,
    /// `s_xx = -s_yy`, and the main plane gives `s_xx = c cos(phi)`.
    #[test]
    fn a_stretch_past_yield_returns_to_the_plane_as_solved_by_hand() {
        for phi in [0.0f64, 20.0, 35.0] {
            let m = soil(phi, 0.0);
            let a: f64 = 0.002;
            let (state, df) = trial([a, -a, 0.0]);
            let r = mohr_coulomb(&m, &state, &(df - Matrix2::identity()), 1.0, true);
            let s = principal(&r, &df);
            let expected = m.cohesion * phi.to_radians().cos();
            let tol = 1e-9 * m.cohesion;
            assert!((s[0] - expected).abs() < tol, "phi {phi}: {s}");
            assert!(
                (s[1] + expected).abs() < tol && s[2].abs() < tol,
                "phi {phi}: {s}"
            );
            let dgamma = a - expected / (2.0 * m.elastic.mu);
            let alpha = (2.0f64 / 3.0).sqrt() * 2f64.sqrt() * dgamma;
            assert!(
                (r.history.plastic_strain - alpha).abs() < 1e-12,
                "phi {phi}"
            );
        }
    }

    /// An elastic trial is not plastic flow: its plastic strain stays as
    /// it was, to the bit, so the point does not read as yielding.
    #[test]
    fn an_elastic_trial_accumulates_no_plastic_strain() {
        let (state, df) = trial([1e-4, -2e-4, 3e-5]);
        let r = mohr_coulomb(
            &soil(30.0, 0.0),
            &state,
            &(df - Matrix2::identity()),
            1.0,
            false,
        );
        assert_eq!(r.history.plastic_strain, 0.0);
    }

    /// Without dilation every flow vector keeps the volume, so the apex,
    /// which an expanding trial reaches by opening, is off the flow rule;
    /// with a little dilation the six planes' vectors together make any
    /// expansion. A trial on the main plane without dilation is not.
    #[test]
    fn without_dilation_an_expansion_to_the_apex_is_off_the_flow_rule() {
        for (psi, off) in [(0.0, true), (1.0, false), (20.0, false)] {
            let (state, df) = trial([0.01, 0.008, 0.009]);
            let r = mohr_coulomb(
                &soil(20.0, psi),
                &state,
                &(df - Matrix2::identity()),
                1.0,
                true,
            );
            assert_eq!(r.off_flow_rule, off, "psi {psi}");
        }
        let (state, df) = trial([0.002, -0.003, -0.0005]);
        let grad_u = df - Matrix2::identity();
        assert!(!mohr_coulomb(&soil(20.0, 0.0), &state, &grad_u, 1.0, true).off_flow_rule);
    }

    /// The six planes of the hexagonal pyramid, unordered.
    fn yield_values(m: &MohrCoulomb, s: &Vector3<f64>) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for a in 0..3 {
            for b in 0..3 {
                if a != b {
                    out.push((a, b, m.yield_value(s, Plane(a, b))));
                }
            }
        }
        out
    }

    /// Returns of every kind checked against the theory's conditions
    /// (Koiter's flow rule at edges): the stress is on the surface and
    /// inside every plane; the plastic strain `e_tr - D^-1 s` is a
    /// non-negative combination of the flow vectors of the planes it lies
    /// on (one on a plane, two on an edge), or it is at the apex
    /// `c cot(phi)`. Trials (tension positive): a stretch (plane),
    /// triaxial extension (the edge `s2 = s3`), triaxial compression (the
    /// edge `s1 = s2`)
    /// and an expansion (apex); associated and not.
    #[test]
    fn returns_of_every_kind_meet_the_flow_rule() {
        let cases = [
            ("plane", [0.002, -0.003, -0.0005], 1),
            ("edge s2 = s3", [0.002, -0.0025, -0.0025], 2),
            ("edge s1 = s2", [0.0015, 0.0015, -0.004], 2),
            ("apex", [0.01, 0.01, 0.01], 0),
        ];
        for (phi, psi) in [(20.0, 20.0), (30.0, 10.0)] {
            let m = soil(phi, psi);
            let d = m.moduli();
            for (name, e, active_planes) in cases {
                let (state, df) = trial(e);
                let r = mohr_coulomb(&m, &state, &(df - Matrix2::identity()), 1.0, true);
                let s = principal(&r, &df);
                let tol = 1e-7 * m.cohesion;
                let values = yield_values(&m, &s);
                assert!(
                    values.iter().all(|v| v.2 < tol),
                    "{name}: outside {values:?}"
                );
                assert!(!r.off_flow_rule, "{name}, psi {psi}");
                if active_planes == 0 {
                    let apex = m.cohesion / m.friction.tan();
                    assert!(
                        (s - Vector3::from_element(apex)).norm() < tol,
                        "{name}: {s}"
                    );
                    continue;
                }
                let on: Vec<_> = values.iter().filter(|v| v.2.abs() < tol).collect();
                assert_eq!(on.len(), active_planes, "{name}, phi {phi}: {values:?}");
                let plastic = Vector3::from(e) - d.try_inverse().unwrap() * s;
                // Least squares on the active planes' flow vectors, then
                // the residual and the signs.
                let flows: Vec<Vector3<f64>> = on
                    .iter()
                    .map(|v| m.plane_vector(Plane(v.0, v.1), m.dilation))
                    .collect();
                let basis = nalgebra::DMatrix::from_fn(3, flows.len(), |i, j| flows[j][i]);
                let rhs = nalgebra::DVector::from_column_slice(plastic.as_slice());
                let gammas =
                    (basis.transpose() * &basis).try_inverse().unwrap() * basis.transpose() * &rhs;
                let residual = (&basis * &gammas - &rhs).norm();
                assert!(
                    residual < 1e-9,
                    "{name}: the flow is off the planes' by {residual}"
                );
                assert!(
                    gammas.iter().all(|&g| g > 0.0),
                    "{name}: multipliers {gammas}"
                );
            }
        }
    }

    /// The tangent against central differences of `P`, turned off the
    /// principal axes by a small shear, at each kind of return and in the
    /// elastic range.
    #[test]
    fn the_tangent_is_the_derivative_of_the_return_map() {
        let shear = Matrix2::new(0.0, 0.0004, -0.0002, 0.0);
        let cases = [
            ("elastic", [0.0001, -0.00005, 0.0]),
            ("plane", [0.002, -0.003, -0.0005]),
            ("edge s2 = s3", [0.002, -0.0024, -0.0025]),
            ("edge s1 = s2", [0.0016, 0.0014, -0.004]),
            ("apex", [0.01, 0.012, 0.01]),
            ("confined", [0.003, -0.012, 0.0]),
        ];
        for (phi, psi) in [(20.0, 20.0), (30.0, 10.0), (30.0, 0.0), (0.0, 0.0)] {
            let m = soil(phi, psi);
            for (name, e) in cases {
                if phi == 0.0 && name == "apex" {
                    continue;
                }
                let (state, df) = trial(e);
                crate::material::assert_tangent_is_the_derivative(
                    |df| mohr_coulomb(&m, &state, &(df - Matrix2::identity()), 1.0, true),
                    &(df + shear),
                    1e-9,
                    1e-6,
                    &format!("{name}, phi {phi}, psi {psi}"),
                );
            }
        }
    }
}
