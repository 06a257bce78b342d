//! `mpm`: run material point method cases from the command line.
//!
//! - `mpm run [CASE.json] [--out DIR]` solves a case (the built-in default
//!   example when no file is given) and writes per-step JSON and VTU files.
//! - `mpm example [NAME]` prints a built-in case (lists them without a name).
//! - `mpm bench` measures cost against problem size and writes a report;
//!   `mpm bench-queue` adds the job queue's section.
//! - `mpm serve` runs the HTTP job service (see the README and openapi.yaml).
//! - `mpm worker` solves the service's jobs on another machine.

mod bench_queue;
mod run;
mod serve;
mod solid;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use mpm_lab::{
    LabError, basis_study, bearing_study, bench, footing_study, robustness_study, slope_study,
    study,
};

/// The built-in case `mpm run` solves when given no file.
pub const DEFAULT_EXAMPLE: &str = "cantilever";

#[derive(Parser)]
#[command(
    name = "mpm",
    version,
    about = "Implicit material point method with B-spline boundaries"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve a case and write its results.
    Run {
        /// Case file (JSON). Without one, runs the built-in example given by
        /// --example (default: cantilever, the paper's case).
        case: Option<PathBuf>,
        /// Run this built-in example instead of a file.
        #[arg(long, conflicts_with = "case")]
        example: Option<String>,
        /// Output directory (empty, or --force): summary.json,
        /// steps/step_NNNN.{json,vtu}, points.pvd; case.json, reports.jsonl
        /// and checkpoint.bin for --resume.
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// Write only summary.json (no per-step point files).
        #[arg(long)]
        summary_only: bool,
        /// Replace an earlier run's files in a non-empty output directory.
        #[arg(long)]
        force: bool,
        /// Go on with the run in this directory (an earlier --out) from its
        /// last checkpoint.
        #[arg(long, conflicts_with_all = ["case", "example", "force"], value_name = "DIR")]
        resume: Option<PathBuf>,
        /// Refuse a case of more material points than this (about 1 KB of
        /// memory each): a typo in a cell size can ask for billions.
        #[arg(long, default_value_t = mpm_service::config::DEFAULT_MAX_POINTS)]
        max_points: usize,
    },
    /// Print a built-in example case (list them when no name is given).
    Example { name: Option<String> },
    /// Print the case format's JSON Schema (served at /schema/case.json).
    Schema,
    /// Print the HTTP contract (OpenAPI 3.0, served at /openapi.yaml).
    Openapi,
    /// Measure wall time, its split and memory against the number of points.
    Bench {
        /// Largest point count to run (sizes go 1e3, 1e4, ... up to it).
        #[arg(long, default_value_t = 1_000_000)]
        max_points: usize,
        /// Markdown report to write.
        #[arg(long, default_value = "BENCHMARKS.md")]
        out: PathBuf,
        /// Repetitions of the small end-to-end case (median reported).
        #[arg(long, default_value_t = 21)]
        repeats: usize,
    },
    /// Measure the job queue (per-job overhead, throughput, checkpoints)
    /// and write its section of the benchmark report.
    BenchQueue(bench_queue::QueueBenchArgs),
    /// Convergence studies written as tables (CSV, markdown) and SVG plots.
    Study {
        /// Which study: `cantilever` (the paper's Figure 3, both support
        /// methods, and the IBM band width, for one basis) or `bases` (the
        /// four bases on the paper's case: convergence, grid origins, load
        /// steps, error against cost) or `footing` (the strip footing on
        /// undrained and frictional soil: collapse loads at three cell
        /// sizes, and a settlement of 0.5 B) or `bearing` (N_c and N_gamma
        /// of a rough footing on frictional soil, the points' own strains
        /// against their cells' mean) or `slope` (Griffiths and Lane's slope: its
        /// factor of safety by strength reduction) or `robustness` (1,000
        /// random valid cases, how many finish, by class).
        name: String,
        /// Output directory.
        #[arg(long, default_value = "study")]
        out: PathBuf,
        /// A small sweep (two cell sizes, three point counts) in seconds.
        #[arg(long)]
        quick: bool,
        /// Shape functions of `cantilever`, as a case's `basis` names
        /// them (the paper's is linear).
        #[arg(long, default_value = "linear")]
        basis: String,
    },
    /// Run the HTTP job service (every flag also reads an environment variable).
    Serve(serve::ServeArgs),
    /// Solve jobs from a shared database without serving HTTP (workers on
    /// other machines; every flag also reads an environment variable).
    Worker(serve::WorkerArgs),
    /// One row of `mpm bench`, printed as JSON (used by `mpm bench`).
    #[command(hide = true)]
    BenchRow { scene: usize, points: usize },
}

fn main() -> ExitCode {
    hold_mmap_threshold();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            resume: Some(dir),
            summary_only,
            max_points,
            ..
        } => run::resume(&dir, !summary_only, max_points),
        Command::Run {
            case,
            example,
            out,
            summary_only,
            force,
            resume: None,
            max_points,
        } => run::run(case, example, &out, !summary_only, force, max_points),
        Command::Example { name } => example(name),
        Command::Schema => {
            let schema = mpm::case::json_schema();
            println!("{}", serde_json::to_string_pretty(&schema).expect("JSON"));
            Ok(())
        }
        Command::Openapi => {
            print!("{}", *mpm_service::http::OPENAPI);
            Ok(())
        }
        Command::Bench {
            max_points,
            out,
            repeats,
        } => bench::bench(max_points, &out, repeats).map_err(CliError::from),
        Command::BenchQueue(args) => bench_queue::bench_queue(args),
        Command::BenchRow { scene, points } => {
            bench::bench_row(scene, points).map_err(CliError::from)
        }
        Command::Study {
            name,
            out,
            quick,
            basis,
        } => match name.as_str() {
            "cantilever" => study::cantilever(&out, quick, &basis).map_err(CliError::from),
            "bases" => basis_study::bases(&out, quick).map_err(CliError::from),
            "footing" => footing_study::footing(&out, quick).map_err(CliError::from),
            "slope" => slope_study::slope(&out, quick).map_err(CliError::from),
            "bearing" => bearing_study::bearing(&out, quick).map_err(CliError::from),
            "robustness" => robustness_study::robustness(&out, quick).map_err(CliError::from),
            other => Err(CliError::input(format!(
                "no study {other:?}; available: cantilever, bases, footing, bearing, slope, robustness"
            ))),
        },
        Command::Serve(args) => serve::serve(args),
        Command::Worker(args) => serve::worker(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}

/// A failure with the process exit code it maps to: 2 for bad input, 1 for
/// a solve or I/O failure.
#[derive(Debug)]
pub struct CliError {
    pub code: u8,
    pub message: String,
}

impl CliError {
    pub fn input(message: impl Into<String>) -> Self {
        Self {
            code: 2,
            message: message.into(),
        }
    }
    pub fn failed(message: impl Into<String>) -> Self {
        Self {
            code: 1,
            message: message.into(),
        }
    }
}

impl From<LabError> for CliError {
    fn from(e: LabError) -> Self {
        match e {
            LabError::Input(message) => CliError::input(message),
            LabError::Failed(message) => CliError::failed(message),
        }
    }
}

impl From<std::io::Error> for CliError {
    fn from(e: std::io::Error) -> Self {
        CliError::failed(e.to_string())
    }
}

fn example(name: Option<String>) -> Result<(), CliError> {
    match name {
        None => {
            for n in mpm::case::builtin::NAMES {
                println!("{n}");
            }
            for n in mpm::case::builtin::SOLID_NAMES {
                println!("{n}");
            }
            Ok(())
        }
        Some(n) => {
            let text = mpm::case::builtin::get(&n).ok_or_else(|| {
                CliError::input(format!(
                    "no built-in example {n:?}; available: {}, {}",
                    mpm::case::builtin::NAMES.join(", "),
                    mpm::case::builtin::SOLID_NAMES.join(", ")
                ))
            })?;
            print!("{text}");
            Ok(())
        }
    }
}

/// Holds glibc's mmap threshold at its default of 128 KiB. Left to itself,
/// glibc raises the threshold (up to 32 MiB) each time a mapped block is
/// freed, after which the solver's blocks of a few MB (the grid reset's
/// per-chunk buffers, the multigrid setup's bands) come from its heaps,
/// which keep what is freed in them: at 1e6 GIMP column points the peak
/// resident set was 1,208 MiB with it, 1,014 MiB held (docs/scale.md).
/// Held, every block above it is mapped, and unmapped when freed. A
/// threshold set in glibc's own `MALLOC_MMAP_THRESHOLD_` is left as it is.
fn hold_mmap_threshold() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() {
        // SAFETY: mallopt only sets a parameter of the allocator, before
        // any thread is started.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
        }
    }
}
