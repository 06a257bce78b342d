//! The JSON shapes the API answers with (see `openapi.yaml`).

use std::collections::BTreeMap;

use mpm::StepReport;
use mpm::report::{RunWarning, StepTimings, StrengthStep};
use serde::Serialize;
use serde_json::Value;
use serde_json::value::RawValue;

use crate::jobs::{JobRow, JobStatus};

/// A job's status, progress, cost and links.
#[derive(Debug, Serialize)]
pub struct JobView {
    pub id: i64,
    pub status: JobStatus,
    pub title: Option<String>,
    pub points: i64,
    pub progress: Progress,
    pub newton_iterations: i64,
    pub attempts: i64,
    /// The step the latest run resumed after, from its checkpoint (null:
    /// it ran from step 1).
    pub resumed_from_step: Option<i64>,
    pub cancel_requested: bool,
    pub created_at: String,
    pub started_at: Option<String>,
    pub finished_at: Option<String>,
    /// Seconds spent solving (set when the job ends).
    pub solve_seconds: Option<f64>,
    /// `{kind, message, step?, iteration?, residual?}` for a failed job.
    pub error: Option<Value>,
    pub links: Links,
}

#[derive(Debug, Serialize)]
pub struct Progress {
    /// Load steps finished.
    pub step: i64,
    /// Load steps in the case.
    pub of: i64,
}

#[derive(Debug, Serialize)]
pub struct Links {
    #[serde(rename = "self")]
    pub this: String,
    pub case: String,
    pub steps: String,
    pub result: String,
    pub cancel: String,
    pub archive: String,
}

impl JobView {
    pub fn new(job: &JobRow) -> Self {
        let base = format!("/jobs/{}", job.id);
        Self {
            id: job.id,
            status: job.status,
            title: job.title.clone(),
            points: job.points,
            progress: Progress {
                step: job.steps_done,
                of: job.load_steps,
            },
            newton_iterations: job.newton_iterations,
            attempts: job.attempts,
            resumed_from_step: job.resumed_from,
            cancel_requested: job.cancel_requested,
            created_at: rfc3339(job.created_at),
            started_at: job.started_at.map(rfc3339),
            finished_at: job.finished_at.map(rfc3339),
            solve_seconds: job.solve_seconds,
            error: job
                .error
                .as_deref()
                .and_then(|e| serde_json::from_str(e).ok()),
            links: Links {
                case: format!("{base}/case"),
                steps: format!("{base}/steps"),
                result: format!("{base}/result"),
                cancel: format!("{base}/cancel"),
                archive: format!("{base}/archive"),
                this: base,
            },
        }
    }
}

/// `GET /jobs/{id}/steps`: the stored report of every finished step.
#[derive(Debug, Serialize)]
pub struct StepsView {
    pub job: i64,
    /// `mpm::StepReport` of each finished step, in step order.
    pub steps: Vec<Box<RawValue>>,
}

/// Everything but the point data: probe histories, reactions, Newton
/// statistics and timings of the steps finished so far.
#[derive(Debug, Serialize)]
pub struct ResultView {
    pub job: JobView,
    /// Per probe name, one entry per finished step.
    pub probes: BTreeMap<String, Vec<ProbeSample>>,
    /// Per finished step, the force of each support (order of the case's
    /// `supports`, or of its step's stage's).
    pub reactions: Vec<StepReactions>,
    pub newton: Vec<StepNewton>,
    /// Summed over the finished steps.
    pub timings: StepTimings,
    /// The last finished step's strength reduction (its factor of
    /// safety once found).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strength_reduction: Option<StrengthStep>,
    /// What the case and its finished steps warn of (`mpm::model::warnings`).
    pub warnings: Vec<RunWarning>,
}

#[derive(Debug, Serialize)]
pub struct ProbeSample {
    pub step: usize,
    /// The step's stage, when the case has stages (the load factor runs
    /// over each).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    pub load_factor: f64,
    pub position: Vec<f64>,
    pub displacement: Vec<f64>,
}

#[derive(Debug, Serialize)]
pub struct StepReactions {
    pub step: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    pub load_factor: f64,
    pub supports: Vec<Vec<f64>>,
    /// Resultant of the applied loads; the supports balance it.
    pub applied_load: Vec<f64>,
}

#[derive(Debug, Serialize)]
pub struct StepNewton {
    pub step: usize,
    pub iterations: usize,
    pub residuals: Vec<f64>,
    pub active_dofs: usize,
    pub substeps: usize,
    pub cutbacks: usize,
    pub failed_iterations: usize,
}

impl ResultView {
    pub fn new(job: &JobRow, steps: &[StepReport], warnings: Vec<RunWarning>) -> Self {
        let mut probes: BTreeMap<String, Vec<ProbeSample>> = BTreeMap::new();
        let mut timings = StepTimings::default();
        for s in steps {
            for p in &s.probes {
                probes.entry(p.name.clone()).or_default().push(ProbeSample {
                    step: s.step,
                    stage: s.stage.clone(),
                    load_factor: s.load_factor,
                    position: p.position.clone(),
                    displacement: p.displacement.clone(),
                });
            }
            timings += &s.timings;
        }
        Self {
            job: JobView::new(job),
            probes,
            reactions: steps
                .iter()
                .map(|s| StepReactions {
                    step: s.step,
                    stage: s.stage.clone(),
                    load_factor: s.load_factor,
                    supports: s.reactions.clone(),
                    applied_load: s.applied_load.clone(),
                })
                .collect(),
            newton: steps
                .iter()
                .map(|s| StepNewton {
                    step: s.step,
                    iterations: s.newton.iterations,
                    residuals: s.newton.residuals.clone(),
                    active_dofs: s.active_dofs,
                    substeps: s.substeps,
                    cutbacks: s.cutbacks,
                    failed_iterations: s.failed_iterations,
                })
                .collect(),
            timings,
            strength_reduction: steps
                .iter()
                .rev()
                .find_map(|s| s.strength_reduction.clone()),
            warnings,
        }
    }
}

/// `2026-11-24T08:40:00.123Z` from Unix seconds (UTC, millisecond precision).
pub fn rfc3339(unix_seconds: f64) -> String {
    let ([year, month, day], ms_of_day) = civil(unix_seconds);
    let s = ms_of_day / 1000;
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}.{:03}Z",
        s / 3600,
        s / 60 % 60,
        s % 60,
        ms_of_day % 1000
    )
}

/// `([year, month, day], milliseconds into the day)` of a Unix time, UTC.
pub fn civil(unix_seconds: f64) -> ([i64; 3], i64) {
    let millis = (unix_seconds * 1000.0).round() as i64;
    let (days, ms_of_day) = (millis.div_euclid(86_400_000), millis.rem_euclid(86_400_000));
    // Civil date from days since 1970-01-01 (H. Hinnant, "chrono-compatible
    // low-level date algorithms", days_from_civil inverse).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    ([year, month, day], ms_of_day)
}

#[cfg(test)]
mod tests {
    use super::rfc3339;

    #[test]
    fn formats_known_instants() {
        // Reference values from `date -u -d @SECONDS +%FT%T`.
        assert_eq!(rfc3339(0.0), "1970-01-01T00:00:00.000Z");
        assert_eq!(rfc3339(951_782_400.5), "2000-02-29T00:00:00.500Z");
        assert_eq!(rfc3339(1_795_507_200.0), "2026-11-24T08:00:00.000Z");
    }

    /// The service answers from step reports stored as JSON text, so they
    /// must parse back to the solver's own bits. serde_json's default
    /// float parser is off by an ulp or two on some numbers: the built-in
    /// slope's factor of safety, 1.3625000000000003 in the CLI's
    /// summary.json, came back from `GET /jobs/{id}/result` as
    /// 1.3625000000000005 (fixed by its `float_roundtrip` feature).
    #[test]
    fn stored_numbers_parse_back_to_the_same_bits() {
        let strength = mpm::report::StrengthStep {
            factor: 1.3625000000000003,
            failed: Some(1.3687500000000004),
            found: true,
            failure: None,
            flow: Some(10.4572125588708),
        };
        let text = serde_json::to_string(&strength).unwrap();
        let back: mpm::report::StrengthStep = serde_json::from_str(&text).unwrap();
        assert_eq!(back, strength, "{text}");
    }
}
