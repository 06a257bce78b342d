//! The HTTP API: routes, handlers and the bearer-token check. The contract
//! is `openapi.yaml` at the repository root.

mod error;
mod views;

use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use mpm::report::PointColumns;
use mpm::vtk::write_vtu;
use mpm::{Case, Simulation};
use serde::Deserialize;
use serde_json::{Value, json};
use tokio::sync::Notify;

pub use error::ApiError;
use views::{JobView, ResultView};

use crate::config::Config;
use crate::jobs::{CancelOutcome, JobStatus, Store};
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
        .route("/jobs", post(submit).get(list))
        .route("/jobs/{id}", get(job))
        .route("/jobs/{id}/cancel", post(cancel))
        .route("/jobs/{id}/case", get(case))
        .route("/jobs/{id}/steps", get(steps))
        .route("/jobs/{id}/steps/{step}", get(step))
        .route("/jobs/{id}/result", get(result))
        .route("/openapi.yaml", get(openapi))
        .route_layer(middleware::from_fn_with_state(state.clone(), require_token));
    Router::new()
        .route("/health", get(health))
        .merge(protected)
        .fallback(|| async { ApiError::NotFound("route".into()) })
        .layer(DefaultBodyLimit::max(state.config.limits.max_body_bytes))
        .with_state(state)
}

async fn require_token(State(state): State<AppState>, request: Request, next: Next) -> Response {
    if let Some(token) = &state.config.token {
        let given = request
            .headers()
            .get(header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "));
        if given != Some(token.as_str()) {
            return ApiError::Unauthorized.into_response();
        }
    }
    next.run(request).await
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

/// `POST /jobs`: validate, store, queue.
async fn submit(
    State(state): State<AppState>,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let limits = &state.config.limits;
    let body = body.map_err(|rejection| {
        if rejection.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::PayloadTooLarge {
                limit: limits.max_body_bytes,
            }
        } else {
            ApiError::MalformedJson(rejection.body_text())
        }
    })?;
    let text = std::str::from_utf8(&body).map_err(|e| ApiError::MalformedJson(e.to_string()))?;
    serde_json::from_str::<Value>(text).map_err(|e| ApiError::MalformedJson(e.to_string()))?;
    let case = Case::from_json(text).map_err(|e| ApiError::InvalidCase {
        path: e.path,
        message: e.message,
    })?;
    if case.analysis.load_steps as usize > limits.max_load_steps {
        return Err(ApiError::LimitExceeded {
            path: "analysis.load_steps".into(),
            message: format!(
                "{} load steps exceed this service's limit of {}",
                case.analysis.load_steps, limits.max_load_steps
            ),
        });
    }
    // Refuse a case far over the limit before generating anything.
    let bound: f64 = case
        .bodies
        .iter()
        .map(|b| mpm::model::max_points(b, case.grid.cell_size))
        .sum();
    if bound > 4.0 * limits.max_points as f64 {
        return Err(ApiError::LimitExceeded {
            path: "bodies".into(),
            message: format!(
                "the bodies make about {bound:.3e} material points, over this service's limit of {}",
                limits.max_points
            ),
        });
    }
    // Generating the points (and the boundary they make) is CPU work: off
    // the async threads. It also checks what only the points can tell, e.g.
    // that a boundary load selects some stretch of boundary.
    let built = {
        let case = case.clone();
        tokio::task::spawn_blocking(move || Simulation::new(&case).map(|sim| sim.points.len()))
            .await
            .map_err(|e| ApiError::Internal(format!("case check: {e}")))?
    };
    let points = built.map_err(|e| ApiError::InvalidCase {
        path: e.path,
        message: e.message,
    })?;
    if points > limits.max_points {
        return Err(ApiError::LimitExceeded {
            path: "bodies".into(),
            message: format!(
                "the bodies make {points} material points, over this service's limit of {}",
                limits.max_points
            ),
        });
    }
    if points == 0 {
        return Err(ApiError::InvalidCase {
            path: "bodies".into(),
            message:
                "the bodies contain no material points (geometry smaller than the point spacing?)"
                    .into(),
        });
    }
    let id = state
        .store
        .insert(
            text,
            case.title.as_deref(),
            points as i64,
            case.analysis.load_steps as i64,
        )
        .await?;
    state.wake.notify_one();
    let job = state
        .store
        .get(id)
        .await?
        .ok_or_else(|| ApiError::Internal(format!("job {id} vanished")))?;
    let mut headers = HeaderMap::new();
    headers.insert(
        header::LOCATION,
        format!("/jobs/{id}").parse().expect("a valid header value"),
    );
    Ok((StatusCode::CREATED, headers, Json(JobView::new(&job))).into_response())
}

#[derive(Deserialize)]
struct ListQuery {
    status: Option<String>,
    limit: Option<i64>,
    offset: Option<i64>,
}

/// `GET /jobs`: newest first, filtered by status, paginated.
async fn list(
    State(state): State<AppState>,
    Query(q): Query<ListQuery>,
) -> Result<Json<Value>, ApiError> {
    let status = match q.status.as_deref() {
        None => None,
        Some(s) => Some(JobStatus::parse(s).ok_or_else(|| ApiError::BadQuery {
            name: "status",
            message: format!(
                "{s:?} is not one of {}",
                JobStatus::ALL.map(|s| s.as_str()).join(", ")
            ),
        })?),
    };
    let limit = q.limit.unwrap_or(50);
    if !(1..=500).contains(&limit) {
        return Err(ApiError::BadQuery {
            name: "limit",
            message: "must be in 1..=500".into(),
        });
    }
    let offset = q.offset.unwrap_or(0);
    if offset < 0 {
        return Err(ApiError::BadQuery {
            name: "offset",
            message: "must not be negative".into(),
        });
    }
    let (rows, total) = state.store.list(status, limit, offset).await?;
    let next = (offset + limit < total).then(|| {
        let filter = status
            .map(|s| format!("status={}&", s.as_str()))
            .unwrap_or_default();
        format!("/jobs?{filter}limit={limit}&offset={}", offset + limit)
    });
    Ok(Json(json!({
        "jobs": rows.iter().map(JobView::new).collect::<Vec<_>>(),
        "total": total,
        "limit": limit,
        "offset": offset,
        "next": next,
    })))
}

async fn job(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Json<JobView>, ApiError> {
    let job = state.store.get(id).await?.ok_or_else(|| not_found(id))?;
    Ok(Json(JobView::new(&job)))
}

/// `POST /jobs/{id}/cancel`: a queued job is cancelled at once; a running one
/// stops at its next Newton iteration (202), its finished steps kept.
async fn cancel(State(state): State<AppState>, Path(id): Path<i64>) -> Result<Response, ApiError> {
    let outcome = state.store.cancel(id).await?;
    let code = match outcome {
        CancelOutcome::Cancelled => StatusCode::OK,
        CancelOutcome::Requested => {
            state.running.cancel(id);
            StatusCode::ACCEPTED
        }
        CancelOutcome::AlreadyFinal(status) => {
            return Err(ApiError::Conflict(format!(
                "job {id} has already ended ({})",
                status.as_str()
            )));
        }
        CancelOutcome::NotFound => return Err(not_found(id)),
    };
    let job = state.store.get(id).await?.ok_or_else(|| not_found(id))?;
    Ok((code, Json(JobView::new(&job))).into_response())
}

async fn case(State(state): State<AppState>, Path(id): Path<i64>) -> Result<Response, ApiError> {
    let text = state
        .store
        .case_json(id)
        .await?
        .ok_or_else(|| not_found(id))?;
    Ok(([(header::CONTENT_TYPE, "application/json")], text).into_response())
}

/// `GET /jobs/{id}/steps`: the report of every finished step.
async fn steps(State(state): State<AppState>, Path(id): Path<i64>) -> Result<Response, ApiError> {
    state.store.get(id).await?.ok_or_else(|| not_found(id))?;
    let reports = state.store.step_reports(id).await?;
    let body = format!("{{\"job\":{id},\"steps\":[{}]}}", reports.join(","));
    Ok(([(header::CONTENT_TYPE, "application/json")], body).into_response())
}

#[derive(Deserialize)]
struct StepQuery {
    format: Option<String>,
}

/// `GET /jobs/{id}/steps/{k}`: report, material points and boundary curves
/// as JSON, or the points as VTU.
async fn step(
    State(state): State<AppState>,
    Path((id, k)): Path<(i64, i64)>,
    Query(q): Query<StepQuery>,
) -> Result<Response, ApiError> {
    let step = state
        .store
        .step(id, k)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("step {k} of job {id}")))?;
    match q.format.as_deref() {
        None | Some("json") => {
            let body = format!(
                "{{\"report\":{},\"points\":{},\"boundaries\":{}}}",
                step.report, step.points, step.boundaries
            );
            Ok(([(header::CONTENT_TYPE, "application/json")], body).into_response())
        }
        Some("vtu") => {
            let columns: PointColumns = serde_json::from_str(&step.points)
                .map_err(|e| ApiError::Internal(format!("stored points: {e}")))?;
            let mut vtu = Vec::new();
            write_vtu(&mut vtu, &columns).map_err(|e| ApiError::Internal(e.to_string()))?;
            let disposition = format!("attachment; filename=\"job-{id}-step-{k:04}.vtu\"");
            Ok((
                [
                    (header::CONTENT_TYPE, "application/xml".to_string()),
                    (header::CONTENT_DISPOSITION, disposition),
                ],
                vtu,
            )
                .into_response())
        }
        Some(other) => Err(ApiError::BadQuery {
            name: "format",
            message: format!("{other:?} is not json or vtu"),
        }),
    }
}

/// `GET /jobs/{id}/result`: probe histories, reactions and cost, so far.
async fn result(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Json<ResultView>, ApiError> {
    let job = state.store.get(id).await?.ok_or_else(|| not_found(id))?;
    let reports = state
        .store
        .step_reports(id)
        .await?
        .iter()
        .map(|r| serde_json::from_str(r))
        .collect::<Result<Vec<mpm::StepReport>, _>>()
        .map_err(|e| ApiError::Internal(format!("stored report: {e}")))?;
    Ok(Json(ResultView::new(&job, &reports)))
}

fn not_found(id: i64) -> ApiError {
    ApiError::NotFound(format!("job {id}"))
}
