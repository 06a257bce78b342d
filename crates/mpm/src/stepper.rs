//! The load-step loop of implicit quasi-static MPM. For each load step `k`
//! of `n` (load factor `k/n`):
//! 1. reset the grid: shape functions at the points' current positions and
//!    the step's active nodes ([`Connectivity`]);
//! 2. assemble the step's system on that configuration: supports, loads,
//!    boundary loads and IBM band terms on the B-spline, the soft background
//!    or the ghost penalty, F-bar's averaging cells, and the stiffness
//!    pattern ([`StepEquilibrium`]);
//! 3. Newton-Raphson with a line search for the incremental nodal
//!    displacements ([`newton`]);
//! 4. reactions, then move the points ([`update`]), probes and IBM anchors with the
//!    converged grid displacement and commit the points' deformation,
//!    history and stress.
//!
//! An increment that fails in 3 commits nothing and is tried again in
//! halves from the same state ([`Simulation::load_step`], [`Substepping`]).

use std::any::Any;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::Matrix2;

use crate::assembly;
use crate::assembly::averaging::{Averaging, Carried, CellAverages};
use crate::assembly::cell_mean::CellMean;
use crate::assembly::solid_ghost_faces::SolidGhostFaces;
use crate::assembly::{FbarCells, GhostFaces, LonePoints, SoftCells, StepTerm, lone_points};
use crate::boundary::BoundaryLoop;
use crate::boundary::face_loads::FaceLoading;
use crate::boundary::face_patches::FacePatch;
use crate::boundary::ibm::{self, Anchor, BandTerms, SurfaceAnchor};
use crate::boundary::loading::BoundaryLoading;
use crate::boundary::surface_loading::SurfaceLoading;
use crate::case::Volumetric;
use crate::configuration::Configuration;
use crate::equilibrium::{AnalysedPattern, StepEquilibrium, StepSpace, StepTerms};
use crate::grid::{Basis, Connectivity, Grid, NodeKey, increment};
use crate::linsolve::{SolveCounts, SolveTally, SolverSettings};
use crate::material::StiffnessScales;
use crate::newton::{self, SolveError};
use crate::observer::{self, Observer, SolidStepState, StepState};
use crate::particles::{Dim, MaterialPoints, Space, geostatic};
use crate::probes::Probes;
use crate::report::{RunReport, Settled, StepReport, StepTimings, StrengthStep, SupportTraction};
use crate::settings::NewtonSettings;
pub use crate::settings::Substepping;
use crate::stages::{self, Stage, StrengthReduction};
use crate::strength_reduction::{self, Flow, FlowLimit, Next, ReductionState};
use crate::supports::HeldDofs;
use crate::update;

/// Newton iterations a sub-increment may take and still count as easy:
/// two easy ones in a row and the next is twice as long.
const EASY_ITERATIONS: usize = 6;

/// The longest arc of an arc-length stage, in first arcs: with the
/// secant predictor steps on a collapse plateau converge easily, and
/// arcs doubling without bound carried a footing to 0.3 B in 70 steps,
/// where the run failed.
const MAX_ARC_GROWTH: f64 = 16.0;

/// Where the step-size control stands between load steps. A step starts at
/// the size of the last one's last sub-increment (a fraction of a step's
/// increment), so a plastic flow that needs halves does not fail a whole
/// step's try again at every step. To let a size cut at a hard spot grow
/// back, a step that follows enough clean steps (no cut) probes twice the
/// size; a probe that has to be cut doubles the clean steps the next one
/// waits for (1, 2, 4, ...), and one that holds resets the wait to one.
/// Steady flow that needs its small size so pays a number of failed
/// probes that grows as the logarithm of the steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StepSize {
    pub size: f64,
    pub easy_in_a_row: usize,
    /// Clean steps since the last cut, and how many the next probe waits for.
    pub clean_steps: usize,
    pub wait: usize,
}

impl Default for StepSize {
    fn default() -> Self {
        Self {
            size: 1.0,
            easy_in_a_row: 0,
            clean_steps: 0,
            wait: 1,
        }
    }
}

impl StepSize {
    /// The size a step starts at, within `[min_fraction, 1]`, and whether
    /// it is a probe.
    fn first_try(&self, min_fraction: f64) -> (f64, bool) {
        let probe = self.size < 1.0 && self.clean_steps >= self.wait;
        let size = if probe { 2.0 * self.size } else { self.size };
        (size.clamp(min_fraction.min(1.0), 1.0), probe)
    }

    /// The state after a step that ended at `size`, with `cutbacks` failed
    /// tries, that started with a probe or not.
    fn after(&self, size: f64, easy_in_a_row: usize, cutbacks: usize, probe: bool) -> Self {
        let (clean_steps, wait) = match (cutbacks > 0, probe) {
            (true, true) => (0, 2 * self.wait),
            (true, false) => (0, self.wait),
            (false, true) => (1, 1),
            (false, false) => (self.clean_steps + 1, self.wait),
        };
        Self {
            size,
            easy_in_a_row,
            clean_steps,
            wait,
        }
    }
}

/// Where the arc-length control stands between the steps of an
/// arc-length stage. The first step is an equal increment (`1 / n` of the
/// loads); its displacement increment's norm is the arc length of those
/// after it. A step that fails is tried again on half the arc, down to
/// [`Substepping::min_fraction`] of the first; after two easy ones in a
/// row ([`EASY_ITERATIONS`]) the arc doubles, up to [`MAX_ARC_GROWTH`]
/// times the first, so that past the elastic range, where the first arc
/// is a small part of the displacement to collapse, the steps reach it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ArcState {
    pub(crate) length: f64,
    pub(crate) first_length: f64,
    /// The stage's load factor the last step reached.
    pub(crate) load_factor: f64,
    pub(crate) easy_in_a_row: usize,
    /// The last converged increment, which the next step's predictor
    /// goes on along.
    pub(crate) last: Option<LastIncrement>,
}

/// A converged increment: the grid displacement on its step's nodes (by
/// key) and its change of load factor.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LastIncrement {
    pub(crate) nodes: Vec<NodeKey>,
    pub(crate) u: Vec<f64>,
    pub(crate) dlambda: f64,
}

impl LastIncrement {
    /// Its displacement on the DOFs of a step's `nodes` (sorted keys, `D`
    /// DOFs each): zero on a node it did not have.
    fn on<const D: usize>(&self, nodes: &[NodeKey]) -> Vec<f64> {
        let mut out = vec![0.0; D * nodes.len()];
        for (i, key) in nodes.iter().enumerate() {
            if let Ok(j) = self.nodes.binary_search(key) {
                out[D * i..D * i + D].copy_from_slice(&self.u[D * j..D * j + D]);
            }
        }
        out
    }

    fn norm(&self) -> f64 {
        self.u.iter().map(|v| v * v).sum::<f64>().sqrt()
    }
}

/// How an increment's load factor is set: given (from, to), with
/// whether a smaller increment can follow if this one fails (then a stuck
/// try gives up early, `newton::stuck`); or found with the displacements
/// on an arc of `length` from `load_factor`; or a strength-reduction
/// trial, at the full load, whose movement `flow` bounds.
#[derive(Debug, Clone, Copy)]
enum Increment {
    To {
        from: f64,
        to: f64,
        cut_follows: bool,
    },
    Arc {
        length: f64,
        load_factor: f64,
    },
    Trial {
        flow: Option<FlowLimit>,
    },
}

/// A case made ready to run: points, grid, loads and supports
/// ([`crate::model`] builds it from a case), in `D` dimensions. The
/// boundary's loops and curve anchors are plane strain's (empty in 3D);
/// the face patches and surface anchors are 3D's (empty in plane strain).
pub struct Simulation<const D: usize = 2>
where
    Dim<D>: StepSpace<D>,
{
    pub grid: Grid<D>,
    pub basis: Basis,
    /// The grid's extent `(min, max)`, if bounded: nodes outside it do not
    /// exist, and material must stay inside it.
    pub extent: Option<([f64; D], [f64; D])>,
    pub points: MaterialPoints<D>,
    /// Boundary loops of the material points, found once (Lagrangian).
    pub loops: Vec<BoundaryLoop>,
    /// The bodies' surfaces as face patches of data points carried by the
    /// points, made once (3D; empty in plane strain).
    pub faces: Vec<FacePatch>,
    pub probes: Probes<D>,
    /// The run's stages (loads and supports; one unless the case lists
    /// stages), and the one the steps are in.
    pub(crate) stages: Vec<Stage<D>>,
    pub(crate) stage: usize,
    /// Quadrature points of the supports imposed on the boundary curves by
    /// the implicit boundary method, and the band width `delta` they use.
    pub(crate) anchors: Vec<Anchor>,
    /// In 3D, the quadrature points of the supports on the surface
    /// patches (empty in plane strain).
    pub(crate) surface_anchors: Vec<SurfaceAnchor>,
    /// How many the first stage has (released supports drop theirs).
    pub(crate) first_stage_anchors: usize,
    pub(crate) band_width: f64,
    pub settings: NewtonSettings,
    pub substepping: Substepping,
    pub(crate) step_size: StepSize,
    /// The arc-length control, once an arc-length stage's first step is done.
    pub(crate) arc: Option<ArcState>,
    /// The last converged increment of the stage's load-factor steps, which
    /// the next one's Newton starts from, scaled to its change of load
    /// factor ([`newton::solve_from`]).
    pub(crate) last_increment: Option<LastIncrement>,
    /// The strength reduction, once its stage has begun.
    pub(crate) reduction: Option<ReductionState>,
    /// What the last converged increment reported of its state.
    pub(crate) settled: Option<Settled>,
    /// How a point's deformation enters its stress: F-bar
    /// ([`crate::assembly::fbar`]) or the cell mean
    /// ([`crate::assembly::cell_mean`]) against locking.
    pub volumetric: Volumetric,
    /// Load steps over all stages.
    pub load_steps: usize,
    /// Load steps converged (and committed) so far.
    pub(crate) steps_done: usize,
    /// The materials' stiffnesses the stabilisation scales by.
    pub(crate) stiffness: StiffnessScales,
    /// How the linear systems are solved (the defaults unless a benchmark
    /// chooses), and the counts of what the run's solvers did.
    pub solver: SolverSettings,
    pub(crate) solve_tally: Arc<SolveTally>,
    /// The last converged step's pattern and solver, for the next step.
    pub(crate) analysed: Option<AnalysedPattern>,
}

impl Simulation {
    /// Step 0: the state before any load, as a report (no Newton solve, no
    /// reactions) and the points, for writers that show the start.
    pub fn initial_step(&self) -> (StepReport, StepState<'_>) {
        (self.initial_report(), self.step_state())
    }

    fn step_state(&self) -> StepState<'_> {
        StepState::new(&self.points, &self.loops, self)
    }
}

impl Simulation<3> {
    /// Step 0 of a 3D run: the state before any load, as a report and the
    /// points, for writers that show the start.
    pub fn initial_step(&self) -> (StepReport, SolidStepState<'_>) {
        (self.initial_report(), SolidStepState::new(self))
    }

    /// The quadrature points of the supports on the surfaces, the
    /// implicit boundary method's anchors.
    pub fn surface_anchor_count(&self) -> usize {
        self.surface_anchors.len()
    }
}

impl<const D: usize> Simulation<D>
where
    Dim<D>: RunSpace<D>,
{
    /// Step 0's report: the state before any load (no Newton solve, no
    /// reactions), for writers that show the start.
    pub fn initial_report(&self) -> StepReport {
        StepReport {
            step: 0,
            load_factor: 0.0,
            newton: Default::default(),
            substeps: 0,
            cutbacks: 0,
            failed_iterations: 0,
            timings: StepTimings::default(),
            points_in_new_cells: 0,
            active_nodes: 0,
            active_dofs: 0,
            probes: self.probes.reports(),
            stage: self.stage_name(0),
            reactions: vec![vec![0.0; D]; self.stages[0].n_supports],
            applied_load: vec![0.0; D],
            support_tractions: Vec::new(),
            strength_reduction: None,
            memory: Default::default(),
        }
    }

    /// Runs the load steps not yet done (all of them, unless the run was
    /// restored from a [`crate::Checkpoint`]), reporting each to `observer`.
    pub fn run(&mut self, observer: &mut dyn Observer) -> Result<RunReport, SolveError> {
        let start = Instant::now();
        let mut steps = Vec::with_capacity(self.load_steps - self.steps_done);
        for step in self.steps_done + 1..=self.load_steps {
            if self.factor_of_safety_found() {
                break;
            }
            observer.step_started(step, self.load_steps);
            let report = self.load_step(step, observer)?;
            self.steps_done = step;
            Dim::<D>::step_finished(self, observer, &report);
            steps.push(report);
        }
        // The last step's solver (and its factor) serves no later step.
        self.analysed = None;
        Ok(RunReport {
            points: self.points.len(),
            load_steps: self.load_steps,
            wall_seconds: start.elapsed().as_secs_f64(),
            steps,
        })
    }

    /// One load step, from load factor `(step - 1) / n` to `step / n`. An
    /// increment that fails is retried from the last converged state in
    /// halves, down to [`Substepping::min_fraction`] of the step; after two
    /// pieces in a row that converged easily (in at most
    /// [`EASY_ITERATIONS`], or half the iteration limit if that is fewer)
    /// the size doubles again, up to the whole step. The first try is the
    /// size the last step ended with, or twice it when probing
    /// ([`StepSize`]).
    pub fn load_step(
        &mut self,
        step: usize,
        observer: &mut dyn Observer,
    ) -> Result<StepReport, SolveError> {
        let (k, before) = stages::stage_of(&self.stages, step);
        self.enter_stage(k);
        if let Some(k0) = self.stages[k].geostatic
            && self.steps_done == before
        {
            Dim::<D>::start_geostatic(self, k, k0);
        }
        // The step within its stage.
        let (step_in_stage, n) = (step - before, self.stages[k].load_steps as f64);
        let end = step_in_stage as f64 / n;
        let easy_limit = EASY_ITERATIONS.min(self.settings.max_iterations / 2);
        if self.stages[k].arc_length
            && let Some(arc) = self.arc.clone()
        {
            return self.arc_step(step, arc, easy_limit, observer);
        }
        if let Some(spec) = self.stages[k].strength_reduction {
            return self.reduction_step(step, &spec, observer);
        }
        // Progress through the step, and the size of the next try, as
        // fractions of its increment (powers of two: exact in binary).
        let (mut size, probe) = self.step_size.first_try(self.substepping.min_fraction);
        let mut easy_in_a_row = self.step_size.easy_in_a_row;
        let mut done = 0.0_f64;
        let mut report: Option<StepReport> = None;
        let (mut cutbacks, mut failed_iterations) = (0, 0);
        let mut failed_seconds = 0.0;
        let mut converged: Option<(LastIncrement, f64)> = None;
        while done < 1.0 {
            let last = done + size >= 1.0 - 1e-12;
            let reach = if last { 1.0 } else { done + size };
            let load_factor = if last {
                end
            } else {
                (step_in_stage as f64 - 1.0 + reach) / n
            };
            let extent_checked_after = if done > 0.0 { step } else { step - 1 };
            let from = (step_in_stage as f64 - 1.0 + done) / n;
            let to = Increment::To {
                from,
                to: load_factor,
                cut_follows: 0.5 * size >= self.substepping.min_fraction
                    && cutbacks < self.substepping.max_cutbacks,
            };
            let started = Instant::now();
            match self.increment(step, extent_checked_after, to, observer) {
                Ok((sub, increment, _)) => {
                    converged = Some((increment, reach - done));
                    easy_in_a_row = if sub.newton.iterations <= easy_limit {
                        easy_in_a_row + 1
                    } else {
                        0
                    };
                    report = Some(match report.take() {
                        None => sub,
                        Some(mut so_far) => {
                            so_far.merge(sub);
                            so_far
                        }
                    });
                    done = reach;
                    if easy_in_a_row >= 2 {
                        size = (2.0 * size).min(1.0);
                        easy_in_a_row = 0;
                    }
                }
                Err(e) if self.worth_cutting(&e) => {
                    cutbacks += 1;
                    failed_iterations += e.location().1.unwrap_or(0);
                    failed_seconds += started.elapsed().as_secs_f64();
                    easy_in_a_row = 0;
                    size *= 0.5;
                    if size < self.substepping.min_fraction
                        || cutbacks > self.substepping.max_cutbacks
                    {
                        return Err(SolveError::SubstepsExhausted {
                            step,
                            load_factor: (step_in_stage as f64 - 1.0 + done) / n,
                            fraction: 2.0 * size,
                            tries: cutbacks,
                            cause: Box::new(e),
                        });
                    }
                }
                Err(e) => return Err(e),
            }
        }
        self.step_size = self.step_size.after(size, easy_in_a_row, cutbacks, probe);
        if self.stages[k].arc_length
            && let Some((increment, span)) = converged
        {
            // The arc of a step: the last sub-increment's, scaled to the
            // whole step.
            let length = increment.norm() / span;
            self.arc = Some(ArcState {
                length,
                first_length: length,
                load_factor: end,
                easy_in_a_row: 0,
                last: Some(increment),
            });
        }
        let mut report = report.expect("the loop converged at least once");
        report.cutbacks = cutbacks;
        report.failed_iterations = failed_iterations;
        report.timings.failed += failed_seconds;
        report.timings.total += failed_seconds;
        Ok(report)
    }

    /// One step of an arc-length stage on the arc `arc` leaves
    /// ([`ArcState`]): tried again on half the arc when it fails, down to
    /// [`Substepping::min_fraction`] of the first arc.
    fn arc_step(
        &mut self,
        step: usize,
        mut arc: ArcState,
        easy_limit: usize,
        observer: &mut dyn Observer,
    ) -> Result<StepReport, SolveError> {
        let (mut cutbacks, mut failed_iterations) = (0, 0);
        let mut failed_seconds = 0.0;
        loop {
            let on = Increment::Arc {
                length: arc.length,
                load_factor: arc.load_factor,
            };
            let started = Instant::now();
            match self.increment(step, step - 1, on, observer) {
                Ok((mut report, increment, _)) => {
                    arc.load_factor = report.load_factor;
                    arc.last = Some(increment);
                    arc.easy_in_a_row = if report.newton.iterations <= easy_limit {
                        arc.easy_in_a_row + 1
                    } else {
                        0
                    };
                    if arc.easy_in_a_row >= 2 {
                        arc.length = (2.0 * arc.length).min(MAX_ARC_GROWTH * arc.first_length);
                        arc.easy_in_a_row = 0;
                    }
                    self.arc = Some(arc);
                    report.cutbacks = cutbacks;
                    report.failed_iterations = failed_iterations;
                    report.timings.failed += failed_seconds;
                    report.timings.total += failed_seconds;
                    return Ok(report);
                }
                Err(e) if self.worth_cutting(&e) => {
                    cutbacks += 1;
                    failed_iterations += e.location().1.unwrap_or(0);
                    failed_seconds += started.elapsed().as_secs_f64();
                    arc.easy_in_a_row = 0;
                    arc.length *= 0.5;
                    let fraction = arc.length / arc.first_length;
                    if fraction < self.substepping.min_fraction
                        || cutbacks > self.substepping.max_cutbacks
                    {
                        return Err(SolveError::SubstepsExhausted {
                            step,
                            load_factor: arc.load_factor,
                            fraction: 2.0 * fraction,
                            tries: cutbacks,
                            cause: Box::new(e),
                        });
                    }
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// One step of a strength-reduction stage: trials from the state of
    /// the last that held ([`crate::strength_reduction`]) until one holds,
    /// the failed ones counted as cutbacks. When a failure finds the
    /// factor of safety, the step is that of the last trial that held, not
    /// solved again (a fresh increment at a factor just below collapse
    /// may itself fail): its points, reactions and tractions, with the
    /// verdict, so that the run's last step is the body at its factor of
    /// safety and its plastic strain the mechanism.
    fn reduction_step(
        &mut self,
        step: usize,
        spec: &StrengthReduction,
        observer: &mut dyn Observer,
    ) -> Result<StepReport, SolveError> {
        let (mut cutbacks, mut failed_iterations) = (0, 0);
        let mut timings = StepTimings::default();
        let mut failure: Option<String> = None;
        if self.reduction.is_none() {
            let points = &self.points;
            let (scale, _) =
                strength_reduction::trial_movement(&points.volume0, |p| points.displacement(p));
            self.reduction = Some(ReductionState::new(points.materials.clone(), scale));
        }
        loop {
            let reduction = self.reduction.as_ref().expect("set above");
            let verdict =
                |reduction: &ReductionState, failure: Option<String>, flow| StrengthStep {
                    factor: reduction.held,
                    failed: reduction.failed.map(|f| f.factor),
                    found: reduction.next(spec) == Next::Found,
                    failure,
                    flow,
                };
            let factor = match reduction.next(spec) {
                Next::Trial(f) => f,
                Next::Found => {
                    let settled = self.settled.clone().expect("a stage before converged");
                    return Ok(StepReport {
                        step,
                        stage: self.stage_name(self.stage),
                        load_factor: 1.0,
                        newton: Default::default(),
                        substeps: 0,
                        cutbacks,
                        failed_iterations,
                        timings,
                        points_in_new_cells: self.points_in_new_cells(),
                        active_nodes: settled.active_nodes,
                        active_dofs: settled.active_dofs,
                        probes: self.probes.reports(),
                        reactions: settled.reactions,
                        applied_load: settled.applied_load,
                        support_tractions: settled.support_tractions,
                        strength_reduction: Some(verdict(reduction, failure, None)),
                        memory: Default::default(),
                    });
                }
            };
            self.points.materials = reduction.materials_at(factor);
            let trial = Increment::Trial {
                flow: reduction.flow_limit(spec, factor, self.grid.h),
            };
            let started = Instant::now();
            let tried = self.increment(step, step - 1, trial, observer);
            let reduction = self.reduction.as_mut().expect("set above");
            match tried {
                Ok((mut report, _, flow)) => {
                    reduction.record(factor, true);
                    reduction.travelled += flow.map_or(0.0, |f| f.largest);
                    let ratio = flow.map(|f| f.ratio);
                    report.strength_reduction = Some(verdict(reduction, failure, ratio));
                    report.cutbacks = cutbacks;
                    report.failed_iterations = failed_iterations;
                    report.timings += &timings;
                    return Ok(report);
                }
                Err(e) if e.may_pass_when_cut() => {
                    cutbacks += 1;
                    failed_iterations += e.location().1.unwrap_or(0);
                    let seconds = started.elapsed().as_secs_f64();
                    timings.failed += seconds;
                    timings.total += seconds;
                    failure = Some(format!("F = {factor:.5}: {e}"));
                    reduction.record(factor, false);
                    self.points.materials = reduction.materials_at(reduction.held);
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// Whether a strength-reduction stage has found the factor of safety
    /// (the run ends there).
    pub fn factor_of_safety_found(&self) -> bool {
        let stage = &self.stages[self.stage];
        match (&self.reduction, &stage.strength_reduction) {
            (Some(r), Some(spec)) => r.next(spec) == Next::Found,
            _ => false,
        }
    }

    /// Whether a smaller increment may succeed where this try failed: not
    /// when cutting is off, and not when Newton stalled (no tenfold fall
    /// over its last two iterations) at the residual's round-off floor
    /// ([`newton::at_round_off_floor`]), which no load increment lowers:
    /// cutting would only repeat the stall some 40 times.
    fn worth_cutting(&self, e: &SolveError) -> bool {
        let floor = matches!(*e, SolveError::NotConverged { residual, stalled, tolerance, .. }
            if newton::at_round_off_floor(residual, stalled, tolerance));
        e.may_pass_when_cut() && self.substepping.min_fraction < 1.0 && !floor
    }

    /// Solves for equilibrium at `load_factor` from the last converged state
    /// and commits it, as in the module docs.
    /// `extent_checked_after` is the step a material point that left the
    /// grid's extent is reported after.
    /// Returns its report, its increment, and what a strength-reduction
    /// trial with a flow limit moved.
    fn increment(
        &mut self,
        step: usize,
        extent_checked_after: usize,
        control: Increment,
        observer: &mut dyn Observer,
    ) -> Result<(StepReport, LastIncrement, Option<Flow>), SolveError> {
        let mut clock = Stopwatch::start();
        self.check_inside_extent(extent_checked_after)?;

        let conn = self.reset_grid();
        let previous = self.analysed.take();
        let (from, start_factor, path) = match control {
            Increment::To { from, to, .. } => (from, to, false),
            Increment::Arc { load_factor, .. } => (load_factor, load_factor, true),
            Increment::Trial { .. } => (1.0, 1.0, false),
        };
        let mut eq = self.assemble(&conn, start_factor, path, previous);
        if let Increment::To { from, to, .. } = control {
            eq.move_supports(
                &self.stages[self.stage].grid_supports,
                &self.grid,
                (from, to),
            );
        }
        let grid_seconds = clock.lap();

        let (u, load_factor, newton) = match control {
            Increment::To { .. } | Increment::Trial { .. } => {
                let to = start_factor;
                let last = self.last_increment.as_ref();
                let predicted = last.filter(|_| self.settings.predictor).and_then(|last| {
                    let scale = (to - from) / last.dlambda;
                    scale.is_finite().then(|| {
                        let mut u = last.on::<D>(&conn.nodes);
                        u.iter_mut().for_each(|x| *x *= scale);
                        u
                    })
                });
                let settings = NewtonSettings {
                    give_up_when_stuck: matches!(
                        control,
                        Increment::To {
                            cut_follows: true,
                            ..
                        }
                    ),
                    ..self.settings
                };
                let (u, info) = newton::solve_from(&mut eq, &settings, step, observer, predicted)?;
                (u, to, info)
            }
            Increment::Arc {
                length,
                load_factor,
            } => {
                let last = (self.arc.as_ref().and_then(|a| a.last.as_ref()))
                    .map(|l| (l.on::<D>(&conn.nodes), l.dlambda));
                let arc = newton::ArcStep {
                    length,
                    load_factor,
                    last,
                };
                newton::solve_arc_length(&mut eq, &self.settings, step, observer, arc)?
            }
        };
        let newton_seconds = clock.lap();
        let flow = match control {
            Increment::Trial { flow: Some(limit) } => {
                let (rms, largest) =
                    strength_reduction::trial_movement(&self.points.volume0, |p| {
                        increment(conn.point_links(p), &u).0
                    });
                match limit.measure(rms, largest) {
                    Ok(flow) => Some(flow),
                    Err(flow) => {
                        return Err(SolveError::Flowed {
                            step,
                            iterations: newton.iterations,
                            moved: rms,
                            ratio: flow.ratio,
                            limit: limit.limit,
                            cells: limit.travelled_with(largest) / self.grid.h,
                        });
                    }
                }
            }
            _ => None,
        };

        let reactions = eq.reactions(&u, self.stages[self.stage].n_supports);
        let applied_load = eq.applied_load();
        let active_dofs = eq.n_free_dofs();
        let non_finite = |quantity: &str| SolveError::NonFinite {
            step,
            quantity: quantity.to_string(),
        };
        if !applied_load.iter().all(|f| f.is_finite()) {
            return Err(non_finite("applied load"));
        }
        if !reactions.iter().flatten().all(|f| f.is_finite()) {
            return Err(non_finite("reactions"));
        }
        let converged = eq.into_converged();
        self.analysed = Some(converged.analysed);
        let states = converged.states;
        let moves = self.stages[self.stage].geostatic.is_none();
        Dim::<D>::before_commit(self, &conn, &u, &converged.carried);
        if moves {
            update::commit(&mut self.points, &conn, &u, &states);
        } else {
            update::commit_in_place(&mut self.points, &states);
        }
        if let Some(p) = Dim::<D>::first_non_finite(&self.points) {
            return Err(non_finite(&format!("state of material point {p}")));
        }
        if moves {
            self.probes.advect(&self.grid, self.basis, &conn, &u);
        }
        let support_tractions =
            Dim::<D>::after_commit(self, &conn, &u, converged.averaged, converged.carried);
        if !support_tractions
            .iter()
            .all(|t| t.at.iter().chain(&t.traction).all(|v| v.is_finite()))
        {
            return Err(non_finite("support tractions"));
        }
        let parts = &converged.timings;
        let timings = StepTimings {
            grid: grid_seconds,
            update: clock.lap(),
            newton: newton_seconds
                - (parts.point_loop + parts.assembly + parts.factorisation + parts.solve),
            total: clock.total(),
            ..converged.timings
        };

        let report = StepReport {
            step,
            stage: self.stage_name(self.stage),
            load_factor,
            newton,
            substeps: 1,
            cutbacks: 0,
            failed_iterations: 0,
            timings,
            points_in_new_cells: self.points_in_new_cells(),
            active_nodes: conn.n_nodes(),
            active_dofs,
            probes: self.probes.reports(),
            reactions: reactions.iter().map(|r| r.to_vec()).collect(),
            applied_load: applied_load.to_vec(),
            support_tractions,
            strength_reduction: None,
            memory: converged.memory,
        };
        self.settled = Some(Settled {
            reactions: report.reactions.clone(),
            applied_load: report.applied_load.clone(),
            support_tractions: report.support_tractions.clone(),
            active_nodes: report.active_nodes,
            active_dofs: report.active_dofs,
        });
        let increment = LastIncrement {
            nodes: conn.nodes.clone(),
            u,
            dlambda: load_factor - from,
        };
        if let Increment::To { .. } | Increment::Trial { .. } = control {
            self.last_increment = Some(increment.clone());
        }
        Ok((report, increment, flow))
    }

    /// Points whose cell is not the one they started the run in.
    fn points_in_new_cells(&self) -> usize {
        let (grid, points) = (&self.grid, &self.points);
        (0..points.len())
            .filter(|&p| grid.cell_of(points.position[p]) != grid.cell_of(points.reference[p]))
            .count()
    }

    /// The grid reset: every point's shape functions at its current
    /// position, on the nodes inside the grid's extent.
    pub(crate) fn reset_grid(&self) -> Connectivity<D> {
        let points = &self.points;
        Connectivity::build(
            &self.grid,
            self.basis,
            &points.position,
            |p| Dim::<D>::support(points, p),
            |node| self.node_in_grid(node),
        )
    }

    /// The points and the grid on the grid reset `conn`: a step's start.
    pub(crate) fn configuration<'a>(&'a self, conn: &'a Connectivity<D>) -> Configuration<'a, D> {
        Configuration {
            grid: &self.grid,
            basis: self.basis,
            conn,
            points: &self.points,
        }
    }

    /// The system of a step at `load_factor` on its grid reset `conn`: the
    /// step's terms, then the stiffness pattern of every coupling they add.
    /// With `path`, the load factor is an unknown that starts there (the
    /// arc-length method).
    pub(crate) fn assemble<'a>(
        &'a self,
        conn: &'a Connectivity<D>,
        load_factor: f64,
        path: bool,
        previous: Option<AnalysedPattern>,
    ) -> StepEquilibrium<'a, D> {
        let start = self.configuration(conn);
        let stage = &self.stages[self.stage];
        let mut terms = StepTerms {
            held: HeldDofs::find(&stage.grid_supports, &self.grid, conn),
            f_ext: assembly::external_force(
                conn,
                &self.points,
                stage.gravity,
                &stage.point_loads,
                load_factor,
            ),
            f_ext_rate: path.then(|| {
                let rate = assembly::external_force_rate(
                    conn,
                    &self.points,
                    stage.gravity,
                    &stage.point_loads,
                );
                (load_factor, rate)
            }),
            averaging: Dim::<D>::averaging(self, &start),
            terms: Dim::<D>::stabilisation_terms(self, &start),
        };
        let made = Instant::now();
        let boundary = Dim::<D>::boundary_terms(self, &start, load_factor);
        let boundary_seconds = made.elapsed().as_secs_f64();
        terms.terms.extend(boundary);
        let pattern = terms.pattern(conn);
        let solving = (&self.solver, &self.solve_tally);
        let mut eq = StepEquilibrium::new(&start, terms, pattern, previous, solving);
        eq.timings.boundary += boundary_seconds;
        eq
    }

    /// Moves on, stage by stage, to stage `k`: its loads and supports,
    /// and the anchors of the supports it keeps continuing from where the
    /// stage before left them.
    pub(crate) fn enter_stage(&mut self, k: usize) {
        while self.stage < k {
            self.stage += 1;
            self.last_increment = None;
            ibm::enter_stage(&mut self.anchors, &self.stages[self.stage].ibm);
        }
    }

    /// Stage `k`'s name in the reports, when the case has stages.
    fn stage_name(&self, k: usize) -> Option<String> {
        self.stages[k].name.clone()
    }

    /// What the run's linear solvers have done so far, every increment
    /// tried counted (failed ones too).
    pub fn solve_counts(&self) -> SolveCounts {
        self.solve_tally.counts()
    }

    /// Whether a node lies in the grid's extent (with a tolerance of 1e-9 h).
    fn node_in_grid(&self, node: NodeKey) -> bool {
        let Some((lo, hi)) = self.extent else {
            return true;
        };
        let x = self.grid.node_position(node);
        let tol = 1e-9 * self.grid.h;
        (0..D).all(|d| x[d] >= lo[d] - tol && x[d] <= hi[d] + tol)
    }

    /// Material must stay inside the extent, or, on an unbounded grid, within
    /// the range of node indices (2^30 cells from the origin).
    fn check_inside_extent(&self, step: usize) -> Result<(), SolveError> {
        let reach = self.grid.h * crate::grid::reach_cells(D);
        let o = self.grid.origin;
        let (lo, hi) = self
            .extent
            .unwrap_or((o.map(|o| o - reach), o.map(|o| o + reach)));
        match self
            .points
            .position
            .iter()
            .position(|x| !(0..D).all(|d| x[d] >= lo[d] && x[d] <= hi[d]))
        {
            Some(point) => Err(SolveError::LeftGrid {
                step,
                point,
                at: self.points.position[point].to_vec(),
            }),
            None => Ok(()),
        }
    }
}

/// What a run's load step does that differs by dimension, beyond what its
/// equilibrium does ([`StepSpace`]). In plane strain, the terms of the
/// B-spline boundary (its loads, the IBM band and anchors), the soft
/// background, the ghost penalty and the lone points' term, and the
/// averagings against locking. In 3D: the ghost penalty on the cells'
/// faces, tractions on box faces, the surface loads and the IBM band on
/// the B-spline surfaces (whose anchors move in `after_commit`); no
/// geostatic stage yet.
pub trait RunSpace<const D: usize>: StepSpace<D>
where
    Dim<D>: StepSpace<D>,
{
    /// The stabilising terms of a step on `start` (ghost penalty, soft
    /// cells, lone points), in the order their stiffness is added to the
    /// tangent, before the boundary's.
    fn stabilisation_terms<'a>(
        sim: &'a Simulation<D>,
        start: &Configuration<'a, D>,
    ) -> Vec<Box<dyn StepTerm<D> + 'a>>;

    /// The boundary's terms of a step at `load_factor` on `start`: its
    /// curves or surfaces rebuilt through the outer points, the tractions
    /// on them and the IBM band.
    fn boundary_terms<'a>(
        sim: &'a Simulation<D>,
        start: &Configuration<'a, D>,
        load_factor: f64,
    ) -> Vec<Box<dyn StepTerm<D> + 'a>>;

    /// The averaging of the points' deformation the run asks for.
    fn averaging(sim: &Simulation<D>, start: &Configuration<D>) -> Option<Averages<D>>;

    /// What the points need of a converged step's terms (`carried`) before
    /// they move with its increment `u`.
    fn before_commit(
        sim: &mut Simulation<D>,
        conn: &Connectivity<D>,
        u: &[f64],
        carried: &[Box<dyn Any>],
    );

    /// What the next step carries once the points moved: the averaging's
    /// part (`averaged`) and the terms' (`carried`). Returns the tractions
    /// of the supports on the boundary.
    fn after_commit(
        sim: &mut Simulation<D>,
        conn: &Connectivity<D>,
        u: &[f64],
        averaged: Option<<Averages<D> as Averaging<D>>::Carried>,
        carried: Vec<Box<dyn Any>>,
    ) -> Vec<SupportTraction>;

    /// The start of geostatic stage `k`: the points in their overburden
    /// stresses, with `k0` (or each material's).
    fn start_geostatic(sim: &mut Simulation<D>, k: usize, k0: Option<f64>);

    /// Shows `observer` the converged step `report` and the run's state.
    fn step_finished(sim: &Simulation<D>, observer: &mut dyn Observer, report: &StepReport);
}

type Averages<const D: usize> = <Dim<D> as StepSpace<D>>::Averages;

impl RunSpace<2> for Dim<2> {
    fn stabilisation_terms<'a>(
        sim: &'a Simulation,
        start: &Configuration<'a>,
    ) -> Vec<Box<dyn StepTerm + 'a>> {
        let mut terms: Vec<Box<dyn StepTerm + 'a>> = Vec::new();
        if let Some(soft) = sim.soft_cells(start) {
            terms.push(Box::new(soft));
        }
        if let Some(ghost) = sim.ghost_faces(start) {
            terms.push(Box::new(ghost));
        }
        if sim.settings.lone_points {
            let lone = LonePoints::new(start);
            if !lone.is_empty() {
                terms.push(Box::new(lone));
            }
        }
        terms
    }

    fn boundary_terms<'a>(
        sim: &'a Simulation,
        start: &Configuration<'a>,
        load_factor: f64,
    ) -> Vec<Box<dyn StepTerm + 'a>> {
        let loops = &sim.loops;
        let mut terms: Vec<Box<dyn StepTerm + 'a>> = Vec::new();
        // The band always: it moves the anchors, those without a band
        // point this step with their material points.
        terms.push(Box::new(BandTerms::new(
            start,
            loops,
            &sim.anchors,
            sim.band_width,
            load_factor,
        )));
        let stage = &sim.stages[sim.stage];
        let loading = BoundaryLoading::new(start, loops, &stage.boundary_loads, load_factor);
        if !loading.is_empty() {
            terms.push(Box::new(loading));
        }
        terms
    }

    fn averaging(sim: &Simulation, start: &Configuration) -> Option<CellAverages> {
        sim.averaging(start)
    }

    /// The stress slopes of the points the one-point cells' term holds
    /// (seeded one a cell or fewer), taken before the points move; the
    /// others' are zero.
    fn before_commit(
        sim: &mut Simulation,
        conn: &Connectivity,
        u: &[f64],
        carried: &[Box<dyn Any>],
    ) {
        let mut slopes = Vec::new();
        for carried in carried {
            if let Some(lone) = carried.downcast_ref::<LonePoints>() {
                slopes = lone.settled(u, |p| {
                    let grad_u = increment(conn.point_links(p), u).1;
                    lone_points::polar_rotation(&(Matrix2::identity() + grad_u))
                });
            }
        }
        sim.points.stress_slopes.fill([0.0; 6]);
        for (p, s) in slopes {
            sim.points.stress_slopes[p] = s;
        }
    }

    fn after_commit(
        sim: &mut Simulation,
        conn: &Connectivity,
        u: &[f64],
        averaged: Option<Carried>,
        carried: Vec<Box<dyn Any>>,
    ) -> Vec<SupportTraction> {
        sim.keep_carried(averaged);
        let mut support_tractions = Vec::new();
        for carried in carried {
            if let Ok(band) = carried.downcast::<BandTerms>() {
                support_tractions = band.tractions(u);
                // A geostatic stage's too: the band's stretch is how its
                // penalty carries the reactions, which the next stage
                // starts from.
                sim.advance_anchors(&band, conn, u);
            }
        }
        support_tractions
    }

    fn start_geostatic(sim: &mut Simulation, k: usize, k0: Option<f64>) {
        let g = -sim.stages[k].gravity[0][1];
        geostatic::set_overburden_stresses(&mut sim.points, g, k0);
    }

    fn step_finished(sim: &Simulation, observer: &mut dyn Observer, report: &StepReport) {
        observer.step_finished(report, &sim.step_state());
    }
}

impl RunSpace<3> for Dim<3> {
    fn stabilisation_terms<'a>(
        sim: &'a Simulation<3>,
        start: &Configuration<'a, 3>,
    ) -> Vec<Box<dyn StepTerm<3> + 'a>> {
        let mut terms: Vec<Box<dyn StepTerm<3> + 'a>> = Vec::new();
        let gamma = sim.settings.ghost_penalty;
        if gamma > 0.0 {
            terms.push(Box::new(SolidGhostFaces::new(start, sim.basis, gamma)));
        }
        terms
    }

    fn boundary_terms<'a>(
        sim: &'a Simulation<3>,
        start: &Configuration<'a, 3>,
        load_factor: f64,
    ) -> Vec<Box<dyn StepTerm<3> + 'a>> {
        let mut terms: Vec<Box<dyn StepTerm<3> + 'a>> = Vec::new();
        let stage = &sim.stages[sim.stage];
        if !stage.face_loads.is_empty() {
            terms.push(Box::new(FaceLoading::new(
                start,
                &stage.face_loads,
                load_factor,
            )));
        }
        if !stage.surface_loads.is_empty() {
            terms.push(Box::new(SurfaceLoading::new(
                start,
                &sim.faces,
                &stage.surface_loads,
                load_factor,
            )));
        }
        if !sim.surface_anchors.is_empty() {
            terms.push(Box::new(BandTerms::on_surfaces(
                start,
                &sim.faces,
                &sim.surface_anchors,
                sim.band_width,
                load_factor,
                sim.settings.ghost_penalty == 0.0,
            )));
        }
        terms
    }

    fn averaging(sim: &Simulation<3>, start: &Configuration<3>) -> Option<CellAverages<3>> {
        sim.averaging(start)
    }

    fn before_commit(_: &mut Simulation<3>, _: &Connectivity<3>, _: &[f64], _: &[Box<dyn Any>]) {}

    /// The surface supports' anchors move with the increment; their
    /// tractions are not reported yet (the reactions carry the totals).
    fn after_commit(
        sim: &mut Simulation<3>,
        conn: &Connectivity<3>,
        u: &[f64],
        averaged: Option<Carried<3>>,
        carried: Vec<Box<dyn Any>>,
    ) -> Vec<SupportTraction> {
        sim.keep_carried(averaged);
        for carried in carried {
            if let Ok(band) = carried.downcast::<BandTerms<3>>() {
                band.advance(&mut sim.surface_anchors, u, |p| {
                    increment(conn.point_links(p), u).0
                });
            }
        }
        Vec::new()
    }

    /// No 3D stage is geostatic: [`Simulation::solid`] makes none.
    fn start_geostatic(_: &mut Simulation<3>, _: usize, _: Option<f64>) {
        unreachable!("a 3D run has no geostatic stage")
    }

    fn step_finished(sim: &Simulation<3>, observer: &mut dyn Observer, report: &StepReport) {
        observer.solid_step_finished(report, &SolidStepState::new(sim));
    }
}

impl<const D: usize> Simulation<D>
where
    Dim<D>: StepSpace<D>,
{
    /// The averaging of the points' deformation the run asks for, with
    /// what the points carry from the last step.
    fn averaging(&self, start: &Configuration<D>) -> Option<CellAverages<D>> {
        match self.volumetric {
            Volumetric::Fbar => Some(CellAverages::Fbar(
                FbarCells::new(start).carrying(start, &self.points.fbar_pressure),
            )),
            Volumetric::CellMean => Some(CellAverages::CellMean(
                CellMean::new(start, self.settings.hourglass)
                    .carrying(start, &self.points.cell_mean_stress),
            )),
            Volumetric::Standard => None,
        }
    }

    /// Keeps what the points carry of a converged step's averaging into
    /// the next.
    fn keep_carried(&mut self, averaged: Option<Carried<D>>) {
        self.points.fbar_pressure = Vec::new();
        self.points.cell_mean_stress = Vec::new();
        match averaged {
            Some(Carried::FbarPressure(pressure)) => self.points.fbar_pressure = pressure,
            Some(Carried::CellMeanStress(stress)) => self.points.cell_mean_stress = stress,
            None => {}
        }
    }
}

impl Simulation {
    /// The soft background of the tangent, with the stiffest material's
    /// constants scaled by the regularisation ratio.
    fn soft_cells(&self, start: &Configuration) -> Option<SoftCells> {
        let ratio = self.settings.tangent_regularisation;
        if ratio == 0.0 {
            return None;
        }
        let stiffest = self.stiffness.stiffest?;
        Some(SoftCells::new(start, self.basis, &stiffest, ratio))
    }

    /// The ghost penalty on the faces of the cells at the material's edge,
    /// with the modulus of the material at each face.
    fn ghost_faces(&self, start: &Configuration) -> Option<GhostFaces> {
        let gamma = self.settings.ghost_penalty;
        if gamma == 0.0 {
            return None;
        }
        Some(GhostFaces::new(start, self.basis, gamma))
    }

    /// Moves the IBM anchors with the converged increment; an anchor off
    /// the active nodes moves with its material point.
    fn advance_anchors(&mut self, band: &BandTerms, conn: &Connectivity, u: &[f64]) {
        band.advance(&mut self.anchors, u, |p| {
            increment(conn.point_links(p), u).0
        });
    }
}

impl observer::Run for Simulation {
    fn load_steps(&self) -> usize {
        self.load_steps
    }

    fn checkpoint(&self) -> crate::Checkpoint {
        Simulation::<2>::checkpoint(self)
    }
}

/// Laps of wall-clock time within a load step.
struct Stopwatch {
    start: Instant,
    lap: Instant,
}

impl Stopwatch {
    fn start() -> Self {
        let now = Instant::now();
        Self {
            start: now,
            lap: now,
        }
    }

    /// Seconds since the last lap (or the start).
    fn lap(&mut self) -> f64 {
        let now = Instant::now();
        let seconds = (now - self.lap).as_secs_f64();
        self.lap = now;
        seconds
    }

    /// Seconds from the start to the last lap: the laps' sum.
    fn total(&self) -> f64 {
        (self.lap - self.start).as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Case;
    use crate::fixtures;
    use crate::newton::Equilibrium;

    /// A size cut at a hard spot grows back once steps pass cleanly, one
    /// doubling per clean step; in flow that needs the small size, failed
    /// probes wait 1, 2, 4 clean steps apart.
    #[test]
    fn a_cut_size_grows_back_and_failed_probes_back_off() {
        let min = 1.0 / 1024.0;
        let cut = StepSize {
            size: 0.25,
            easy_in_a_row: 0,
            clean_steps: 0,
            wait: 1,
        };
        // Recovery: every probe holds.
        let mut s = cut;
        let mut sizes = Vec::new();
        for _ in 0..4 {
            let (size, probe) = s.first_try(min);
            sizes.push(size);
            s = s.after(size, 0, 0, probe);
        }
        assert_eq!(sizes, [0.25, 0.5, 1.0, 1.0]);
        // Steady flow: every probe is cut back to the old size.
        let mut s = cut;
        let mut probes = Vec::new();
        for step in 0..12 {
            let (size, probe) = s.first_try(min);
            if probe {
                probes.push(step);
            }
            s = s.after(0.25, 0, usize::from(probe), probe);
            assert!(size == 0.25 || (probe && size == 0.5));
        }
        assert_eq!(probes, [1, 4, 9]);
    }

    /// Condition number (2-norm) of the first step's tangent on the free
    /// DOFs, from the dense inverse built column by column with the
    /// step's own solver.
    fn first_tangent_condition(case: &Case) -> f64 {
        let sim = Simulation::new(case).unwrap();
        let conn = sim.reset_grid();
        let mut eq = sim.assemble(&conn, 1.0 / sim.load_steps as f64, false, None);
        let n = conn.n_dofs();
        eq.out_of_balance(&vec![0.0; n]).unwrap();
        let free: Vec<usize> = (0..n).filter(|&i| !eq.is_held(i)).collect();
        let mut inverse = nalgebra::DMatrix::zeros(free.len(), free.len());
        for (j, &dof) in free.iter().enumerate() {
            let mut e = vec![0.0; n];
            e[dof] = 1.0;
            let (column, _) = eq.correction(&e, 1e-12).unwrap();
            for (i, &row) in free.iter().enumerate() {
                inverse[(i, j)] = column[row];
            }
        }
        let sym = (&inverse + inverse.transpose()) * 0.5;
        let eig = sym.symmetric_eigenvalues();
        let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(a, b), v| {
            (a.min(v.abs()), b.max(v.abs()))
        });
        hi / lo
    }

    /// How the band width conditions the system: the IBM patch test (unit
    /// block, rollers and a prescribed stretch by the IBM, GIMP, grid cut
    /// at (0.1, 0.07), h = 0.25). The penalty is about (4/3) h / delta times
    /// a cell's stiffness, so the condition number should grow tenfold per
    /// decade of delta once the penalty dominates. Measured: 3.1e2, 2.7e3,
    /// 2.6e4, 2.6e5, 2.6e6 for delta = h/10 .. h/10^5; the same block on
    /// grid-node supports (aligned grid): 3.6e1.
    #[test]
    fn band_width_sets_the_conditioning() {
        let case = |delta: Option<f64>| {
            let mut c = fixtures::block([1.0, 1.0], [8, 8], 0.25, [0.1, 0.07]);
            c["basis"] = "gimp".into();
            c["bodies"][0]["material"]["model"] = "linear_elastic".into();
            c["supports"] = serde_json::json!([
                { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
                { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" },
                { "on": { "x": 1.0 }, "fix": "x", "method": "ibm", "displacement": [0.01, 0.0] }
            ]);
            if let Some(d) = delta {
                c["boundary"] = serde_json::json!({ "band_width": d });
            }
            fixtures::case(&c)
        };
        let mut grid = case(None);
        grid.grid.origin = [0.0, 0.0];
        grid.supports = serde_json::from_value(serde_json::json!([
            { "on": { "x": 0.0 }, "fix": "x" },
            { "on": { "y": 0.0 }, "fix": "y" },
            { "on": { "x": 1.0 }, "fix": "x" }
        ]))
        .unwrap();
        let baseline = first_tangent_condition(&grid);
        eprintln!("grid-node supports, aligned grid: condition number {baseline:.2e}");
        let mut conditions = Vec::new();
        for k in 1..=5 {
            let kappa = first_tangent_condition(&case(Some(0.25 / 10f64.powi(k))));
            eprintln!("delta = h/1e{k}: condition number {kappa:.2e}");
            conditions.push(kappa);
        }
        for w in conditions.windows(2).skip(1) {
            let ratio = w[1] / w[0];
            assert!(ratio > 8.0 && ratio < 12.0, "{conditions:?}");
        }
    }

    /// The tangent is the exact derivative of the out-of-balance force, for
    /// each term that builds it: F-bar's coupling (cells of one, two and
    /// four points of unequal volumes, GIMP, a grid cut at an offset, held
    /// nodes, a follower pressure), the ghost penalty, the return maps
    /// of non-associated flow (Mohr-Coulomb and Drucker-Prager, `psi = 0`,
    /// every point flowing) and von Mises's with and without F-bar (every
    /// point flowing: the pushed footing's model). Checked through
    /// the step's own solver: for a direction `v` on the free DOFs,
    /// `K^-1 (r(u + e v) - r(u - e v)) / (2 e)` must be `-v`, at a trial
    /// state `u` away from the start, to the central difference's error
    /// (e^2 times the third derivative; e = 1e-6 of the state). Measured:
    /// 6.2e-9 (F-bar), 6.1e-10 (ghost), 1.2e-9 (both); without F-bar's
    /// coupling term, 85; 1.4e-7 (Mohr-Coulomb) and 1.3e-7
    /// (Drucker-Prager), where perfect plastic flow leaves the tangent soft;
    /// von Mises 7.0e-9 with F-bar and 2.5e-9 without.
    #[test]
    fn the_tangent_is_the_derivative_of_the_residual() {
        for (volumetric, ghost, model) in [
            ("fbar", 0.0, "hencky"),
            ("standard", 1e-2, "hencky"),
            ("fbar", 1e-2, "hencky"),
            ("fbar", 0.0, "linear_elastic"),
            ("standard", 0.0, "mohr_coulomb"),
            ("standard", 0.0, "drucker_prager"),
            ("fbar", 0.0, "von_mises"),
            ("standard", 0.0, "von_mises"),
        ] {
            let mut case = fixtures::block([2.0, 1.0], [7, 5], 0.5, [0.1, 0.13]);
            case["analysis"]["volumetric"] = volumetric.into();
            case["analysis"]["stabilisation"] = serde_json::json!({ "ghost_penalty": ghost });
            case["basis"] = "gimp".into();
            case["bodies"][0]["material"]["model"] = model.into();
            let frictional = matches!(model, "mohr_coulomb" | "drucker_prager");
            case["bodies"][0]["material"]["poisson_ratio"] =
                if frictional { 0.3 } else { 0.45 }.into();
            if model == "von_mises" {
                case["bodies"][0]["material"]["yield_stress"] = 2e3.into();
            }
            if frictional {
                let material = &mut case["bodies"][0]["material"];
                material["cohesion"] = 2e3.into();
                material["friction_angle"] = 30.0.into();
                material["dilation_angle"] = 0.0.into();
            }
            case["loads"] =
                serde_json::json!({ "boundary": [ { "on": { "y": 1.0 }, "pressure": 2e4 } ] });
            case["supports"] = serde_json::json!([ { "on": { "x": 0.1 }, "fix": "xy" } ]);
            let sim = fixtures::simulation(&case);
            let conn = sim.reset_grid();
            let mut eq = sim.assemble(&conn, 1.0, false, None);
            let n = conn.n_dofs();
            // A smooth trial state and direction: bending and squeezing.
            let field = |a: f64, b: f64| -> Vec<f64> {
                (0..n)
                    .map(|dof| {
                        let x = sim.grid.node_position(conn.nodes[dof / 2]);
                        if eq.is_held(dof) {
                            0.0
                        } else if dof % 2 == 0 {
                            a * x[1] * x[0] + b * x[0] * x[0]
                        } else {
                            -a * x[0] * x[0] + b * x[1]
                        }
                    })
                    .collect()
            };
            // Frictional points sheared and squeezed everywhere (div u < 0,
            // zero on the held line x = 0.1), away from the apex their flow
            // rule cannot reach without dilation.
            let sheared = || -> Vec<f64> {
                (0..n)
                    .map(|dof| {
                        let x = sim.grid.node_position(conn.nodes[dof / 2]);
                        let from_held = x[0] - 0.1;
                        if dof % 2 == 0 {
                            -0.006 * from_held
                        } else {
                            (0.05 - 0.003 * x[1]) * from_held
                        }
                    })
                    .collect()
            };
            let u = if frictional {
                sheared()
            } else {
                field(0.02, -0.01)
            };
            let v = field(-0.3, 0.5);
            if frictional || model == "von_mises" {
                let mp = &sim.points;
                let flowing = (0..mp.len())
                    .filter(|&p| {
                        let (_, grad_u) =
                            crate::grid::connectivity::increment(conn.point_links(p), &u);
                        let material = &mp.materials[mp.material[p] as usize];
                        let j_start = mp.deformation[p].determinant();
                        let response = material.respond(&mp.history[p], &grad_u, j_start);
                        response.history.plastic_strain > 0.0
                    })
                    .count();
                eprintln!("{model}: {flowing} of {} points flow at u", mp.len());
                assert!(2 * flowing > mp.len(), "{model}: {flowing} flow");
            }
            let e = 1e-6;
            let shifted = |eq: &mut StepEquilibrium, sign: f64| {
                let w: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a + sign * e * b).collect();
                eq.out_of_balance(&w).unwrap().0
            };
            let (plus, minus) = (shifted(&mut eq, 1.0), shifted(&mut eq, -1.0));
            let dr: Vec<f64> = plus
                .iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * e))
                .collect();
            eq.out_of_balance(&u).unwrap();
            let (w, _) = eq.correction(&dr, 1e-12).unwrap();
            let norm = |x: &[f64]| x.iter().map(|a| a * a).sum::<f64>().sqrt();
            let error: Vec<f64> = w.iter().zip(&v).map(|(a, b)| a + b).collect();
            let relative = norm(&error) / norm(&v);
            eprintln!("{volumetric}, ghost {ghost}, {model}: {relative:e}");
            assert!(
                relative < 1e-6,
                "{volumetric}, ghost {ghost}, {model}: {relative:e}"
            );
        }
    }

    /// A step whose pattern is the last step's reuses its solver and the
    /// symbolic analysis, and gets the answer of a fresh one to the bit:
    /// the cantilever under 1/750 of its weight moves 3.6 mm at most, and
    /// its points start 0.125 m from the edges of their 0.5 m cells, so all
    /// four steps have one pattern.
    #[test]
    fn an_unchanged_pattern_reuses_the_analysis_exactly() {
        let mut case = crate::case::builtin::json("cantilever-grid").unwrap();
        case["bodies"][0]["material"]["density"] = 0.1.into();
        case["analysis"]["load_steps"] = 4.into();
        let case = Case::from_json(&case.to_string()).unwrap();
        let run = |reuse: bool| {
            let mut sim = Simulation::new(&case).unwrap();
            for step in 1..=4 {
                if !reuse {
                    sim.analysed = None;
                }
                sim.load_step(step, &mut crate::NoObserver).unwrap();
            }
            let reuses = sim.analysed.as_ref().map(|a| a.solver.reuses());
            (sim.points.position, reuses)
        };
        let (reusing, reuses) = run(true);
        let (fresh, none) = run(false);
        assert_eq!(reuses, Some(3));
        assert_eq!(none, Some(0));
        assert_eq!(reusing, fresh);
    }
}
