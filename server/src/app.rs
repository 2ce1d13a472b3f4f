//! The HTTP surface (API.md §4): `/healthz`, `/metrics`, the REST API with
//! token checks, the WebSocket at `/ws` and the static web client. Tokens
//! come as `Authorization: Bearer <token>` or `?token=`.

use crate::cad;
use crate::config::Config;
use crate::design::{ErrorKind, Hub};
use crate::export::MeshFormat;
use crate::metrics::Metrics;
use crate::store::{DesignId, DesignRecord, Role, Store};
use axum::Router;
use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde::Deserialize;
use serde_json::json;
use std::collections::HashMap;
use std::sync::Arc;

/// Everything handlers share.
pub struct Shared {
    /// Configuration.
    pub config: Config,
    /// The store.
    pub store: Arc<Store>,
    /// Metrics.
    pub metrics: Arc<Metrics>,
    /// Running designs.
    pub hub: Hub,
    /// The administrator token (in `DATA/admin-token`).
    pub admin_token: String,
    /// Next WebSocket connection id.
    pub next_client: std::sync::atomic::AtomicU64,
    /// Triggered when the server shuts down (WebSocket tasks close).
    pub shutdown: crate::shutdown::Shutdown,
}

/// Handler state.
pub type AppState = Arc<Shared>;

/// An error response: status plus `{"error": {"code", "message"}}`.
pub struct ApiError(
    /// The HTTP status.
    pub StatusCode,
    /// The stable error code.
    pub &'static str,
    /// What went wrong.
    pub String,
);

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (
            self.0,
            axum::Json(json!({ "error": { "code": self.1, "message": self.2 } })),
        )
            .into_response()
    }
}

impl From<crate::design::CommandError> for ApiError {
    fn from(e: crate::design::CommandError) -> Self {
        let status = match e.kind {
            ErrorKind::Forbidden => StatusCode::FORBIDDEN,
            ErrorKind::UnknownDesign
            | ErrorKind::UnknownIcon
            | ErrorKind::UnknownVersion
            | ErrorKind::UnknownPart
            | ErrorKind::UnknownRelation => StatusCode::NOT_FOUND,
            ErrorKind::Locked => StatusCode::CONFLICT,
            ErrorKind::Incompatible => StatusCode::BAD_REQUEST,
            ErrorKind::InvalidValue
            | ErrorKind::NotFinite
            | ErrorKind::OutOfDomain
            | ErrorKind::Unsupported => StatusCode::BAD_REQUEST,
            ErrorKind::NothingToUndo | ErrorKind::Conflict => StatusCode::CONFLICT,
            ErrorKind::Solver => StatusCode::UNPROCESSABLE_ENTITY,
            ErrorKind::TooLarge => StatusCode::PAYLOAD_TOO_LARGE,
            ErrorKind::Unavailable | ErrorKind::Storage => StatusCode::SERVICE_UNAVAILABLE,
        };
        let w = crate::convert::WireError::from(e);
        ApiError(status, code_name(w.code), w.message)
    }
}

/// The snake_case name of a protocol error code.
fn code_name(code: vsculpt_protocol::ErrorCode) -> &'static str {
    use vsculpt_protocol::ErrorCode as C;
    match code {
        C::BadVersion => "bad_version",
        C::BadToken => "bad_token",
        C::BadHandshake => "bad_handshake",
        C::Malformed => "malformed",
        C::UnknownMessage => "unknown_message",
        C::TooLarge => "too_large",
        C::NotFinite => "not_finite",
        C::OutOfRange => "out_of_range",
        C::UnknownDesign => "unknown_design",
        C::UnknownIcon => "unknown_icon",
        C::UnknownVersion => "unknown_version",
        C::UnknownPart => "unknown_part",
        C::UnknownRelation => "unknown_relation",
        C::Locked => "locked",
        C::Incompatible => "incompatible",
        C::OutOfDomain => "out_of_domain",
        C::Forbidden => "forbidden",
        C::Conflict => "conflict",
        C::Unsupported => "unsupported",
        C::Solver => "solver",
        C::Internal => "internal",
        C::Unavailable => "unavailable",
        C::Storage => "storage",
        C::RateLimited => "rate_limited",
    }
}

fn unauthorized() -> ApiError {
    ApiError(
        StatusCode::UNAUTHORIZED,
        "bad_token",
        "a valid token is required (Authorization: Bearer <token> or ?token=)".into(),
    )
}

fn storage(e: impl std::fmt::Display) -> ApiError {
    ApiError(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string())
}

/// The token of a request, from the Authorization header or `?token=`.
pub fn request_token(headers: &HeaderMap, query: &HashMap<String, String>) -> Option<String> {
    if let Some(v) = headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        && let Some(t) = v.strip_prefix("Bearer ")
    {
        return Some(t.trim().to_string());
    }
    query.get("token").cloned()
}

/// Who holds a token.
#[derive(Clone, Debug, PartialEq)]
pub enum Caller {
    /// The administrator token.
    Admin,
    /// A design token.
    Design(DesignId, Role),
}

impl Shared {
    /// Runs `call` against the store on the blocking pool (SQLite blocks),
    /// a store failure or a lost task answering `internal`.
    pub async fn on_store<T: Send + 'static>(
        &self,
        call: impl FnOnce(&Store) -> Result<T, crate::store::StoreError> + Send + 'static,
    ) -> Result<T, ApiError> {
        let store = self.store.clone();
        tokio::task::spawn_blocking(move || call(&store))
            .await
            .map_err(storage)?
            .map_err(storage)
    }

    /// Who `token` belongs to.
    pub async fn caller(&self, token: &str) -> Result<Option<Caller>, ApiError> {
        if token.is_empty() {
            return Ok(None);
        }
        if token.len() == self.admin_token.len()
            && token
                .bytes()
                .zip(self.admin_token.bytes())
                .fold(0u8, |a, (x, y)| a | (x ^ y))
                == 0
        {
            return Ok(Some(Caller::Admin));
        }
        let token = token.to_owned();
        let found = self
            .on_store(move |store| store.design_by_token(&token))
            .await?;
        Ok(found.map(|(d, role)| Caller::Design(d.id, role)))
    }

    /// The role a token grants on design `id` (admin = editor).
    pub async fn role_on(&self, token: &str, id: DesignId) -> Result<Option<Role>, ApiError> {
        if let Some(Caller::Admin) = self.caller(token).await? {
            return Ok(Some(Role::Editor));
        }
        let rec = self.on_store(move |store| store.design(id)).await?;
        Ok(rec.and_then(|r| r.tokens.role_of(token)))
    }
}

type Q = Query<HashMap<String, String>>;

/// The `part` query parameter (one part of the product), if given.
fn part_param(q: &HashMap<String, String>) -> Result<Option<u64>, ApiError> {
    q.get("part")
        .map(|p| {
            p.parse::<u64>().map_err(|_| {
                ApiError(
                    StatusCode::BAD_REQUEST,
                    "malformed",
                    format!("part {p:?} is not a part id"),
                )
            })
        })
        .transpose()
}

async fn need_role(
    state: &Shared,
    headers: &HeaderMap,
    query: &HashMap<String, String>,
    id: DesignId,
) -> Result<Role, ApiError> {
    let token = request_token(headers, query).ok_or_else(unauthorized)?;
    match state.role_on(&token, id).await? {
        Some(r) => Ok(r),
        None => {
            // Same answer for a wrong token and a missing design: no probing.
            Err(unauthorized())
        }
    }
}

/// `ok`, or `degraded` with the designs whose actor is down or restarting
/// (still 200: the rest of the studio serves).
async fn healthz(State(s): State<AppState>) -> impl IntoResponse {
    let down = s.hub.down();
    if down.is_empty() {
        axum::Json(json!({ "status": "ok" }))
    } else {
        axum::Json(json!({ "status": "degraded", "designs_down": down }))
    }
}

async fn metrics(
    State(s): State<AppState>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    let token = request_token(&headers, &q).ok_or_else(unauthorized)?;
    match s.caller(&token).await? {
        Some(Caller::Admin) | Some(Caller::Design(_, Role::Editor)) => Ok((
            [(header::CONTENT_TYPE, "text/plain; version=0.0.4")],
            s.metrics.render(),
        )
            .into_response()),
        _ => Err(unauthorized()),
    }
}

fn design_json(d: &DesignRecord, role: Option<Role>) -> serde_json::Value {
    json!({ "id": d.id, "name": d.name, "created_ms": d.created_ms, "role": role })
}

async fn list_designs(
    State(s): State<AppState>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    let token = request_token(&headers, &q).ok_or_else(unauthorized)?;
    let caller = s.caller(&token).await?.ok_or_else(unauthorized)?;
    let list: Vec<_> = match caller {
        Caller::Admin => s
            .on_store(|store| store.designs())
            .await?
            .iter()
            .map(|d| design_json(d, Some(Role::Editor)))
            .collect(),
        Caller::Design(..) => s
            .on_store(move |store| store.design_by_token(&token))
            .await?
            .iter()
            .map(|(d, r)| design_json(d, Some(*r)))
            .collect(),
    };
    Ok(axum::Json(json!({ "designs": list })).into_response())
}

/// Body of `POST /api/designs`.
#[derive(Debug, Deserialize)]
pub struct CreateDesign {
    /// Name of the new design.
    pub name: String,
    /// Control points along u (default 16).
    #[serde(default)]
    pub nu: Option<usize>,
    /// Control points along v (default 12).
    #[serde(default)]
    pub nv: Option<usize>,
    /// `"bottle"`: the styling-curve bottle network (paper 004) instead of
    /// a plate.
    #[serde(default)]
    pub template: Option<String>,
}

async fn create_design(
    State(s): State<AppState>,
    headers: HeaderMap,
    Query(q): Q,
    body: Bytes,
) -> Result<Response, ApiError> {
    let token = request_token(&headers, &q).ok_or_else(unauthorized)?;
    match s.caller(&token).await? {
        Some(Caller::Admin) | Some(Caller::Design(_, Role::Editor)) => {}
        _ => return Err(unauthorized()),
    }
    let req: CreateDesign = serde_json::from_slice(&body)
        .map_err(|e| ApiError(StatusCode::BAD_REQUEST, "malformed", e.to_string()))?;
    let name = req.name.trim();
    crate::design::demo::check_name(name)?;
    let (nu, nv) = (req.nu.unwrap_or(16), req.nv.unwrap_or(12));
    if !(4..=200).contains(&nu) || !(4..=200).contains(&nv) {
        return Err(ApiError(
            StatusCode::BAD_REQUEST,
            "out_of_range",
            "nu and nv must be between 4 and 200".into(),
        ));
    }
    let doc = match req.template.as_deref() {
        None => crate::design::demo::plate(name, nu, nv)?,
        Some("bottle") => crate::design::network_demo::bottle_design(name)?,
        Some(other) => {
            return Err(ApiError(
                StatusCode::BAD_REQUEST,
                "out_of_range",
                format!("no template {other:?} (known: \"bottle\")"),
            ));
        }
    };
    let rec = s.hub.create(doc, "rest").await?;
    Ok((
        StatusCode::CREATED,
        axum::Json(json!({
            "id": rec.id,
            "name": rec.name,
            "tokens": { "editor": rec.tokens.editor, "viewer": rec.tokens.viewer, "device": rec.tokens.device }
        })),
    )
        .into_response())
}

async fn get_design(
    State(s): State<AppState>,
    Path(id): Path<DesignId>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    let role = need_role(&s, &headers, &q, id).await?;
    let handle = s.hub.open(id).await?;
    let view = handle.state().await?;
    Ok(axum::Json(json!({
        "id": id,
        "role": role,
        "revision": view.revision,
        "design": &*view.doc,
    }))
    .into_response())
}

async fn list_versions(
    State(s): State<AppState>,
    Path(id): Path<DesignId>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    need_role(&s, &headers, &q, id).await?;
    let v = s.on_store(move |store| store.versions(id)).await?;
    Ok(axum::Json(json!({ "id": id, "versions": v })).into_response())
}

async fn get_version(
    State(s): State<AppState>,
    Path((id, number)): Path<(DesignId, u64)>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    need_role(&s, &headers, &q, id).await?;
    let v = s.on_store(move |store| store.version(id, number)).await?;
    let (info, bytes) = v.ok_or_else(|| {
        ApiError(
            StatusCode::NOT_FOUND,
            "unknown_version",
            format!("design {id} has no version {number}"),
        )
    })?;
    let doc = crate::design::DesignDoc::from_bytes(&bytes)?;
    Ok(axum::Json(json!({ "id": id, "version": info, "design": doc })).into_response())
}

/// `GET /api/designs/{id}/comments`: every comment of the design with its
/// replies, oldest first, as a snapshot's `comments` (protocol/README.md);
/// any token that may join the design over `/ws` may read them.
async fn list_comments(
    State(s): State<AppState>,
    Path(id): Path<DesignId>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    need_role(&s, &headers, &q, id).await?;
    let rows = s.on_store(move |store| store.comments(id)).await?;
    // Every stored row, whatever a server's configured limit.
    let book = crate::design::comments::CommentBook::new(rows, usize::MAX);
    let comments: Vec<_> = book
        .view()
        .iter()
        .map(crate::convert::comments::thread_to_wire)
        .collect();
    Ok(axum::Json(json!({ "id": id, "comments": comments })).into_response())
}

async fn import(
    State(s): State<AppState>,
    Path(id): Path<DesignId>,
    headers: HeaderMap,
    Query(q): Q,
    body: Bytes,
) -> Result<Response, ApiError> {
    let role = need_role(&s, &headers, &q, id).await?;
    if !role.can_manage() {
        return Err(ApiError(
            StatusCode::FORBIDDEN,
            "forbidden",
            "only an editor may import".into(),
        ));
    }
    let text = std::str::from_utf8(&body).map_err(|_| {
        ApiError(
            StatusCode::BAD_REQUEST,
            "malformed",
            "IGES must be ASCII".into(),
        )
    })?;
    let text = text.to_owned();
    drop(body);
    let target = part_param(&q)?;
    let handle = s.hub.open(id).await?;
    let current = handle.state().await?;
    // Parsing and building the new parts are CPU work proportional to the
    // file: off the async threads.
    let (doc, added) = tokio::task::spawn_blocking(move || {
        let parts = cad::read_iges_parts(&text).map_err(|e| {
            let code = match e {
                cad::IgesError::TooLarge { .. } => "out_of_range",
                _ => "malformed",
            };
            ApiError(StatusCode::BAD_REQUEST, code, format!("IGES: {e}"))
        })?;
        drop(text);
        match target {
            // `?part=ID`: the file's first surface replaces that surface
            // part's shape (its icons are kept where they still fit).
            Some(part_id) => {
                let surface = parts
                    .iter()
                    .find_map(|p| match &p.entity {
                        cad::IgesEntity::Surface(s) => Some(s),
                        _ => None,
                    })
                    .ok_or_else(|| {
                        ApiError(
                            StatusCode::BAD_REQUEST,
                            "malformed",
                            "IGES: the file has no surface (entity 128)".into(),
                        )
                    })?;
                let mut doc = (*current.doc).clone();
                let part = doc.part_mut(part_id).ok_or_else(|| {
                    ApiError(
                        StatusCode::NOT_FOUND,
                        "unknown_part",
                        format!("design {id} has no part {part_id}"),
                    )
                })?;
                let crate::design::part::PartBody::Surface(sp) = &mut part.body else {
                    return Err(ApiError(
                        StatusCode::BAD_REQUEST,
                        "incompatible",
                        format!("part {part_id} is not a surface"),
                    ));
                };
                *sp = crate::design::model::with_surface(sp, surface)?;
                Ok::<_, ApiError>((doc, vec![part_id]))
            }
            // Every surface and curve of the file becomes a new part.
            None => Ok(crate::design::exchange::with_iges_parts(
                &current.doc,
                &parts,
            )?),
        }
    })
    .await
    .map_err(storage)??;
    handle.replace(doc).await?;
    let view = handle.state().await?;
    Ok(axum::Json(json!({ "id": id, "parts": added, "design": &*view.doc })).into_response())
}

async fn export(
    State(s): State<AppState>,
    Path((id, file)): Path<(DesignId, String)>,
    headers: HeaderMap,
    Query(q): Q,
) -> Result<Response, ApiError> {
    need_role(&s, &headers, &q, id).await?;
    let ext = file.strip_prefix("export.").ok_or_else(|| {
        ApiError(
            StatusCode::NOT_FOUND,
            "unknown_message",
            format!("no resource {file}"),
        )
    })?;
    // None: IGES (the exact surface); Some: a mesh format.
    let (ctype, format) = match ext {
        "igs" => ("model/iges", None),
        "obj" => ("model/obj", Some(MeshFormat::Obj)),
        "stl" => ("model/stl", Some(MeshFormat::Stl)),
        "gltf" => ("model/gltf+json", Some(MeshFormat::Gltf)),
        "vtu" => ("model/vnd.vtu+xml", None),
        _ => {
            return Err(ApiError(
                StatusCode::NOT_FOUND,
                "unknown_message",
                format!("unknown export format {ext} (igs, obj, stl, gltf, vtu)"),
            ));
        }
    };
    let part = part_param(&q)?;
    let handle = s.hub.open(id).await?;
    let doc = handle.state().await?.doc.clone();
    let body = match format {
        None if ext == "vtu" => crate::export::vtu(doc, part).await,
        None => crate::export::iges(doc, part).await,
        Some(f) => crate::export::mesh(doc, part, f, s.config.export_max_vertices).await,
    }
    .map_err(|e| match e {
        crate::export::ExportError::Part(m) => ApiError(StatusCode::NOT_FOUND, "unknown_part", m),
        e => ApiError(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()),
    })?;
    let disposition = format!("attachment; filename=\"design-{id}.{ext}\"");
    Ok((
        [
            (header::CONTENT_TYPE, ctype.to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        body,
    )
        .into_response())
}

/// The paper 002 demo body (cube → spool) as a `create_part` spec, for a
/// page's "add spool" button: public data, no token needed.
async fn spool_spec() -> Result<Response, ApiError> {
    let part = crate::design::body_demo::spool_part()
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.message))?;
    Ok(axum::Json(crate::convert::parts::body_spec("spool", &part)).into_response())
}

/// The whole router.
pub fn router(state: AppState) -> Router {
    let web = crate::web::router(&state.config.web_dir);
    let limit = state.config.max_body_bytes;
    Router::new()
        .route("/healthz", get(healthz))
        .route("/metrics", get(metrics))
        .route("/ws", get(crate::ws::upgrade))
        .route("/api/designs", get(list_designs).post(create_design))
        .route("/api/designs/{id}", get(get_design))
        .route("/api/designs/{id}/versions", get(list_versions))
        .route("/api/designs/{id}/versions/{v}", get(get_version))
        .route("/api/designs/{id}/comments", get(list_comments))
        .route("/api/designs/{id}/import", post(import))
        .route("/api/designs/{id}/{file}", get(export))
        .route("/api/demo-parts/spool", get(spool_spec))
        .layer(DefaultBodyLimit::max(limit))
        .layer(axum::middleware::map_response(
            crate::rejection::json_errors,
        ))
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            crate::origin::check,
        ))
        .with_state(state)
        .merge(web)
        .layer(axum::middleware::map_response(no_referrer))
}

/// Every answer says `Referrer-Policy: no-referrer`, so no page of this
/// server leaks its address (which may hold a token) to another site.
async fn no_referrer(mut res: Response) -> Response {
    res.headers_mut().insert(
        header::REFERRER_POLICY,
        axum::http::HeaderValue::from_static("no-referrer"),
    );
    res
}
