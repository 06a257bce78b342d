//! What every case must do, checked on a run: finish, or fail with a
//! [`SolveError`] that names its step and cause. Never a panic, a
//! non-finite number in a finished step's output, a point in a finished
//! step that is inverted or whose volume jumped past what a step admits,
//! or a run past its time limit (proportional to its size).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::{Duration, Instant};

use mpm::particles::admissible::MAX_STEP_VOLUME_RATIO;
use mpm::{Case, Observer, Simulation, StepReport, StepState};

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Finished,
    /// A clean failure: the solver's error (its kind, as the job service
    /// names it) and where.
    Failed {
        kind: &'static str,
        step: usize,
        message: String,
    },
    /// The case was refused: a drawn case must be valid.
    Refused(String),
    /// The solver panicked.
    Panicked(String),
    /// A finished step broke the contract (a non-finite number, an
    /// inverted or exploded point).
    Broken(String),
    /// The run went past its time limit.
    TimedOut {
        seconds: f64,
    },
}

impl Outcome {
    /// Whether the contract held: finished, or failed cleanly.
    pub fn kept(&self) -> bool {
        matches!(self, Outcome::Finished | Outcome::Failed { .. })
    }

    pub fn name(&self) -> &'static str {
        match self {
            Outcome::Finished => "finished",
            Outcome::Failed { .. } => "failed",
            Outcome::Refused(_) => "refused",
            Outcome::Panicked(_) => "panicked",
            Outcome::Broken(_) => "broken",
            Outcome::TimedOut { .. } => "timed out",
        }
    }
}

/// A run's outcome and cost.
#[derive(Debug, Clone)]
pub struct Tried {
    pub outcome: Outcome,
    pub points: usize,
    pub steps_done: usize,
    pub iterations: usize,
    pub cutbacks: usize,
    pub seconds: f64,
}

/// The time a run of `points` points in `steps` load steps may take before
/// it counts as hung: a minute, and 5 ms per point and step. A failing
/// step may try 12 sizes of 30 iterations each; the 1,000 cases of
/// `mpm study robustness` took at most 16 s (0.2 s median) in the test
/// profile on this project's 2-core machines, the limit being 60-400 s.
pub fn time_limit(points: usize, steps: usize) -> Duration {
    Duration::from_secs_f64(60.0 + 5e-3 * (points * steps.max(1)) as f64)
}

/// Watches the finished steps and the clock.
struct Watch {
    started: Instant,
    limit: Option<Duration>,
    timed_out: bool,
    /// Each point's `J` after the last finished step.
    jacobians: Vec<f64>,
    broken: Option<String>,
    steps: usize,
    iterations: usize,
    cutbacks: usize,
}

impl Watch {
    fn check(&self, report: &StepReport, state: &StepState<'_>) -> Result<(), String> {
        let step = report.step;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !report.reactions.iter().all(|r| finite(r)) || !finite(&report.applied_load) {
            return Err(format!("step {step}: a non-finite reaction or load"));
        }
        if !report.probes.iter().all(|p| finite(&p.displacement)) {
            return Err(format!("step {step}: a non-finite probe"));
        }
        let points = state.points;
        if let Some(p) = points.first_non_finite() {
            return Err(format!("step {step}: point {p} is not finite"));
        }
        // A step solved in pieces may change a volume by the ratio once a
        // piece.
        let pieces = report.substeps.max(1) as i32;
        let ratio = MAX_STEP_VOLUME_RATIO.powi(pieces);
        for p in 0..points.len() {
            let j = points.jacobian(p);
            if j.is_nan() || j <= 0.0 {
                return Err(format!("step {step}: point {p} is inverted (J = {j:.3e})"));
            }
            if let Some(&before) = self.jacobians.get(p)
                && (j > ratio * before || j * ratio < before)
            {
                return Err(format!(
                    "step {step}: point {p}'s volume went from J = {before:.3e} to {j:.3e}"
                ));
            }
        }
        Ok(())
    }
}

impl Observer for Watch {
    fn step_finished(&mut self, report: &StepReport, state: &StepState<'_>) {
        self.steps += 1;
        self.iterations += report.newton.iterations;
        self.cutbacks += report.cutbacks;
        if self.broken.is_none()
            && let Err(e) = self.check(report, state)
        {
            self.broken = Some(e);
        }
        self.jacobians = (0..state.points.len())
            .map(|p| state.points.jacobian(p))
            .collect();
    }

    fn should_cancel(&mut self) -> bool {
        let over = self.limit.is_some_and(|l| self.started.elapsed() > l);
        self.timed_out |= over;
        over
    }
}

/// Runs `case` (JSON) under the contract.
pub fn try_case(case: &str) -> Tried {
    let started = Instant::now();
    let mut tried = Tried {
        outcome: Outcome::Finished,
        points: 0,
        steps_done: 0,
        iterations: 0,
        cutbacks: 0,
        seconds: 0.0,
    };
    let run = catch_unwind(AssertUnwindSafe(|| {
        let case = Case::from_json(case).map_err(|e| Outcome::Refused(e.to_string()))?;
        let mut sim = Simulation::new(&case).map_err(|e| Outcome::Refused(e.to_string()))?;
        let points = sim.points.len();
        let mut watch = Watch {
            started: Instant::now(),
            limit: Some(time_limit(points, sim.load_steps)),
            timed_out: false,
            jacobians: (0..points).map(|p| sim.points.jacobian(p)).collect(),
            broken: None,
            steps: 0,
            iterations: 0,
            cutbacks: 0,
        };
        let result = sim.run(&mut watch);
        Ok::<_, Outcome>((points, watch, result))
    }));
    tried.seconds = started.elapsed().as_secs_f64();
    let (points, watch, result) = match run {
        Err(panic) => {
            let message = (panic.downcast_ref::<String>().cloned())
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            tried.outcome = Outcome::Panicked(message);
            return tried;
        }
        Ok(Err(outcome)) => {
            tried.outcome = outcome;
            return tried;
        }
        Ok(Ok(run)) => run,
    };
    tried.points = points;
    tried.steps_done = watch.steps;
    tried.iterations = watch.iterations;
    tried.cutbacks = watch.cutbacks;
    tried.outcome = match result {
        Ok(_) => Outcome::Finished,
        Err(_) if watch.timed_out => Outcome::TimedOut {
            seconds: tried.seconds,
        },
        Err(e) => Outcome::Failed {
            kind: e.kind().name(),
            step: e.location().0,
            message: e.to_string(),
        },
    };
    if let Some(broken) = watch.broken {
        tried.outcome = Outcome::Broken(broken);
    }
    tried
}
