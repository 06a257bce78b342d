//! The HTTP API: the router and the state its handlers share. The contract
//! is `openapi.yaml` at the repository root.

mod archive;
mod auth;
pub mod connection;
mod error;
mod extract;
mod jobs;
mod steps;
mod stream;
mod viewer;
mod views;

use std::sync::{Arc, LazyLock};

use axum::extract::{DefaultBodyLimit, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::middleware;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde_json::json;
use tokio::sync::{Notify, Semaphore, watch};

pub use error::ApiError;

use crate::config::Config;
use crate::jobs::{Backend, Store};
use crate::worker::RunningJobs;

/// The contract, served at `/openapi.yaml`: `openapi.yaml` at the
/// repository root, with the case format's schemas generated from the
/// solver's types appended to its `components.schemas` (which end it).
pub static OPENAPI: LazyLock<String> = LazyLock::new(|| {
    let mut document = include_str!("../../openapi.yaml").to_string();
    for (name, schema) in mpm::case::openapi_schemas() {
        // JSON is YAML: each schema on one line, in flow style.
        document.push_str(&format!("    {name}: {schema}\n"));
    }
    document
});

/// The case format's JSON Schema, served at `/schema/case.json`.
static CASE_SCHEMA: LazyLock<String> = LazyLock::new(|| mpm::case::json_schema().to_string());

#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    pub config: Arc<Config>,
    /// Wakes an idle worker when a job is queued.
    pub wake: Arc<Notify>,
    /// Jobs running in this process, to pass cancel requests on at once.
    pub running: Arc<RunningJobs>,
    /// Submissions being checked at once: one per core.
    pub admissions: Arc<Semaphore>,
    /// Becomes true when the server shuts down.
    pub stopping: watch::Receiver<bool>,
}

pub fn router(state: AppState) -> Router {
    let protected = Router::new()
        .route("/jobs", post(jobs::submit).get(jobs::list))
        .route("/jobs/{id}", get(jobs::job).delete(jobs::delete))
        .route("/jobs/{id}/cancel", post(jobs::cancel))
        .route("/jobs/{id}/case", get(jobs::case))
        .route("/jobs/{id}/steps", get(steps::steps))
        .route("/jobs/{id}/steps/{step}", get(steps::step))
        .route("/jobs/{id}/result", get(jobs::result))
        .route("/jobs/{id}/archive", get(archive::archive))
        .route("/openapi.yaml", get(openapi))
        .route_layer(middleware::from_fn_with_state(
            state.clone(),
            auth::require_token,
        ))
        .route_layer(middleware::from_fn(auth::require_same_origin));
    Router::new()
        .route("/health", get(health))
        .route("/schema/case.json", get(case_schema))
        .merge(viewer::routes())
        .merge(protected)
        .fallback(unknown_route)
        .method_not_allowed_fallback(method_not_allowed)
        .layer(DefaultBodyLimit::max(state.config.limits.max_body_bytes))
        .layer(middleware::from_fn(limit_headers))
        .layer(middleware::map_response(security_headers))
        .with_state(state)
}

/// What a browser may do with any response: load the viewer's script,
/// style and images from this origin only and run nothing inline; show no
/// page of ours in another's frame; read no type but the one declared.
const CONTENT_SECURITY_POLICY: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
     img-src 'self' data: blob:; connect-src 'self'; base-uri 'none'; form-action 'self'; \
     frame-ancestors 'none'";

async fn security_headers(mut response: Response) -> Response {
    let headers = response.headers_mut();
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        header::HeaderValue::from_static(CONTENT_SECURITY_POLICY),
    );
    headers.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        header::HeaderValue::from_static("nosniff"),
    );
    headers.insert(
        header::X_FRAME_OPTIONS,
        header::HeaderValue::from_static("DENY"),
    );
    response
}

/// Headers a request may carry, and their bytes (names and values). The
/// connection lets through more (`connection::HEADERS_READ`), so that a
/// request over these is answered in the error body rather than by the
/// HTTP layer's bare 431.
pub const MAX_HEADERS: usize = 100;
pub const MAX_HEADER_BYTES: usize = 64 * 1024;

async fn limit_headers(
    request: axum::extract::Request,
    next: middleware::Next,
) -> Result<Response, ApiError> {
    let headers = request.headers();
    let count = headers.len();
    let bytes = headers
        .iter()
        .map(|(name, value)| name.as_str().len() + value.len())
        .sum();
    if count > MAX_HEADERS || bytes > MAX_HEADER_BYTES {
        return Err(ApiError::HeadersTooLarge {
            count,
            bytes,
            max_headers: MAX_HEADERS,
            max_bytes: MAX_HEADER_BYTES,
        });
    }
    Ok(next.run(request).await)
}

/// No such route: 404, or 401 without the token when one is set.
async fn unknown_route(State(state): State<AppState>, headers: HeaderMap) -> ApiError {
    if auth::authorized(&state, &headers) {
        ApiError::NotFound("route".into())
    } else {
        ApiError::Unauthorized
    }
}

/// A route that does not answer this method: 405, or 401 without the
/// token when one is set.
async fn method_not_allowed(State(state): State<AppState>, headers: HeaderMap) -> ApiError {
    if auth::authorized(&state, &headers) {
        ApiError::MethodNotAllowed
    } else {
        ApiError::Unauthorized
    }
}

/// `GET /health`: 200 with `status: ok` when the database answers and its
/// last write did not fail on storage; 503 with `degraded` (a write failed
/// for want of space or on an I/O error, until a write succeeds: the
/// check tries one of its own) or `unavailable` (the database does not
/// answer). The counts,
/// the size and the failure go only to a caller the token admits.
async fn health(State(state): State<AppState>, headers: HeaderMap) -> Response {
    let detailed = auth::authorized(&state, &headers);
    let checked = async {
        state.store.ping().await?;
        Ok::<_, sqlx::Error>((state.store.size_bytes().await?, state.store.counts().await?))
    };
    let (bytes, counts) = match checked.await {
        Ok(found) => found,
        Err(e) => {
            tracing::error!(error = %e, "health check: database unavailable");
            let body = if detailed {
                json!({"status": "unavailable", "database": "error"})
            } else {
                json!({"status": "unavailable"})
            };
            return (StatusCode::SERVICE_UNAVAILABLE, Json(body)).into_response();
        }
    };
    let trouble = state.store.recheck_storage().await;
    let (code, status) = match trouble {
        Some(_) => (StatusCode::SERVICE_UNAVAILABLE, "degraded"),
        None => (StatusCode::OK, "ok"),
    };
    if !detailed {
        return (code, Json(json!({ "status": status }))).into_response();
    }
    let jobs: serde_json::Map<String, serde_json::Value> = counts
        .into_iter()
        .map(|(status, n)| (status.as_str().to_string(), n.into()))
        .collect();
    let backend = match state.store.backend() {
        Backend::Sqlite => "sqlite",
        Backend::Postgres => "postgres",
    };
    let mut body = json!({
        "status": status,
        "database": if trouble.is_some() { "storage_error" } else { "ok" },
        "backend": backend,
        "database_bytes": bytes,
        "jobs": jobs,
        "max_queued": state.config.limits.max_queued,
        "workers": state.config.workers,
    });
    if let Some(error) = trouble {
        body["database_error"] = error.into();
    }
    (code, Json(body)).into_response()
}

async fn openapi() -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "application/yaml")],
        OPENAPI.as_str(),
    )
}

async fn case_schema() -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "application/schema+json")],
        CASE_SCHEMA.as_str(),
    )
}

#[cfg(test)]
mod tests {
    /// The Python client validates cases locally against its copy of the
    /// schema: it must be this build's.
    #[test]
    fn the_python_clients_schema_is_the_generated_one() {
        let bundled: serde_json::Value =
            serde_json::from_str(include_str!("../../python/src/mpm_client/case.schema.json"))
                .expect("JSON");
        assert!(
            bundled == mpm::case::json_schema(),
            "python/src/mpm_client/case.schema.json is stale: \
             `mpm schema > python/src/mpm_client/case.schema.json`"
        );
    }

    /// The Python client bundles the built-in examples: they must be this
    /// build's.
    #[test]
    fn the_python_clients_examples_are_the_built_in_ones() {
        let bundled = [
            (
                "column",
                include_str!("../../python/src/mpm_client/examples/column.json"),
            ),
            (
                "cantilever-grid",
                include_str!("../../python/src/mpm_client/examples/cantilever-grid.json"),
            ),
            (
                "cantilever",
                include_str!("../../python/src/mpm_client/examples/cantilever.json"),
            ),
            (
                "plate-with-hole",
                include_str!("../../python/src/mpm_client/examples/plate-with-hole.json"),
            ),
            (
                "footing",
                include_str!("../../python/src/mpm_client/examples/footing.json"),
            ),
            (
                "slope",
                include_str!("../../python/src/mpm_client/examples/slope.json"),
            ),
            (
                "column3d",
                include_str!("../../python/src/mpm_client/examples/column3d.json"),
            ),
            (
                "sphere3d",
                include_str!("../../python/src/mpm_client/examples/sphere3d.json"),
            ),
            (
                "footing3d",
                include_str!("../../python/src/mpm_client/examples/footing3d.json"),
            ),
        ];
        let names: Vec<&str> = (mpm::case::builtin::NAMES.iter())
            .chain(&mpm::case::builtin::SOLID_NAMES)
            .copied()
            .collect();
        assert_eq!(bundled.map(|(name, _)| name).to_vec(), names);
        for (name, text) in bundled {
            assert!(
                Some(text) == mpm::case::builtin::get(name),
                "python/src/mpm_client/examples/{name}.json is stale: copy crates/mpm/cases/{name}.json"
            );
        }
    }

    /// The generated case schemas take no name of a hand-written one.
    #[test]
    fn generated_schemas_add_to_the_contract_and_replace_nothing() {
        let written: serde_yaml::Value =
            serde_yaml::from_str(include_str!("../../openapi.yaml")).expect("YAML");
        let served: serde_yaml::Value = serde_yaml::from_str(&super::OPENAPI).expect("YAML");
        let generated = mpm::case::openapi_schemas();
        let names =
            |doc: &serde_yaml::Value| doc["components"]["schemas"].as_mapping().unwrap().len();
        assert_eq!(names(&served), names(&written) + generated.len());
        assert!(generated.contains_key("Case"));
    }

    /// YAML 1.1 parsers (PyYAML, and tools built on it) read the keys `on`,
    /// `off`, `yes`, `no`, `y` and `n` as booleans: a selector's `on` became
    /// `true`, and the spec's own example failed with
    /// `supports[0].true`. Every such key in the contract is quoted.
    #[test]
    fn the_contract_has_no_key_that_yaml_1_1_reads_as_a_boolean() {
        let booleans = ["on", "off", "yes", "no", "y", "n", "true", "false"];
        for (number, line) in super::OPENAPI.lines().enumerate() {
            // Keys start a line (after `- ` in a list) or follow `{` or `,`.
            let starts = std::iter::once(line.trim_start().trim_start_matches("- "))
                .chain(line.split(['{', ',']).skip(1).map(str::trim_start));
            for key in starts.filter_map(|s| s.split_once(':').map(|(k, _)| k.trim())) {
                assert!(
                    !booleans.contains(&key.to_ascii_lowercase().as_str()),
                    "openapi.yaml line {}: unquoted key {key:?}",
                    number + 1
                );
            }
        }
    }
}
