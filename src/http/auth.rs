//! The bearer-token check in front of every endpoint but `/health`, and
//! the same-origin check in front of every request that changes jobs.

use axum::extract::{Request, State};
use axum::http::{HeaderMap, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::extract::drain;
use super::{ApiError, AppState};

/// Lets a request through when no token is configured or it carries
/// `Authorization: Bearer <token>` (the scheme in any case, RFC 7235);
/// answers 401 otherwise. The router's fallbacks check it too, so with a
/// token set an unknown route answers 401 and routes cannot be listed
/// without it.
pub async fn require_token(
    State(state): State<AppState>,
    request: Request,
    next: Next,
) -> Response {
    if !authorized(&state, request.headers()) {
        return ApiError::Unauthorized.into_response();
    }
    next.run(request).await
}

/// Refuses (403) a request that changes jobs (any method but GET and HEAD)
/// sent by a browser from a page of another origin: browsers name the
/// page's origin in `Origin` on such requests, and a page may send a form,
/// or a POST with no body, to any address without asking first. Without a
/// token (the default), that would let any page a user visits cancel or
/// submit jobs on their service. Clients other than browsers send no
/// `Origin` and pass. Behind a proxy that rewrites `Host`, the
/// `X-Forwarded-Host` it sets is the service's host (a page cannot set
/// that header on a request to another site without asking first).
pub async fn require_same_origin(request: Request, next: Next) -> Response {
    let method = request.method();
    if method != axum::http::Method::GET && method != axum::http::Method::HEAD {
        let headers = request.headers();
        if let Some(origin) = headers.get(header::ORIGIN) {
            let origin = origin.to_str().unwrap_or("?");
            let host = |name| {
                headers
                    .get(name)
                    .and_then(|h: &header::HeaderValue| h.to_str().ok())
            };
            if !same_origin(origin, host(header::HOST))
                && !same_origin(
                    origin,
                    host(header::HeaderName::from_static("x-forwarded-host")),
                )
            {
                let refused = ApiError::CrossOrigin {
                    origin: origin.to_string(),
                };
                drain(request.into_body()).await;
                return refused.into_response();
            }
        }
    }
    next.run(request).await
}

/// Whether `origin` (`scheme://host[:port]`, or `null`) names the host the
/// request was sent to.
fn same_origin(origin: &str, host: Option<&str>) -> bool {
    let Some(host) = host else {
        return false;
    };
    origin
        .split_once("://")
        .is_some_and(|(_, authority)| authority.eq_ignore_ascii_case(host))
}

/// Whether a request with these headers may pass: no token is configured,
/// or it carries the token.
pub fn authorized(state: &AppState, headers: &HeaderMap) -> bool {
    let Some(token) = &state.config.token else {
        return true;
    };
    headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(bearer)
        .is_some_and(|given| same_secret(given.as_bytes(), token.as_bytes()))
}

/// The credentials of a `Bearer` authorization value.
fn bearer(value: &str) -> Option<&str> {
    let (scheme, credentials) = value.split_once(' ')?;
    scheme
        .eq_ignore_ascii_case("bearer")
        .then(|| credentials.trim_start())
}

/// Compares two secrets in time that depends on their lengths only, not on
/// where they first differ.
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |diff, (x, y)| diff | (x ^ y)) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bearer_scheme_is_read_in_any_case() {
        assert_eq!(bearer("Bearer abc"), Some("abc"));
        assert_eq!(bearer("bearer abc"), Some("abc"));
        assert_eq!(bearer("BEARER  abc"), Some("abc"));
        assert_eq!(bearer("Basic abc"), None);
        assert_eq!(bearer("Bearerabc"), None);
    }

    #[test]
    fn an_origin_matches_only_its_own_host_and_port() {
        assert!(same_origin("http://127.0.0.1:8080", Some("127.0.0.1:8080")));
        assert!(same_origin("https://Mpm.example", Some("mpm.example")));
        assert!(!same_origin("http://evil.example", Some("127.0.0.1:8080")));
        assert!(!same_origin(
            "http://127.0.0.1:8081",
            Some("127.0.0.1:8080")
        ));
        assert!(!same_origin("null", Some("127.0.0.1:8080")));
        assert!(!same_origin("http://127.0.0.1:8080", None));
    }

    #[test]
    fn secrets_match_only_when_equal() {
        assert!(same_secret(b"s3cret", b"s3cret"));
        assert!(!same_secret(b"s3cret", b"s3creT"));
        assert!(!same_secret(b"s3cret", b"s3cret!"));
        assert!(!same_secret(b"", b"x"));
    }
}
