//! The static web client: `/` (index.html) and the client's files from the
//! web-client folder, and its vendored npm packages from its node_modules —
//! `/vendor/three/`, `/vendor/iwer/` and `/vendor/webxr-profiles/` (the VR
//! controller profiles and glTF models of `@webxr-input-profiles/assets`,
//! its `dist/profiles`) — so the client fetches nothing from a CDN. When the
//! client or its npm packages are missing, `/` answers a page that says how
//! to install them.
//!
//! What a cold load costs on a slow link is mostly bytes and round trips, so:
//! - each vendored package is also served under a versioned prefix
//!   (`/vendor/three@0.187.0/`, the version read from its package.json) with
//!   `Cache-Control: immutable` for a year, and index.html is served with
//!   its vendor URLs rewritten to those prefixes: a warm load asks nothing
//!   of them again, and a package upgrade changes the URL;
//! - vendored files are sent precompressed (`.br`, `.gz` written next to them
//!   at install time by `web-client/tools/precompress.mjs`) to a browser
//!   that accepts them, with `Vary: Accept-Encoding`;
//! - the client's own files (small, and edited while the server runs) are
//!   gzipped per request; index.html names each by the hash of its current
//!   content (`/src/app.js?v=…`, in the entry script, the stylesheet, the
//!   `modulepreload` hints that let the browser fetch every module in
//!   parallel, and import-map entries that send the modules' relative
//!   imports to the hashed URLs), and a hashed URL whose hash is current is
//!   immutable; index.html itself, and any other URL, is `no-cache`,
//!   revalidated by `ETag`. A warm visit asks for index.html and nothing
//!   else of the page.
//! - when the install built a bundle of the current modules
//!   (`web-client/tools/bundle.mjs`, [`bundle`]), index.html loads it
//!   instead: a few minified, precompressed files under
//!   `/dist/<sources>/`, immutable, with three.js tree-shaken into them.

use axum::Router;
use axum::body::Body;
use axum::extract::Request;
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tower_http::compression::CompressionLayer;
use tower_http::services::ServeDir;
use tower_http::set_header::SetResponseHeaderLayer;

pub mod bundle;

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

/// `Cache-Control` of the versioned vendor prefixes: their content never changes.
pub const IMMUTABLE: &str = "public, max-age=31536000, immutable";

/// `Cache-Control` of everything else: cache, but revalidate (by `ETag`) before use.
pub const REVALIDATE: &str = "no-cache";

/// A vendored npm package: its URL name under `/vendor/`, its folder in
/// node_modules, and the sub-folder of it that is served.
struct Vendored {
    name: &'static str,
    package: &'static str,
    served: &'static str,
}

const VENDORED: [Vendored; 3] = [
    Vendored {
        name: "three",
        package: "three",
        served: "",
    },
    Vendored {
        name: "iwer",
        package: "iwer",
        served: "",
    },
    Vendored {
        name: "webxr-profiles",
        package: "@webxr-input-profiles/assets",
        served: "dist/profiles",
    },
];

/// Whether the client in `web_dir` can be served (index.html and node_modules present).
pub fn client_installed(web_dir: &Path) -> bool {
    web_dir.join("index.html").is_file() && web_dir.join("node_modules").is_dir()
}

/// The installed version of an npm package in `modules` (its package.json's
/// `version`), if it is installed and names one made of URL-safe characters.
fn package_version(modules: &Path, package: &str) -> Option<String> {
    let text = std::fs::read_to_string(modules.join(package).join("package.json")).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    let version = json.get("version")?.as_str()?;
    let safe = !version.is_empty()
        && version
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b".-+_".contains(&b));
    safe.then(|| version.to_string())
}

/// index.html with every `/vendor/NAME/` URL pointed at its versioned prefix.
pub fn versioned_index(html: &str, versions: &[(String, String)]) -> String {
    let mut out = html.to_string();
    for (name, version) in versions {
        out = out.replace(
            &format!("/vendor/{name}/"),
            &format!("/vendor/{name}@{version}/"),
        );
    }
    out
}

/// A short hash of a file's content (FNV-1a, 64 bits, hex): the `?v=` of
/// the client's own files, so a changed file gets a new URL.
pub fn content_hash(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The client's own files index.html can name (`/src/NAME.js`, `.css`),
/// each with its content hash; read at every page load, so an edited file
/// is named by its new hash at once.
fn own_files(web_dir: &Path) -> Vec<(String, String)> {
    let Ok(dir) = std::fs::read_dir(web_dir.join("src")) else {
        return Vec::new();
    };
    let mut out: Vec<(String, String)> = dir
        .filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            (name.ends_with(".js") || name.ends_with(".css")).then_some(())?;
            let bytes = std::fs::read(e.path()).ok()?;
            Some((format!("/src/{name}"), content_hash(&bytes)))
        })
        .collect();
    out.sort();
    out
}

/// index.html with every quoted `"/src/NAME"` of `own` given its `?v=HASH`
/// (the entry script, the stylesheet, the modulepreload hints), and the
/// import map given an entry per own module, so that the relative imports
/// between the client's modules load the hashed URLs too.
pub fn hashed_index(html: &str, own: &[(String, String)]) -> String {
    let mut out = html.to_string();
    for (path, hash) in own {
        out = out.replace(&format!("\"{path}\""), &format!("\"{path}?v={hash}\""));
    }
    const OPEN: &str = "<script type=\"importmap\">";
    let Some(start) = out.find(OPEN).map(|i| i + OPEN.len()) else {
        return out;
    };
    let Some(len) = out[start..].find("</script>") else {
        return out;
    };
    let Ok(mut map) = serde_json::from_str::<serde_json::Value>(&out[start..start + len]) else {
        return out;
    };
    if let Some(imports) = map.get_mut("imports").and_then(|i| i.as_object_mut()) {
        for (path, hash) in own.iter().filter(|(p, _)| p.ends_with(".js")) {
            imports.insert(path.clone(), format!("{path}?v={hash}").into());
        }
    }
    out.replace_range(start..start + len, &format!("\n    {map}\n  "));
    out
}

/// One of the client's own files: `Cache-Control: immutable` when the URL
/// carries the hash of the file's current content (`?v=`, from index.html),
/// else `no-cache` (revalidated by ETag).
async fn own_file(web_dir: Arc<PathBuf>, request: Request) -> Response {
    use tower::ServiceExt;
    let path = request.uri().path().trim_start_matches('/').to_string();
    let asked = request
        .uri()
        .query()
        .and_then(|q| q.strip_prefix("v="))
        .map(str::to_string);
    let safe = Path::new(&path)
        .components()
        .all(|c| matches!(c, std::path::Component::Normal(_)));
    let current = match (&asked, safe) {
        (Some(v), true) => tokio::fs::read(web_dir.join(&path))
            .await
            .is_ok_and(|b| content_hash(&b) == *v),
        _ => false,
    };
    let mut res = match ServeDir::new(web_dir.as_ref()).oneshot(request).await {
        Ok(r) => r.map(Body::new),
        Err(never) => match never {},
    };
    let cache = if current && res.status() == StatusCode::OK {
        IMMUTABLE
    } else {
        REVALIDATE
    };
    res.headers_mut()
        .insert(header::CACHE_CONTROL, HeaderValue::from_static(cache));
    res
}

async fn index(
    web_dir: Arc<PathBuf>,
    versions: Arc<Vec<(String, String)>>,
    request: HeaderMap,
) -> Response {
    if !client_installed(&web_dir) {
        return (StatusCode::SERVICE_UNAVAILABLE, Html(MISSING_CLIENT_PAGE)).into_response();
    }
    let html = match tokio::fs::read_to_string(web_dir.join("index.html")).await {
        Ok(html) => {
            let own = own_files(&web_dir);
            let three = versions.iter().find(|(name, _)| name == "three");
            let html = match three.and_then(|(_, v)| bundle::current(&web_dir, &own, v)) {
                Some(b) => bundle::bundled_index(&html, &b),
                None => html,
            };
            hashed_index(&versioned_index(&html, &versions), &own)
        }
        Err(e) => {
            tracing::warn!("cannot read index.html: {e}");
            return (StatusCode::SERVICE_UNAVAILABLE, Html(MISSING_CLIENT_PAGE)).into_response();
        }
    };
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    html.hash(&mut hasher);
    let etag = format!("\"{:016x}\"", hasher.finish());
    let matches = request
        .get(header::IF_NONE_MATCH)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| {
            v.split(',')
                .any(|t| t.trim().trim_start_matches("W/") == etag)
        });
    let (status, body) = if matches {
        (StatusCode::NOT_MODIFIED, Body::empty())
    } else {
        (StatusCode::OK, Body::from(html))
    };
    (
        status,
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8".to_string()),
            (header::CACHE_CONTROL, REVALIDATE.to_string()),
            (header::ETAG, etag),
        ],
        body,
    )
        .into_response()
}

/// Routes for the static client. Merge this router last: its fallback
/// serves any other path from `web_dir`.
pub fn router<S: Clone + Send + Sync + 'static>(web_dir: &Path) -> Router<S> {
    let modules = web_dir.join("node_modules");
    let mut versions = Vec::new();
    let mut router = Router::new();
    for v in &VENDORED {
        let dir = modules.join(v.package).join(v.served);
        let serve = || ServeDir::new(&dir).precompressed_br().precompressed_gzip();
        let cache = |value: &'static str| {
            SetResponseHeaderLayer::overriding(
                header::CACHE_CONTROL,
                HeaderValue::from_static(value),
            )
        };
        router = router.nest_service(
            &format!("/vendor/{}", v.name),
            tower::ServiceBuilder::new()
                .layer(cache(REVALIDATE))
                .service(serve()),
        );
        if let Some(version) = package_version(&modules, v.package) {
            router = router.nest_service(
                &format!("/vendor/{}@{version}", v.name),
                tower::ServiceBuilder::new()
                    .layer(cache(IMMUTABLE))
                    .service(serve()),
            );
            versions.push((v.name.to_string(), version));
        }
    }
    let dir = Arc::new(web_dir.to_path_buf());
    let versions = Arc::new(versions);
    let page = {
        let (dir, versions) = (dir.clone(), versions.clone());
        move |headers: HeaderMap| index(dir.clone(), versions.clone(), headers)
    };
    let own = tower::ServiceBuilder::new()
        .layer(SetResponseHeaderLayer::if_not_present(
            header::CACHE_CONTROL,
            HeaderValue::from_static(REVALIDATE),
        ))
        .layer(CompressionLayer::new())
        .service(ServeDir::new(web_dir).append_index_html_on_directories(false));
    let src = {
        let dir = dir.clone();
        get(move |request: Request| own_file(dir.clone(), request)).layer(CompressionLayer::new())
    };
    // The bundle's files: named by the sources' hash, so they never change.
    let dist = tower::ServiceBuilder::new()
        .layer(SetResponseHeaderLayer::overriding(
            header::CACHE_CONTROL,
            HeaderValue::from_static(IMMUTABLE),
        ))
        .service(
            ServeDir::new(web_dir.join("dist"))
                .precompressed_br()
                .precompressed_gzip(),
        );
    router
        .nest_service("/dist", dist)
        .route("/", get(page.clone()))
        .route("/index.html", get(page))
        .route("/src/{*file}", src)
        .fallback_service(own)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_vendor_urls_are_versioned_and_nothing_else_changes() {
        let html = r#"{"three": "/vendor/three/build/three.module.js"} <link href="/vendor/three/a.js"> /vendor/threex/ /src/app.js"#;
        let v = vec![("three".to_string(), "0.187.0".to_string())];
        assert_eq!(
            versioned_index(html, &v),
            r#"{"three": "/vendor/three@0.187.0/build/three.module.js"} <link href="/vendor/three@0.187.0/a.js"> /vendor/threex/ /src/app.js"#
        );
    }

    #[test]
    fn a_package_version_is_read_only_when_it_is_url_safe() {
        /// A scratch node_modules, removed when the test ends (also on failure).
        struct Scratch(PathBuf);
        impl Drop for Scratch {
            fn drop(&mut self) {
                let _ = std::fs::remove_dir_all(&self.0);
            }
        }
        let dir = Scratch(
            std::env::temp_dir().join(format!("vsculpt-web-versions-{}", std::process::id())),
        );
        let write = |pkg: &str, json: &str| {
            std::fs::create_dir_all(dir.0.join(pkg)).unwrap();
            std::fs::write(dir.0.join(pkg).join("package.json"), json).unwrap();
        };
        write("good", r#"{"version": "1.2.3-beta.1+b5"}"#);
        write("route", r#"{"version": "1.0{id}"}"#);
        write("path", r#"{"version": "../../etc"}"#);
        write("none", r#"{"name": "x"}"#);
        write("bad", "not json");
        assert_eq!(
            package_version(&dir.0, "good").as_deref(),
            Some("1.2.3-beta.1+b5")
        );
        for pkg in ["route", "path", "none", "bad", "missing"] {
            assert_eq!(package_version(&dir.0, pkg), None, "{pkg}");
        }
    }
}
