//! Service settings. Every one has a command-line flag and an environment
//! variable (see `mpm serve --help` and the README).

use std::path::PathBuf;
use std::time::Duration;

// The defaults, shared by `Config::new` and the flags of `mpm serve`.
/// Where `mpm serve` listens.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";
/// The database file of `mpm serve`.
pub const DEFAULT_DATABASE: &str = "mpm.sqlite";
pub const DEFAULT_WORKERS: usize = 1;
pub const DEFAULT_LEASE: Duration = Duration::from_secs(30);
pub const DEFAULT_MAX_ATTEMPTS: u32 = 3;
pub const DEFAULT_POLL_INTERVAL: Duration = Duration::from_secs(1);
pub const DEFAULT_MAX_BODY_BYTES: usize = 1 << 20;
pub const DEFAULT_MAX_POINTS: usize = 1_000_000;
pub const DEFAULT_MAX_LOAD_STEPS: usize = 10_000;
/// Jobs that may wait in the queue; a submission beyond them gets 429.
pub const DEFAULT_MAX_QUEUED: usize = 1_000;
/// What one job may store (its steps' points), in bytes: 4 GiB, e.g.
/// 100,000 points over 150 load steps.
pub const DEFAULT_MAX_JOB_BYTES: u64 = 1 << 32;
/// How long checking one submission (seeding its bodies) may take: far
/// more than a case within the point limit needs (about 1.2 s a million
/// points).
pub const DEFAULT_ADMISSION_TIME_LIMIT: Duration = Duration::from_secs(20);
pub const DEFAULT_JOB_TIME_LIMIT: Duration = Duration::from_secs(3600);

#[derive(Debug, Clone)]
pub struct Config {
    /// SQLite file, created on first start.
    pub database: PathBuf,
    /// Jobs solved at once. Each solve uses rayon's pool of all cores, so
    /// one worker is the default; more workers share the cores.
    pub workers: usize,
    /// A running job's lease; renewed every third of it.
    pub lease: Duration,
    /// Claims of one job (first run plus retries after a crash) before it
    /// is failed.
    pub max_attempts: u32,
    /// How often an idle worker looks for jobs whose lease expired.
    pub poll_interval: Duration,
    /// When set, every endpoint but /health needs `Authorization: Bearer`.
    pub token: Option<String>,
    pub limits: Limits,
}

/// Bounds on what one submission may ask for.
#[derive(Debug, Clone)]
pub struct Limits {
    pub max_body_bytes: usize,
    pub max_points: usize,
    pub max_load_steps: usize,
    pub max_queued: usize,
    /// What one job's stored steps may take, estimated before it is queued.
    pub max_job_bytes: u64,
    pub job_time_limit: Duration,
    /// How long checking one submission may take; 503 past it.
    pub admission_time_limit: Duration,
}

impl Config {
    /// Defaults for a database file, as documented in the README.
    pub fn new(database: PathBuf) -> Self {
        Self {
            database,
            workers: DEFAULT_WORKERS,
            lease: DEFAULT_LEASE,
            max_attempts: DEFAULT_MAX_ATTEMPTS,
            poll_interval: DEFAULT_POLL_INTERVAL,
            token: None,
            limits: Limits {
                max_body_bytes: DEFAULT_MAX_BODY_BYTES,
                max_points: DEFAULT_MAX_POINTS,
                max_load_steps: DEFAULT_MAX_LOAD_STEPS,
                max_queued: DEFAULT_MAX_QUEUED,
                max_job_bytes: DEFAULT_MAX_JOB_BYTES,
                job_time_limit: DEFAULT_JOB_TIME_LIMIT,
                admission_time_limit: DEFAULT_ADMISSION_TIME_LIMIT,
            },
        }
    }
}
