//! What a run reports: per-step summaries, Newton's history and the
//! material-point state as JSON columns (all serialisable). The VTK writers
//! for ParaView are in [`crate::vtk`].

use serde::Serialize;

use crate::linsolve::{Factorisation, SolverMemory};
use crate::particles::MaterialPoints;

/// Wall-clock seconds spent in each stage of a load step. The stages add
/// up to `total`, the step's wall time, within the clock's laps.
#[derive(Debug, Clone, Copy, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct StepTimings {
    /// Grid reset: shape functions, active nodes, stiffness pattern, loads.
    pub grid: f64,
    /// Point loop: trial stress and tangent of every point, internal force.
    pub point_loop: f64,
    /// Tangent stiffness assembly (with constraints).
    pub assembly: f64,
    /// Sparse factorisation (symbolic analysis included on first use).
    pub factorisation: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Moving points and probes, committing state.
    pub update: f64,
    /// Newton's own work besides the point loop (which makes the
    /// residuals), the assembly and the solves: its vector updates and
    /// convergence checks, the line search's bookkeeping, the predictor.
    #[serde(default)]
    pub newton: f64,
    /// Tries of the step that failed and were cut (their work is done
    /// again in smaller pieces), whole.
    #[serde(default)]
    pub failed: f64,
    pub total: f64,
    /// Of the stages above, the boundary's terms (tractions on curves and
    /// surfaces, the IBM band): made at the step's start (the boundary
    /// rebuilt through the outer points, its quadrature, the band's
    /// anchors located on the grid) within `grid`, their forces within
    /// `point_loop`, their stiffness within `assembly`.
    #[serde(default)]
    pub boundary: f64,
}

impl std::ops::AddAssign<&StepTimings> for StepTimings {
    /// Sums stage by stage (timings of several steps).
    fn add_assign(&mut self, t: &StepTimings) {
        self.grid += t.grid;
        self.point_loop += t.point_loop;
        self.assembly += t.assembly;
        self.factorisation += t.factorisation;
        self.solve += t.solve;
        self.update += t.update;
        self.newton += t.newton;
        self.failed += t.failed;
        self.total += t.total;
        self.boundary += t.boundary;
    }
}

/// Heap bytes of a load step's largest data, by component, at the end of
/// its last Newton iteration. The factorisation's scratch lives only while
/// a factorisation runs; the rest is alive together at the tangent's
/// assembly and solve.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct StepMemory {
    /// The material points' state: positions, volumes, deformation,
    /// history, stress.
    pub points: usize,
    /// Point-node links (node, shape function value and gradient) and the
    /// active nodes' keys.
    pub links: usize,
    /// The stiffness pattern: node adjacency, the points in tiles for the
    /// assembly, and the compressed columns' pointers and row indices.
    pub pattern: usize,
    /// The tangent's values.
    pub tangent: usize,
    /// What the point loop keeps between Newton iterations: F-bar's cell
    /// averages and coupling terms (the points' responses are made again
    /// where they are used, not kept).
    pub responses: usize,
    /// The factorisation.
    pub solver: SolverMemory,
}

impl StepMemory {
    pub fn total(&self) -> usize {
        self.points
            + self.links
            + self.pattern
            + self.tangent
            + self.responses
            + self.solver.factor_values
            + self.solver.factor_structure
            + self.solver.scratch
            + self.solver.multigrid
            + self.solver.gmres
    }
}

#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct ProbeReport {
    pub name: String,
    /// Where the probe is now, and how far it moved (`D` components).
    pub position: Vec<f64>,
    pub displacement: Vec<f64>,
}

/// The zero load of a step stored before steps reported theirs (plane
/// strain).
fn plane_zero() -> Vec<f64> {
    vec![0.0; 2]
}

/// Summary of one converged load step.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct StepReport {
    /// Counts from 1, over all stages.
    pub step: usize,
    /// The stage it belongs to, when the case has stages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    /// The load factor within its stage (from 0 at its start to 1 at its
    /// end).
    pub load_factor: f64,
    pub newton: NewtonInfo,
    /// Sub-increments the step was solved in: 1 unless a failed increment
    /// was cut (see [`crate::Substepping`]).
    #[serde(default = "one")]
    pub substeps: usize,
    /// Sub-increments that failed and were retried at half the size.
    #[serde(default)]
    pub cutbacks: usize,
    /// Linear solves spent on the failed tries (not in `newton`, which
    /// holds the converged sub-increments').
    #[serde(default)]
    pub failed_iterations: usize,
    pub timings: StepTimings,
    /// Points whose cell is not the one they started the run in (the
    /// bilinear basis's gradient jumps where they crossed).
    #[serde(default)]
    pub points_in_new_cells: usize,
    pub active_nodes: usize,
    /// Unconstrained degrees of freedom in the system.
    pub active_dofs: usize,
    pub probes: Vec<ProbeReport>,
    /// Force each support exerts on the body, in the order of the case's
    /// `supports`.
    pub reactions: Vec<Vec<f64>>,
    /// Resultant of the loads applied to the grid in this step (gravity,
    /// point loads and boundary loads on the converged boundary): at
    /// equilibrium the reactions add up to minus this, unless two grid
    /// supports hold the same component of a node (both then report its
    /// force). Zero when absent from a stored step.
    #[serde(default = "plane_zero")]
    pub applied_load: Vec<f64>,
    /// How the implicit-boundary supports' reactions are spread along
    /// their stretches: one entry per constraint of the band (a quadrature
    /// point of a pointwise support, a piece of an averaged one), in the
    /// order of the case's supports. Empty when absent from a stored step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub support_tractions: Vec<SupportTraction>,
    /// A strength-reduction step's factors: the one its state holds at,
    /// and the bisection's bracket then.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength_reduction: Option<StrengthStep>,
    /// What the step's data weighed (for benchmarks; not stored).
    #[serde(skip)]
    pub memory: StepMemory,
}

/// What the last converged increment reported of the state it left,
/// besides the points: the step that finds the factor of safety after a
/// failed trial reports the state of the last trial that held, which it
/// does not solve again.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub(crate) struct Settled {
    pub(crate) reactions: Vec<Vec<f64>>,
    pub(crate) applied_load: Vec<f64>,
    pub(crate) support_tractions: Vec<SupportTraction>,
    pub(crate) active_nodes: usize,
    pub(crate) active_dofs: usize,
}

/// Where a strength-reduction stage stood after one of its steps.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct StrengthStep {
    /// The factor the strengths were divided by in the step's state (the
    /// largest that held so far).
    pub factor: f64,
    /// The smallest factor that failed so far, if one has.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failed: Option<f64>,
    /// Whether `factor` is the factor of safety: `failed` is within the
    /// stage's tolerance above it, and was tried from close below. The
    /// run ends at the step that finds it.
    pub found: bool,
    /// Why the step's last failed trial failed, if one did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// How far the trial that held in this step moved the points, per
    /// unit of the factor's rise, as a multiple of their displacement at
    /// the stage's start (root mean squares over the volume): what the
    /// stage's `flow_limit` bounds. Left out where nothing measured it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flow: Option<f64>,
}

/// The traction an implicit-boundary support exerts on the body at one of
/// its constraints: its force over the length of boundary the constraint
/// stands for, at the (length-weighted) mean place of that length.
#[derive(Debug, Clone, Copy, Serialize, serde::Deserialize, PartialEq)]
pub struct SupportTraction {
    /// Index of the support in the case.
    pub support: usize,
    /// Current position (m).
    pub at: [f64; 2],
    /// Length of boundary it stands for (m).
    pub length: f64,
    /// Force per unit length on the body (Pa).
    pub traction: [f64; 2],
}

impl StepReport {
    /// Folds the next sub-increment of the same load step into this one:
    /// its Newton history and costs add, its state (load factor, probes,
    /// reactions) replaces.
    pub fn merge(&mut self, next: StepReport) {
        let mut newton = std::mem::take(&mut self.newton);
        newton.extend(next.newton);
        let mut timings = self.timings;
        timings += &next.timings;
        let substeps = self.substeps + next.substeps;
        *self = StepReport {
            newton,
            timings,
            substeps,
            cutbacks: self.cutbacks,
            failed_iterations: self.failed_iterations,
            ..next
        };
    }
}

fn one() -> usize {
    1
}

/// What a run's reader should know beside its numbers
/// (`model::warnings`): `kind` for scripts, `message` for people.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunWarning {
    pub kind: &'static str,
    pub message: String,
}

/// Summary of a whole run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunReport {
    pub points: usize,
    pub load_steps: usize,
    pub wall_seconds: f64,
    pub steps: Vec<StepReport>,
}

/// A column of [`PointColumns`] (a case's `output.fields` names them:
/// `crate::model::point_fields`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointField {
    Position,
    Displacement,
    Stress,
    Volume,
    Jacobian,
    Body,
    PlasticStrain,
    Yielding,
}

/// The material-point state as columns, for JSON. A column left out by the
/// case's `output.fields` is empty and not written.
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct PointColumns {
    pub position: Vec<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub displacement: Vec<[f64; 2]>,
    /// Cauchy stress `[xx, yy, xy, zz]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stress: Vec<[f64; 4]>,
    /// Current volume `J V0`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub volume: Vec<f64>,
    /// Volume ratio `J = det F`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub jacobian: Vec<f64>,
    /// Index of the body the point belongs to.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub body: Vec<u32>,
    /// Accumulated plastic strain (zero for the elastic models).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub plastic_strain: Vec<f64>,
    /// Whether the point flowed plastically in the step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub yielding: Vec<bool>,
}

impl PointColumns {
    /// Every column.
    pub fn new(mp: &MaterialPoints) -> Self {
        Self::selected(mp, None)
    }

    /// `position` and the columns in `fields` (all when `None`).
    pub fn selected(mp: &MaterialPoints, fields: Option<&[PointField]>) -> Self {
        let n = mp.len();
        let wanted = |f: PointField| fields.is_none_or(|fs| fs.contains(&f));
        let mut columns = Self {
            position: mp.position.clone(),
            ..Self::default()
        };
        if wanted(PointField::Displacement) {
            columns.displacement = (0..n).map(|p| mp.displacement(p)).collect();
        }
        if wanted(PointField::Stress) {
            columns.stress = mp
                .stress
                .iter()
                .map(|s| [s.plane[0], s.plane[1], s.plane[2], s.zz])
                .collect();
        }
        if wanted(PointField::Volume) {
            columns.volume = (0..n).map(|p| mp.volume(p)).collect();
        }
        if wanted(PointField::Jacobian) {
            columns.jacobian = (0..n).map(|p| mp.jacobian(p)).collect();
        }
        if wanted(PointField::Body) {
            columns.body = mp.material.clone();
        }
        if wanted(PointField::PlasticStrain) {
            columns.plastic_strain = mp.history.iter().map(|h| h.plastic_strain).collect();
        }
        if wanted(PointField::Yielding) {
            columns.yielding = mp.yielding.clone();
        }
        columns
    }
}

/// A 3D run's material points as columns, for JSON: every column of
/// [`PointColumns`], vectors of three components, and the Cauchy stress
/// as the full symmetric tensor `[xx, yy, zz, xy, yz, xz]` (VTK's order).
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct SolidPointColumns {
    pub position: Vec<[f64; 3]>,
    pub displacement: Vec<[f64; 3]>,
    pub stress: Vec<[f64; 6]>,
    pub volume: Vec<f64>,
    pub jacobian: Vec<f64>,
    pub body: Vec<u32>,
    pub plastic_strain: Vec<f64>,
    pub yielding: Vec<bool>,
}

impl SolidPointColumns {
    pub fn new(mp: &MaterialPoints<3>) -> Self {
        let n = mp.len();
        Self {
            position: mp.position.clone(),
            displacement: (0..n).map(|p| mp.displacement(p)).collect(),
            stress: (mp.stress.iter())
                .map(|s| {
                    [
                        s[(0, 0)],
                        s[(1, 1)],
                        s[(2, 2)],
                        s[(0, 1)],
                        s[(1, 2)],
                        s[(0, 2)],
                    ]
                })
                .collect(),
            volume: (0..n).map(|p| mp.volume(p)).collect(),
            jacobian: (0..n).map(|p| mp.jacobian(p)).collect(),
            body: mp.material.clone(),
            plastic_strain: mp.history.iter().map(|h| h.plastic_strain).collect(),
            yielding: mp.yielding.clone(),
        }
    }
}

impl StepReport {
    /// What a series of steps runs along (a `.pvd`'s times): the load
    /// factor, or the step when the case has stages, whose load factor
    /// runs over each.
    pub fn series_time(&self) -> f64 {
        if self.stage.is_some() {
            self.step as f64
        } else {
            self.load_factor
        }
    }
}

/// How a load step's Newton solves went (over all its sub-increments, in
/// order, when it was cut).
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct NewtonInfo {
    /// Linear solves performed.
    pub iterations: usize,
    /// Relative out-of-balance force before each solve and at convergence.
    pub residuals: Vec<f64>,
    /// Length of each step taken along a Newton direction: 1 for the full
    /// step, less where the line search cut it.
    #[serde(default)]
    pub step_lengths: Vec<f64>,
    /// Factorisation of the last solve (`None` if no solve was needed).
    pub factorisation: Option<Factorisation>,
}

impl NewtonInfo {
    /// Appends the solve of the next sub-increment.
    pub fn extend(&mut self, next: NewtonInfo) {
        self.iterations += next.iterations;
        self.residuals.extend(next.residuals);
        self.step_lengths.extend(next.step_lengths);
        self.factorisation = next.factorisation.or(self.factorisation);
    }
}
