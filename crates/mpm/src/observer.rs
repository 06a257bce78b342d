//! How the solver reports progress without doing I/O itself: the command-line
//! runner and the job service implement [`Observer`].

use crate::output::StepReport;
use crate::points::MaterialPoints;

pub trait Observer {
    /// A load step is about to start (`step` counts from 1).
    fn step_started(&mut self, _step: usize, _n_steps: usize) {}
    /// The relative out-of-balance force at a Newton iteration.
    fn newton_iteration(&mut self, _step: usize, _iteration: usize, _residual: f64) {}
    /// A load step converged; `points` is the updated state.
    fn step_finished(&mut self, _report: &StepReport, _points: &MaterialPoints) {}
    /// Polled at every Newton iteration; `true` stops the run with
    /// [`crate::SolveError::Cancelled`].
    fn should_cancel(&mut self) -> bool {
        false
    }
}

/// Observes nothing.
pub struct NoObserver;

impl Observer for NoObserver {}
