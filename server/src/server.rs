//! Starting and stopping the whole service: lock the data directory (one
//! server owns it, see `store::lock`), open the store (creating the demo
//! design on first start), bind the router to a listener, serve until
//! the shutdown signal, then stop every design actor so working states are
//! flushed. [`Server::links`] gives the start banner of API.md §4.

use crate::app::{self, Shared};
use crate::config::Config;
use crate::design::Hub;
use crate::metrics::Metrics;
use crate::shutdown::Shutdown;
use crate::store::{DesignRecord, Store, StoreError};
use axum::serve::ListenerExt;
use std::future::IntoFuture;
use std::net::SocketAddr;
use std::sync::Arc;
use thiserror::Error;
use tokio::net::TcpListener;

/// Why the server could not start or run.
#[derive(Debug, Error)]
pub enum ServerError {
    /// The store failed.
    #[error("store: {0}")]
    Store(#[from] StoreError),
    /// Binding or serving failed.
    #[error("network: {0}")]
    Io(#[from] std::io::Error),
    /// The demo design could not be built.
    #[error("demo design: {0}")]
    Demo(String),
    /// Some design actors did not flush their working state in time at
    /// shutdown (the others did).
    #[error("some designs could not flush their working state in time")]
    Unflushed,
    /// Another server owns the data directory.
    #[error("{0}")]
    Locked(#[from] crate::store::lock::LockError),
    /// The TLS certificate or key could not be loaded.
    #[error("{0}")]
    Tls(#[from] crate::tls::TlsError),
}

/// How long open connections get to close after the shutdown signal.
pub const DRAIN: std::time::Duration = std::time::Duration::from_millis(1000);
/// How long the design actors get to flush after the connections closed.
pub const STOP_ACTORS: std::time::Duration = std::time::Duration::from_millis(1200);

/// A started server (store open, listener bound), not yet serving.
pub struct Server {
    /// Held until [`Server::run`] returns: no other server uses the directory.
    lock: crate::store::lock::DataDirLock,
    shared: Arc<Shared>,
    listener: TcpListener,
    addr: SocketAddr,
    tls: Option<Arc<tokio_rustls::rustls::ServerConfig>>,
}

fn read_or_create_admin_token(config: &Config) -> Result<String, ServerError> {
    let path = config.data_dir.join("admin-token");
    if let Ok(t) = std::fs::read_to_string(&path) {
        let t = t.trim().to_string();
        if t.len() >= 32 {
            return Ok(t);
        }
    }
    let token =
        crate::store::tokens::random_token().map_err(|e| ServerError::Demo(e.to_string()))?;
    std::fs::write(&path, format!("{token}\n"))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600))?;
    }
    Ok(token)
}

impl Server {
    /// Opens the store in `config.data_dir` (creating the demo design when
    /// the store is empty and `config.demo`) and takes `listener`.
    pub async fn start(
        listener: TcpListener,
        config: Config,
        shutdown: Shutdown,
    ) -> Result<Self, ServerError> {
        let addr = listener.local_addr()?;
        // A bad certificate or key stops the start, before anything else.
        let tls = config.tls.as_ref().map(crate::tls::load).transpose()?;
        let lock = crate::store::lock::DataDirLock::acquire(&config.data_dir)?;
        let dir = config.data_dir.clone();
        let store = Arc::new(
            tokio::task::spawn_blocking(move || {
                crate::permissions::private_dir(&dir)?;
                let store = Store::open(&dir)?;
                store.ensure_token_indexes()?;
                crate::permissions::private_db_files(&dir)?;
                Ok::<_, ServerError>(store)
            })
            .await
            .map_err(|e| ServerError::Demo(e.to_string()))??,
        );
        let admin_token = read_or_create_admin_token(&config)?;
        let metrics = Arc::new(Metrics::new());
        let hub = Hub::new(store.clone(), metrics.clone(), config.persist_delay)
            .with_comment_limit(config.max_comments);
        let empty = {
            let s = store.clone();
            tokio::task::spawn_blocking(move || s.designs())
                .await
                .map_err(|e| ServerError::Demo(e.to_string()))??
                .is_empty()
        };
        if empty && config.demo {
            let doc = crate::design::demo::demo().map_err(|e| ServerError::Demo(e.to_string()))?;
            let rec = hub
                .create(doc, "vsculpt")
                .await
                .map_err(|e| ServerError::Demo(e.to_string()))?;
            tracing::info!(design = rec.id, "created the demo design");
        }
        let shared = Arc::new(Shared {
            config,
            store,
            metrics,
            hub,
            admin_token,
            next_client: std::sync::atomic::AtomicU64::new(1),
            shutdown,
        });
        Ok(Self {
            lock,
            shared,
            listener,
            addr,
            tls,
        })
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The registry of design actors (tests drive fault injection through it).
    pub fn hub(&self) -> crate::design::Hub {
        self.shared.hub.clone()
    }

    /// The administrator token (also in `DATA/admin-token`).
    pub fn admin_token(&self) -> &str {
        &self.shared.admin_token
    }

    /// Every live design with its tokens.
    pub fn designs(&self) -> Result<Vec<DesignRecord>, ServerError> {
        Ok(self.shared.store.designs()?)
    }

    /// The start banner, one line each, exactly as API.md §4 gives it.
    pub fn links(&self) -> Result<String, ServerError> {
        let (http, ws) = if self.tls.is_some() {
            ("https", "wss")
        } else {
            ("http", "ws")
        };
        let base = format!("{http}://{}", self.addr);
        let ws = format!("{ws}://{}", self.addr);
        let mut out = format!("vsculpt-server listening on {base}\nweb client: {base}/\n");
        for d in self.designs()? {
            // Escaped (quotes, line breaks, control characters) so a name
            // can neither end its quotes nor start a forged line.
            let (id, name) = (d.id, d.name.escape_debug().to_string());
            out.push_str(&format!(
                "design {id} \"{name}\" editor: {base}/?design={id}&token={}\n",
                d.tokens.editor
            ));
            out.push_str(&format!(
                "design {id} \"{name}\" viewer: {base}/?design={id}&token={}\n",
                d.tokens.viewer
            ));
            out.push_str(&format!(
                "design {id} \"{name}\" device: {ws}/ws?design={id}&token={}\n",
                d.tokens.device
            ));
        }
        Ok(out)
    }

    /// Serves until `shutdown` triggers, then stops every design actor
    /// (flushing working states to the store).
    pub async fn run(self) -> Result<(), ServerError> {
        let shared = self.shared.clone();
        let router = app::router(self.shared.clone());
        let stop = shared.shutdown.clone();
        tracing::info!(addr = %self.addr, "serving");
        // Replies and geometry frames are small writes that must leave at
        // once: without TCP_NODELAY, Nagle holds each one until the peer's
        // delayed ACK (~40 ms on Linux) when a previous write is unacked.
        let nodelay = shared.config.tcp_nodelay;
        let graceful = async move { stop.wait().await };
        let serving: std::pin::Pin<Box<dyn Future<Output = std::io::Result<()>> + Send>> =
            match &self.tls {
                Some(config) => {
                    let listener =
                        crate::tls::TlsListener::new(self.listener, config.clone(), nodelay)?;
                    Box::pin(
                        axum::serve(listener, router)
                            .with_graceful_shutdown(graceful)
                            .into_future(),
                    )
                }
                None => {
                    let listener = self.listener.tap_io(move |tcp| {
                        if let Err(e) = tcp.set_nodelay(nodelay) {
                            tracing::debug!(
                                "cannot set TCP_NODELAY on an accepted connection: {e}"
                            );
                        }
                    });
                    Box::pin(
                        axum::serve(listener, router)
                            .with_graceful_shutdown(graceful)
                            .into_future(),
                    )
                }
            };
        // WebSocket tasks close on the signal; clients that do not answer
        // the close get DRAIN before the server stops anyway, and the design
        // actors get STOP_ACTORS to flush: the process ends well within the
        // 3 s a supervisor allows.
        let stop = shared.shutdown.clone();
        let served = tokio::select! {
            r = serving => r,
            _ = async {
                stop.wait().await;
                tokio::time::sleep(DRAIN).await;
            } => Ok(()),
        };
        let flushed = tokio::time::timeout(STOP_ACTORS, shared.hub.stop_all())
            .await
            .is_ok();
        if flushed {
            tracing::info!("store flushed, server stopped");
        } else {
            tracing::error!("some designs could not flush their working state in time");
        }
        tracing::debug!(dir = %self.lock.dir().display(), "data directory released");
        drop(self.lock);
        served.map_err(ServerError::Io)?;
        if flushed {
            Ok(())
        } else {
            Err(ServerError::Unflushed)
        }
    }
}

/// Starts a server on `listener` and serves until `shutdown` triggers.
pub async fn serve(
    listener: TcpListener,
    config: Config,
    shutdown: Shutdown,
) -> Result<(), ServerError> {
    Server::start(listener, config, shutdown).await?.run().await
}
