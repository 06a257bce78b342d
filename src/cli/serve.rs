//! `mpm serve` (the job service) and `mpm worker` (its solvers on another
//! machine), with their settings from flags or environment.

use std::io::IsTerminal;
use std::net::SocketAddr;
use std::time::Duration;

use clap::Args;
use mpm_service::{Config, Server, Workers, config, redact};

use crate::CliError;

/// What the serving and the solving roles share: the database, the
/// workers and how they run jobs, and the log format.
#[derive(Args)]
pub struct SolverArgs {
    /// The database: a SQLite file (a path or sqlite://PATH, created on
    /// first start) or a PostgreSQL URL (postgres://user:password@host/db),
    /// which several serving and worker processes may share.
    #[arg(long, env = "MPM_DATABASE", default_value = config::DEFAULT_DATABASE)]
    database: String,
    /// Jobs solved at once in this process; each uses all cores through
    /// rayon. `mpm serve --workers 0` serves without solving.
    #[arg(long, env = "MPM_WORKERS", default_value_t = config::DEFAULT_WORKERS)]
    workers: usize,
    /// Threads in rayon's pool for the solver (default: one per core).
    #[arg(long, env = "MPM_SOLVER_THREADS")]
    solver_threads: Option<usize>,
    /// Wall-time limit of one job, in seconds; a job over it fails.
    #[arg(long, env = "MPM_JOB_TIME_LIMIT", default_value_t = config::DEFAULT_JOB_TIME_LIMIT.as_secs())]
    job_time_limit: u64,
    /// Lease of a running job, in seconds; a job whose worker died is
    /// claimed again this long after its last renewal.
    #[arg(long, env = "MPM_LEASE_SECONDS", default_value_t = config::DEFAULT_LEASE.as_secs_f64())]
    lease_seconds: f64,
    /// Runs of one job (first plus retries after crashes) before it fails.
    #[arg(long, env = "MPM_MAX_ATTEMPTS", default_value_t = config::DEFAULT_MAX_ATTEMPTS)]
    max_attempts: u32,
    /// Store a running job's solver state every this many load steps, to
    /// resume from after a crash or restart; 0 picks by size (every step up
    /// to 20,000 points, then every points/20,000 steps).
    #[arg(long, env = "MPM_CHECKPOINT_EVERY", default_value_t = 0)]
    checkpoint_every: usize,
    /// Log lines as `text` (colour only on a terminal) or `json` (one
    /// object a line, for container log collectors).
    #[arg(long, env = "MPM_LOG_FORMAT", default_value = "text")]
    log_format: LogFormat,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum LogFormat {
    Text,
    Json,
}

#[derive(Args)]
pub struct ServeArgs {
    #[command(flatten)]
    solver: SolverArgs,
    /// Address to listen on (port 0 picks a free port).
    #[arg(long, env = "MPM_ADDR", default_value = config::DEFAULT_ADDR)]
    addr: SocketAddr,
    /// Bearer token required on every endpoint but /health.
    #[arg(long, env = "MPM_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// Delete ended jobs (and their results) this many days after they
    /// ended; kept for ever when not given.
    #[arg(long, env = "MPM_RETENTION_DAYS")]
    retention_days: Option<f64>,
    /// Largest accepted request body, in bytes.
    #[arg(long, env = "MPM_MAX_BODY_BYTES", default_value_t = config::DEFAULT_MAX_BODY_BYTES)]
    max_body_bytes: usize,
    /// Most material points a case may generate.
    #[arg(long, env = "MPM_MAX_POINTS", default_value_t = config::DEFAULT_MAX_POINTS)]
    max_points: usize,
    /// Most load steps a case may ask for.
    #[arg(long, env = "MPM_MAX_LOAD_STEPS", default_value_t = config::DEFAULT_MAX_LOAD_STEPS)]
    max_load_steps: usize,
    /// Jobs that may wait in the queue; more submissions get 429.
    #[arg(long, env = "MPM_MAX_QUEUED", default_value_t = config::DEFAULT_MAX_QUEUED)]
    max_queued: usize,
    /// Bytes one job may store (its steps' points, estimated from the
    /// points and load steps before it is queued).
    #[arg(long, env = "MPM_MAX_JOB_BYTES", default_value_t = config::DEFAULT_MAX_JOB_BYTES)]
    max_job_bytes: u64,
    /// Time limit of checking one submission (seeding its bodies), in
    /// seconds; past it the submission gets 503.
    #[arg(long, env = "MPM_ADMISSION_TIME_LIMIT", default_value_t = config::DEFAULT_ADMISSION_TIME_LIMIT.as_secs_f64())]
    admission_time_limit: f64,
    /// Seconds a client may take to send a request's body, or leave a
    /// response unread, before the server closes the connection.
    #[arg(long, env = "MPM_CLIENT_TIMEOUT", default_value_t = config::DEFAULT_CLIENT_TIMEOUT.as_secs_f64())]
    client_timeout: f64,
}

/// `mpm worker`: solves jobs from a shared database without serving.
#[derive(Args)]
pub struct WorkerArgs {
    #[command(flatten)]
    solver: SolverArgs,
}

/// Logging, the rayon pool and the settings shared by both roles.
fn solver_config(args: SolverArgs) -> Result<Config, CliError> {
    let logs = tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("MPM_LOG")
                .unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        // Colour codes only where a terminal shows them, not in container
        // logs or files.
        .with_ansi(std::io::stderr().is_terminal());
    match args.log_format {
        LogFormat::Text => logs.init(),
        LogFormat::Json => logs.json().init(),
    }
    if let Some(n) = args.solver_threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| CliError::failed(e.to_string()))?;
    }
    let Some(lease) = seconds(args.lease_seconds) else {
        return Err(CliError::input(
            "--lease-seconds must be a positive number of seconds",
        ));
    };
    if args.max_attempts == 0 {
        return Err(CliError::input("--max-attempts must be positive"));
    }
    let mut config = Config::new(args.database);
    config.workers = args.workers;
    config.lease = lease;
    config.poll_interval = config.poll_interval.min(config.lease / 3);
    config.max_attempts = args.max_attempts;
    config.checkpoint_every = args.checkpoint_every;
    config.limits.job_time_limit = Duration::from_secs(args.job_time_limit);
    Ok(config)
}

pub fn serve(args: ServeArgs) -> Result<(), CliError> {
    let mut config = solver_config(args.solver)?;
    let Some(admission_time_limit) = seconds(args.admission_time_limit) else {
        return Err(CliError::input(
            "--admission-time-limit must be a positive number of seconds",
        ));
    };
    if args.token.as_deref().is_some_and(|t| t.trim().is_empty()) {
        // An empty token would match no request's, or turn authentication
        // off if it were read as "none": neither is what was meant.
        return Err(CliError::input(
            "--token (MPM_TOKEN) is empty: give a token, or unset it to run without one",
        ));
    }
    if let Some(days) = args.retention_days {
        config.retention = Some(seconds(days * 86_400.0).ok_or_else(|| {
            CliError::input("--retention-days must be a positive number of days")
        })?);
    }
    config.token = args.token;
    config.limits.max_body_bytes = args.max_body_bytes;
    config.limits.max_points = args.max_points;
    config.limits.max_load_steps = args.max_load_steps;
    config.limits.max_queued = args.max_queued;
    config.limits.max_job_bytes = args.max_job_bytes;
    config.limits.admission_time_limit = admission_time_limit;
    config.limits.client_timeout = seconds(args.client_timeout)
        .ok_or_else(|| CliError::input("--client-timeout must be a positive number of seconds"))?;

    let runtime = tokio::runtime::Runtime::new()?;
    let served = runtime.block_on(async {
        let database = redact(&config.database);
        let workers = config.workers;
        let server = Server::start(config, args.addr)
            .await
            .map_err(|e| CliError::failed(e.to_string()))?;
        let stop = shutdown_signal();
        // Scripts (and the tests) read the bound address from this line.
        println!(
            "listening on http://{} (database {database}, {})",
            server.addr,
            workers_text(workers)
        );
        stop.await;
        tracing::info!("shutting down: running jobs go back to the queue");
        server.shutdown().await;
        Ok(())
    });
    // The workers have stopped; what may still run is a submission's check,
    // whose client was answered 503. Exit without waiting for it.
    runtime.shutdown_timeout(Duration::from_millis(100));
    served
}

pub fn worker(args: WorkerArgs) -> Result<(), CliError> {
    let config = solver_config(args.solver)?;
    if config.workers == 0 {
        return Err(CliError::input("--workers must be positive for mpm worker"));
    }
    let runtime = tokio::runtime::Runtime::new()?;
    runtime.block_on(async {
        let database = redact(&config.database);
        let workers = config.workers;
        let pool = Workers::start(config)
            .await
            .map_err(|e| CliError::failed(e.to_string()))?;
        let stop = shutdown_signal();
        // Scripts (and the tests) wait for this line.
        println!(
            "solving jobs from {database} with {}",
            workers_text(workers)
        );
        stop.await;
        tracing::info!("shutting down: running jobs go back to the queue");
        pool.shutdown().await;
        Ok(())
    })
}

/// A positive, finite number of seconds as a duration.
fn seconds(s: f64) -> Option<Duration> {
    Duration::try_from_secs_f64(s).ok().filter(|d| !d.is_zero())
}

/// Ctrl-C or SIGTERM (what `docker stop` sends), listened for from this
/// call on: call it before announcing the start, or a signal sent as soon as
/// the announcement is read kills the process without a clean shutdown.
fn shutdown_signal() -> impl std::future::Future<Output = ()> {
    // Both handlers are installed here, not when first polled (as
    // `tokio::signal::ctrl_c()` would be).
    #[cfg(unix)]
    let (mut term, mut interrupt) = {
        use tokio::signal::unix::{SignalKind, signal};
        (
            signal(SignalKind::terminate()).expect("install the SIGTERM handler"),
            signal(SignalKind::interrupt()).expect("install the SIGINT handler"),
        )
    };
    #[cfg(not(unix))]
    let ctrl_c = tokio::signal::ctrl_c();
    async move {
        #[cfg(unix)]
        tokio::select! {
            _ = interrupt.recv() => {}
            _ = term.recv() => {}
        }
        #[cfg(not(unix))]
        let _ = ctrl_c.await;
    }
}

/// "1 worker", "2 workers", "no workers".
fn workers_text(n: usize) -> String {
    match n {
        0 => "no workers".into(),
        1 => "1 worker".into(),
        n => format!("{n} workers"),
    }
}
