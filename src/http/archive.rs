//! `GET /jobs/{id}/archive`: a job's results as one zip, in the layout
//! `mpm run` writes its output directory in (`crate::results`).

use std::io::{BufWriter, Write};

use axum::extract::State;
use axum::http::header;
use axum::response::{IntoResponse, Response};
use mpm::StepReport;
use tokio::runtime::Handle;
use tokio::sync::Semaphore;
use zip::ZipWriter;
use zip::write::SimpleFileOptions;

use super::extract::IdPath;
use super::stream::{self, PieceWriter};
use super::views::civil;
use super::{ApiError, AppState, jobs, steps};
use crate::jobs::{JobRow, Store};
use crate::results::{
    BOUNDARY_SERIES, CASE_FILE, POINTS_SERIES, SUMMARY_FILE, Series, StepFiles, Summary,
};

/// Archives made at once, each on a thread of its own, sent as they are
/// made: each holds one step in memory at a time, and a client that reads
/// slowly slows its own archive alone. A request past them is answered 503
/// at once, with a `Retry-After`, rather than queued behind them.
static BUILDING: Semaphore = Semaphore::const_new(4);

pub async fn archive(
    State(state): State<AppState>,
    IdPath(id): IdPath<i64>,
) -> Result<Response, ApiError> {
    let job = jobs::find(&state.store, id).await?;
    let case = state
        .store
        .case_json(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id}")))?;
    let reports = jobs::reports(&state.store, id).await?;
    let building = BUILDING.try_acquire().map_err(|_| {
        ApiError::Unavailable("other archives are being made; try again shortly".into())
    })?;
    let store = state.store.clone();
    let runtime = Handle::current();
    let (pieces, body) = stream::channel();
    // Compressing a large job takes a while: off the async threads.
    tokio::task::spawn_blocking(move || {
        let _building = building;
        let mut writer = PieceWriter::new(pieces.clone());
        let made =
            write_archive(&runtime, &store, &job, &case, &reports, &mut writer).and_then(|()| {
                writer
                    .flush()
                    .map_err(|e| ApiError::Internal(e.to_string()))
            });
        if let Err(e) = made {
            // Past the headers, an error can only end the download short.
            tracing::warn!(job = id, "archive of job {id} cut short: {e:?}");
            let _ = pieces.blocking_send(Err(std::io::Error::other(format!("{e:?}"))));
        }
    });
    let disposition = format!("attachment; filename=\"job-{id}.zip\"");
    Ok((
        [
            (header::CONTENT_TYPE, "application/zip".to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        body,
    )
        .into_response())
}

/// The zip: the case, the summary, and the files of each step with stored
/// points, read from the store one step at a time.
fn write_archive(
    runtime: &Handle,
    store: &Store,
    job: &JobRow,
    case: &str,
    reports: &[StepReport],
    out: &mut PieceWriter,
) -> Result<(), ApiError> {
    let zip_error = |e: zip::result::ZipError| ApiError::Internal(format!("archive: {e}"));
    let io_error = |e: std::io::Error| ApiError::Internal(format!("archive: {e}"));
    // Entries dated when the job ended (or was submitted): zip's default
    // is 1980.
    let ([year, month, day], ms) = civil(job.finished_at.unwrap_or(job.created_at));
    let s = ms / 1000;
    let dated = zip::DateTime::from_date_and_time(
        year.clamp(1980, 2107) as u16,
        month as u8,
        day as u8,
        (s / 3600) as u8,
        (s / 60 % 60) as u8,
        (s % 60) as u8,
    )
    .unwrap_or_default();
    let options = SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(dated);
    let mut zip = ZipWriter::new_stream(out);
    let start =
        |zip: &mut ZipWriter<_>, name: &str| zip.start_file(name, options).map_err(zip_error);
    let add = |zip: &mut ZipWriter<_>, name: &str, bytes: &[u8]| -> Result<(), ApiError> {
        start(zip, name)?;
        zip.write_all(bytes).map_err(io_error)
    };
    add(&mut zip, CASE_FILE, case.as_bytes())?;
    // A 3D run's boundary files are its surfaces.
    let solid = mpm::case::solid::is_solid(case);

    // Each step's files are written into the zip as they are made: one
    // step's stored document is what the archive holds.
    let mut series = Series::default();
    for report in reports {
        let Some(step) = runtime.block_on(store.step(job.id, report.step as i64))? else {
            continue;
        };
        if !step.has_points() {
            continue;
        }
        let files = StepFiles::new(report.step);
        start(&mut zip, &files.document)?;
        let mut document = BufWriter::new(&mut zip);
        serde_json::to_writer(&mut document, &step)
            .map_err(|e| ApiError::Internal(e.to_string()))?;
        document.flush().map_err(io_error)?;
        drop(document);
        start(&mut zip, &files.points)?;
        steps::write_points(&step, solid, &mut zip)?;
        start(&mut zip, &files.boundary)?;
        steps::write_boundaries(&step, solid, &mut zip)?;
        series.add(report.series_time(), files);
    }
    let mut pvd = Vec::new();
    series.write_points(&mut pvd).map_err(io_error)?;
    add(&mut zip, POINTS_SERIES, &pvd)?;
    pvd.clear();
    series.write_boundary(&mut pvd).map_err(io_error)?;
    add(&mut zip, BOUNDARY_SERIES, &pvd)?;

    let source = format!("job {}", job.id);
    let warnings = mpm::Case::from_json(case)
        .map(|case| mpm::model::warnings(&case, reports))
        .unwrap_or_default();
    let summary = Summary {
        warnings,
        error: job
            .error
            .as_deref()
            .and_then(|e| serde_json::from_str(e).ok()),
        ..Summary::new(
            &source,
            job.title.as_deref(),
            job.points as usize,
            job.load_steps as usize,
            job.solve_seconds
                .unwrap_or_else(|| reports.iter().map(|r| r.timings.total).sum()),
            reports,
        )
    };
    let summary =
        serde_json::to_vec_pretty(&summary).map_err(|e| ApiError::Internal(e.to_string()))?;
    add(&mut zip, SUMMARY_FILE, &summary)?;
    zip.finish().map_err(zip_error)?;
    Ok(())
}
