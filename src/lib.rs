//! The job service around the `mpm` solver: an HTTP API (axum) over a job
//! queue in SQLite (sqlx), solved by a pool of worker threads.
//!
//! [`Server::start`] opens the database, starts the workers and serves;
//! [`Server::shutdown`] stops serving, hands running jobs back to the queue
//! and waits for the workers.

pub mod config;
pub mod http;
pub mod jobs;
pub mod step;
pub mod worker;

use std::net::SocketAddr;
use std::sync::Arc;

use tokio::net::TcpListener;
use tokio::sync::{Notify, Semaphore, watch};
use tokio::task::JoinHandle;

pub use config::{Config, Limits};
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
    serving: JoinHandle<std::io::Result<()>>,
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

impl Server {
    /// Opens the database, starts the workers and serves on `addr`. Call
    /// from within a multi-threaded tokio runtime.
    pub async fn start(config: Config, addr: SocketAddr) -> Result<Server, StartError> {
        let store = Store::open(&config.database)
            .await
            .map_err(|source| StartError::Database {
                path: config.database.display().to_string(),
                source,
            })?;
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
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let (stop, mut stopped) = watch::channel(false);
        let app = http::router(AppState {
            store,
            config,
            wake,
            running,
            admissions: Arc::new(Semaphore::new(cores)),
            stopping: stopped.clone(),
        });
        let serving = tokio::spawn(async move {
            axum::serve(listener, app)
                .with_graceful_shutdown(async move {
                    let _ = stopped.wait_for(|stop| *stop).await;
                })
                .await
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
            Ok(Ok(())) => {}
            Ok(Err(e)) => tracing::error!(error = %e, "server stopped with an error"),
            Err(e) => tracing::error!(error = %e, "server task failed"),
        }
        let workers = self.workers;
        let _ = tokio::task::spawn_blocking(move || workers.shutdown()).await;
    }
}
