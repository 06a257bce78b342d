//! `mpm run`: solve one case, show progress on stderr, print a line per step
//! and write the results.

use std::fs::{self, File};
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};

use mpm::report::PointColumns;
use mpm::vtk::{write_pvd, write_vtp, write_vtu};
use mpm::{Case, Observer, RunReport, Simulation, StepReport, StepState};
use mpm_service::step::StepDocument;
use serde::Serialize;

use crate::{CliError, DEFAULT_EXAMPLE};

pub fn run(
    case_path: Option<PathBuf>,
    example: Option<String>,
    out: &Path,
    point_files: bool,
) -> Result<(), CliError> {
    let (source, text) = match case_path {
        Some(path) => {
            let text = fs::read_to_string(&path)
                .map_err(|e| CliError::input(format!("cannot read {}: {e}", path.display())))?;
            (path.display().to_string(), text)
        }
        None => {
            let name = example.as_deref().unwrap_or(DEFAULT_EXAMPLE);
            let text = mpm::case::builtin::get(name)
                .ok_or_else(|| CliError::input(format!("no built-in example {name:?}")))?;
            (format!("built-in example {name}"), text.to_string())
        }
    };
    let case = Case::from_json(&text).map_err(|e| CliError::input(format!("{source}: {e}")))?;
    let mut sim = Simulation::new(&case).map_err(|e| CliError::input(format!("{source}: {e}")))?;
    eprintln!(
        "{}: {} material points, {} load steps, {:?} basis, cells of {} m",
        case.title.as_deref().unwrap_or(&source),
        sim.points.len(),
        sim.load_steps,
        sim.basis,
        sim.grid.h
    );
    let steps_dir = out.join("steps");
    fs::create_dir_all(&steps_dir)?;
    let mut writer = ResultWriter {
        steps_dir,
        point_files,
        step_files: Vec::new(),
        boundary_files: Vec::new(),
        progress: Progress::new(),
        io_error: None,
    };
    let result = sim.run(&mut writer);
    writer.progress.finish();
    if let Some(e) = writer.io_error {
        return Err(e.into());
    }
    let report = result.map_err(|e| CliError::failed(format!("solve failed: {e}")))?;
    if point_files {
        write_pvd(
            BufWriter::new(File::create(out.join("points.pvd"))?),
            &writer.step_files,
        )?;
        write_pvd(
            BufWriter::new(File::create(out.join("boundary.pvd"))?),
            &writer.boundary_files,
        )?;
    }
    let summary = Summary::new(&case, &source, &report);
    let mut f = BufWriter::new(File::create(out.join("summary.json"))?);
    serde_json::to_writer_pretty(&mut f, &summary).map_err(|e| CliError::failed(e.to_string()))?;
    f.flush()?;
    eprintln!(
        "done in {:.3} s; results in {}",
        report.wall_seconds,
        out.display()
    );
    Ok(())
}

/// `summary.json`: the run's cost and per-step convergence, probes keyed by
/// name.
#[derive(Serialize)]
struct Summary<'a> {
    case: &'a str,
    title: Option<&'a str>,
    points: usize,
    load_steps: usize,
    wall_seconds: f64,
    newton_iterations: usize,
    steps: Vec<StepSummary<'a>>,
}

#[derive(Serialize)]
struct StepSummary<'a> {
    step: usize,
    load_factor: f64,
    newton_iterations: usize,
    residuals: &'a [f64],
    wall_seconds: f64,
    active_dofs: usize,
    timings: &'a mpm::report::StepTimings,
    probes: std::collections::BTreeMap<&'a str, ProbeSummary>,
    reactions: &'a [[f64; 2]],
    applied_load: [f64; 2],
}

#[derive(Serialize)]
struct ProbeSummary {
    position: [f64; 2],
    displacement: [f64; 2],
}

impl<'a> Summary<'a> {
    fn new(case: &'a Case, source: &'a str, report: &'a RunReport) -> Self {
        Self {
            case: source,
            title: case.title.as_deref(),
            points: report.points,
            load_steps: report.load_steps,
            wall_seconds: report.wall_seconds,
            newton_iterations: report.steps.iter().map(|s| s.newton.iterations).sum(),
            steps: report
                .steps
                .iter()
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
                            (
                                p.name.as_str(),
                                ProbeSummary {
                                    position: p.position,
                                    displacement: p.displacement,
                                },
                            )
                        })
                        .collect(),
                    reactions: &s.reactions,
                    applied_load: s.applied_load,
                })
                .collect(),
        }
    }
}

struct ResultWriter {
    steps_dir: PathBuf,
    point_files: bool,
    /// `(load factor, file name relative to the output directory)`.
    step_files: Vec<(f64, String)>,
    boundary_files: Vec<(f64, String)>,
    progress: Progress,
    io_error: Option<std::io::Error>,
}

impl ResultWriter {
    fn write_step(&mut self, report: &StepReport, state: &StepState<'_>) -> std::io::Result<()> {
        let stem = format!("step_{:04}", report.step);
        let json = File::create(self.steps_dir.join(format!("{stem}.json")))?;
        let columns = PointColumns::new(state.points);
        let boundaries = state.boundaries();
        let document = StepDocument {
            report,
            points: &columns,
            boundaries: &boundaries,
        };
        let mut w = BufWriter::new(json);
        serde_json::to_writer(&mut w, &document)?;
        w.flush()?;
        let mut vtu = BufWriter::new(File::create(self.steps_dir.join(format!("{stem}.vtu")))?);
        write_vtu(&mut vtu, &columns)?;
        vtu.flush()?;
        let mut vtp = BufWriter::new(File::create(
            self.steps_dir.join(format!("{stem}_boundary.vtp")),
        )?);
        write_vtp(&mut vtp, &boundaries)?;
        vtp.flush()?;
        self.step_files
            .push((report.load_factor, format!("steps/{stem}.vtu")));
        self.boundary_files
            .push((report.load_factor, format!("steps/{stem}_boundary.vtp")));
        Ok(())
    }
}

impl Observer for ResultWriter {
    fn step_started(&mut self, step: usize, n_steps: usize) {
        self.progress.start_step(step, n_steps);
    }

    fn newton_iteration(&mut self, _step: usize, iteration: usize, residual: f64) {
        self.progress.iteration(iteration, residual);
    }

    fn step_finished(&mut self, report: &StepReport, state: &StepState<'_>) {
        self.progress.clear();
        let probes: Vec<String> = report
            .probes
            .iter()
            .map(|p| {
                format!(
                    "{} ({:+.6e}, {:+.6e})",
                    p.name, p.displacement[0], p.displacement[1]
                )
            })
            .collect();
        println!(
            "step {:>4}  load {:.4}  iterations {:>2}  residual {:.2e}  dofs {:>8}  {:.3} s  {}",
            report.step,
            report.load_factor,
            report.newton.iterations,
            report.newton.residuals.last().copied().unwrap_or(0.0),
            report.active_dofs,
            report.timings.total,
            probes.join("  ")
        );
        if self.point_files
            && self.io_error.is_none()
            && let Err(e) = self.write_step(report, state)
        {
            self.io_error = Some(e);
        }
    }

    fn should_cancel(&mut self) -> bool {
        // Stop solving once the results can no longer be written.
        self.io_error.is_some()
    }
}

/// A one-line progress bar on stderr (only when stderr is a terminal).
struct Progress {
    live: bool,
    step: usize,
    n_steps: usize,
}

impl Progress {
    fn new() -> Self {
        Self {
            live: std::io::stderr().is_terminal(),
            step: 0,
            n_steps: 0,
        }
    }

    fn start_step(&mut self, step: usize, n_steps: usize) {
        self.step = step;
        self.n_steps = n_steps;
        self.draw("");
    }

    fn iteration(&mut self, iteration: usize, residual: f64) {
        self.draw(&format!("iteration {iteration} residual {residual:.2e}"));
    }

    fn draw(&self, detail: &str) {
        if !self.live {
            return;
        }
        const WIDTH: usize = 30;
        let done = WIDTH * (self.step - 1) / self.n_steps.max(1);
        eprint!(
            "\r\x1b[2K[{}{}] step {}/{} {detail}",
            "#".repeat(done),
            "-".repeat(WIDTH - done),
            self.step,
            self.n_steps
        );
    }

    fn clear(&self) {
        if self.live {
            eprint!("\r\x1b[2K");
        }
    }

    fn finish(&self) {
        self.clear();
    }
}
