//! A group's deployment on one PostgreSQL database: an API process that does
//! not solve (`mpm serve --workers 0`) and three `mpm worker` processes,
//! killed with SIGKILL while they run. Workers store a checkpoint after every
//! step, so a job whose worker dies resumes where it stood.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::time::{Duration, Instant};

use common::{
    Process, TempDir, agent, base_url, cli_final_positions, example, largest_difference, positions,
    postgres_database, request, slow_case, spawn_mpm, spawn_mpm_with, submit_to, try_get_json,
};
use serde_json::Value;

/// Short leases, so a dead worker's job is taken over within seconds.
const LEASE_SECONDS: &str = "2";

/// Positions of a resumed run agree with the straight run's to round-off
/// (rayon may group sums differently); the bodies are metres in size.
const SAME_POSITIONS: f64 = 1e-9;

fn start_api(database: &str) -> (Process, String) {
    let (child, line) = spawn_mpm(
        &[
            "serve",
            "--workers",
            "0",
            "--addr",
            "127.0.0.1:0",
            "--database",
            database,
            "--lease-seconds",
            LEASE_SECONDS,
        ],
        None,
    );
    (child, base_url(&line))
}

/// A worker with one solver thread (three share two cores here), JSON
/// logs in `log`, a checkpoint every step and room for many crashes.
fn start_worker(database: &str, log: &Path) -> Process {
    spawn_mpm(
        &[
            "worker",
            "--database",
            database,
            "--lease-seconds",
            LEASE_SECONDS,
            "--checkpoint-every",
            "1",
            "--max-attempts",
            "30",
            "--solver-threads",
            "1",
            "--log-format",
            "json",
        ],
        Some(log),
    )
    .0
}

fn kill(child: &mut Child) {
    child.kill().unwrap(); // SIGKILL: no chance to hand the job back
    child.wait().unwrap();
}

/// Every job, by id, as `GET /jobs` lists it; `None` while the API is down.
fn all_jobs(base: &str) -> Option<BTreeMap<i64, Value>> {
    let list = try_get_json(&agent(), &format!("{base}/jobs?limit=500"))?;
    Some(
        list["jobs"]
            .as_array()?
            .iter()
            .map(|j| (j["id"].as_i64().unwrap(), j.clone()))
            .collect(),
    )
}

/// `(job, attempt)` of each "job started" line in the workers' JSON logs.
fn starts(logs: &[PathBuf]) -> Vec<(i64, i64)> {
    logs.iter()
        .flat_map(|log| {
            std::fs::read_to_string(log)
                .unwrap_or_default()
                .lines()
                .filter_map(|l| serde_json::from_str::<Value>(l).ok())
                .filter(|l| l["fields"]["message"] == "job started")
                .map(|l| {
                    (
                        l["fields"]["job"].as_i64().unwrap(),
                        l["fields"]["attempt"].as_i64().unwrap(),
                    )
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Waits until every job has ended; panics on a job stuck past `limit`.
fn wait_all_final(base: &str, limit: Duration) -> BTreeMap<i64, Value> {
    let start = Instant::now();
    loop {
        if let Some(jobs) = all_jobs(base)
            && jobs.values().all(common::is_final)
        {
            return jobs;
        }
        assert!(
            start.elapsed() < limit,
            "jobs still not ended after {limit:?}: {:?}",
            all_jobs(base).map(|j| j
                .values()
                .filter(|j| !common::is_final(j))
                .map(|j| (j["id"].clone(), j["status"].clone(), j["progress"].clone()))
                .collect::<Vec<_>>())
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The largest distance of each job's final points from the CLI's run of
/// the same case.
fn worst_against_cli(base: &str, jobs: &BTreeMap<i64, Value>, cases: &BTreeMap<i64, Value>) -> f64 {
    let mut reference: BTreeMap<String, Vec<Vec<f64>>> = BTreeMap::new();
    let mut worst: f64 = 0.0;
    for (id, job) in jobs {
        let case = &cases[id];
        let cli = reference
            .entry(case.to_string())
            .or_insert_with(|| cli_final_positions(case));
        let last = job["progress"]["of"].as_i64().unwrap();
        let step = try_get_json(&agent(), &format!("{base}/jobs/{id}/steps/{last}"))
            .unwrap_or_else(|| panic!("job {id} step {last}"));
        worst = worst.max(largest_difference(&positions(&step), cli));
    }
    worst
}

/// Fifty jobs of three sizes on three workers: each is claimed once (one
/// start in the logs, one attempt). One worker is killed while it runs a
/// long job: that job is taken over by another worker after the lease,
/// resumes after exactly the step its dead worker last stored, and ends with
/// the CLI's result, as every other job does.
#[test]
fn three_workers_share_fifty_jobs_and_a_killed_ones_job_resumes_elsewhere() {
    let dir = TempDir::new("cluster");
    let database = postgres_database();
    let (mut api, base) = start_api(&database);
    let logs: Vec<PathBuf> = (0..3)
        .map(|i| dir.0.join(format!("worker{i}.log")))
        .collect();
    let mut workers: Vec<Process> = logs.iter().map(|l| start_worker(&database, l)).collect();

    let (tiny, medium, long) = (example("cantilever-grid"), slow_case(4), slow_case(30));
    let mut cases = BTreeMap::new();
    let mut long_jobs = Vec::new();
    for i in 0..50 {
        let case = match i % 10 {
            0 => long.clone(),
            3 | 6 | 9 => medium.clone(),
            _ => tiny.clone(),
        };
        let id = submit_to(&base, &case);
        if i % 10 == 0 {
            long_jobs.push(id);
        }
        cases.insert(id, case);
    }

    // A long job three steps in, and the worker that runs it.
    let start = Instant::now();
    let (victim, worker) = loop {
        let jobs = all_jobs(&base).unwrap();
        let running = long_jobs.iter().find(|id| {
            jobs[id]["status"] == "running" && jobs[id]["progress"]["step"].as_i64() >= Some(3)
        });
        if let Some(&id) = running {
            let worker = logs
                .iter()
                .position(|log| starts(std::slice::from_ref(log)).iter().any(|s| s.0 == id));
            if let Some(worker) = worker {
                break (id, worker);
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no long job got going"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    kill(&mut workers[worker]);
    // A step the worker committed as it died lands within milliseconds;
    // no one may take the job over before its lease (2 s) expires.
    std::thread::sleep(Duration::from_millis(200));
    let dead_at = all_jobs(&base).unwrap()[&victim]["progress"]["step"]
        .as_i64()
        .unwrap();

    let jobs = wait_all_final(&base, Duration::from_secs(600));
    let started = starts(&logs);
    for (id, job) in &jobs {
        assert_eq!(job["status"], "succeeded", "{job}");
        let runs = started.iter().filter(|s| s.0 == *id).count() as i64;
        assert_eq!(
            job["attempts"].as_i64(),
            Some(runs),
            "job {id}: one start per attempt"
        );
        if *id == victim {
            assert_eq!(runs, 2, "{job}");
            assert_eq!(job["resumed_from_step"].as_i64(), Some(dead_at), "{job}");
        } else {
            assert_eq!(runs, 1, "job {id} claimed once: {job}");
            assert!(job["resumed_from_step"].is_null(), "{job}");
        }
    }
    let worst = worst_against_cli(&base, &jobs, &cases);
    eprintln!(
        "job {victim}: worker {worker} killed after step {dead_at} of 30, resumed from step {}; \
         50 jobs against the CLI: largest difference {worst:.1e} m",
        jobs[&victim]["resumed_from_step"]
    );
    assert!(worst <= SAME_POSITIONS, "{worst:e}");

    for w in &mut workers {
        if w.try_wait().unwrap().is_none() {
            kill(w);
        }
    }
    kill(&mut api);
}

/// Twenty jobs while a process picked at random (the API or one of three
/// workers) is killed and restarted twenty times: every job ends succeeded,
/// none is stuck, none ever goes back past a step it stored (its progress,
/// polled throughout, never falls: each step is a checkpoint), and every
/// result equals the CLI's.
#[test]
fn a_crash_loop_loses_no_job_and_never_goes_back_past_a_checkpoint() {
    let dir = TempDir::new("crash-loop");
    let database = postgres_database();
    let (mut api, mut base) = start_api(&database);
    let mut logs: Vec<PathBuf> = (0..3)
        .map(|i| dir.0.join(format!("worker{i}-0.log")))
        .collect();
    let mut workers: Vec<Process> = logs.iter().map(|l| start_worker(&database, l)).collect();
    let mut cases = BTreeMap::new();
    for i in 0..20 {
        let case = slow_case(if i % 2 == 0 { 12 } else { 20 });
        cases.insert(submit_to(&base, &case), case);
    }

    let mut highest: BTreeMap<i64, i64> = BTreeMap::new();
    let mut went_back = Vec::new();
    let mut watch = |base: &str, highest: &mut BTreeMap<i64, i64>| {
        if let Some(jobs) = all_jobs(base) {
            for (id, job) in jobs {
                let step = job["progress"]["step"].as_i64().unwrap();
                let best = highest.entry(id).or_insert(0);
                if step < *best {
                    went_back.push((id, *best, step));
                }
                *best = step.max(*best);
            }
        }
    };
    // A fixed pseudo-random sequence (LCG), so a failure can be replayed.
    let mut seed: u64 = 0x5eed;
    let mut killed = [0; 4];
    for round in 0..20 {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let victim = (seed >> 33) as usize % 4;
        let pause = Duration::from_millis(300 + (seed >> 40) % 700);
        let until = Instant::now() + pause;
        while Instant::now() < until {
            watch(&base, &mut highest);
            std::thread::sleep(Duration::from_millis(30));
        }
        killed[victim] += 1;
        if victim == 0 {
            kill(&mut api);
            (api, base) = start_api(&database);
        } else {
            let w = victim - 1;
            kill(&mut workers[w]);
            logs.push(dir.0.join(format!("worker{w}-{round}.log")));
            workers[w] = start_worker(&database, logs.last().unwrap());
        }
    }
    let start = Instant::now();
    let jobs = loop {
        watch(&base, &mut highest);
        if let Some(jobs) = all_jobs(&base)
            && jobs.values().all(common::is_final)
        {
            break jobs;
        }
        assert!(start.elapsed() < Duration::from_secs(600), "jobs stuck");
        std::thread::sleep(Duration::from_millis(50));
    };

    let attempts: i64 = jobs.values().map(|j| j["attempts"].as_i64().unwrap()).sum();
    let resumed = jobs
        .values()
        .filter(|j| !j["resumed_from_step"].is_null())
        .count();
    let worst = worst_against_cli(&base, &jobs, &cases);
    eprintln!(
        "20 kills (API {}, workers {}, {}, {}): 20 jobs succeeded in {attempts} attempts, \
         {resumed} resumed from a checkpoint in their last attempt; largest difference \
         from the CLI {worst:.1e} m",
        killed[0], killed[1], killed[2], killed[3]
    );
    assert!(
        went_back.is_empty(),
        "progress fell (job, highest, then): {went_back:?}"
    );
    // The loop tested something: kills landed on running jobs, and some
    // resumed from a checkpoint.
    assert!(attempts > 20, "no job was interrupted");
    assert!(resumed > 0, "no job resumed from a checkpoint");
    for job in jobs.values() {
        assert_eq!(job["status"], "succeeded", "{job}");
    }
    assert_eq!(jobs.len(), 20, "no job lost");
    assert!(worst <= SAME_POSITIONS, "{worst:e}");

    for w in &mut workers {
        kill(w);
    }
    kill(&mut api);
}

/// A worker of its own lease length, with extra environment variables.
fn start_worker_with(database: &str, lease: &str, log: &Path, env: &[(&str, &str)]) -> Process {
    spawn_mpm_with(
        &[
            "worker",
            "--database",
            database,
            "--lease-seconds",
            lease,
            "--solver-threads",
            "1",
            "--log-format",
            "json",
        ],
        Some(log),
        env,
    )
    .0
}

/// The job once it has finished `step` steps (or ended).
fn wait_for_step(base: &str, id: i64, step: i64) -> Value {
    let start = Instant::now();
    loop {
        if let Some(job) = all_jobs(base).and_then(|mut jobs| jobs.remove(&id))
            && (job["progress"]["step"].as_i64() >= Some(step) || common::is_final(&job))
        {
            return job;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "job {id} never reached step {step}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A cancel answered 202 while a worker runs the job, then SIGTERM to the
/// worker before its lease renewal (every 10 s with a 30 s lease) told it
/// of the cancel: the job ends cancelled with its steps. It went back to
/// the queue with the request still set, and ran to success, 5 of 5 times.
#[test]
fn a_cancel_asked_for_before_a_worker_stops_is_kept() {
    let dir = TempDir::new("cancel-sigterm");
    let database = postgres_database();
    let (mut api, base) = start_api(&database);
    let mut worker = start_worker_with(&database, "30", &dir.0.join("worker.log"), &[]);
    let id = submit_to(&base, &slow_case(60));
    wait_for_step(&base, id, 2);
    let (status, body) = request(&agent(), "POST", &format!("{base}/jobs/{id}/cancel"), None);
    assert_eq!(status, 202, "{body}");
    // SIGTERM: the worker hands its running job back and exits.
    assert_eq!(unsafe { libc::kill(worker.id() as i32, libc::SIGTERM) }, 0);
    assert!(worker.wait().unwrap().success());
    let job = all_jobs(&base).unwrap()[&id].clone();
    assert_eq!(job["status"], "cancelled", "{job}");
    assert!(job["progress"]["step"].as_i64() >= Some(2), "{job}");
    kill(&mut api);
}

/// libfaketime's library, which shifts a process's clock, if installed
/// (Debian: apt-get install faketime).
fn libfaketime() -> Option<PathBuf> {
    [
        "/usr/lib/x86_64-linux-gnu/faketime",
        "/usr/lib/aarch64-linux-gnu/faketime",
        "/usr/lib/faketime",
    ]
    .iter()
    .map(|dir| Path::new(dir).join("libfaketime.so.1"))
    .find(|lib| lib.exists())
}

/// A worker whose clock runs 45 s ahead takes no job that another holds:
/// leases are judged by the database's clock. It stole jobs and restarted
/// them from step 1 (with --max-attempts 1, a healthy job failed at step
/// 38 of 40).
#[test]
fn a_worker_whose_clock_runs_ahead_takes_no_job_another_holds() {
    let Some(lib) = libfaketime() else {
        assert!(
            std::env::var_os("MPM_TEST_REQUIRE_FAKETIME").is_none(),
            "libfaketime is not installed (apt-get install faketime)"
        );
        eprintln!("skipped: libfaketime is not installed (apt-get install faketime)");
        return;
    };
    let dir = TempDir::new("clock-skew");
    let database = postgres_database();
    let (mut api, base) = start_api(&database);
    let (honest_log, ahead_log) = (dir.0.join("honest.log"), dir.0.join("ahead.log"));
    let mut honest = start_worker_with(&database, "5", &honest_log, &[]);
    let id = submit_to(&base, &slow_case(40));
    wait_for_step(&base, id, 1);
    let mut ahead = start_worker_with(
        &database,
        "5",
        &ahead_log,
        &[
            ("LD_PRELOAD", lib.to_str().unwrap()),
            ("FAKETIME", "+45s"),
            ("FAKETIME_DONT_FAKE_MONOTONIC", "1"),
        ],
    );
    let jobs = wait_all_final(&base, Duration::from_secs(300));
    let job = &jobs[&id];
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["attempts"], 1, "claimed once: {job}");
    assert!(
        starts(&[ahead_log]).is_empty(),
        "the worker ahead took the job"
    );
    for w in [&mut honest, &mut ahead, &mut api] {
        kill(w);
    }
}
