//! Service settings. Every one has a command-line flag and an environment
//! variable (see `mpm serve --help` and the README).

use std::time::Duration;

// The defaults, shared by `Config::new` and the flags of `mpm serve`.
/// Where `mpm serve` listens.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";
/// The database of `mpm serve`: a SQLite file beside it.
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
/// A client's time to send a request's body, and to take each part of a
/// response: what a slow or idle client can hold memory for.
pub const DEFAULT_CLIENT_TIMEOUT: Duration = Duration::from_secs(30);

#[derive(Debug, Clone)]
pub struct Config {
    /// The database: a SQLite file (a path or `sqlite://PATH`, created on
    /// first start) or a PostgreSQL URL (`postgres://...`).
    pub database: String,
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
    /// Every how many load steps a running job stores its solver state to
    /// resume from; 0 picks by size ([`checkpoint_interval`]).
    pub checkpoint_every: usize,
    /// Ended jobs older than this are deleted (checked every few minutes
    /// by the serving process).
    pub retention: Option<Duration>,
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
    /// How long a client may take to send a request body, or leave a
    /// response untaken, before the server gives up on it.
    pub client_timeout: Duration,
    /// How long checking one submission may take; 503 past it.
    pub admission_time_limit: Duration,
}

/// Every how many load steps a job's solver state is stored, with the
/// interval 0 ("auto"): every step up to this many points, and above it
/// every `points / AUTO_CHECKPOINT_POINTS` steps (rounded up), so that
/// checkpoints write about 2.6 MB a step at most (130 bytes a point).
pub const AUTO_CHECKPOINT_POINTS: usize = 20_000;

/// The checkpoint interval in load steps for a job of `points` points,
/// given the setting `every` (0: auto).
pub fn checkpoint_interval(every: usize, points: usize) -> usize {
    if every > 0 {
        every
    } else {
        points.div_ceil(AUTO_CHECKPOINT_POINTS).max(1)
    }
}

/// The longest stretch of solving a run goes without storing its state,
/// whatever its step interval: a job of 10 steps over 20,000 points never
/// reached its interval, and lost all its work to a crash.
pub const CHECKPOINT_MAX_WAIT: Duration = Duration::from_secs(180);

/// When a run stores its solver's state: every `every` load steps, and
/// after any step that ends [`CHECKPOINT_MAX_WAIT`] or more after the last
/// checkpoint (or the run's start).
#[derive(Debug, Clone)]
pub struct CheckpointSchedule {
    every: usize,
    max_wait: Duration,
    last: std::time::Instant,
}

impl CheckpointSchedule {
    /// For a run of `points` points with the setting `every` (0: auto).
    pub fn new(every: usize, points: usize) -> Self {
        Self::with_wait(checkpoint_interval(every, points), CHECKPOINT_MAX_WAIT)
    }

    pub fn with_wait(every: usize, max_wait: Duration) -> Self {
        CheckpointSchedule {
            every: every.max(1),
            max_wait,
            last: std::time::Instant::now(),
        }
    }

    /// Whether step `step`, just finished, stores a checkpoint; if so, the
    /// wait starts again.
    pub fn due(&mut self, step: usize) -> bool {
        let due =
            step > 0 && (step.is_multiple_of(self.every) || self.last.elapsed() >= self.max_wait);
        if due {
            self.last = std::time::Instant::now();
        }
        due
    }
}

/// The database URL with its password, if any, replaced by `***` (for
/// logs and error messages).
pub fn redact(database: &str) -> String {
    let Some((scheme, rest)) = database.split_once("://") else {
        return database.to_string();
    };
    // The last '@': a password written with an '@' of its own (which a URL
    // should percent-encode) showed its tail in the logs.
    match rest.rsplit_once('@') {
        Some((user_info, host)) if user_info.contains(':') => {
            let user = user_info.split(':').next().unwrap_or_default();
            format!("{scheme}://{user}:***@{host}")
        }
        _ => database.to_string(),
    }
}

impl Config {
    /// Defaults for a database file, as documented in the README.
    pub fn new(database: impl Into<String>) -> Self {
        Self {
            database: database.into(),
            workers: DEFAULT_WORKERS,
            lease: DEFAULT_LEASE,
            max_attempts: DEFAULT_MAX_ATTEMPTS,
            poll_interval: DEFAULT_POLL_INTERVAL,
            checkpoint_every: 0,
            retention: None,
            token: None,
            limits: Limits {
                max_body_bytes: DEFAULT_MAX_BODY_BYTES,
                max_points: DEFAULT_MAX_POINTS,
                max_load_steps: DEFAULT_MAX_LOAD_STEPS,
                max_queued: DEFAULT_MAX_QUEUED,
                max_job_bytes: DEFAULT_MAX_JOB_BYTES,
                job_time_limit: DEFAULT_JOB_TIME_LIMIT,
                client_timeout: DEFAULT_CLIENT_TIMEOUT,
                admission_time_limit: DEFAULT_ADMISSION_TIME_LIMIT,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    /// Steps on the interval checkpoint; so does the first step past the
    /// longest wait, however far from the interval it is.
    #[test]
    fn a_checkpoint_is_due_on_the_interval_and_after_the_longest_wait() {
        let mut steps =
            super::CheckpointSchedule::with_wait(3, std::time::Duration::from_secs(3600));
        let due: Vec<usize> = (1..=7).filter(|&s| steps.due(s)).collect();
        assert_eq!(due, [3, 6]);
        let mut slow = super::CheckpointSchedule::with_wait(1000, std::time::Duration::ZERO);
        assert!((1..=5).all(|s| slow.due(s)), "every step past the wait");
        assert!(!slow.due(0), "step 0 is the undeformed state");
    }

    use super::*;

    #[test]
    fn a_password_in_the_database_url_is_not_shown() {
        assert_eq!(
            redact("postgres://mpm:s3cret@db:5432/jobs"),
            "postgres://mpm:***@db:5432/jobs"
        );
        assert_eq!(redact("postgres://db/jobs"), "postgres://db/jobs");
        assert_eq!(
            redact("postgres://mpm:p@ss/w:rd@db:5432/jobs"),
            "postgres://mpm:***@db:5432/jobs"
        );
        assert_eq!(redact("jobs.sqlite"), "jobs.sqlite");
    }

    #[test]
    fn checkpoints_thin_out_with_size() {
        assert_eq!(checkpoint_interval(0, 1_000), 1);
        assert_eq!(checkpoint_interval(0, 20_000), 1);
        assert_eq!(checkpoint_interval(0, 100_000), 5);
        assert_eq!(checkpoint_interval(3, 100_000), 3);
    }
}
