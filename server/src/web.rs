//! The static web client: `/` (index.html) and the client's files from the
//! web-client folder, `/vendor/three/` and `/vendor/iwer/` from its
//! node_modules, and `/vendor/webxr-profiles/` (the VR controller profiles
//! and glTF models of `@webxr-input-profiles/assets`, its `dist/profiles`),
//! so the client fetches nothing from a CDN. When the client or its npm
//! packages are missing, `/` answers a page that says how to install them.

use axum::Router;
use axum::http::{StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use std::path::{Path, PathBuf};
use tower_http::services::ServeDir;

/// The page served at `/` when the web client cannot be served.
pub const MISSING_CLIENT_PAGE: &str = "<!doctype html>
<html lang=\"en\"><head><meta charset=\"utf-8\"><title>vsculpt: web client not installed</title></head>
<body style=\"font-family: sans-serif; max-width: 40em; margin: 3em auto\">
<h1>vsculpt server is running</h1>
<p>The web client is not installed next to this server: its npm packages
(web-client/node_modules) are missing.</p>
<p>Run <code>scripts/run.sh</code> from the repository root (it installs them and
starts the server), or run <code>npm ci</code> in <code>web-client/</code> and reload this page.</p>
</body></html>
";

/// Whether the client in `web_dir` can be served (index.html and node_modules present).
pub fn client_installed(web_dir: &Path) -> bool {
    web_dir.join("index.html").is_file() && web_dir.join("node_modules").is_dir()
}

async fn index(web_dir: PathBuf) -> Response {
    if !client_installed(&web_dir) {
        return (StatusCode::SERVICE_UNAVAILABLE, Html(MISSING_CLIENT_PAGE)).into_response();
    }
    match tokio::fs::read(web_dir.join("index.html")).await {
        Ok(bytes) => (
            [
                (header::CONTENT_TYPE, "text/html; charset=utf-8"),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            bytes,
        )
            .into_response(),
        Err(e) => {
            tracing::warn!("cannot read index.html: {e}");
            (StatusCode::SERVICE_UNAVAILABLE, Html(MISSING_CLIENT_PAGE)).into_response()
        }
    }
}

/// Routes for the static client. Merge this router last: its fallback
/// serves any other path from `web_dir`.
pub fn router<S: Clone + Send + Sync + 'static>(web_dir: &Path) -> Router<S> {
    let dir = web_dir.to_path_buf();
    let dir2 = dir.clone();
    let modules = web_dir.join("node_modules");
    Router::new()
        .route("/", get(move || index(dir.clone())))
        .route("/index.html", get(move || index(dir2.clone())))
        .nest_service("/vendor/three", ServeDir::new(modules.join("three")))
        .nest_service("/vendor/iwer", ServeDir::new(modules.join("iwer")))
        .nest_service(
            "/vendor/webxr-profiles",
            ServeDir::new(modules.join("@webxr-input-profiles/assets/dist/profiles")),
        )
        .fallback_service(ServeDir::new(web_dir).append_index_html_on_directories(false))
}
