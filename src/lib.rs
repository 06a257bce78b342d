//! The job service around the `mpm` solver: an HTTP API (axum) over a job
//! queue in SQLite or PostgreSQL (sqlx), solved by pools of worker threads.
//!
//! [`Server::start`] opens the database, starts its workers (none with
//! `workers = 0`) and serves; [`Server::shutdown`] stops serving, hands
//! running jobs back to the queue and waits for the workers.
//! [`Workers::start`] solves without serving, for machines that share a
//! PostgreSQL queue with the serving ones.

pub mod config;
pub mod http;
pub mod jobs;
pub mod results;
pub mod step;
pub mod worker;

use std::net::SocketAddr;
use std::sync::Arc;

use tokio::net::TcpListener;
use tokio::sync::{Notify, Semaphore, watch};
use tokio::task::JoinHandle;

pub use config::{Config, Limits, redact};
use http::AppState;
use jobs::Store;
use worker::{RunningJobs, WorkerPool};

/// A running service.
pub struct Server {
    /// The address it listens on (the real port when bound to port 0).
    pub addr: SocketAddr,
    /// Set once at shutdown: the server stops accepting, and submissions
    /// still being checked give up.
    stop: watch::Sender<bool>,
    serving: JoinHandle<()>,
    workers: WorkerPool,
}

#[derive(Debug, thiserror::Error)]
pub enum StartError {
    #[error("database {path}: {source}")]
    Database { path: String, source: sqlx::Error },
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        addr: SocketAddr,
        source: std::io::Error,
    },
}

async fn open_store(config: &Config) -> Result<Store, StartError> {
    Store::open(&config.database)
        .await
        .map_err(|source| StartError::Database {
            path: redact(&config.database),
            source,
        })
}

impl Server {
    /// Opens the database, starts the workers and serves on `addr`. Call
    /// from within a multi-threaded tokio runtime.
    pub async fn start(config: Config, addr: SocketAddr) -> Result<Server, StartError> {
        let store = open_store(&config).await?;
        let listener = TcpListener::bind(addr)
            .await
            .map_err(|source| StartError::Bind { addr, source })?;
        let addr = listener
            .local_addr()
            .map_err(|source| StartError::Bind { addr, source })?;
        let config = Arc::new(config);
        let wake = Arc::new(Notify::new());
        let running = Arc::new(RunningJobs::default());
        let workers =
            WorkerPool::start(store.clone(), config.clone(), wake.clone(), running.clone());
        let (stop, stopped) = watch::channel(false);
        if let Some(retention) = config.retention {
            tokio::spawn(prune_ended_jobs(store.clone(), retention, stopped.clone()));
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let client_timeout = config.limits.client_timeout;
        let app = http::router(AppState {
            store,
            config,
            wake,
            running,
            admissions: Arc::new(Semaphore::new(cores)),
            stopping: stopped.clone(),
        });
        let serving = tokio::spawn(async move {
            let listener = http::connection::StallLimitedListener {
                listener,
                limit: client_timeout,
            };
            http::connection::serve(listener, app, stopped).await;
        });
        Ok(Server {
            addr,
            stop,
            serving,
            workers,
        })
    }

    /// Stops accepting requests, lets in-flight ones finish, stops the
    /// workers (running jobs return to the queue at their next Newton
    /// iteration) and waits for them.
    pub async fn shutdown(self) {
        let _ = self.stop.send(true);
        match self.serving.await {
            Ok(()) => {}
            Err(e) => tracing::error!(error = %e, "server task failed"),
        }
        let workers = self.workers;
        let _ = tokio::task::spawn_blocking(move || workers.shutdown()).await;
    }
}

/// Solver workers without an HTTP server: they claim jobs from a database
/// that serving processes fill.
pub struct Workers {
    pool: WorkerPool,
}

impl Workers {
    /// Opens the database and starts `config.workers` workers. Call from
    /// within a multi-threaded tokio runtime.
    pub async fn start(config: Config) -> Result<Workers, StartError> {
        let store = open_store(&config).await?;
        let pool = WorkerPool::start(
            store,
            Arc::new(config),
            Arc::new(Notify::new()),
            Arc::new(RunningJobs::default()),
        );
        Ok(Workers { pool })
    }

    /// Stops claiming; running jobs go back to the queue at their next
    /// Newton iteration, to resume from their checkpoints.
    pub async fn shutdown(self) {
        let pool = self.pool;
        let _ = tokio::task::spawn_blocking(move || pool.shutdown()).await;
    }
}

/// How often the serving process deletes jobs past their retention.
const PRUNE_INTERVAL: std::time::Duration = std::time::Duration::from_secs(300);

/// Deletes ended jobs older than `retention`, at start and every
/// [`PRUNE_INTERVAL`], until `stopped` turns true.
async fn prune_ended_jobs(
    store: Store,
    retention: std::time::Duration,
    mut stopped: watch::Receiver<bool>,
) {
    loop {
        match store.prune(retention).await {
            Ok(0) => {}
            Ok(n) => tracing::info!(jobs = n, "deleted ended jobs past their retention"),
            Err(e) => tracing::warn!(error = %e, "pruning ended jobs failed; will retry"),
        }
        tokio::select! {
            _ = tokio::time::sleep(PRUNE_INTERVAL) => {}
            _ = stopped.wait_for(|stop| *stop) => return,
        }
    }
}
