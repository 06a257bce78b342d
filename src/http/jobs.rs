//! The job endpoints: submit, list, one job, cancel, its case and its
//! result.

use axum::Json;
use axum::body::Bytes;
use axum::extract::State;
use axum::extract::rejection::BytesRejection;

use super::extract::{IdPath, Params, integer};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{Value, json};

use super::views::{JobView, ResultView};
use super::{ApiError, AppState};
use crate::jobs::{CancelOutcome, JobRow, JobStatus, Store, admission};

/// `POST /jobs`: validate, store, queue.
pub async fn submit(
    State(state): State<AppState>,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let body = body.map_err(|rejection| {
        if rejection.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::PayloadTooLarge {
                limit: state.config.limits.max_body_bytes,
            }
        } else {
            ApiError::MalformedJson(rejection.body_text())
        }
    })?;
    let limits = &state.config.limits;
    if state.store.queued().await? >= limits.max_queued as i64 {
        return Err(ApiError::QueueFull {
            limit: limits.max_queued,
        });
    }
    let (text, case) = admission::read(&body)?;
    // Seeding a case is CPU work: off the async threads, and no more of it
    // at once than there are cores. The permit goes with the blocking task,
    // so a client that hangs up does not free it before the work ends.
    let permit = state
        .admissions
        .clone()
        .acquire_owned()
        .await
        .map_err(|e| ApiError::Internal(format!("admissions: {e}")))?;
    let admitted = {
        let config = state.config.clone();
        tokio::task::spawn_blocking(move || {
            let _permit = permit;
            admission::admit(case, &config.limits)
        })
        .await
        .map_err(|e| ApiError::Internal(format!("case check: {e}")))??
    };
    let id = state
        .store
        .insert(
            text,
            admitted.case.title.as_deref(),
            admitted.points as i64,
            admitted.case.analysis.load_steps as i64,
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
pub struct ListQuery {
    status: Option<String>,
    limit: Option<String>,
    offset: Option<String>,
}

/// The furthest a page may start: far beyond any queue, and far from
/// overflowing `offset + limit` in the next link.
const MAX_OFFSET: i64 = 1 << 40;

/// `GET /jobs`: newest first, filtered by status, paginated.
pub async fn list(
    State(state): State<AppState>,
    Params(q): Params<ListQuery>,
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
    let limit = integer("limit", q.limit.as_deref())?.unwrap_or(50);
    if !(1..=500).contains(&limit) {
        return Err(ApiError::BadQuery {
            name: "limit",
            message: "must be in 1..=500".into(),
        });
    }
    let offset = integer("offset", q.offset.as_deref())?.unwrap_or(0);
    if !(0..=MAX_OFFSET).contains(&offset) {
        return Err(ApiError::BadQuery {
            name: "offset",
            message: format!("must be in 0..={MAX_OFFSET}"),
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

pub async fn job(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<Json<JobView>, ApiError> {
    let job = find(&state.store, id).await?;
    Ok(Json(JobView::new(&job)))
}

/// `POST /jobs/{id}/cancel`: a queued job is cancelled at once; a running one
/// stops at its next Newton iteration (202), its finished steps kept.
pub async fn cancel(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<Response, ApiError> {
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
    let job = find(&state.store, id).await?;
    Ok((code, Json(JobView::new(&job))).into_response())
}

/// `GET /jobs/{id}/case`: the case as it was submitted.
pub async fn case(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<Response, ApiError> {
    let text = state
        .store
        .case_json(id)
        .await?
        .ok_or_else(|| not_found(id))?;
    Ok(([(header::CONTENT_TYPE, "application/json")], text).into_response())
}

/// `GET /jobs/{id}/result`: probe histories, reactions and cost, so far.
pub async fn result(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<Json<ResultView>, ApiError> {
    let job = find(&state.store, id).await?;
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

/// Job `id`, or 404.
pub(super) async fn find(store: &Store, id: i64) -> Result<JobRow, ApiError> {
    store.get(id).await?.ok_or_else(|| not_found(id))
}

fn not_found(id: i64) -> ApiError {
    ApiError::NotFound(format!("job {id}"))
}
