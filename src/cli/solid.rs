//! `mpm run` on a 3D case (`analysis.type: "3d"`): a line a step on
//! stdout, and in the output directory the case, `reports.jsonl`,
//! `summary.json`, and the stored steps as `steps/*.json` (the report
//! and the points' columns, as the service serves a step) and
//! `steps/*.vtu` with their `points.pvd` series; a checkpoint every few
//! steps, from which `mpm run --resume DIR` goes on as with a plane-strain
//! run; each stored step's surfaces as `steps/*_boundary.vtp` (quads on
//! the B-spline patches) with their `boundary.pvd` series.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use mpm::case::solid::{SolidCase, SolidOutput};
use mpm::report::SolidPointColumns;
use mpm::vtk::{write_solid_vtu, write_surface_vtp};
use mpm::{Observer, Simulation, SolidCheckpoint, SolidStepState, StepReport};
use mpm_service::config::CheckpointSchedule;
use mpm_service::jobs::admission::{PointLimit, Rejection, check_points};
use mpm_service::results::{
    BOUNDARY_SERIES, CASE_FILE, POINTS_SERIES, STEPS_DIR, SUMMARY_FILE, Series, StepFiles, Summary,
};
use mpm_service::step::StepDocument;

use crate::CliError;
use crate::run::{
    CHECKPOINT_FILE, Progress, REPORTS_FILE, append_report, checkpoint_bytes, prepare_output,
    print_step, reports_until, resume_hint, write_checkpoint,
};

/// Solves the 3D case `text` (from `source`) into `out`.
pub fn run(
    text: &str,
    source: &str,
    out: &Path,
    point_files: bool,
    force: bool,
    max_points: usize,
) -> Result<(), CliError> {
    let (case, sim) = build(text, source, max_points)?;
    prepare_output(out, force)?;
    fs::write(out.join(CASE_FILE), text)?;
    solve(&case, sim, source, out, point_files, Vec::new(), None)
}

/// `mpm run --resume DIR` on a 3D run: goes on from its last checkpoint,
/// as a plane-strain run does.
pub fn resume(
    dir: &Path,
    text: &str,
    source: &str,
    point_files: bool,
    max_points: usize,
) -> Result<(), CliError> {
    let (case, mut sim) = build(text, source, max_points)?;
    let bytes = checkpoint_bytes(dir)?;
    let checkpoint = SolidCheckpoint::from_bytes(&bytes)
        .and_then(|c| sim.restore(&c).map(|()| c))
        .map_err(|e| CliError::input(format!("{}: {e}", dir.join(CHECKPOINT_FILE).display())))?;
    let done = checkpoint.steps_done();
    let earlier = reports_until(dir, done)?;
    eprintln!("resuming after step {done} of {}", sim.load_steps);
    solve(&case, sim, source, dir, point_files, earlier, Some(done))
}

/// Reads a 3D case and builds its points, within `max_points`: bounded
/// before seeding (the bodies' boxes at their spacings) and after.
fn build(
    text: &str,
    source: &str,
    max_points: usize,
) -> Result<(SolidCase, Simulation<3>), CliError> {
    let case = SolidCase::from_json(text).map_err(|e| CliError::input(format!("{source}: {e}")))?;
    let limit = PointLimit {
        max: max_points,
        name: "the point limit (--max-points)",
    };
    let refused = |r: Rejection| match r {
        Rejection::LimitExceeded { path, message } | Rejection::InvalidCase { path, message } => {
            CliError::input(format!("{source}: {path}: {message}"))
        }
        Rejection::MalformedJson(message) => CliError::input(format!("{source}: $: {message}")),
    };
    let bound = case.points_bound();
    if bound > 2.0 * max_points as f64 {
        return Err(CliError::input(format!(
            "{source}: bodies: about {bound:.3e} points at these spacings, over {} ({max_points})",
            limit.name
        )));
    }
    let sim = Simulation::from_solid_case(&case)
        .map_err(|e| CliError::input(format!("{source}: {e}")))?;
    check_points(sim.points.len(), limit).map_err(refused)?;
    Ok((case, sim))
}

/// Solves the steps `sim` has not done, writing into `out`, with a
/// checkpoint every few steps; `earlier` are the reports of the steps done
/// before a run resumed after step `resumed_from`.
fn solve(
    case: &SolidCase,
    mut sim: Simulation<3>,
    source: &str,
    out: &Path,
    point_files: bool,
    earlier: Vec<StepReport>,
    resumed_from: Option<usize>,
) -> Result<(), CliError> {
    eprintln!(
        "{}: {} material points in 3D, {} load steps, {:?} basis, cells of {} m",
        case.title.as_deref().unwrap_or(source),
        sim.points.len(),
        sim.load_steps,
        sim.basis,
        sim.grid.h
    );
    let n = sim.load_steps;
    let mut writer = SolidWriter {
        out: out.to_path_buf(),
        point_files,
        output: case.output.clone(),
        checkpoints: CheckpointSchedule::new(0, sim.points.len()),
        load_steps: n,
        reports: fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(out.join(REPORTS_FILE))?,
        series: Series::default(),
        progress: Progress::new(),
        io_error: None,
    };
    if point_files {
        fs::create_dir_all(out.join(STEPS_DIR))?;
    }
    // The step files kept from before a resumed run's checkpoint.
    for step in 0..=sim.steps_done() {
        let files = StepFiles::new(step);
        if out.join(&files.points).exists() {
            writer.series.add(step as f64 / n as f64, files);
        }
    }
    if point_files && sim.steps_done() == 0 {
        let (report, state) = sim.initial_step();
        writer.write_step(&report, &state)?;
    }
    let result = sim.run(&mut writer);
    writer.progress.clear();
    if let Some(e) = writer.io_error {
        return Err(e.into());
    }
    let mut report =
        result.map_err(|e| CliError::failed(format!("solve failed: {e}{}", resume_hint(out))))?;
    if point_files {
        let series = &writer.series;
        series.write_points(BufWriter::new(File::create(out.join(POINTS_SERIES))?))?;
        series.write_boundary(BufWriter::new(File::create(out.join(BOUNDARY_SERIES))?))?;
    }
    report.wall_seconds += earlier.iter().map(|s| s.timings.total).sum::<f64>();
    report.steps.splice(0..0, earlier);
    let summary = Summary {
        resumed_from,
        ..Summary::new(
            source,
            case.title.as_deref(),
            report.points,
            report.load_steps,
            report.wall_seconds,
            &report.steps,
        )
    };
    let mut f = BufWriter::new(File::create(out.join(SUMMARY_FILE))?);
    serde_json::to_writer_pretty(&mut f, &summary).map_err(|e| CliError::failed(e.to_string()))?;
    f.flush()?;
    // The run is complete: nothing to resume.
    let _ = fs::remove_file(out.join(CHECKPOINT_FILE));
    eprintln!(
        "done in {:.3} s; results in {}",
        report.wall_seconds,
        out.display()
    );
    Ok(())
}

/// Writes a 3D run's steps as they converge.
struct SolidWriter {
    out: PathBuf,
    point_files: bool,
    /// Which steps store their points.
    output: SolidOutput,
    /// When to write the solver's state.
    checkpoints: CheckpointSchedule,
    load_steps: usize,
    reports: File,
    series: Series,
    progress: Progress,
    io_error: Option<std::io::Error>,
}

impl SolidWriter {
    /// A stored step's document (the report and the points' columns, as
    /// the service stores it) and its VTU file, when the case stores this
    /// step's points.
    fn write_step(
        &mut self,
        report: &StepReport,
        state: &SolidStepState<'_>,
    ) -> std::io::Result<()> {
        if !self.output.stores_points(report.step, self.load_steps) {
            return Ok(());
        }
        let files = StepFiles::new(report.step);
        let columns = SolidPointColumns::new(state.points);
        let surfaces = state.surfaces();
        let document = StepDocument {
            report,
            points: &columns,
            boundaries: &surfaces,
        };
        let mut w = BufWriter::new(File::create(self.out.join(&files.document))?);
        serde_json::to_writer(&mut w, &document)?;
        w.flush()?;
        let mut vtu = BufWriter::new(File::create(self.out.join(&files.points))?);
        write_solid_vtu(&mut vtu, &columns)?;
        vtu.flush()?;
        let mut vtp = BufWriter::new(File::create(self.out.join(&files.boundary))?);
        write_surface_vtp(&mut vtp, &surfaces)?;
        vtp.flush()?;
        self.series.add(report.series_time(), files);
        Ok(())
    }

    /// The step's report as a line of `reports.jsonl`, its files, then,
    /// when one is due, the checkpoint (written aside and renamed, so a
    /// kill leaves the previous one whole).
    fn record(&mut self, report: &StepReport, state: &SolidStepState<'_>) -> std::io::Result<()> {
        append_report(&mut self.reports, report)?;
        if self.point_files {
            self.write_step(report, state)?;
        }
        if self.checkpoints.due(report.step) {
            write_checkpoint(&self.out, &state.checkpoint().to_bytes())?;
        }
        Ok(())
    }
}

impl Observer for SolidWriter {
    fn step_started(&mut self, step: usize, n_steps: usize) {
        self.progress.start_step(step, n_steps);
    }

    fn newton_iteration(&mut self, _step: usize, iteration: usize, residual: f64) {
        self.progress.iteration(iteration, residual);
    }

    fn solid_step_finished(&mut self, report: &StepReport, state: &SolidStepState<'_>) {
        self.progress.clear();
        print_step(report);
        if self.io_error.is_none()
            && let Err(e) = self.record(report, state)
        {
            self.io_error = Some(e);
        }
    }

    fn should_cancel(&mut self) -> bool {
        self.io_error.is_some()
    }
}
