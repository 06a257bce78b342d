//! A server killed with SIGKILL mid-job loses nothing: restarted on the same
//! database, it claims the job again once the dead worker's lease expires and
//! runs it to the end.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{TempDir, agent, is_final, request, slow_case, wait_for};
use serde_json::{Value, json};

/// Starts `mpm serve` on a free port; returns the child and its base URL.
fn start_server(database: &Path) -> (Child, String) {
    start_server_with(database, &[])
}

/// Starts `mpm serve` with extra flags.
fn start_server_with(database: &Path, flags: &[&str]) -> (Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mpm"))
        .args([
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--lease-seconds",
            "1",
            "--database",
        ])
        .arg(database)
        .args(flags)
        .env("MPM_LOG", "warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap_or_else(|| panic!("unexpected first line: {line:?}"));
    (child, format!("http://{addr}"))
}

#[test]
fn a_job_survives_the_server_being_killed() {
    let dir = TempDir::new("recovery");
    let database = dir.0.join("jobs.sqlite");
    let http = agent();

    let (mut first, base) = start_server(&database);
    let (status, body) = request(
        &http,
        "POST",
        &format!("{base}/jobs"),
        Some(&slow_case(40).to_string()),
    );
    assert_eq!(status, 201, "{body}");
    let id = serde_json::from_str::<Value>(&body).unwrap()["id"]
        .as_i64()
        .unwrap();
    let before = wait_for(&http, &base, id, Duration::from_secs(120), |j| {
        j["progress"]["step"].as_i64() >= Some(2)
    });
    assert_eq!(before["status"], "running");
    first.kill().unwrap(); // SIGKILL: no chance to clean up
    first.wait().unwrap();

    let (mut second, base) = start_server(&database);
    let after = wait_for(&http, &base, id, Duration::from_secs(300), is_final);
    second.kill().unwrap();
    second.wait().unwrap();
    eprintln!(
        "killed at step {} of 40 (attempt 1); after restart: {} in attempt {}, {} steps",
        before["progress"]["step"], after["status"], after["attempts"], after["progress"]["step"]
    );
    assert_eq!(after["status"], "succeeded", "{after}");
    assert_eq!(after["attempts"], 2);
    assert_eq!(after["progress"]["step"], 40);
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
        5
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
        common::filled_at_1mm(json!({"polygon": {"vertices": [[0, 0], [1e-12, 0], [0, 3e5]]}}));
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
