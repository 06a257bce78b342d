//! The step endpoints: every finished step's report, and one step's
//! document or its points as VTU.

use axum::extract::{Path, Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use mpm::output::{PointColumns, write_vtu};
use serde::Deserialize;

use super::{ApiError, AppState, jobs};

/// `GET /jobs/{id}/steps`: the report of every finished step.
pub async fn steps(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Response, ApiError> {
    jobs::find(&state.store, id).await?;
    let reports = state.store.step_reports(id).await?;
    let body = format!("{{\"job\":{id},\"steps\":[{}]}}", reports.join(","));
    Ok(([(header::CONTENT_TYPE, "application/json")], body).into_response())
}

#[derive(Deserialize)]
pub struct StepQuery {
    format: Option<String>,
}

/// `GET /jobs/{id}/steps/{k}`: report, material points and boundary curves
/// as JSON, or the points as VTU.
pub async fn step(
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
