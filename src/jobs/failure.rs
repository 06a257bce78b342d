//! Why a job failed: the one definition of the failure document stored in
//! `jobs.error` and served as a job's `error` (see `openapi.yaml`).

use mpm::SolveError;
use serde::Serialize;

/// What went wrong, by the name the API gives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// Newton did not converge within its iteration cap.
    NotConverged,
    Diverged,
    /// A material point's deformation gradient lost its positive determinant.
    InvertedPoint,
    /// A material point's trial state was otherwise not admissible however
    /// far the step was cut (`mpm::particles::admissible`): its volume grew
    /// or shrank more than fourfold in a step, its stress was not finite, or
    /// its return map left the flow rule.
    InadmissiblePoint,
    LinearSolve,
    /// Material left the grid's extent.
    LeftGrid,
    /// A step converged to results that are not finite numbers.
    NonFinite,
    /// The per-job wall-time limit was reached.
    TimeLimit,
    /// The job's worker stopped (crashed or was killed) on every attempt.
    AttemptsExhausted,
    /// The stored case no longer reads or builds.
    InvalidCase,
    Internal,
    /// The solver stopped because it was asked to. Never stored: the worker
    /// turns it into the job's end (cancelled, time limit, requeued, ...).
    Cancelled,
}

/// A job's failure as stored in `jobs.error` and served by the API.
#[derive(Debug, Serialize)]
pub struct Failure {
    pub kind: FailureKind,
    pub message: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iteration: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual: Option<f64>,
    /// The load factor reached when a step failed however far it was cut.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_factor: Option<f64>,
}

impl Failure {
    pub fn new(kind: FailureKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            message: message.into(),
            step: None,
            iteration: None,
            residual: None,
            load_factor: None,
        }
    }

    /// The text stored in `jobs.error`.
    pub fn json(&self) -> String {
        serde_json::to_string(self).expect("failures serialise")
    }
}

/// A hint of units for a first load step that failed with its loads far
/// beyond the bodies' stiffness: the largest stress the loads make (a
/// pressure, a traction, a body's weight over its height) against the
/// smallest Young's modulus, when over a tenth of it. A modulus of 1
/// meant as 1 MPa fails so, and the solver's message (an inverted point,
/// a diverged Newton) says nothing of why.
pub fn units_hint(case: &mpm::Case, e: &SolveError) -> Option<String> {
    if e.location().0 != 1 || matches!(e.cause(), SolveError::Cancelled { .. }) {
        return None;
    }
    let stiffness = case
        .bodies
        .iter()
        .map(|b| b.material.constants().0)
        .fold(f64::INFINITY, f64::min);
    let gravity = case.loads.gravity.map_or(0.0, |g| g[0].hypot(g[1]));
    let weight = case
        .bodies
        .iter()
        .map(|b| {
            let (lo, hi) = b.geometry.bounding_box();
            let height = (hi[0] - lo[0]).max(hi[1] - lo[1]);
            b.material.constants().2 * gravity * height
        })
        .fold(0.0, f64::max);
    let surface = case
        .loads
        .boundary
        .iter()
        .map(|l| match (l.traction, l.pressure) {
            (Some(t), _) => t[0].hypot(t[1]),
            (None, Some(p)) => p.abs(),
            (None, None) => 0.0,
        })
        .fold(0.0, f64::max);
    let stress = weight.max(surface);
    (stress > 0.1 * stiffness).then(|| {
        format!(
            "; the loads make stresses of about {stress:.3e} Pa against a Young's modulus of \
             {stiffness:.3e} Pa: are the units SI throughout (moduli and pressures in Pa, \
             1 MPa = 1e6)?"
        )
    })
}

impl From<SolveError> for Failure {
    fn from(e: SolveError) -> Self {
        let kind = match e.kind() {
            mpm::newton::FailureKind::NotConverged => FailureKind::NotConverged,
            mpm::newton::FailureKind::Diverged => FailureKind::Diverged,
            mpm::newton::FailureKind::InvertedPoint => FailureKind::InvertedPoint,
            mpm::newton::FailureKind::InadmissiblePoint => FailureKind::InadmissiblePoint,
            mpm::newton::FailureKind::LinearSolve => FailureKind::LinearSolve,
            mpm::newton::FailureKind::LeftGrid => FailureKind::LeftGrid,
            mpm::newton::FailureKind::NonFinite => FailureKind::NonFinite,
            mpm::newton::FailureKind::Cancelled => FailureKind::Cancelled,
        };
        let load_factor = match e {
            SolveError::SubstepsExhausted { load_factor, .. } => Some(load_factor),
            _ => None,
        };
        let (step, iteration, residual) = e.location();
        Failure {
            kind,
            message: e.to_string(),
            step: Some(step),
            iteration,
            residual: residual.filter(|r| r.is_finite()),
            load_factor,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const STORED: [FailureKind; 11] = [
        FailureKind::NotConverged,
        FailureKind::Diverged,
        FailureKind::InvertedPoint,
        FailureKind::InadmissiblePoint,
        FailureKind::LinearSolve,
        FailureKind::LeftGrid,
        FailureKind::NonFinite,
        FailureKind::TimeLimit,
        FailureKind::AttemptsExhausted,
        FailureKind::InvalidCase,
        FailureKind::Internal,
    ];

    #[test]
    fn stored_kinds_are_the_documented_enum() {
        let spec = include_str!("../../openapi.yaml");
        let names = STORED
            .map(|k| {
                serde_json::to_value(k)
                    .unwrap()
                    .as_str()
                    .unwrap()
                    .to_string()
            })
            .join(", ");
        assert!(spec.contains(&format!("enum: [{names}]")), "{names}");
    }

    #[test]
    fn optional_fields_are_left_out() {
        let f = Failure::new(FailureKind::AttemptsExhausted, "stopped 3 times");
        assert_eq!(
            f.json(),
            r#"{"kind":"attempts_exhausted","message":"stopped 3 times"}"#
        );
    }
}
