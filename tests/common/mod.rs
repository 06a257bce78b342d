//! Test helpers: a real server on 127.0.0.1 port 0 with a fresh database,
//! a SQLite file or a PostgreSQL database ([`postgres`]).
#![allow(dead_code)]

use std::cell::Cell;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use mpm_service::{Config, Server};
use serde_json::Value;

/// A fresh directory under the system's temp dir, removed on drop.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> Self {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::SeqCst);
        let dir = std::env::temp_dir().join(format!("mpm-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// HTTP client that returns 4xx/5xx responses instead of errors.
pub fn agent() -> ureq::Agent {
    ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(Duration::from_secs(60)))
        .build()
        .into()
}

/// A running service and its client.
pub struct TestApp {
    pub base: String,
    pub agent: ureq::Agent,
    runtime: Option<tokio::runtime::Runtime>,
    server: Option<Server>,
    pub dir: TempDir,
}

/// Starts the service with default settings on a fresh database.
pub fn spawn_app() -> TestApp {
    spawn_app_with(|_| {})
}

/// Which database the tests of this thread use ([`on_both_databases`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Database {
    Sqlite,
    Postgres,
}

thread_local! {
    static DATABASE: Cell<Database> = const { Cell::new(Database::Sqlite) };
}

/// Runs `test` with the servers it starts on `database`.
pub fn with_database(database: Database, test: fn()) {
    DATABASE.with(|d| d.set(database));
    test();
}

/// Makes two tests of each function named: `sqlite::name` and
/// `postgres::name`, each starting its servers on that database.
#[allow(unused_macros)]
macro_rules! on_both_databases {
    ($($name:ident),* $(,)?) => {
        mod sqlite {
            $(#[test]
            fn $name() {
                crate::common::with_database(crate::common::Database::Sqlite, super::$name);
            })*
        }
        mod postgres {
            $(#[test]
            fn $name() {
                crate::common::with_database(crate::common::Database::Postgres, super::$name);
            })*
        }
    };
}
#[allow(unused_imports)]
pub(crate) use on_both_databases;

/// A fresh database of the kind this thread's tests use: a file in `dir`,
/// or a new database on the test PostgreSQL server.
pub fn fresh_database(dir: &TempDir) -> String {
    match DATABASE.with(Cell::get) {
        Database::Sqlite => dir.0.join("jobs.sqlite").to_str().unwrap().to_string(),
        Database::Postgres => postgres_database(),
    }
}

/// The PostgreSQL server the tests use: `MPM_TEST_POSTGRES`
/// (`postgres://user@host:port`, a user that may create databases) if set;
/// otherwise a throwaway cluster of this test process, started from
/// PostgreSQL's binaries (`pg_config --bindir`) and stopped, its files
/// removed, when the process ends.
pub fn postgres() -> &'static str {
    static SERVER: OnceLock<String> = OnceLock::new();
    SERVER.get_or_init(|| std::env::var("MPM_TEST_POSTGRES").unwrap_or_else(|_| start_postgres()))
}

/// A new, empty database on [`postgres`]; its URL.
pub fn postgres_database() -> String {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let name = format!(
        "mpm_test_{}_{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::SeqCst)
    );
    let server = postgres();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    runtime.block_on(async {
        use sqlx::Connection;
        let mut admin = sqlx::PgConnection::connect(&format!("{server}/postgres"))
            .await
            .unwrap_or_else(|e| panic!("connect to the test PostgreSQL at {server}: {e}"));
        sqlx::query(sqlx::AssertSqlSafe(format!("CREATE DATABASE {name}")))
            .execute(&mut admin)
            .await
            .unwrap();
    });
    format!("{server}/{name}")
}

/// Starts a PostgreSQL cluster in a temporary folder on a free port, as
/// the `postgres` user when run as root (the server refuses root). A
/// watchdog shell stops it and removes its folder once this process exits.
fn start_postgres() -> String {
    let bindir = Command::new("pg_config")
        .arg("--bindir")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()))
        .filter(|dir| dir.join("initdb").exists())
        .expect(
            "the PostgreSQL tests need PostgreSQL's server binaries (Debian: apt-get install \
             postgresql) or MPM_TEST_POSTGRES=postgres://user@host:port (see .ci/run)",
        );
    let dir = std::env::temp_dir().join(format!("mpm-postgres-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let as_root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if as_root {
        let status = Command::new("chown")
            .args(["postgres:postgres"])
            .arg(&dir)
            .status();
        assert!(status.unwrap().success(), "chown the cluster folder");
    }
    let data = dir.join("data");
    let run = |program: &str, args: &str| {
        shell(as_root, &format!("{}/{program} {args}", bindir.display()))
    };
    let initdb = run(
        "initdb",
        &format!("-D {} -U mpm -A trust -N --no-instructions", data.display()),
    )
    .stdout(Stdio::null())
    .status()
    .unwrap();
    assert!(initdb.success(), "initdb failed");
    let test_pid = std::process::id();
    // The watchdog looks for this process in /proc (as the postgres user,
    // `kill -0` on a root process fails as if it were gone; Linux only),
    // then stops the server with SIGINT, a fast shutdown that does not wait
    // for clients (a server that has not installed its handlers yet ignores
    // it, as a background job of a non-interactive shell: by then it has).
    let watchdog = format!(
        "{bin}/postgres -D {data} -p {port} -k {dir} -c listen_addresses=127.0.0.1 -c fsync=off \
             -c synchronous_commit=off -c full_page_writes=off -c max_connections=300 >{dir}/log 2>&1 & \
         server=$!; while [ -e /proc/{test_pid} ]; do sleep 1; done; \
         kill -INT $server; wait $server; rm -rf {dir}",
        bin = bindir.display(),
        data = data.display(),
        dir = dir.display(),
    );
    // Not waited for: it outlives this process, to stop the server after it.
    #[allow(clippy::zombie_processes)]
    shell(as_root, &watchdog)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let ready = run(
            "pg_isready",
            &format!("-q -h 127.0.0.1 -p {port} -U mpm -d postgres"),
        )
        .status()
        .is_ok_and(|s| s.success());
        if ready {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "PostgreSQL did not start: see {}/log",
            dir.display()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    format!("postgres://mpm@127.0.0.1:{port}")
}

/// `sh -c line`, as the `postgres` user when `as_root`.
fn shell(as_root: bool, line: &str) -> Command {
    let mut command = Command::new(if as_root { "runuser" } else { "sh" });
    if as_root {
        command.args(["-u", "postgres", "--", "sh"]);
    }
    command.args(["-c", line]);
    command
}

/// Starts the service after `adjust` has changed its settings.
pub fn spawn_app_with(adjust: impl FnOnce(&mut Config)) -> TestApp {
    let dir = TempDir::new("api");
    let mut config = Config::new(fresh_database(&dir));
    config.poll_interval = Duration::from_millis(100);
    adjust(&mut config);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let server = runtime
        .block_on(Server::start(config, "127.0.0.1:0".parse().unwrap()))
        .expect("server starts");
    TestApp {
        base: format!("http://{}", server.addr),
        agent: agent(),
        runtime: Some(runtime),
        server: Some(server),
        dir,
    }
}

impl Drop for TestApp {
    fn drop(&mut self) {
        if let (Some(rt), Some(server)) = (self.runtime.take(), self.server.take()) {
            rt.block_on(server.shutdown());
        }
    }
}

/// Submits a case to the service at `base`; returns the job id.
#[allow(dead_code)] // not every test binary submits this way
pub fn submit_to(base: &str, case: &Value) -> i64 {
    let (status, body) = request(
        &agent(),
        "POST",
        &format!("{base}/jobs"),
        Some(&case.to_string()),
    );
    assert_eq!(status, 201, "{body}");
    serde_json::from_str::<Value>(&body).unwrap()["id"]
        .as_i64()
        .unwrap()
}

/// `(status, body)` of a request.
pub fn request(agent: &ureq::Agent, method: &str, url: &str, body: Option<&str>) -> (u16, String) {
    let response = match (method, body) {
        ("GET", _) => agent.get(url).call(),
        ("POST", Some(b)) => agent
            .post(url)
            .header("content-type", "application/json")
            .send(b),
        ("POST", None) => agent.post(url).send_empty(),
        ("DELETE", _) => agent.delete(url).call(),
        _ => panic!("unsupported {method}"),
    };
    let mut response = response.unwrap_or_else(|e| panic!("{method} {url}: {e}"));
    let status = response.status().as_u16();
    let bytes = response
        .body_mut()
        .with_config()
        .limit(1 << 30)
        .read_to_vec()
        .unwrap_or_default();
    (status, String::from_utf8_lossy(&bytes).into_owned())
}

impl TestApp {
    pub fn get(&self, path: &str) -> (u16, String) {
        request(&self.agent, "GET", &format!("{}{path}", self.base), None)
    }

    pub fn get_json(&self, path: &str) -> Value {
        let (status, body) = self.get(path);
        assert_eq!(status, 200, "GET {path}: {body}");
        serde_json::from_str(&body).unwrap()
    }

    pub fn post(&self, path: &str, body: &str) -> (u16, String) {
        request(
            &self.agent,
            "POST",
            &format!("{}{path}", self.base),
            Some(body),
        )
    }

    pub fn delete(&self, path: &str) -> (u16, String) {
        request(&self.agent, "DELETE", &format!("{}{path}", self.base), None)
    }

    /// Submits a case; returns the job id.
    pub fn submit(&self, case: &Value) -> i64 {
        let (status, body) = self.post("/jobs", &case.to_string());
        assert_eq!(status, 201, "{body}");
        serde_json::from_str::<Value>(&body).unwrap()["id"]
            .as_i64()
            .unwrap()
    }

    /// Polls a job until `done` holds for it (at most `limit`).
    pub fn wait_for(&self, id: i64, limit: Duration, done: impl Fn(&Value) -> bool) -> Value {
        wait_for(&self.agent, &self.base, id, limit, done)
    }

    pub fn total_jobs(&self) -> i64 {
        self.get_json("/jobs")["total"].as_i64().unwrap()
    }
}

pub fn wait_for(
    agent: &ureq::Agent,
    base: &str,
    id: i64,
    limit: Duration,
    done: impl Fn(&Value) -> bool,
) -> Value {
    let start = Instant::now();
    loop {
        let (status, body) = request(agent, "GET", &format!("{base}/jobs/{id}"), None);
        assert_eq!(status, 200, "{body}");
        let job: Value = serde_json::from_str(&body).unwrap();
        if done(&job) {
            return job;
        }
        assert!(
            start.elapsed() < limit,
            "job {id} did not get there in {limit:?}: {job}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

pub fn is_final(job: &Value) -> bool {
    matches!(
        job["status"].as_str(),
        Some("succeeded" | "failed" | "cancelled")
    )
}

/// A built-in example case as JSON.
pub fn example(name: &str) -> Value {
    mpm::case::builtin::json(name).unwrap()
}

/// A case that takes tens of milliseconds a step: the self-weight column
/// made 10 m wide at 0.5 m cells (8000 points, GIMP) over `steps` steps.
/// A 3D case that takes tens of milliseconds a step: the built-in 3D
/// column at 0.78125 m cells, 4 x 4 x 64 of them (8192 points, GIMP),
/// over `steps` steps.
pub fn slow_solid_case(steps: u32) -> Value {
    let mut case = example("column3d");
    case["grid"]["cell_size"] = 0.78125.into();
    case["analysis"]["load_steps"] = steps.into();
    case
}

pub fn slow_case(steps: u32) -> Value {
    let mut case = example("column");
    case["grid"]["cell_size"] = 0.5.into();
    case["grid"]["extent"] = serde_json::json!({"min": [0.0, 0.0], "max": [10.0, 50.0]});
    case["bodies"][0]["geometry"]["rectangle"]["max"] = serde_json::json!([10.0, 50.0]);
    case["supports"][1]["on"]["x"] = 10.0.into();
    case["analysis"]["load_steps"] = steps.into();
    case
}

/// The cantilever's body replaced by `geometry`, filled one point per 1 mm
/// cell, with no loads, supports or probes: a case that is all seeding
/// (about 1.2 s a million points).
pub fn filled_at_1mm(geometry: Value) -> Value {
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 1e-3.into();
    case["bodies"][0]["geometry"] = geometry;
    case["bodies"][0]["points"] = serde_json::json!({"per_cell": 1});
    case["loads"] = serde_json::json!({});
    case["supports"] = serde_json::json!([]);
    case["probes"] = serde_json::json!([]);
    case
}

/// A child process killed when dropped, so a test that fails part-way
/// leaves no server running (one that holds the test's stderr open keeps
/// cargo waiting for ever).
pub struct Process(pub std::process::Child);

impl std::ops::Deref for Process {
    type Target = std::process::Child;
    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl std::ops::DerefMut for Process {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.0
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts the `mpm` binary with `args` and waits for its first line on
/// stdout (`mpm serve` prints its address there, `mpm worker` its start);
/// its stderr goes to `log` when given. Returns the child and the line.
pub fn spawn_mpm(args: &[&str], log: Option<&std::path::Path>) -> (Process, String) {
    spawn_mpm_with(args, log, &[])
}

/// [`spawn_mpm`] with these environment variables set.
pub fn spawn_mpm_with(
    args: &[&str],
    log: Option<&std::path::Path>,
    env: &[(&str, &str)],
) -> (Process, String) {
    use std::io::{BufRead, BufReader};
    // Logs to a file in full; to the terminal, only what went wrong.
    let (stderr, level) = match log {
        Some(path) => (Stdio::from(std::fs::File::create(path).unwrap()), "info"),
        None => (Stdio::inherit(), "warn"),
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_mpm"))
        .args(args)
        .envs(env.iter().copied())
        .env("MPM_LOG", level)
        .stdout(Stdio::piped())
        .stderr(stderr)
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(!line.is_empty(), "mpm {args:?} exited before starting");
    (Process(child), line)
}

/// The base URL in `mpm serve`'s first line.
pub fn base_url(first_line: &str) -> String {
    let addr = first_line
        .split("http://")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap_or_else(|| panic!("unexpected first line: {first_line:?}"));
    format!("http://{addr}")
}

/// GET `url` as JSON, or `None` if the server does not answer 200 (it may
/// have been killed).
pub fn try_get_json(agent: &ureq::Agent, url: &str) -> Option<Value> {
    let mut response = agent.get(url).call().ok()?;
    if response.status().as_u16() != 200 {
        return None;
    }
    response.body_mut().read_json().ok()
}

/// Final point positions of the CLI's run of `case` (`mpm run`).
pub fn cli_final_positions(case: &Value) -> Vec<Vec<f64>> {
    let dir = TempDir::new("cli-reference");
    let path = dir.0.join("case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    let out = dir.0.join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_mpm"))
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "mpm run failed");
    let steps = case["analysis"]["load_steps"].as_u64().unwrap();
    let text = std::fs::read_to_string(out.join(format!("steps/step_{steps:04}.json"))).unwrap();
    positions(&serde_json::from_str::<Value>(&text).unwrap())
}

/// `points.position` of a step document.
pub fn positions(step: &Value) -> Vec<Vec<f64>> {
    serde_json::from_value(step["points"]["position"].clone()).unwrap()
}

/// The largest coordinate difference between two point sets.
pub fn largest_difference(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    assert_eq!(a.len(), b.len(), "point counts differ");
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max)
}
