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
use mpm::report::StepTimings;
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

/// The `.pvd` series: the VTK files of each step written, by load factor.
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
    pub newton_iterations: usize,
    /// Why a job failed (`{kind, message, step?, iteration?, residual?}`):
    /// its steps are those finished before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<serde_json::Value>,
    pub steps: Vec<StepSummary<'a>>,
}

#[derive(Serialize)]
pub struct StepSummary<'a> {
    pub step: usize,
    pub load_factor: f64,
    pub newton_iterations: usize,
    pub residuals: &'a [f64],
    pub wall_seconds: f64,
    pub active_dofs: usize,
    pub timings: &'a StepTimings,
    pub probes: BTreeMap<&'a str, ProbeSummary>,
    /// Force on each support (N/m, the order of the case's `supports`).
    pub reactions: &'a [[f64; 2]],
    pub applied_load: [f64; 2],
}

#[derive(Serialize)]
pub struct ProbeSummary {
    pub position: [f64; 2],
    pub displacement: [f64; 2],
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
        let steps: Vec<StepSummary<'a>> = steps
            .iter()
            .filter(|s| s.step > 0)
            .map(|s| StepSummary {
                step: s.step,
                load_factor: s.load_factor,
                newton_iterations: s.newton.iterations,
                residuals: &s.newton.residuals,
                wall_seconds: s.timings.total,
                active_dofs: s.active_dofs,
                timings: &s.timings,
                probes: s
                    .probes
                    .iter()
                    .map(|p| {
                        let probe = ProbeSummary {
                            position: p.position,
                            displacement: p.displacement,
                        };
                        (p.name.as_str(), probe)
                    })
                    .collect(),
                reactions: &s.reactions,
                applied_load: s.applied_load,
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
            error: None,
            steps,
        }
    }
}
