//! Every error answer of the HTTP API has the documented shape
//! `{"error": {"code", "message"}}`: the answers axum's extractors give on
//! their own (a path segment that is not a number, a body over the limit, a
//! wrong method, a missing WebSocket upgrade) are plain text, so they are
//! rewritten here with the stable code for their status.

use crate::app::ApiError;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

/// Largest plain-text rejection body carried over into the JSON message.
const MAX_MESSAGE: usize = 1024;

/// The stable code for an error status.
pub fn code_for(status: StatusCode) -> &'static str {
    match status.as_u16() {
        401 => "bad_token",
        403 => "forbidden",
        404 | 405 => "unknown_message",
        409 => "conflict",
        413 => "too_large",
        400..=499 => "malformed",
        _ => "internal",
    }
}

/// `map_response` middleware: an error answer that is not JSON becomes the
/// JSON error shape with the same status (and its `Allow` header, if any).
pub async fn json_errors(res: Response) -> Response {
    let status = res.status();
    if !(status.is_client_error() || status.is_server_error()) {
        return res;
    }
    let is_json = res
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|c| c.to_str().ok())
        .is_some_and(|c| c.starts_with("application/json"));
    if is_json {
        return res;
    }
    let allow = res.headers().get(header::ALLOW).cloned();
    let body = axum::body::to_bytes(res.into_body(), 64 * 1024)
        .await
        .unwrap_or_default();
    let mut message: String = String::from_utf8_lossy(&body)
        .chars()
        .take(MAX_MESSAGE)
        .collect();
    if message.trim().is_empty() {
        message = status
            .canonical_reason()
            .unwrap_or("request refused")
            .to_string();
    }
    let mut out = ApiError(status, code_for(status), message).into_response();
    if let Some(allow) = allow {
        out.headers_mut().insert(header::ALLOW, allow);
    }
    out
}
