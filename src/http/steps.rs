//! The step endpoints: every finished step's report, and one step's
//! document, its points as VTU or its boundary curves as VTP.

use axum::Json;
use axum::extract::State;

use super::extract::{IdPath, Params};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use mpm::boundary::BoundaryOutput;
use mpm::report::PointColumns;
use mpm::vtk::{write_vtp, write_vtu};
use serde::Deserialize;
use serde_json::value::RawValue;

use super::views::StepsView;
use super::{ApiError, AppState, jobs};
use crate::step::StoredStep;

/// `GET /jobs/{id}/steps`: the report of every finished step.
pub async fn steps(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<Json<StepsView>, ApiError> {
    jobs::find(&state.store, id).await?;
    let steps = state
        .store
        .step_reports(id)
        .await?
        .into_iter()
        .map(RawValue::from_string)
        .collect::<Result<_, _>>()
        .map_err(|e| ApiError::Internal(format!("stored report: {e}")))?;
    Ok(Json(StepsView { job: id, steps }))
}

#[derive(Deserialize)]
pub struct StepQuery {
    format: Option<String>,
}

/// `GET /jobs/{id}/steps/{k}`: report, material points and boundary curves
/// as JSON, or the points as VTU.
pub async fn step(
    State(state): State<AppState>,
    IdPath((id, k)): IdPath<(i64, i64)>,
    Params(q): Params<StepQuery>,
) -> Result<Response, ApiError> {
    let step: StoredStep = state
        .store
        .step(id, k)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("step {k} of job {id}")))?;
    match q.format.as_deref() {
        None | Some("json") => Ok(Json(step).into_response()),
        Some("vtu" | "vtp") if !step.has_points() => Err(ApiError::NotFound(format!(
            "points of step {k} of job {id}: its case stores them every output.every steps"
        ))),
        Some("vtu") => Ok(vtk_file(vtu(&step)?, &format!("job-{id}-step-{k:04}.vtu"))),
        Some("vtp") => Ok(vtk_file(
            vtp(&step)?,
            &format!("job-{id}-step-{k:04}_boundary.vtp"),
        )),
        Some(other) => Err(ApiError::BadQuery {
            name: "format",
            message: format!("{other:?} is not json, vtu or vtp"),
        }),
    }
}

/// A stored step's points as VTU.
pub(super) fn vtu(step: &StoredStep) -> Result<Vec<u8>, ApiError> {
    let columns: PointColumns = serde_json::from_str(step.points.get())
        .map_err(|e| ApiError::Internal(format!("stored points: {e}")))?;
    let mut vtu = Vec::new();
    write_vtu(&mut vtu, &columns).map_err(|e| ApiError::Internal(e.to_string()))?;
    Ok(vtu)
}

/// A stored step's boundary curves as VTP.
pub(super) fn vtp(step: &StoredStep) -> Result<Vec<u8>, ApiError> {
    let boundaries: Vec<BoundaryOutput> = serde_json::from_str(step.boundaries.get())
        .map_err(|e| ApiError::Internal(format!("stored boundaries: {e}")))?;
    let mut vtp = Vec::new();
    write_vtp(&mut vtp, &boundaries).map_err(|e| ApiError::Internal(e.to_string()))?;
    Ok(vtp)
}

/// A VTK XML file as a download named `name`.
fn vtk_file(bytes: Vec<u8>, name: &str) -> Response {
    let disposition = format!("attachment; filename=\"{name}\"");
    (
        [
            (header::CONTENT_TYPE, "application/xml".to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        bytes,
    )
        .into_response()
}
