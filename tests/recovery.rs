//! A server killed with SIGKILL mid-job loses nothing: restarted on the same
//! database, it claims the job again once the dead worker's lease expires and
//! runs it to the end.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use common::{TempDir, agent, is_final, request, slow_case, wait_for};
use serde_json::Value;

/// Starts `mpm serve` on a free port; returns the child and its base URL.
fn start_server(database: &Path) -> (Child, String) {
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
