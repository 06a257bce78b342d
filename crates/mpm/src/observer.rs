//! How the solver reports progress without doing I/O itself: the command-line
//! runner and the job service implement [`Observer`].

use crate::boundary::{self, BoundaryLoop, BoundaryOutput};
use crate::checkpoint::Checkpoint;
use crate::particles::MaterialPoints;
use crate::report::StepReport;
use crate::stepper::Simulation;

/// The state after a converged step, as observers see it.
pub struct StepState<'a> {
    pub points: &'a MaterialPoints,
    pub loops: &'a [BoundaryLoop],
    simulation: &'a Simulation,
}

impl<'a> StepState<'a> {
    pub(crate) fn new(simulation: &'a Simulation) -> Self {
        Self {
            points: &simulation.points,
            loops: &simulation.loops,
            simulation,
        }
    }

    /// Load steps in the run.
    pub fn load_steps(&self) -> usize {
        self.simulation.load_steps
    }

    /// The run's state after this step, to resume from
    /// ([`Simulation::restore`]).
    pub fn checkpoint(&self) -> Checkpoint {
        self.simulation.checkpoint()
    }

    /// The boundary curves through the points' current positions (built on
    /// request: interpolation costs work proportional to the boundary).
    pub fn boundaries(&self) -> Vec<BoundaryOutput> {
        boundary::outputs(self.loops, self.points)
    }
}

pub trait Observer {
    /// A load step is about to start (`step` counts from 1).
    fn step_started(&mut self, _step: usize, _n_steps: usize) {}
    /// The relative out-of-balance force at a Newton iteration.
    fn newton_iteration(&mut self, _step: usize, _iteration: usize, _residual: f64) {}
    /// A load step converged; `state` holds the updated points.
    fn step_finished(&mut self, _report: &StepReport, _state: &StepState<'_>) {}
    /// Polled at every Newton iteration; `true` stops the run with
    /// [`crate::SolveError::Cancelled`].
    fn should_cancel(&mut self) -> bool {
        false
    }
}

/// Observes nothing.
pub struct NoObserver;

impl Observer for NoObserver {}
