//! The step endpoints: every finished step's report, and one step's
//! document, its points as VTU or its boundary curves as VTP.

use axum::Json;
use axum::extract::State;

use super::extract::{IdPath, Params};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use mpm::boundary::BoundaryOutput;
use mpm::boundary::face_patches::SurfaceOutput;
use mpm::case::solid::is_solid;
use mpm::report::{PointColumns, SolidPointColumns};
use mpm::vtk::{write_solid_vtu, write_surface_vtp, write_vtp, write_vtu};
use serde::Deserialize;
use serde_json::value::RawValue;
use std::io::{BufWriter, Write};

use super::views::StepsView;
use super::{ApiError, AppState, jobs, stream};
use crate::jobs::{StepHead, StepPart, Store};
use crate::step::StoredStep;
use tokio::sync::Semaphore;

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
/// as JSON, or the points as VTU or the curves as VTP. Each is streamed: the
/// JSON a piece at a time from the database, a VTK file from memory once
/// made, with at most `CONVERTING` made at once.
pub async fn step(
    State(state): State<AppState>,
    IdPath((id, k)): IdPath<(i64, i64)>,
    Params(q): Params<StepQuery>,
) -> Result<Response, ApiError> {
    let format = match q.format.as_deref() {
        None | Some("json") => None,
        Some(vtk @ ("vtu" | "vtp")) => Some(vtk),
        Some(other) => {
            return Err(ApiError::BadQuery {
                name: "format",
                message: format!("{other:?} is not json, vtu or vtp"),
            });
        }
    };
    let head = state
        .store
        .step_head(id, k)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("step {k} of job {id}")))?;
    let Some(format) = format else {
        return Ok(json_document(state.store.clone(), id, k, head));
    };
    if !head.has_points {
        return Err(ApiError::NotFound(format!(
            "points of step {k} of job {id}: its case stores them every output.every steps"
        )));
    }
    let converting = CONVERTING.try_acquire().map_err(|_| {
        ApiError::Unavailable("other steps are being converted; try again shortly".into())
    })?;
    let solid = (state.store.case_json(id).await?).is_some_and(|case| is_solid(&case));
    let step = state
        .store
        .step(id, k)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("step {k} of job {id}")))?;
    let mut bytes = Vec::new();
    let name = if format == "vtu" {
        write_points(&step, solid, &mut bytes)?;
        format!("job-{id}-step-{k:04}.vtu")
    } else {
        write_boundaries(&step, solid, &mut bytes)?;
        format!("job-{id}-step-{k:04}_boundary.vtp")
    };
    drop(step);
    let (pieces, body) = stream::channel();
    tokio::spawn(async move {
        let _converting = converting;
        let _ = stream::send_whole(&pieces, bytes.into()).await;
    });
    let disposition = format!("attachment; filename=\"{name}\"");
    Ok((
        [
            (header::CONTENT_TYPE, "application/xml".to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        body,
    )
        .into_response())
}

/// VTK files made from stored steps and not yet sent whole: each holds its
/// step's points in memory, parsed and written out. One past them is
/// answered 503 at once, with a `Retry-After`.
static CONVERTING: Semaphore = Semaphore::const_new(4);

/// The step document (`crate::step::StepDocument`), its large parts read
/// from the database a piece at a time as the client takes them.
fn json_document(store: Store, id: i64, k: i64, head: StepHead) -> Response {
    let (pieces, body) = stream::channel();
    tokio::spawn(async move {
        let opening = format!("{{\"report\":{},\"points\":", head.report);
        let sent = async {
            send(&pieces, opening).await?;
            let points = (StepPart::Points, head.points_chars);
            send_part(&store, &pieces, id, k, points).await?;
            send(&pieces, ",\"boundaries\":".into()).await?;
            let boundaries = (StepPart::Boundaries, head.boundaries_chars);
            send_part(&store, &pieces, id, k, boundaries).await?;
            send(&pieces, "}".into()).await
        };
        if let Err(Unsent::Store(e)) = sent.await {
            tracing::warn!(job = id, step = k, "step {k} cut short: {e}");
            let _ = pieces.send(Err(std::io::Error::other(e))).await;
        }
    });
    ([(header::CONTENT_TYPE, "application/json")], body).into_response()
}

/// Why a streamed document stopped.
enum Unsent {
    Client,
    Store(String),
}

async fn send(pieces: &stream::Pieces, text: String) -> Result<(), Unsent> {
    pieces
        .send(Ok(text.into()))
        .await
        .map_err(|_| Unsent::Client)
}

/// Reads of a large part: each costs a read of the whole part (SQLite and
/// PostgreSQL load a text value whole to cut it), so a part is read in at
/// most this many pieces, of `stream::PIECE` or more. A 28 MB step took
/// 2.2 s to send in 0.5 MB pieces, 0.7 s in sixteen; one left unread
/// holds 5 MB.
const READS: usize = 16;

/// One stored part of a step of `chars` characters, a piece at a time,
/// until a read comes back short.
async fn send_part(
    store: &Store,
    pieces: &stream::Pieces,
    id: i64,
    k: i64,
    (part, chars): (StepPart, usize),
) -> Result<(), Unsent> {
    let size = stream::PIECE.max(chars.div_ceil(READS));
    let mut from = 0;
    loop {
        let piece = store
            .step_part(id, k, part, from, size)
            .await
            .map_err(|e| Unsent::Store(e.to_string()))?
            .ok_or_else(|| Unsent::Store("the step was deleted".into()))?;
        let read = piece.chars().count();
        if read > 0 {
            send(pieces, piece).await?;
        }
        if read < size {
            return Ok(());
        }
        from += read;
    }
}

/// A stored step's points as VTU, written to `out`: a 3D run's when
/// `solid`.
pub(super) fn write_points(
    step: &StoredStep,
    solid: bool,
    out: impl Write,
) -> Result<(), ApiError> {
    let stored = |e: serde_json::Error| ApiError::Internal(format!("stored points: {e}"));
    let mut out = BufWriter::new(out);
    if solid {
        let columns: SolidPointColumns = serde_json::from_str(step.points.get()).map_err(stored)?;
        write_solid_vtu(&mut out, &columns)
    } else {
        let columns: PointColumns = serde_json::from_str(step.points.get()).map_err(stored)?;
        write_vtu(&mut out, &columns)
    }
    .and_then(|()| out.flush())
    .map_err(|e| ApiError::Internal(e.to_string()))
}

/// A stored step's boundary curves (a 3D run's surfaces) as VTP, written
/// to `out`.
pub(super) fn write_boundaries(
    step: &StoredStep,
    solid: bool,
    out: impl Write,
) -> Result<(), ApiError> {
    let stored = |e: serde_json::Error| ApiError::Internal(format!("stored boundaries: {e}"));
    let mut out = BufWriter::new(out);
    if solid {
        let surfaces: Vec<SurfaceOutput> =
            serde_json::from_str(step.boundaries.get()).map_err(stored)?;
        write_surface_vtp(&mut out, &surfaces)
    } else {
        let boundaries: Vec<BoundaryOutput> =
            serde_json::from_str(step.boundaries.get()).map_err(stored)?;
        write_vtp(&mut out, &boundaries)
    }
    .and_then(|()| out.flush())
    .map_err(|e| ApiError::Internal(e.to_string()))
}
