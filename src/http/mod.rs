//! The HTTP API: the router and the state its handlers share. The contract
//! is `openapi.yaml` at the repository root.

mod auth;
mod error;
mod jobs;
mod steps;
mod views;

use std::sync::Arc;

use axum::extract::{DefaultBodyLimit, State};
use axum::http::{StatusCode, header};
use axum::middleware;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde_json::json;
use tokio::sync::Notify;

pub use error::ApiError;

use crate::config::Config;
use crate::jobs::Store;
use crate::worker::RunningJobs;

/// The contract, served at `/openapi.yaml`.
pub const OPENAPI: &str = include_str!("../../openapi.yaml");

#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    pub config: Arc<Config>,
    /// Wakes an idle worker when a job is queued.
    pub wake: Arc<Notify>,
    /// Jobs running in this process, to pass cancel requests on at once.
    pub running: Arc<RunningJobs>,
}

pub fn router(state: AppState) -> Router {
    let protected = Router::new()
        .route("/jobs", post(jobs::submit).get(jobs::list))
        .route("/jobs/{id}", get(jobs::job))
        .route("/jobs/{id}/cancel", post(jobs::cancel))
        .route("/jobs/{id}/case", get(jobs::case))
        .route("/jobs/{id}/steps", get(steps::steps))
        .route("/jobs/{id}/steps/{step}", get(steps::step))
        .route("/jobs/{id}/result", get(jobs::result))
        .route("/openapi.yaml", get(openapi))
        .route_layer(middleware::from_fn_with_state(
            state.clone(),
            auth::require_token,
        ));
    Router::new()
        .route("/health", get(health))
        .merge(protected)
        .fallback(|| async { ApiError::NotFound("route".into()) })
        .layer(DefaultBodyLimit::max(state.config.limits.max_body_bytes))
        .with_state(state)
}

async fn health(State(state): State<AppState>) -> Response {
    match state.store.ping().await {
        Ok(()) => Json(json!({"status": "ok", "database": "ok"})).into_response(),
        Err(e) => {
            tracing::error!(error = %e, "health check: database unavailable");
            (
                StatusCode::SERVICE_UNAVAILABLE,
                Json(json!({"status": "unavailable", "database": "error"})),
            )
                .into_response()
        }
    }
}

async fn openapi() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "application/yaml")], OPENAPI)
}
