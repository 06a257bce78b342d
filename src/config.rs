//! Service settings. Every one has a command-line flag and an environment
//! variable (see `mpm serve --help` and the README).

use std::path::PathBuf;
use std::time::Duration;

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
    pub job_time_limit: Duration,
}

impl Config {
    /// Defaults for a database file, as documented in the README.
    pub fn new(database: PathBuf) -> Self {
        Self {
            database,
            workers: 1,
            lease: Duration::from_secs(30),
            max_attempts: 3,
            poll_interval: Duration::from_secs(1),
            token: None,
            limits: Limits {
                max_body_bytes: 1 << 20,
                max_points: 1_000_000,
                max_load_steps: 10_000,
                job_time_limit: Duration::from_secs(3600),
            },
        }
    }
}
