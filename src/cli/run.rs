//! `mpm run`: solve one case, show progress on stderr, print a line per step
//! and write the results; with a checkpoint every few steps, so that
//! `mpm run --resume DIR` goes on with a run that stopped.

use std::fs::{self, File};
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};

use mpm::case::OutputSpec;
use mpm::report::PointColumns;
use mpm::vtk::{write_vtp, write_vtu};
use mpm::{Case, Checkpoint, Observer, Simulation, StepReport, StepState};
use mpm_service::config::CheckpointSchedule;
use mpm_service::jobs::admission::{PointLimit, Rejection, check_fill_sizes, check_points};
use mpm_service::jobs::failure::units_hint;
use mpm_service::results::{
    BOUNDARY_SERIES, CASE_FILE, POINTS_SERIES, STEPS_DIR, SUMMARY_FILE, Series, StepFiles, Summary,
};
use mpm_service::step::StepDocument;

use crate::{CliError, DEFAULT_EXAMPLE};

/// The files `mpm run` writes in its output directory (and `--force`
/// removes): these, and `steps/step_*`.
const OWNED_FILES: [&str; 7] = [
    SUMMARY_FILE,
    POINTS_SERIES,
    BOUNDARY_SERIES,
    CASE_FILE,
    CHECKPOINT_FILE,
    NEW_CHECKPOINT_FILE,
    REPORTS_FILE,
];
/// The solver's state after the last checkpointed step (`mpm::Checkpoint`).
pub(crate) const CHECKPOINT_FILE: &str = "checkpoint.bin";
/// A checkpoint being written, renamed to [`CHECKPOINT_FILE`] when whole.
const NEW_CHECKPOINT_FILE: &str = "checkpoint.bin.new";
/// One step report (JSON) a line, appended as steps finish.
pub(crate) const REPORTS_FILE: &str = "reports.jsonl";

/// `mpm run`: solves a case (a file, or a built-in example) into `out`,
/// which must be empty unless `force` (then the files of an earlier run
/// there are removed first).
pub fn run(
    case_path: Option<PathBuf>,
    example: Option<String>,
    out: &Path,
    point_files: bool,
    force: bool,
    max_points: usize,
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
    if mpm::case::solid::is_solid(&text) {
        return crate::solid::run(&text, &source, out, point_files, force, max_points);
    }
    let (case, sim) = build(&text, &source, max_points)?;
    prepare_output(out, force)?;
    fs::write(out.join(CASE_FILE), &text)?;
    solve(case, sim, &source, out, point_files, Vec::new(), None)
}

/// `mpm run --resume DIR`: goes on with the run in `dir` from its last
/// checkpoint, dropping what was written after it.
pub fn resume(dir: &Path, point_files: bool, max_points: usize) -> Result<(), CliError> {
    let source = dir.join(CASE_FILE);
    let text = fs::read_to_string(&source).map_err(|e| {
        CliError::input(format!(
            "{}: {e} (is {} the output of an mpm run?)",
            source.display(),
            dir.display()
        ))
    })?;
    let source = source.display().to_string();
    if mpm::case::solid::is_solid(&text) {
        return crate::solid::resume(dir, &text, &source, point_files, max_points);
    }
    let (case, mut sim) = build(&text, &source, max_points)?;
    let bytes = checkpoint_bytes(dir)?;
    let checkpoint = Checkpoint::from_bytes(&bytes)
        .and_then(|c| sim.restore(&c).map(|()| c))
        .map_err(|e| CliError::input(format!("{}: {e}", dir.join(CHECKPOINT_FILE).display())))?;
    let done = checkpoint.steps_done();
    let earlier = reports_until(dir, done)?;
    eprintln!("resuming after step {done} of {}", sim.load_steps);
    solve(case, sim, &source, dir, point_files, earlier, Some(done))
}

/// What a failed run in `out` says of going on: `mpm run --resume` when
/// it left a checkpoint.
pub(crate) fn resume_hint(out: &Path) -> String {
    if out.join(CHECKPOINT_FILE).exists() {
        format!(
            " (mpm run --resume {} goes on from the last checkpoint)",
            out.display()
        )
    } else {
        String::new()
    }
}

/// The checkpoint a stopped run in `dir` left.
pub(crate) fn checkpoint_bytes(dir: &Path) -> Result<Vec<u8>, CliError> {
    fs::read(dir.join(CHECKPOINT_FILE)).map_err(|e| {
        CliError::input(format!(
            "{}: {e} (the run stopped before its first checkpoint: run it again)",
            dir.join(CHECKPOINT_FILE).display()
        ))
    })
}

/// The reports of steps 1 to `done` (a checkpoint's) of the stopped run in
/// `dir`, which keeps only them and the step files up to `done`.
pub(crate) fn reports_until(dir: &Path, done: usize) -> Result<Vec<StepReport>, CliError> {
    // Reports and step files past the checkpoint belong to the stopped try;
    // a kill may have cut its last report line short.
    let reports_path = dir.join(REPORTS_FILE);
    let text = fs::read_to_string(&reports_path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    let mut earlier = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        match serde_json::from_str::<StepReport>(line) {
            Ok(r) if r.step <= done => earlier.push(r),
            Ok(_) => {}
            Err(_) if i + 1 == lines.len() => {}
            Err(e) => {
                return Err(CliError::input(format!(
                    "{} line {}: {e}",
                    reports_path.display(),
                    i + 1
                )));
            }
        }
    }
    if !earlier.iter().map(|r| r.step).eq(1..=done) {
        return Err(CliError::input(format!(
            "{} does not hold the reports of steps 1 to {done}, the checkpoint's",
            reports_path.display()
        )));
    }
    remove_step_files(dir, |step| step > done)?;
    let mut kept = String::new();
    for r in &earlier {
        kept.push_str(&serde_json::to_string(r).map_err(|e| CliError::failed(e.to_string()))?);
        kept.push('\n');
    }
    let aside = dir.join(format!("{REPORTS_FILE}.new"));
    fs::write(&aside, kept)?;
    fs::rename(aside, &reports_path)?;
    Ok(earlier)
}

/// Reads a case and builds its points, within `max_points`: the count is
/// checked before seeding (from each body's lattice) and after.
fn build(text: &str, source: &str, max_points: usize) -> Result<(Case, Simulation), CliError> {
    let refused =
        |path: &str, message: &str| CliError::input(format!("{source}: {path}: {message}"));
    let limit = PointLimit {
        max: max_points,
        name: "the point limit (--max-points)",
    };
    let case = Case::from_json(text).map_err(|e| CliError::input(format!("{source}: {e}")))?;
    let over = |r: Rejection| match r {
        Rejection::LimitExceeded { path, message } | Rejection::InvalidCase { path, message } => {
            refused(&path, &message)
        }
        Rejection::MalformedJson(message) => refused("$", &message),
    };
    check_fill_sizes(&case, limit).map_err(over)?;
    let sim = Simulation::new(&case).map_err(|e| CliError::input(format!("{source}: {e}")))?;
    check_points(sim.points.len(), limit).map_err(over)?;
    Ok((case, sim))
}

/// Refuses a non-empty output directory, unless `force`: then removes the
/// files an earlier run wrote there (and nothing else).
pub(crate) fn prepare_output(out: &Path, force: bool) -> Result<(), CliError> {
    let occupied = fs::read_dir(out).is_ok_and(|mut entries| entries.next().is_some());
    if occupied && !force {
        return Err(CliError::input(format!(
            "{} is not empty: give --force to replace an earlier run's files there, or \
             --resume {} to go on with a run that stopped",
            out.display(),
            out.display()
        )));
    }
    if occupied {
        for name in OWNED_FILES {
            match fs::remove_file(out.join(name)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
                _ => {}
            }
        }
        remove_step_files(out, |_| true)?;
        // Gone if it held only step files.
        let _ = fs::remove_dir(out.join(STEPS_DIR));
    }
    fs::create_dir_all(out)?;
    Ok(())
}

/// Removes the step files (`steps/step_N.json`, `.vtu`,
/// `_boundary.vtp`) whose step `N` satisfies `remove`.
fn remove_step_files(out: &Path, remove: impl Fn(usize) -> bool) -> Result<(), CliError> {
    let Ok(entries) = fs::read_dir(out.join(STEPS_DIR)) else {
        return Ok(());
    };
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name();
        let step = name.to_str().and_then(|n| {
            let n = n.strip_prefix("step_")?;
            let digits = n.find(|c: char| !c.is_ascii_digit()).unwrap_or(n.len());
            let suffix = &n[digits..];
            [".json", ".vtu", "_boundary.vtp"]
                .contains(&suffix)
                .then(|| n[..digits].parse::<usize>().ok())?
        });
        if step.is_some_and(&remove) {
            fs::remove_file(entry.path())?;
        }
    }
    Ok(())
}

/// Solves the steps `sim` has not done, writing into `out`; `earlier` are
/// the reports of the steps done before a run resumed after step
/// `resumed_from`.
fn solve(
    case: Case,
    mut sim: Simulation,
    source: &str,
    out: &Path,
    point_files: bool,
    earlier: Vec<StepReport>,
    resumed_from: Option<usize>,
) -> Result<(), CliError> {
    eprintln!(
        "{}: {} material points, {} load steps, {:?} basis, cells of {} m",
        case.title.as_deref().unwrap_or(source),
        sim.points.len(),
        sim.load_steps,
        sim.basis,
        sim.grid.h
    );
    if point_files {
        fs::create_dir_all(out.join(STEPS_DIR))?;
    }
    let n = sim.load_steps;
    let mut writer = ResultWriter {
        out: out.to_path_buf(),
        point_files,
        output: case.output.clone(),
        checkpoints: CheckpointSchedule::new(0, sim.points.len()),
        series: Series::default(),
        reports: fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(out.join(REPORTS_FILE))?,
        progress: Progress::new(),
        io_error: None,
    };
    // The step files kept from before a resumed run's checkpoint.
    for step in 0..=sim.steps_done() {
        let files = StepFiles::new(step);
        if out.join(&files.points).exists() {
            writer.series.add(step as f64 / n as f64, files);
        }
    }
    if sim.steps_done() == 0 && point_files {
        let (report, state) = sim.initial_step();
        writer.write_step(&report, &state)?;
    }
    let result = sim.run(&mut writer);
    writer.progress.finish();
    if let Some(e) = writer.io_error {
        return Err(e.into());
    }
    let mut report = result.map_err(|e| {
        // A hint of units where the first step fails on loads far beyond
        // the stiffness: E = 1 meant as 1 MPa, say.
        let units = units_hint(&case, &e).unwrap_or_default();
        CliError::failed(format!("solve failed: {e}{}{units}", resume_hint(out)))
    })?;
    if point_files {
        let series = &writer.series;
        series.write_points(BufWriter::new(File::create(out.join(POINTS_SERIES))?))?;
        series.write_boundary(BufWriter::new(File::create(out.join(BOUNDARY_SERIES))?))?;
    }
    report.wall_seconds += earlier.iter().map(|s| s.timings.total).sum::<f64>();
    report.steps.splice(0..0, earlier);
    let summary = Summary {
        resumed_from,
        warnings: mpm::model::warnings(&case, &report.steps),
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

struct ResultWriter {
    out: PathBuf,
    point_files: bool,
    /// Which steps write their points, and which columns.
    output: OutputSpec,
    /// When to write the solver's state.
    checkpoints: CheckpointSchedule,
    /// `reports.jsonl`, unbuffered: a line goes out in one write.
    reports: File,
    series: Series,
    progress: Progress,
    io_error: Option<std::io::Error>,
}

impl ResultWriter {
    fn write_step(&mut self, report: &StepReport, state: &StepState<'_>) -> std::io::Result<()> {
        if !self.output.stores_points(report.step, state.load_steps()) {
            return Ok(());
        }
        let files = StepFiles::new(report.step);
        let fields = mpm::model::point_fields(&self.output);
        let columns = PointColumns::selected(state.points, fields.as_deref());
        let boundaries = state.boundaries();
        let document = StepDocument {
            report,
            points: &columns,
            boundaries: &boundaries,
        };
        let mut w = BufWriter::new(File::create(self.out.join(&files.document))?);
        serde_json::to_writer(&mut w, &document)?;
        w.flush()?;
        let mut vtu = BufWriter::new(File::create(self.out.join(&files.points))?);
        write_vtu(&mut vtu, &columns)?;
        vtu.flush()?;
        let mut vtp = BufWriter::new(File::create(self.out.join(&files.boundary))?);
        write_vtp(&mut vtp, &boundaries)?;
        vtp.flush()?;
        self.series.add(report.series_time(), files);
        Ok(())
    }

    /// The step's report as a line of `reports.jsonl`, then, when one is
    /// due, the checkpoint (written aside and renamed, so a kill leaves the
    /// previous one whole).
    fn record_step(&mut self, report: &StepReport, state: &StepState<'_>) -> std::io::Result<()> {
        append_report(&mut self.reports, report)?;
        if self.checkpoints.due(report.step) {
            write_checkpoint(&self.out, &state.checkpoint().to_bytes())?;
        }
        Ok(())
    }
}

/// Appends `report` to `reports.jsonl` in one write: a kill cuts at most
/// the last line.
pub(crate) fn append_report(reports: &mut File, report: &StepReport) -> std::io::Result<()> {
    let mut line = serde_json::to_string(report)?;
    line.push('\n');
    reports.write_all(line.as_bytes())
}

/// Writes a checkpoint into `out` aside and renames it, so that a kill
/// leaves the previous one whole.
pub(crate) fn write_checkpoint(out: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let aside = out.join(NEW_CHECKPOINT_FILE);
    fs::write(&aside, bytes)?;
    fs::rename(aside, out.join(CHECKPOINT_FILE))
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
        print_step(report);
        if self.point_files
            && self.io_error.is_none()
            && let Err(e) = self.write_step(report, state)
        {
            self.io_error = Some(e);
        }
        if self.io_error.is_none()
            && let Err(e) = self.record_step(report, state)
        {
            self.io_error = Some(e);
        }
    }

    fn should_cancel(&mut self) -> bool {
        // Stop solving once the results can no longer be written.
        self.io_error.is_some()
    }
}

/// A converged step's line on stdout.
pub(crate) fn print_step(report: &StepReport) {
    let probes: Vec<String> = report
        .probes
        .iter()
        .map(|p| {
            let components: Vec<String> =
                p.displacement.iter().map(|u| format!("{u:+.6e}")).collect();
            format!("{} ({})", p.name, components.join(", "))
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
}

/// A one-line progress bar on stderr (only when stderr is a terminal).
pub(crate) struct Progress {
    live: bool,
    step: usize,
    n_steps: usize,
}

impl Progress {
    pub(crate) fn new() -> Self {
        Self {
            live: std::io::stderr().is_terminal(),
            step: 0,
            n_steps: 0,
        }
    }

    pub(crate) fn start_step(&mut self, step: usize, n_steps: usize) {
        self.step = step;
        self.n_steps = n_steps;
        self.draw("");
    }

    pub(crate) fn iteration(&mut self, iteration: usize, residual: f64) {
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

    pub(crate) fn clear(&self) {
        if self.live {
            eprint!("\r\x1b[2K");
        }
    }

    fn finish(&self) {
        self.clear();
    }
}
