//! The job endpoints: submit, list, one job, cancel, its case and its
//! result.

use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequest, Request, State};

use super::extract::{IdPath, Params, drain, integer};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{Value, json};

use super::views::{JobView, ResultView};
use super::{ApiError, AppState};
use crate::jobs::{
    CancelOutcome, DeleteOutcome, Earlier, Inserted, JobRow, JobStatus, NewJob, Store, admission,
};

/// `POST /jobs`: validate, store, queue. With an `Idempotency-Key`, a
/// retry of the same body returns the job the first request made (200).
/// The body must come within the client timeout: a client trickling it
/// holds its memory meanwhile.
pub async fn submit(State(state): State<AppState>, request: Request) -> Result<Response, ApiError> {
    let headers = request.headers().clone();
    if let Err(refused) = json_content_type(&headers) {
        drain(request.into_body()).await;
        return Err(refused);
    }
    let limit = state.config.limits.client_timeout;
    let body = tokio::time::timeout(limit, Bytes::from_request(request, &state))
        .await
        .map_err(|_| ApiError::RequestTimeout {
            seconds: limit.as_secs_f64(),
        })?
        .map_err(|rejection: BytesRejection| {
            if rejection.status() == StatusCode::PAYLOAD_TOO_LARGE {
                ApiError::PayloadTooLarge {
                    limit: state.config.limits.max_body_bytes,
                }
            } else {
                ApiError::MalformedJson(rejection.body_text())
            }
        })?;
    let Some(key) = idempotency_key(&headers)? else {
        return queue(&state, body, None).await;
    };
    if let Some(earlier) = state.store.by_idempotency_key(key).await? {
        return replay(&state.store, key, earlier, &body).await;
    }
    match queue(&state, body.clone(), Some(key)).await {
        // A request with the same key that raced this one may have queued
        // the job meanwhile (and filled the queue, or held up the check).
        Err(e @ (ApiError::QueueFull { .. } | ApiError::Unavailable(_))) => {
            match state.store.by_idempotency_key(key).await? {
                Some(earlier) => replay(&state.store, key, earlier, &body).await,
                None => Err(e),
            }
        }
        done => done,
    }
}

/// Refuses a body not declared JSON (415): a browser sends forms, text and
/// XML to any address without asking first, but not JSON.
fn json_content_type(headers: &HeaderMap) -> Result<(), ApiError> {
    let given = headers
        .get(header::CONTENT_TYPE)
        .map(|v| String::from_utf8_lossy(v.as_bytes()).into_owned());
    let media_type = given
        .as_deref()
        .and_then(|v| v.split(';').next())
        .map(str::trim);
    if media_type.is_some_and(|m| m.eq_ignore_ascii_case("application/json")) {
        return Ok(());
    }
    Err(ApiError::UnsupportedMediaType {
        given: given.unwrap_or_else(|| "missing".into()),
    })
}

/// Checks a new submission and queues it (201), or, if its key was taken
/// meanwhile, answers as a replay.
async fn queue(state: &AppState, body: Bytes, key: Option<&str>) -> Result<Response, ApiError> {
    let limits = &state.config.limits;
    let full = ApiError::QueueFull {
        limit: limits.max_queued,
    };
    // Cheap, before the check; the insert counts again, atomically.
    if state.store.queued().await? >= limits.max_queued as i64 {
        return Err(full);
    }
    let admitted = check(state, body.clone()).await?;
    let text = std::str::from_utf8(&body)
        .map_err(|e| ApiError::Internal(format!("checked body is not UTF-8: {e}")))?;
    let inserted = state
        .store
        .insert(
            &NewJob {
                case_json: text,
                title: admitted.case.title(),
                points: admitted.points as i64,
                load_steps: admitted.case.load_steps() as i64,
                idempotency_key: key,
            },
            limits.max_queued as i64,
        )
        .await?;
    match (inserted, key) {
        (Inserted::QueueFull, _) => Err(full),
        (Inserted::New(id), _) => {
            state.wake.notify_one();
            job_response(StatusCode::CREATED, find(&state.store, id).await?)
        }
        (Inserted::Earlier(earlier), Some(key)) => replay(&state.store, key, earlier, &body).await,
        (Inserted::Earlier(earlier), None) => Err(ApiError::Internal(format!(
            "job {} returned for a submission without a key",
            earlier.id
        ))),
    }
}

/// Reads and seeds a case to check it. That is CPU work (reading a case
/// checks its polygons, in time quadratic in their vertices; seeding
/// scans lattices): off the async threads, no more of it at once than
/// there are cores, within the admission time limit (the wait for a core
/// included), and given up at shutdown. The permit goes with the blocking
/// task, so neither a client that hangs up nor a time-out frees it before
/// the work ends.
async fn check(state: &AppState, body: Bytes) -> Result<admission::Admitted, ApiError> {
    let limits = state.config.limits.clone();
    let seeding = async {
        let permit = state
            .admissions
            .clone()
            .acquire_owned()
            .await
            .map_err(|e| ApiError::Internal(format!("admissions: {e}")))?;
        let checked = tokio::task::spawn_blocking(move || {
            let _permit = permit;
            let (_, case) = admission::read(&body)?;
            admission::admit(case, &limits)
        })
        .await
        .map_err(|e| ApiError::Internal(format!("case check: {e}")))?;
        Ok::<_, ApiError>(checked?)
    };
    let limit = state.config.limits.admission_time_limit;
    let mut stopping = state.stopping.clone();
    tokio::select! {
        checked = tokio::time::timeout(limit, seeding) => checked.unwrap_or_else(|_| {
            Err(ApiError::Unavailable(format!(
                "checking the case took longer than {limit:?} (the service is busy, or the \
                 case is near its limits); try again later"
            )))
        }),
        _ = stopping.wait_for(|stop| *stop) => Err(ApiError::Unavailable(
            "the service is shutting down; submit again once it is back".into(),
        )),
    }
}

const IDEMPOTENCY_KEY: &str = "idempotency-key";
/// The longest `Idempotency-Key` accepted, in bytes.
const MAX_IDEMPOTENCY_KEY_BYTES: usize = 255;

/// The `Idempotency-Key` header: 1 to 255 visible ASCII characters.
fn idempotency_key(headers: &HeaderMap) -> Result<Option<&str>, ApiError> {
    let Some(value) = headers.get(IDEMPOTENCY_KEY) else {
        return Ok(None);
    };
    let bad = |message: String| ApiError::BadHeader {
        name: "Idempotency-Key",
        message,
    };
    let key = value
        .to_str()
        .ok()
        .filter(|k| k.bytes().all(|b| b.is_ascii_graphic()))
        .ok_or_else(|| bad("must be visible ASCII characters, without spaces".into()))?;
    if key.is_empty() || key.len() > MAX_IDEMPOTENCY_KEY_BYTES {
        return Err(bad(format!(
            "must be 1 to {MAX_IDEMPOTENCY_KEY_BYTES} characters long"
        )));
    }
    Ok(Some(key))
}

/// A retry with a key already used: the job it made if the body is the
/// same, 422 if it is not.
async fn replay(
    store: &Store,
    key: &str,
    earlier: Earlier,
    body: &[u8],
) -> Result<Response, ApiError> {
    if earlier.case_json.as_bytes() != body {
        return Err(ApiError::IdempotencyKeyReused {
            key: key.to_owned(),
            job: earlier.id,
        });
    }
    job_response(StatusCode::OK, find(store, earlier.id).await?)
}

/// A job's view with its `Location`.
fn job_response(code: StatusCode, job: JobRow) -> Result<Response, ApiError> {
    let mut headers = HeaderMap::new();
    headers.insert(
        header::LOCATION,
        format!("/jobs/{}", job.id)
            .parse()
            .expect("a valid header value"),
    );
    Ok((code, headers, Json(JobView::new(&job))).into_response())
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

/// `DELETE /jobs/{id}`: removes an ended job with its steps (204); a queued
/// or running job answers 409 until cancelled.
pub async fn delete(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<StatusCode, ApiError> {
    match state.store.delete(id).await? {
        DeleteOutcome::Deleted => Ok(StatusCode::NO_CONTENT),
        DeleteOutcome::NotEnded(status) => Err(ApiError::Conflict(format!(
            "job {id} is {}: cancel it first",
            status.as_str()
        ))),
        DeleteOutcome::NotFound => Err(not_found(id)),
    }
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
    let reports = reports(&state.store, id).await?;
    let case = state.store.case_json(id).await?;
    let warnings = (case.as_deref())
        .and_then(|text| mpm::Case::from_json(text).ok())
        .map(|case| mpm::model::warnings(&case, &reports))
        .unwrap_or_default();
    Ok(Json(ResultView::new(&job, &reports, warnings)))
}

/// The reports of job `id`'s stored steps, in step order.
pub(super) async fn reports(store: &Store, id: i64) -> Result<Vec<mpm::StepReport>, ApiError> {
    store
        .step_reports(id)
        .await?
        .iter()
        .map(|r| serde_json::from_str(r))
        .collect::<Result<_, _>>()
        .map_err(|e| ApiError::Internal(format!("stored report: {e}")))
}

/// Job `id`, or 404.
pub(super) async fn find(store: &Store, id: i64) -> Result<JobRow, ApiError> {
    store.get(id).await?.ok_or_else(|| not_found(id))
}

fn not_found(id: i64) -> ApiError {
    ApiError::NotFound(format!("job {id}"))
}
