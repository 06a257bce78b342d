//! The service's one error type: it is the HTTP response. The body is always
//! `{"error": {"code", "message", "details"}}`; internal errors are logged
//! with their cause and answered without it.

use axum::Json;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::{Value, json};

use crate::jobs::admission::Rejection;

/// What a 429, 503 or 507 asks a client to wait before it submits again, in seconds.
const RETRY_AFTER_SECONDS: &str = "10";

#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// The body is not JSON at all.
    #[error("the request body is not valid JSON: {0}")]
    MalformedJson(String),
    /// JSON, but not a valid case; `path` names the field.
    #[error("{path}: {message}")]
    InvalidCase { path: String, message: String },
    /// A valid case that exceeds a configured limit.
    #[error("{path}: {message}")]
    LimitExceeded { path: String, message: String },
    #[error("the request body exceeds the limit of {limit} bytes")]
    PayloadTooLarge { limit: usize },
    #[error("the request body did not arrive within {seconds} s")]
    RequestTimeout { seconds: f64 },
    #[error("invalid query parameter {name}: {message}")]
    BadQuery { name: &'static str, message: String },
    #[error("invalid header {name}: {message}")]
    BadHeader { name: &'static str, message: String },
    #[error(
        "the Idempotency-Key {key:?} was first used for job {job} with another body; \
         a new submission needs a new key"
    )]
    IdempotencyKeyReused { key: String, job: i64 },
    #[error("{0} not found")]
    NotFound(String),
    #[error("{0}")]
    Conflict(String),
    #[error("missing or wrong bearer token")]
    Unauthorized,
    /// A browser's request from a page of another origin.
    #[error("a request from another origin ({origin}) may not change jobs")]
    CrossOrigin { origin: String },
    #[error("the body must be declared Content-Type: application/json (it was {given})")]
    UnsupportedMediaType { given: String },
    #[error(
        "the request's headers exceed the limit of {max_headers} headers or {max_bytes} bytes \
         (they were {count} headers, {bytes} bytes)"
    )]
    HeadersTooLarge {
        count: usize,
        bytes: usize,
        max_headers: usize,
        max_bytes: usize,
    },
    #[error("this route does not answer that method")]
    MethodNotAllowed,
    #[error("the queue is full ({limit} jobs wait); try again later")]
    QueueFull { limit: usize },
    /// Shutting down, or a submission's check ran out of time.
    #[error("{0}")]
    Unavailable(String),
    /// The database's disk is full: nothing of the request was stored.
    #[error("the database's disk is full: nothing was stored; try again when space is freed")]
    InsufficientStorage,
    #[error("internal error")]
    Internal(String),
}

impl From<Rejection> for ApiError {
    fn from(r: Rejection) -> Self {
        match r {
            Rejection::MalformedJson(message) => ApiError::MalformedJson(message),
            Rejection::InvalidCase { path, message } => ApiError::InvalidCase { path, message },
            Rejection::LimitExceeded { path, message } => ApiError::LimitExceeded { path, message },
        }
    }
}

impl From<sqlx::Error> for ApiError {
    fn from(e: sqlx::Error) -> Self {
        if crate::jobs::store::is_disk_full(&e) {
            tracing::error!(error = %e, "the database's disk is full");
            return ApiError::InsufficientStorage;
        }
        ApiError::Internal(format!("database: {e}"))
    }
}

impl ApiError {
    fn status_code_details(&self) -> (StatusCode, &'static str, Value) {
        match self {
            ApiError::MalformedJson(_) => (StatusCode::BAD_REQUEST, "malformed_json", Value::Null),
            ApiError::InvalidCase { path, .. } => (
                StatusCode::UNPROCESSABLE_ENTITY,
                "invalid_case",
                json!({ "path": path }),
            ),
            ApiError::LimitExceeded { path, .. } => (
                StatusCode::UNPROCESSABLE_ENTITY,
                "limit_exceeded",
                json!({ "path": path }),
            ),
            ApiError::PayloadTooLarge { limit } => (
                StatusCode::PAYLOAD_TOO_LARGE,
                "payload_too_large",
                json!({ "limit_bytes": limit }),
            ),
            ApiError::RequestTimeout { .. } => {
                (StatusCode::REQUEST_TIMEOUT, "request_timeout", Value::Null)
            }
            ApiError::BadQuery { name, .. } => (
                StatusCode::BAD_REQUEST,
                "bad_query",
                json!({ "parameter": name }),
            ),
            ApiError::BadHeader { name, .. } => (
                StatusCode::BAD_REQUEST,
                "bad_header",
                json!({ "header": name }),
            ),
            ApiError::IdempotencyKeyReused { job, .. } => (
                StatusCode::UNPROCESSABLE_ENTITY,
                "idempotency_key_reused",
                json!({ "header": "Idempotency-Key", "job": job }),
            ),
            ApiError::NotFound(_) => (StatusCode::NOT_FOUND, "not_found", Value::Null),
            ApiError::Conflict(_) => (StatusCode::CONFLICT, "conflict", Value::Null),
            ApiError::Unauthorized => (StatusCode::UNAUTHORIZED, "unauthorized", Value::Null),
            ApiError::CrossOrigin { .. } => (
                StatusCode::FORBIDDEN,
                "cross_origin",
                json!({ "header": "Origin" }),
            ),
            ApiError::UnsupportedMediaType { .. } => (
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "unsupported_media_type",
                json!({ "header": "Content-Type" }),
            ),
            ApiError::HeadersTooLarge {
                max_headers,
                max_bytes,
                ..
            } => (
                StatusCode::REQUEST_HEADER_FIELDS_TOO_LARGE,
                "headers_too_large",
                json!({ "max_headers": max_headers, "max_header_bytes": max_bytes }),
            ),
            ApiError::QueueFull { limit } => (
                StatusCode::TOO_MANY_REQUESTS,
                "queue_full",
                json!({ "max_queued": limit }),
            ),
            ApiError::MethodNotAllowed => (
                StatusCode::METHOD_NOT_ALLOWED,
                "method_not_allowed",
                Value::Null,
            ),
            ApiError::Unavailable(_) => {
                (StatusCode::SERVICE_UNAVAILABLE, "unavailable", Value::Null)
            }
            ApiError::InsufficientStorage => (
                StatusCode::INSUFFICIENT_STORAGE,
                "insufficient_storage",
                Value::Null,
            ),
            ApiError::Internal(_) => (StatusCode::INTERNAL_SERVER_ERROR, "internal", Value::Null),
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let (status, code, details) = self.status_code_details();
        if let ApiError::Internal(cause) = &self {
            tracing::error!(%cause, "internal error");
        }
        let body = Json(
            json!({ "error": { "code": code, "message": self.to_string(), "details": details } }),
        );
        let mut response = (status, body).into_response();
        if matches!(
            status,
            StatusCode::TOO_MANY_REQUESTS
                | StatusCode::SERVICE_UNAVAILABLE
                | StatusCode::INSUFFICIENT_STORAGE
        ) {
            response.headers_mut().insert(
                axum::http::header::RETRY_AFTER,
                axum::http::HeaderValue::from_static(RETRY_AFTER_SECONDS),
            );
        }
        if status == StatusCode::UNAUTHORIZED {
            response.headers_mut().insert(
                axum::http::header::WWW_AUTHENTICATE,
                axum::http::HeaderValue::from_static("Bearer"),
            );
        }
        response
    }
}
