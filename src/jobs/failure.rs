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
    LinearSolve,
    /// Material left the grid's extent.
    LeftGrid,
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

impl From<SolveError> for Failure {
    fn from(e: SolveError) -> Self {
        let kind = match e.cause() {
            SolveError::NotConverged { .. } => FailureKind::NotConverged,
            SolveError::Diverged { .. } => FailureKind::Diverged,
            SolveError::Inverted { .. } => FailureKind::InvertedPoint,
            SolveError::LinearSolve { .. } => FailureKind::LinearSolve,
            SolveError::LeftGrid { .. } => FailureKind::LeftGrid,
            SolveError::Cancelled { .. } => FailureKind::Cancelled,
            // cause() never returns it.
            SolveError::SubstepsExhausted { .. } => FailureKind::NotConverged,
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

    const STORED: [FailureKind; 9] = [
        FailureKind::NotConverged,
        FailureKind::Diverged,
        FailureKind::InvertedPoint,
        FailureKind::LinearSolve,
        FailureKind::LeftGrid,
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
