//! How the solver reports progress without doing I/O itself: the command-line
//! runner and the job service implement [`Observer`].

use crate::boundary::{self, BoundaryLoop, BoundaryOutput};
use crate::checkpoint::{Checkpoint, SolidCheckpoint};
use crate::newton::Monitor;
use crate::particles::MaterialPoints;
use crate::report::StepReport;

/// The state after a converged step, as observers see it.
pub struct StepState<'a> {
    pub points: &'a MaterialPoints,
    pub loops: &'a [BoundaryLoop],
    run: &'a dyn Run,
}

/// The run behind a step's state: what an observer may ask of it besides
/// the points (the simulation implements it).
pub(crate) trait Run {
    fn load_steps(&self) -> usize;
    /// A copy of every point's state: made only for an observer that asks.
    fn checkpoint(&self) -> Checkpoint;
}

impl<'a> StepState<'a> {
    pub(crate) fn new(
        points: &'a MaterialPoints,
        loops: &'a [BoundaryLoop],
        run: &'a dyn Run,
    ) -> Self {
        Self { points, loops, run }
    }

    /// Load steps in the run.
    pub fn load_steps(&self) -> usize {
        self.run.load_steps()
    }

    /// The run's state after this step, to resume from
    /// ([`crate::Simulation::restore`]).
    pub fn checkpoint(&self) -> Checkpoint {
        self.run.checkpoint()
    }

    /// The boundary curves through the points' current positions (built on
    /// request: interpolation costs work proportional to the boundary).
    pub fn boundaries(&self) -> Vec<BoundaryOutput> {
        boundary::outputs(self.loops, self.points)
    }
}

/// The state after a converged step of a 3D run, as observers see it.
pub struct SolidStepState<'a> {
    pub points: &'a MaterialPoints<3>,
    run: &'a crate::Simulation<3>,
}

impl<'a> SolidStepState<'a> {
    pub(crate) fn new(run: &'a crate::Simulation<3>) -> Self {
        Self {
            points: &run.points,
            run,
        }
    }

    /// Load steps in the run.
    pub fn load_steps(&self) -> usize {
        self.run.load_steps
    }

    /// The run's state after this step, to resume from
    /// ([`crate::Simulation::<3>::restore`]).
    pub fn checkpoint(&self) -> SolidCheckpoint {
        self.run.checkpoint()
    }

    /// The bodies' surfaces through the points' places after this step.
    pub fn surfaces(&self) -> Vec<crate::boundary::face_patches::SurfaceOutput> {
        crate::boundary::face_patches::surface_outputs(&self.run.faces, self.points)
    }
}

pub trait Observer {
    /// A load step is about to start (`step` counts from 1).
    fn step_started(&mut self, _step: usize, _n_steps: usize) {}
    /// The relative out-of-balance force at a Newton iteration.
    fn newton_iteration(&mut self, _step: usize, _iteration: usize, _residual: f64) {}
    /// A load step converged; `state` holds the updated points.
    fn step_finished(&mut self, _report: &StepReport, _state: &StepState<'_>) {}
    /// A load step of a 3D run converged; `state` holds the updated points.
    fn solid_step_finished(&mut self, _report: &StepReport, _state: &SolidStepState<'_>) {}
    /// Polled at every Newton iteration; `true` stops the run with
    /// [`crate::SolveError::Cancelled`].
    fn should_cancel(&mut self) -> bool {
        false
    }
}

impl<O: Observer + ?Sized> Monitor for O {
    fn newton_iteration(&mut self, step: usize, iteration: usize, residual: f64) {
        Observer::newton_iteration(self, step, iteration, residual);
    }

    fn should_cancel(&mut self) -> bool {
        Observer::should_cancel(self)
    }
}

/// Observes nothing.
pub struct NoObserver;

impl Observer for NoObserver {}
