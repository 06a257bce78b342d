//! `mpm bench-queue`: what the job queue costs around the solver, written as
//! the "Job queue" section of BENCHMARKS.md (the rest is `mpm bench`'s).
//!
//! - Per-job overhead: a one-step job (`cantilever-grid` under a thousandth
//!   of its weight, 320 points) posted
//!   to a running service, which is polled every millisecond until the job
//!   has succeeded; the wall time from `POST` minus the solve time the job
//!   reports. Median over the repeats, one worker.
//! - Throughput: that job posted many times as fast as one client can, with
//!   1, 2 and 4 workers in the process (sharing rayon's pool); jobs a second
//!   from the first `POST` to the last job's end.
//! - Checkpoints: the solver's state after one load step of the wide column
//!   at 1e4 and 1e5 points, encoded and decoded (restore included).
//!
//! Each on SQLite and, given `--postgres URL` (an empty database), on
//! PostgreSQL.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::Args;
use mpm::{Case, Checkpoint, NoObserver, Simulation};
use mpm_service::{Config, Server};
use serde_json::Value;

use crate::CliError;

#[derive(Args)]
pub struct QueueBenchArgs {
    /// A PostgreSQL database to measure too (its jobs table grows).
    #[arg(long)]
    postgres: Option<String>,
    /// Jobs per throughput measurement.
    #[arg(long, default_value_t = 200)]
    jobs: usize,
    /// Jobs timed one at a time for the overhead (median reported).
    #[arg(long, default_value_t = 41)]
    repeats: usize,
    /// The report whose "Job queue" section is written (replaced if there).
    #[arg(long, default_value = "BENCHMARKS.md")]
    out: PathBuf,
}

const SECTION: &str = "## Job queue";

pub fn bench_queue(args: QueueBenchArgs) -> Result<(), CliError> {
    let scratch = std::env::temp_dir().join(format!("mpm-bench-queue-{}", std::process::id()));
    std::fs::create_dir_all(&scratch)?;
    let mut tiny = mpm::case::builtin::json("cantilever-grid").expect("built-in");
    tiny["analysis"]["load_steps"] = 1.into();
    // A thousandth of the beam's weight: a small deflection, solved in a
    // couple of Newton iterations, so the queue's own cost shows.
    tiny["loads"]["gravity"] = serde_json::json!([0.0, -0.01]);
    let tiny = tiny.to_string();

    let mut backends = vec![("SQLite", scratch.join("bench.sqlite").display().to_string())];
    if let Some(url) = &args.postgres {
        backends.push(("PostgreSQL", url.clone()));
    }
    let runtime = tokio::runtime::Runtime::new()?;
    let mut overhead_rows = String::new();
    let mut throughput_rows = String::new();
    for (name, database) in &backends {
        let (overhead, solve) = runtime.block_on(overhead(database, &tiny, args.repeats))?;
        let line = format!(
            "| {name} | {:.2} | {:.2} | {:.2} |\n",
            (overhead + solve) * 1e3,
            solve * 1e3,
            overhead * 1e3
        );
        eprint!("{line}");
        overhead_rows.push_str(&line);
        let mut line = format!("| {name} |");
        for workers in [1, 2, 4] {
            let rate = runtime.block_on(throughput(database, &tiny, args.jobs, workers))?;
            line.push_str(&format!(" {rate:.0} |"));
        }
        line.push('\n');
        eprint!("{line}");
        throughput_rows.push_str(&line);
    }
    let _ = std::fs::remove_dir_all(&scratch);

    let mut section = format!(
        "{SECTION}\n\nWritten by `mpm bench-queue` ({} threads in rayon's pool). A one-step job \
         (`cantilever-grid` with `load_steps: 1` and a thousandth of its weight, 320 points, \
         a few milliseconds of solving) through the service in this \
         process, on a SQLite file{}.\n\n",
        rayon::current_num_threads(),
        if args.postgres.is_some() {
            " and on a local PostgreSQL 15 (fsync off, as in the tests)"
        } else {
            ""
        }
    );
    section.push_str(&format!(
        "Per-job overhead: `POST /jobs` to `succeeded` seen by a client polling every millisecond \
         (so up to 1 ms of it is the polling), minus the solve time the job reports (`solve_seconds`: \
         reading the case, solving, and storing step 0, the step and its checkpoint); medians of \
         {} jobs run one at a time, one worker.\n\n\
         | database | POST to succeeded (ms) | solve (ms) | overhead (ms) |\n|---|---:|---:|---:|\n{overhead_rows}\n",
        args.repeats
    ));
    section.push_str(&format!(
        "Throughput: {} such jobs posted as fast as one client can, jobs a second from the first \
         `POST` to the last job's end, with 1, 2 and 4 workers in the process (sharing rayon's \
         pool on these cores).\n\n\
         | database | 1 worker | 2 workers | 4 workers |\n|---|---:|---:|---:|\n{throughput_rows}\n",
        args.jobs
    ));
    section.push_str(&checkpoint_rows()?);
    write_section(&args.out, &section)?;
    println!("{section}");
    Ok(())
}

/// Median `(POST to succeeded minus solve, solve)` in seconds.
async fn overhead(database: &str, case: &str, repeats: usize) -> Result<(f64, f64), CliError> {
    let server = start(database, 1).await?;
    let addr = server.addr;
    let measured = tokio::task::spawn_blocking({
        let case = case.to_string();
        move || -> Result<(Vec<f64>, Vec<f64>), CliError> {
            let (mut overheads, mut solves) = (Vec::new(), Vec::new());
            for _ in 0..repeats {
                let start = Instant::now();
                let id = submit(addr, &case)?;
                let job = loop {
                    let (_, body) = http(addr, "GET", &format!("/jobs/{id}"), None)?;
                    let job: Value = serde_json::from_str(&body).map_err(failed)?;
                    if job["status"] != "queued" && job["status"] != "running" {
                        break job;
                    }
                    std::thread::sleep(Duration::from_millis(1));
                };
                let wall = start.elapsed().as_secs_f64();
                if job["status"] != "succeeded" {
                    return Err(CliError::failed(format!("benchmark job ended {job}")));
                }
                let solve = job["solve_seconds"].as_f64().unwrap_or_default();
                overheads.push(wall - solve);
                solves.push(solve);
            }
            Ok((overheads, solves))
        }
    })
    .await
    .map_err(failed)??;
    server.shutdown().await;
    Ok((median(measured.0), median(measured.1)))
}

/// Jobs a second through `workers` workers.
async fn throughput(
    database: &str,
    case: &str,
    jobs: usize,
    workers: usize,
) -> Result<f64, CliError> {
    let server = start(database, workers).await?;
    let addr = server.addr;
    let seconds = tokio::task::spawn_blocking({
        let case = case.to_string();
        move || -> Result<f64, CliError> {
            let start = Instant::now();
            let ids = (0..jobs)
                .map(|_| submit(addr, &case))
                .collect::<Result<Vec<_>, _>>()?;
            for id in ids {
                loop {
                    let (_, body) = http(addr, "GET", &format!("/jobs/{id}"), None)?;
                    let job: Value = serde_json::from_str(&body).map_err(failed)?;
                    if job["status"] == "succeeded" {
                        break;
                    }
                    if job["status"] != "queued" && job["status"] != "running" {
                        return Err(CliError::failed(format!("benchmark job ended {job}")));
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
            }
            Ok(start.elapsed().as_secs_f64())
        }
    })
    .await
    .map_err(failed)??;
    server.shutdown().await;
    Ok(jobs as f64 / seconds)
}

async fn start(database: &str, workers: usize) -> Result<Server, CliError> {
    let mut config = Config::new(database);
    config.workers = workers;
    config.limits.max_queued = 100_000;
    Server::start(config, "127.0.0.1:0".parse().expect("an address"))
        .await
        .map_err(|e| CliError::failed(e.to_string()))
}

fn submit(addr: SocketAddr, case: &str) -> Result<i64, CliError> {
    let (status, body) = http(addr, "POST", "/jobs", Some(case))?;
    if status != 201 {
        return Err(CliError::failed(format!("POST /jobs: {status} {body}")));
    }
    let job: Value = serde_json::from_str(&body).map_err(failed)?;
    job["id"]
        .as_i64()
        .ok_or_else(|| CliError::failed(format!("no job id in {body}")))
}

/// One HTTP/1.1 request on its own connection: `(status, body)`.
fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    body: Option<&str>,
) -> Result<(u16, String), CliError> {
    let mut stream = TcpStream::connect(addr)?;
    let body = body.unwrap_or("");
    write!(
        stream,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )?;
    let mut response = String::new();
    stream.read_to_string(&mut response)?;
    let status = response
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| CliError::failed(format!("not an HTTP response: {response:.80}")))?;
    let body = response
        .split_once("\r\n\r\n")
        .map_or("", |(_, b)| b)
        .to_string();
    Ok((status, body))
}

/// Checkpoint size and cost against a load step's, at 1e4 and 1e5 points.
fn checkpoint_rows() -> Result<String, CliError> {
    let mut rows = String::from(
        "Checkpoints: the state after the first load step of the wide column (`mpm bench`'s \
         first scene), encoded (`Simulation::checkpoint` + `to_bytes`) and decoded \
         (`from_bytes` + `restore` into a fresh simulation); medians of 5. The step's own wall \
         time is beside them.\n\n\
         | points | bytes | bytes / point | encode (ms) | decode + restore (ms) | load step (s) |\n\
         |---:|---:|---:|---:|---:|---:|\n",
    );
    for target in [10_000, 100_000] {
        let case = Case::from_json(&mpm_lab::bench::wide_column(target).to_string())
            .map_err(|e| CliError::failed(e.to_string()))?;
        let mut sim = Simulation::new(&case).map_err(|e| CliError::failed(e.to_string()))?;
        let step = Instant::now();
        sim.load_step(1, &mut NoObserver)
            .map_err(|e| CliError::failed(e.to_string()))?;
        let step = step.elapsed().as_secs_f64();
        let mut encode = Vec::new();
        let mut decode = Vec::new();
        let mut bytes = Vec::new();
        for _ in 0..5 {
            let t = Instant::now();
            bytes = sim.checkpoint().to_bytes();
            encode.push(t.elapsed().as_secs_f64());
            let mut fresh = Simulation::new(&case).map_err(|e| CliError::failed(e.to_string()))?;
            let t = Instant::now();
            Checkpoint::from_bytes(&bytes)
                .and_then(|c| fresh.restore(&c))
                .map_err(|e| CliError::failed(e.to_string()))?;
            decode.push(t.elapsed().as_secs_f64());
        }
        let points = sim.points.len();
        let line = format!(
            "| {points} | {} | {:.0} | {:.2} | {:.2} | {step:.3} |\n",
            bytes.len(),
            bytes.len() as f64 / points as f64,
            median(encode) * 1e3,
            median(decode) * 1e3,
        );
        eprint!("{line}");
        rows.push_str(&line);
    }
    rows.push('\n');
    Ok(rows)
}

/// Replaces the report's "Job queue" section (up to the next `## `), or
/// appends it.
fn write_section(out: &Path, section: &str) -> Result<(), CliError> {
    let report = std::fs::read_to_string(out).unwrap_or_default();
    let updated = match report.find(SECTION) {
        Some(start) => {
            let rest = &report[start + SECTION.len()..];
            let end = rest
                .find("\n## ")
                .map_or(report.len(), |i| start + SECTION.len() + i + 1);
            format!("{}{section}{}", &report[..start], &report[end..])
        }
        None if report.is_empty() => section.to_string(),
        None => format!("{}\n\n{section}", report.trim_end()),
    };
    std::fs::write(out, updated)?;
    Ok(())
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

fn failed(e: impl std::fmt::Display) -> CliError {
    CliError::failed(e.to_string())
}
