//! Path and query extractors whose rejections keep the error contract: the
//! one JSON error body, never axum's plain-text rejections.

use axum::extract::{FromRequestParts, Path, Query};
use axum::http::request::Parts;
use serde::de::DeserializeOwned;

use super::ApiError;

/// A path's parameters (`{id}`, `{step}`): a segment that does not parse
/// (`/jobs/abc`, an id past i64) names nothing there, so it is a 404.
pub struct IdPath<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned + Send> FromRequestParts<S> for IdPath<T> {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, ApiError> {
        Path::<T>::from_request_parts(parts, state)
            .await
            .map(|Path(value)| IdPath(value))
            .map_err(|_| ApiError::NotFound(parts.uri.path().to_string()))
    }
}

/// Query parameters: a query string that does not deserialize (a
/// parameter given twice, an unknown shape) is a 400 `bad_query`.
pub struct Params<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned + Send> FromRequestParts<S> for Params<T> {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, ApiError> {
        Query::<T>::from_request_parts(parts, state)
            .await
            .map(|Query(value)| Params(value))
            .map_err(|rejection| ApiError::BadQuery {
                name: "query",
                message: rejection.body_text(),
            })
    }
}

/// An integer query parameter, named in the error when it is not one.
pub fn integer(name: &'static str, value: Option<&str>) -> Result<Option<i64>, ApiError> {
    value
        .map(|v| {
            v.parse::<i64>().map_err(|_| ApiError::BadQuery {
                name,
                message: format!("{v:?} is not an integer"),
            })
        })
        .transpose()
}

/// The most of a refused request's body [`drain`] reads, and for how long.
const DRAIN_BYTES: usize = 256 * 1024;
const DRAIN_TIME: std::time::Duration = std::time::Duration::from_secs(2);

/// Reads and drops a refused request's body, up to [`DRAIN_BYTES`] and
/// [`DRAIN_TIME`]. A connection closed with data unread is reset, and the
/// reset can reach the client before the refusal does: it then sees the
/// connection drop instead of the 4xx (a 415 was lost so once in CI). A
/// larger or slower body is left unread.
pub async fn drain(body: axum::body::Body) {
    let _ = tokio::time::timeout(DRAIN_TIME, axum::body::to_bytes(body, DRAIN_BYTES)).await;
}
