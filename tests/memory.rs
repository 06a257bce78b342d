//! The server process's memory while clients leave large responses unread:
//! a step is sent as it is read from the database, so an unread one holds
//! a few pieces, not the whole response (300 unread 5.9 MB steps held 1.7
//! GB when each was built whole).

mod common;

use std::io::Write;
use std::net::TcpStream;
use std::time::Duration;

use common::{TempDir, example, is_final, spawn_mpm, submit_to, wait_for};

/// The resident set of process `pid`, in bytes.
fn resident_bytes(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("VmRSS in /proc/PID/status");
    kib * 1024
}

#[test]
fn unread_steps_hold_a_few_pieces_each() {
    let dir = TempDir::new("memory");
    let database = dir.0.join("jobs.sqlite");
    let (server, line) = spawn_mpm(
        &[
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--client-timeout",
            "600",
            "--database",
            database.to_str().unwrap(),
        ],
        None,
    );
    let base = common::base_url(&line);
    let addr = base.trim_start_matches("http://").to_string();

    // One step of some 40 MB of JSON, more than the sockets' buffers hold
    // (a few MB each way on loopback).
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.025.into();
    case["analysis"]["load_steps"] = 1.into();
    let id = submit_to(&base, &case);
    let agent = common::agent();
    let done = wait_for(&agent, &base, id, Duration::from_secs(300), is_final);
    assert_eq!(done["status"], "succeeded", "{done}");

    let before = resident_bytes(server.id());
    let mut unread = Vec::new();
    for _ in 0..10 {
        let mut stream = TcpStream::connect(&addr).unwrap();
        write!(
            stream,
            "GET /jobs/{id}/steps/1 HTTP/1.1\r\nhost: {addr}\r\n\r\n"
        )
        .unwrap();
        unread.push(stream);
    }
    // Long enough for every response to fill its socket and stop.
    std::thread::sleep(Duration::from_secs(6));
    let after = resident_bytes(server.id());
    let grown = after.saturating_sub(before) as f64 / 1e6;
    // Built whole, each of the 10 held at least its 28 MB document (the
    // issue measured 1.7 GB for 300 unread 5.9 MB steps): some 280 MB.
    // Streamed, each holds three pieces of a sixteenth of the document
    // (`READS` in src/http/steps.rs); measured: 5 MB each.
    assert!(
        grown < 100.0,
        "the server grew {grown:.0} MB with 10 steps of 28 MB unread ({before} -> {after} bytes)"
    );
    drop(unread);
    drop(server);
}
