//! The browser viewer: a page and its script and style, embedded in the
//! binary and served without the token (the page asks for it and sends it
//! with each API request).

use axum::Router;
use axum::extract::Path;
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::routing::get;

use super::{ApiError, AppState};

const INDEX: &str = include_str!("viewer/index.html");
/// The viewer's files under `/viewer/`: name, content type, text.
const FILES: [(&str, &str, &str); 3] = [
    (
        "viewer.js",
        "text/javascript; charset=utf-8",
        include_str!("viewer/viewer.js"),
    ),
    (
        "viewer.css",
        "text/css; charset=utf-8",
        include_str!("viewer/viewer.css"),
    ),
    (
        "favicon.svg",
        "image/svg+xml",
        include_str!("viewer/favicon.svg"),
    ),
];

pub fn routes() -> Router<AppState> {
    Router::new()
        .route("/", get(index))
        .route("/viewer/{file}", get(file))
}

async fn index() -> Response {
    text("text/html; charset=utf-8", INDEX)
}

async fn file(Path(name): Path<String>) -> Result<Response, ApiError> {
    FILES
        .iter()
        .find(|(file, _, _)| *file == name)
        .map(|(_, kind, body)| text(kind, body))
        .ok_or_else(|| ApiError::NotFound(format!("viewer file {name:?}")))
}

fn text(kind: &'static str, body: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, kind),
            // Ask again after an upgrade rather than run a stale script.
            (header::CACHE_CONTROL, "no-cache"),
        ],
        body,
    )
        .into_response()
}
