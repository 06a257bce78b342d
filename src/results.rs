//! The layout of a run's results, the same in `mpm run`'s output directory
//! and in a job's archive (`GET /jobs/{id}/archive`):
//!
//! - `case.json`: the case as run;
//! - `summary.json`: cost, and per step the convergence, probes and reactions;
//! - `points.pvd`, `boundary.pvd`: the VTK series (open them in ParaView);
//! - `steps/step_NNNN.json`: a step's document (report, points, boundaries);
//! - `steps/step_NNNN.vtu`: its material points;
//! - `steps/step_NNNN_boundary.vtp`: its boundary curves.
//!
//! Steps whose points the case's `output` does not store have no files.

use std::collections::BTreeMap;
use std::io::{self, Write};

use mpm::StepReport;
use mpm::report::{RunWarning, StepTimings, StrengthStep};
use mpm::vtk::write_pvd;
use serde::Serialize;

pub const CASE_FILE: &str = "case.json";
pub const SUMMARY_FILE: &str = "summary.json";
pub const POINTS_SERIES: &str = "points.pvd";
pub const BOUNDARY_SERIES: &str = "boundary.pvd";
pub const STEPS_DIR: &str = "steps";

/// A step's three files, relative to the results' root.
pub struct StepFiles {
    pub document: String,
    pub points: String,
    pub boundary: String,
}

impl StepFiles {
    pub fn new(step: usize) -> Self {
        let stem = format!("{STEPS_DIR}/step_{step:04}");
        Self {
            document: format!("{stem}.json"),
            points: format!("{stem}.vtu"),
            boundary: format!("{stem}_boundary.vtp"),
        }
    }
}

/// The `.pvd` series: the VTK files of each step written, by load factor
/// (by step for a case with stages: [`mpm::StepReport::series_time`]).
#[derive(Default)]
pub struct Series {
    points: Vec<(f64, String)>,
    boundary: Vec<(f64, String)>,
}

impl Series {
    pub fn add(&mut self, load_factor: f64, files: StepFiles) {
        self.points.push((load_factor, files.points));
        self.boundary.push((load_factor, files.boundary));
    }

    pub fn write_points(&self, out: impl Write) -> io::Result<()> {
        write_pvd(out, &self.points)
    }

    pub fn write_boundary(&self, out: impl Write) -> io::Result<()> {
        write_pvd(out, &self.boundary)
    }
}

/// `summary.json`: the run's cost and per-step convergence, probes keyed by
/// name.
#[derive(Serialize)]
pub struct Summary<'a> {
    /// Where the case came from: its file, the built-in example, the job.
    pub case: &'a str,
    /// The step a resumed run went on after.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resumed_from: Option<usize>,
    pub title: Option<&'a str>,
    pub points: usize,
    pub load_steps: usize,
    pub wall_seconds: f64,
    /// Newton iterations of the steps' converged pieces.
    pub newton_iterations: usize,
    /// Pieces the steps were solved in (one for a step solved whole).
    pub substeps: usize,
    /// Tries that failed and were cut (a strength reduction's failed
    /// trials among them).
    pub cutbacks: usize,
    /// Newton iterations spent on the tries that failed.
    pub failed_iterations: usize,
    /// Why a job failed (`{kind, message, step?, iteration?, residual?}`):
    /// its steps are those finished before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<serde_json::Value>,
    /// The largest loads the finished steps carried.
    pub peaks: Peaks<'a>,
    /// A strength-reduction run's last step's factors: its factor of
    /// safety once `found`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strength_reduction: Option<&'a StrengthStep>,
    /// What the case and its steps warn of (`mpm::model::warnings`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<RunWarning>,
    pub steps: Vec<StepSummary<'a>>,
}

/// The largest loads a run carried, by magnitude: its applied load (a
/// load-controlled run's peak) and each support's reaction (a
/// displacement-controlled run's, on the support that pushes). A run that
/// failed past its peak has passed it in these steps; one that failed
/// before its peak (a load-controlled collapse) gives, in its `error`, the
/// load factor it reached.
#[derive(Serialize, Default)]
pub struct Peaks<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub applied_load: Option<Peak<'a>>,
    /// One per support (of each stage, when the case has stages).
    pub reactions: Vec<Peak<'a>>,
}

#[derive(Serialize, Clone)]
pub struct Peak<'a> {
    pub step: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<&'a str>,
    pub load_factor: f64,
    /// The support's place among the case's (or its stage's) supports.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub support: Option<usize>,
    /// The force (N per metre), `D` components.
    pub value: &'a [f64],
}

impl<'a> Peaks<'a> {
    pub fn of(steps: &'a [StepReport]) -> Self {
        let magnitude = |v: &[f64]| v.iter().fold(0.0, |m: f64, c| m.hypot(*c));
        let peak = |s: &'a StepReport, support: Option<usize>, value: &'a [f64]| Peak {
            step: s.step,
            stage: s.stage.as_deref(),
            load_factor: s.load_factor,
            support,
            value,
        };
        let mut peaks = Peaks::default();
        // Per (stage, support), the first step of the largest magnitude.
        let mut reactions: Vec<Peak<'a>> = Vec::new();
        for s in steps.iter().filter(|s| s.step > 0) {
            if peaks
                .applied_load
                .as_ref()
                .is_none_or(|p| magnitude(&s.applied_load) > magnitude(p.value))
            {
                peaks.applied_load = Some(peak(s, None, &s.applied_load));
            }
            for (j, r) in s.reactions.iter().enumerate() {
                let at = reactions
                    .iter()
                    .position(|p| p.stage == s.stage.as_deref() && p.support == Some(j));
                match at {
                    None => reactions.push(peak(s, Some(j), r)),
                    Some(i) if magnitude(r) > magnitude(reactions[i].value) => {
                        reactions[i] = peak(s, Some(j), r);
                    }
                    Some(_) => {}
                }
            }
        }
        peaks.reactions = reactions;
        peaks
    }
}

#[derive(Serialize)]
pub struct StepSummary<'a> {
    pub step: usize,
    /// The step's stage, when the case has stages.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<&'a str>,
    pub load_factor: f64,
    pub newton_iterations: usize,
    pub residuals: &'a [f64],
    pub substeps: usize,
    pub cutbacks: usize,
    pub failed_iterations: usize,
    /// Points whose cell is not the one they started the run in.
    pub points_in_new_cells: usize,
    pub wall_seconds: f64,
    pub active_dofs: usize,
    pub timings: &'a StepTimings,
    pub probes: BTreeMap<&'a str, ProbeSummary<'a>>,
    /// Force on each support (N/m, the order of the case's `supports`, or
    /// of the step's stage's).
    pub reactions: &'a [Vec<f64>],
    pub applied_load: &'a [f64],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strength_reduction: Option<&'a StrengthStep>,
}

#[derive(Serialize)]
pub struct ProbeSummary<'a> {
    pub position: &'a [f64],
    pub displacement: &'a [f64],
}

impl<'a> Summary<'a> {
    /// The summary of the load steps in `steps` (step 0, the initial
    /// state, is left out).
    pub fn new(
        case: &'a str,
        title: Option<&'a str>,
        points: usize,
        load_steps: usize,
        wall_seconds: f64,
        steps: &'a [StepReport],
    ) -> Self {
        let all = steps;
        let steps: Vec<StepSummary<'a>> = steps
            .iter()
            .filter(|s| s.step > 0)
            .map(|s| StepSummary {
                step: s.step,
                stage: s.stage.as_deref(),
                load_factor: s.load_factor,
                newton_iterations: s.newton.iterations,
                residuals: &s.newton.residuals,
                substeps: s.substeps,
                cutbacks: s.cutbacks,
                failed_iterations: s.failed_iterations,
                points_in_new_cells: s.points_in_new_cells,
                wall_seconds: s.timings.total,
                active_dofs: s.active_dofs,
                timings: &s.timings,
                probes: s
                    .probes
                    .iter()
                    .map(|p| {
                        let probe = ProbeSummary {
                            position: &p.position,
                            displacement: &p.displacement,
                        };
                        (p.name.as_str(), probe)
                    })
                    .collect(),
                reactions: &s.reactions,
                applied_load: &s.applied_load,
                strength_reduction: s.strength_reduction.as_ref(),
            })
            .collect();
        Self {
            case,
            resumed_from: None,
            title,
            points,
            load_steps,
            wall_seconds,
            newton_iterations: steps.iter().map(|s| s.newton_iterations).sum(),
            substeps: steps.iter().map(|s| s.substeps).sum(),
            cutbacks: steps.iter().map(|s| s.cutbacks).sum(),
            failed_iterations: steps.iter().map(|s| s.failed_iterations).sum(),
            error: None,
            peaks: Peaks::of(all),
            strength_reduction: all.iter().rev().find_map(|s| s.strength_reduction.as_ref()),
            warnings: Vec::new(),
            steps,
        }
    }
}
