//! A server stopped mid-job (SIGKILL or SIGTERM) loses nothing: restarted on
//! the same SQLite file, it resumes the job from its last checkpoint and
//! runs it to the end. (tests/cluster.rs does the same with several
//! processes on PostgreSQL.)

mod common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use common::{
    Process, TempDir, agent, base_url, cli_final_positions, example, is_final, largest_difference,
    positions, request, slow_case, slow_solid_case, spawn_mpm, submit_to, try_get_json, wait_for,
};
use serde_json::{Value, json};

/// Starts `mpm serve` on a free port; returns the child and its base URL.
fn start_server(database: &Path) -> (Process, String) {
    start_server_with(database, &[])
}

/// Starts `mpm serve` with extra flags.
fn start_server_with(database: &Path, flags: &[&str]) -> (Process, String) {
    let database = database.to_str().unwrap();
    let mut args = vec![
        "serve",
        "--addr",
        "127.0.0.1:0",
        "--lease-seconds",
        "1",
        "--database",
        database,
    ];
    args.extend_from_slice(flags);
    let (child, line) = spawn_mpm(&args, None);
    (child, base_url(&line))
}

/// Stops the server running a 40-step job at step 2 or later with `signal`,
/// reads where the job stood with a server that does not solve, then
/// restarts with workers: the job resumes after exactly that step (the
/// worker stored a checkpoint with every step) and ends where the CLI's
/// uninterrupted run ends.
fn a_job_resumes_after_its_server_is_stopped_with(signal: &str, case: Value) {
    let dir = TempDir::new("recovery");
    let database = dir.0.join("jobs.sqlite");
    let http = agent();

    let (mut first, base) = start_server_with(&database, &["--checkpoint-every", "1"]);
    let id = submit_to(&base, &case);
    let before = wait_for(&http, &base, id, Duration::from_secs(120), |j| {
        j["progress"]["step"].as_i64() >= Some(2)
    });
    assert_eq!(before["status"], "running");
    let killed = Command::new("kill")
        .args([signal, &first.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    first.wait().unwrap();

    let (mut reader, base) = start_server_with(&database, &["--workers", "0"]);
    let stopped = wait_for(&http, &base, id, Duration::from_secs(10), |_| true);
    let stopped_at = stopped["progress"]["step"].as_i64().unwrap();
    reader.kill().unwrap();
    reader.wait().unwrap();

    let (mut second, base) = start_server(&database);
    let after = wait_for(&http, &base, id, Duration::from_secs(300), is_final);
    let (_, last) = request(&http, "GET", &format!("{base}/jobs/{id}/steps/40"), None);
    second.kill().unwrap();
    second.wait().unwrap();
    let worst = largest_difference(
        &positions(&serde_json::from_str(&last).unwrap()),
        &cli_final_positions(&case),
    );
    eprintln!(
        "{signal} at step {stopped_at} of 40 ({}); after restart: {} in attempt {}, resumed \
         from step {}; final positions within {worst:.1e} m of the CLI's",
        stopped["status"], after["status"], after["attempts"], after["resumed_from_step"]
    );
    assert_eq!(after["status"], "succeeded", "{after}");
    assert_eq!(after["progress"]["step"], 40);
    assert_eq!(
        after["resumed_from_step"].as_i64(),
        Some(stopped_at),
        "{after}"
    );
    assert!(worst <= 1e-9, "{worst:e}");
}

/// SIGKILL: no chance to clean up; the job is claimed again once the dead
/// worker's lease expires, as its second attempt.
#[test]
fn a_job_resumes_after_its_server_is_killed() {
    a_job_resumes_after_its_server_is_stopped_with("-KILL", slow_case(40));
}

/// The same for a 3D job, whose checkpoints are its own format.
#[test]
fn a_3d_job_resumes_after_its_server_is_killed() {
    a_job_resumes_after_its_server_is_stopped_with("-KILL", slow_solid_case(40));
}

/// SIGTERM (`docker stop`): the running job goes back to the queue at its
/// next Newton iteration, keeping its steps up to its checkpoint; it once
/// ran again from step 1.
#[test]
fn a_job_resumes_after_its_server_is_stopped() {
    a_job_resumes_after_its_server_is_stopped_with("-TERM", slow_case(40));
}

#[test]
fn finished_jobs_and_their_steps_survive_a_restart() {
    let dir = TempDir::new("restart");
    let database = dir.0.join("jobs.sqlite");
    let http = agent();
    let (mut first, base) = start_server(&database);
    let small = common::example("cantilever-grid").to_string();
    let (_, body) = request(&http, "POST", &format!("{base}/jobs"), Some(&small));
    let done = serde_json::from_str::<Value>(&body).unwrap()["id"]
        .as_i64()
        .unwrap();
    wait_for(&http, &base, done, Duration::from_secs(120), is_final);
    first.kill().unwrap();
    first.wait().unwrap();

    let (mut second, base) = start_server(&database);
    let job = wait_for(&http, &base, done, Duration::from_secs(10), |_| true);
    assert_eq!(job["status"], "succeeded");
    let (status, steps) = request(&http, "GET", &format!("{base}/jobs/{done}/steps"), None);
    assert_eq!(status, 200);
    assert_eq!(
        serde_json::from_str::<Value>(&steps).unwrap()["steps"]
            .as_array()
            .unwrap()
            .len(),
        6,
        "step 0 and five load steps"
    );
    second.kill().unwrap();
    second.wait().unwrap();
}

/// SIGTERM while a submission is being checked: the check is given up, its
/// client is answered 503, and the server exits at once instead of waiting
/// for the seeding (a sliver that scanned for seconds once kept a server
/// from stopping for over 20 s). The sliver here, on the grid's lattice, scans 6e8 lattice sites (two columns),
/// about 9 s of seeding (1.5e-8 s a site); the server must be gone within
/// 3 s of the signal (measured: 0.13 s).
#[test]
fn sigterm_does_not_wait_for_a_submission_being_checked() {
    let dir = TempDir::new("sigterm");
    let (mut server, base) =
        start_server_with(&dir.0.join("jobs.sqlite"), &["--max-points", "200000000"]);
    let mut case =
        common::filled_at_1mm(json!({"polygon": {"vertices": [[0, 0], [1e-6, 0], [0, 3e5]]}}));
    // On the grid's lattice, where counting its sites means scanning them.
    case["bodies"][0]["points"]["lattice"] = "grid".into();
    let response = std::thread::scope(|s| {
        let submit = s.spawn(|| {
            request(
                &agent(),
                "POST",
                &format!("{base}/jobs"),
                Some(&case.to_string()),
            )
        });
        std::thread::sleep(Duration::from_millis(300));
        let term = Instant::now();
        let killed = Command::new("kill")
            .args(["-TERM", &server.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let status = loop {
            if let Some(status) = server.try_wait().unwrap() {
                break status;
            }
            assert!(
                term.elapsed() < Duration::from_secs(3),
                "still running 3 s after SIGTERM"
            );
            std::thread::sleep(Duration::from_millis(10));
        };
        eprintln!("exited {:.2} s after SIGTERM", term.elapsed().as_secs_f64());
        assert!(status.success(), "{status}");
        submit.join().unwrap()
    });
    let (status, body) = response;
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("\"unavailable\""), "{body}");
}

/// Logs written to a file (a container's stderr) carry no colour codes;
/// they once did, and container logs showed the escape sequences.
#[test]
fn logs_off_a_terminal_have_no_colour_codes() {
    let dir = TempDir::new("logs");
    let log = dir.0.join("serve.log");
    let database = dir.0.join("jobs.sqlite");
    let (server, _) = spawn_mpm(
        &[
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--database",
            database.to_str().unwrap(),
        ],
        Some(&log),
    );
    let term = Command::new("kill")
        .args(["-TERM", &server.id().to_string()])
        .status()
        .unwrap();
    assert!(term.success());
    let mut server = server;
    server.wait().unwrap();
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.contains("shutting down"), "{text}");
    assert!(!text.contains('\u{1b}'), "escape codes in: {text:?}");
}

/// A small filesystem of its own (tmpfs), unmounted when dropped; `None`
/// where this process may not mount one (not root, or in a container
/// without the right).
struct SmallDisk(std::path::PathBuf);

impl SmallDisk {
    fn mount(dir: &Path, megabytes: u32) -> Option<SmallDisk> {
        let point = dir.join("disk");
        std::fs::create_dir_all(&point).unwrap();
        let mounted = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={megabytes}m"), "tmpfs"])
            .arg(&point)
            .status()
            .is_ok_and(|s| s.success());
        mounted.then_some(SmallDisk(point))
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.0).status();
    }
}

/// The reproduction: jobs storing their steps on a disk that
/// fills. Before, the first "database or disk is full" left a pooled
/// connection inside a transaction: every claim failed with "database is
/// locked" for ten minutes and more, /health said ok, and the job whose
/// step did not fit failed. Now /health says degraded, the jobs go back to
/// the queue with their steps, and once space is freed every job ends
/// succeeded without anyone's help; a delete answered 204 meanwhile stands.
#[test]
fn jobs_on_a_full_disk_wait_for_space_and_then_finish() {
    let dir = TempDir::new("full-disk");
    let Some(disk) = SmallDisk::mount(&dir.0, 24) else {
        assert!(
            std::env::var_os("MPM_TEST_REQUIRE_MOUNT").is_none(),
            "cannot mount a tmpfs here"
        );
        eprintln!("skipped: cannot mount a tmpfs here (needs root)");
        return;
    };
    // Room to free later. The three jobs store some 13 MB of steps (1,280
    // points, 11 steps each, about 400 kB a step), and the write-ahead log
    // up to 4 MB more: past the 8 MB left at first (two jobs, 9 MB, fitted
    // once), within the 24 MB once the ballast goes.
    let ballast = disk.0.join("ballast");
    std::fs::write(&ballast, vec![0u8; 16 << 20]).unwrap();
    let (mut server, base) = start_server_with(&disk.0.join("jobs.sqlite"), &["--workers", "2"]);
    let http = agent();
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.25.into();
    case["analysis"]["load_steps"] = 10.into();
    let ids: Vec<i64> = (0..3).map(|_| submit_to(&base, &case)).collect();
    let health = || request(&http, "GET", &format!("{base}/health"), None);
    let start = Instant::now();
    while health().0 == 200 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the disk never filled"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let (status, body) = health();
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("database or disk is full"), "{body}");
    // No job fails for the disk's sake.
    std::thread::sleep(Duration::from_secs(3));
    for id in &ids {
        let job = try_get_json(&http, &format!("{base}/jobs/{id}")).unwrap();
        assert_ne!(job["status"], "failed", "{job}");
    }
    std::fs::remove_file(&ballast).unwrap();
    let start = Instant::now();
    loop {
        let jobs: Vec<Value> = ids
            .iter()
            .map(|id| try_get_json(&http, &format!("{base}/jobs/{id}")).unwrap())
            .collect();
        if jobs.iter().all(|j| j["status"] == "succeeded") {
            break;
        }
        assert!(jobs.iter().all(|j| j["status"] != "failed"), "{jobs:?}");
        assert!(start.elapsed() < Duration::from_secs(300), "{jobs:?}");
        std::thread::sleep(Duration::from_millis(200));
    }
    assert_eq!(health().0, 200);
    let (status, _) = request(&http, "DELETE", &format!("{base}/jobs/{}", ids[0]), None);
    assert_eq!(status, 204);
    server.kill().unwrap();
    server.wait().unwrap();
    let (_server, base) = start_server_with(&disk.0.join("jobs.sqlite"), &["--workers", "0"]);
    let (status, _) = request(&http, "GET", &format!("{base}/jobs/{}", ids[0]), None);
    assert_eq!(status, 404, "the delete stands after kill -9");
}
