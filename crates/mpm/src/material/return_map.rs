//! What the plastic models share: the elastic predictor on the trial
//! elastic left Cauchy-Green tensor and the exponential map back to it
//! (Simo 1992; de Souza Neto, Peric & Owen 2008, ch. 14).
//!
//! The trial `b_tr = dF b_n dF^T` (plane strain: its out-of-plane
//! component carried from the step's start, `dF_zz = 1`) gives, in its
//! principal directions, three logarithmic strains `e_i = ln(l_i) / 2`. A
//! model returns them in those strains exactly as in the small-strain
//! theory ([`Returned`]); the elastic strains it keeps go back into
//! `b = sum exp(2 e_i) n_i n_i^T`, kept as `b - I` (with `expm1`, and the
//! trial's strains found from `b - I` with `ln_1p`) so that small strains
//! keep their relative precision (`hencky::trial_excess`).
//!
//! The returns of von Mises and Drucker-Prager are isotropic tensor
//! functions of the trial strain made of its trace and its unit deviator
//! `N`, so their derivative in those strains is a tensor expression
//! ([`InvariantModuli`], no spectral terms); Mohr-Coulomb's is given in
//! principal strains and adds the spin of the principal directions. Either
//! is chained to `dP / d(dF)` as the Hencky model's
//! (`hencky::piola_and_tangent`).

use nalgebra::Matrix2;

use super::hencky::{SymEigen2, piola_and_tangent, trial_excess};
use super::{CauchyStress, History, Response};

/// The elastic predictor of a step.
pub(super) struct Trial {
    eig: SymEigen2,
    /// Principal logarithmic strains: the two in-plane, then `zz`.
    pub strains: [f64; 3],
}

impl Trial {
    /// From the history (`b_n - I`, and `b_zz - 1` out of plane) and the
    /// step's `grad_u`, to the precision of `b - I` ([`trial_excess`]).
    pub fn new(state: &History, grad_u: &Matrix2<f64>) -> Self {
        let eig = SymEigen2::of_excess(&trial_excess(&state.tensor, grad_u));
        let [e0, e1] = eig.log_strains();
        let strains = [e0, e1, 0.5 * state.zz.ln_1p()];
        Self { eig, strains }
    }
}

/// The trace of principal strains and their deviator.
fn split(strains: [f64; 3]) -> (f64, [f64; 3]) {
    let volumetric = strains.iter().sum::<f64>();
    (volumetric, strains.map(|e| e - volumetric / 3.0))
}

/// The derivative of the returned Kirchhoff stress in the trial strains.
#[derive(Debug, Clone, Copy)]
pub(super) enum Moduli {
    /// A return made of the trace and the unit deviator `N`
    /// ([`Returned::unit`]) of the trial strain.
    Invariant(InvariantModuli),
    /// `d tau_a / d e_b` in the trial's principal strains (in-plane, then
    /// `zz`); the tangent adds the spin of the principal directions,
    /// `(tau_0 - tau_1) / (e_0 - e_1)` on the in-plane shear.
    Principal([[f64; 3]; 3]),
}

/// `dtau = identity de + trace tr(de) I + nn N (N : de) + n_tr N tr(de) +
/// tr_n I (N : de)`.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct InvariantModuli {
    pub identity: f64,
    pub trace: f64,
    pub nn: f64,
    pub n_tr: f64,
    pub tr_n: f64,
}

impl InvariantModuli {
    /// Hencky's: `kappa tr(de) I + 2 mu dev(de)`.
    pub fn elastic(kappa: f64, mu: f64) -> Self {
        Self {
            identity: 2.0 * mu,
            trace: kappa - 2.0 * mu / 3.0,
            ..Self::default()
        }
    }
}

/// A model's return in the principal trial strains.
pub(super) struct Returned {
    /// Principal Kirchhoff stresses (in-plane, then `zz`).
    pub tau: [f64; 3],
    /// Principal elastic logarithmic strains to keep.
    pub elastic_strains: [f64; 3],
    /// Increment of the accumulated plastic strain.
    pub plastic_increment: f64,
    /// Unit trial deviator (principal components), zero if there is none.
    pub unit: [f64; 3],
    pub moduli: Moduli,
    /// An apex return the flow rule cannot make ([`Response::off_flow_rule`]).
    pub off_flow_rule: bool,
}

/// The volume change beyond its flow rule an apex return may take in one
/// step: 1% of the point's volume. At the apex a frictional soil has no
/// strength left, and what it opens beyond its flow rule there is
/// separation, as under a tension cut-off: a point at the free surface
/// beside a footing opens by far less a step. A point pulled apart by
/// nodes that nothing else holds opens by much more: the rows measured
/// broken (`particles::admissible`) opened 19% and 145% in one step.
pub const APEX_SEPARATION: f64 = 0.01;

/// Whether an apex return is off its flow rule. At the apex of a
/// frictional surface the plastic strain may point anywhere in the cone of
/// the flow vectors of the planes (or the cone) meeting there; each adds
/// volume at the rate the dilation sets for its shear, so the cone holds
/// the strains whose volume change `volume` is at least `least`, the
/// least the dilation gives their shear (Drucker-Prager: `sqrt(2) eta_g
/// |dev|`; Mohr-Coulomb: `sin(psi)` times the principal range). Without
/// dilation every flow vector keeps the volume: the volume change must be
/// zero. What is beyond that is separation, admissible up to
/// [`APEX_SEPARATION`].
pub(super) fn off_apex_flow_rule(volume: f64, least: f64, dilates: bool) -> bool {
    let beyond = if dilates {
        least - volume
    } else {
        volume.abs()
    };
    beyond > APEX_SEPARATION
}

/// The response of a returned trial state: `P`, its tangent, the history
/// to keep (the exponential map of the elastic strains) and the Cauchy
/// stress on `J = j_start det(dF)`; without `want_tangent`, the tangent is
/// left zero.
pub(super) fn respond(
    state: &History,
    df: &Matrix2<f64>,
    j_start: f64,
    trial: &Trial,
    ret: &Returned,
    want_tangent: bool,
) -> Response {
    let eig = &trial.eig;
    let in_plane = |v: [f64; 3]| -> Matrix2<f64> {
        (0..2)
            .map(|k| eig.vectors[k] * eig.vectors[k].transpose() * v[k])
            .sum()
    };
    let tau_plane = in_plane(ret.tau);
    let next = History {
        tensor: in_plane(ret.elastic_strains.map(|e| (2.0 * e).exp_m1())),
        zz: (2.0 * ret.elastic_strains[2]).exp_m1(),
        plastic_strain: state.plastic_strain + ret.plastic_increment,
    };
    // An in-plane strain increment: its zz component is zero (dF_zz = 0).
    let n_plane = in_plane(ret.unit);
    let [n0, n1] = eig.vectors;
    let spin = match ret.moduli {
        Moduli::Principal(d) => {
            let gap = trial.strains[0] - trial.strains[1];
            if gap.abs() > 1e-9 {
                (ret.tau[0] - ret.tau[1]) / gap
            } else {
                d[0][0] - d[0][1]
            }
        }
        Moduli::Invariant(_) => 0.0,
    };
    let dtau = |de: &Matrix2<f64>| -> Matrix2<f64> {
        match ret.moduli {
            Moduli::Invariant(m) => {
                let tr = de.trace();
                let n_de = (n_plane.transpose() * de).trace();
                de * m.identity
                    + Matrix2::identity() * (m.trace * tr + m.tr_n * n_de)
                    + n_plane * (m.nn * n_de + m.n_tr * tr)
            }
            Moduli::Principal(d) => {
                let de_p = [n0.dot(&(de * n0)), n1.dot(&(de * n1))];
                let shear = n0.dot(&(de * n1));
                (0..2)
                    .map(|a| {
                        eig.vectors[a]
                            * eig.vectors[a].transpose()
                            * (d[a][0] * de_p[0] + d[a][1] * de_p[1])
                    })
                    .sum::<Matrix2<f64>>()
                    + (n0 * n1.transpose() + n1 * n0.transpose()) * (spin * shear)
            }
        }
    };
    let b_n = Matrix2::identity() + state.tensor;
    let (p, tangent) = piola_and_tangent(&b_n, df, eig, &tau_plane, dtau, want_tangent);
    let j = j_start * df.determinant();
    Response {
        p,
        tangent,
        history: next,
        cauchy: CauchyStress {
            plane: [
                tau_plane[(0, 0)] / j,
                tau_plane[(1, 1)] / j,
                tau_plane[(0, 1)] / j,
            ],
            zz: ret.tau[2] / j,
        },
        off_flow_rule: ret.off_flow_rule,
    }
}

/// The elastic predictor of the invariant return maps, in any dimension:
/// of the trial's principal logarithmic strains, their trace and deviator,
/// and the unit direction and norm of its deviatoric Kirchhoff stress
/// `2 mu e_dev` (shear modulus `mu`).
pub(super) struct Predictor {
    pub volumetric: f64,
    pub deviator: [f64; 3],
    pub unit: [f64; 3],
    pub norm: f64,
}

impl Predictor {
    pub fn new(strains: [f64; 3], mu: f64) -> Self {
        let (volumetric, deviator) = split(strains);
        let (unit, norm) = unit(deviator.map(|e| 2.0 * mu * e));
        Self {
            volumetric,
            deviator,
            unit,
            norm,
        }
    }
}

/// `v / |v|`, or zero for a zero vector.
pub(super) fn unit(v: [f64; 3]) -> ([f64; 3], f64) {
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm > 0.0 {
        (v.map(|x| x / norm), norm)
    } else {
        ([0.0; 3], 0.0)
    }
}
