//! Keeping hostile web pages out: a request that carries an `Origin`
//! header (every browser WebSocket handshake and every cross-site or
//! non-GET fetch does) is served only when that origin is the server's own
//! (`http(s)://` + the request's `Host`) or on the configured allow-list
//! (`--allow-origin`). `null` (sandboxed frames, `file:` pages) is never
//! allowed. Programs that send no `Origin` — the device bridge, scripts,
//! curl — are unaffected: they must still present a token.

use crate::app::{ApiError, AppState};
use axum::extract::{Request, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

/// Whether a request with these headers may be served.
pub fn allowed(headers: &HeaderMap, allow_list: &[String]) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let Ok(origin) = origin.to_str() else {
        return false;
    };
    let origin = origin.trim().trim_end_matches('/');
    if allow_list
        .iter()
        .any(|a| a.trim_end_matches('/').eq_ignore_ascii_case(origin))
    {
        return true;
    }
    let Some(host) = headers.get(header::HOST).and_then(|h| h.to_str().ok()) else {
        return false;
    };
    ["http://", "https://"].iter().any(|scheme| {
        origin
            .get(..scheme.len())
            .is_some_and(|s| s.eq_ignore_ascii_case(scheme))
            && origin[scheme.len()..].eq_ignore_ascii_case(host.trim())
    })
}

/// Middleware: refuses (403, `forbidden`) a request from a foreign origin.
pub async fn check(State(state): State<AppState>, req: Request, next: Next) -> Response {
    if allowed(req.headers(), &state.config.allowed_origins) {
        return next.run(req).await;
    }
    let origin = req
        .headers()
        .get(header::ORIGIN)
        .map(|o| String::from_utf8_lossy(o.as_bytes()).into_owned())
        .unwrap_or_default();
    tracing::warn!(origin = ?origin, path = %req.uri().path(), "refused a request from a foreign origin");
    ApiError(
        StatusCode::FORBIDDEN,
        "forbidden",
        format!(
            "requests from origin {origin:?} are not allowed (only this server's own pages or --allow-origin)"
        ),
    )
    .into_response()
}
