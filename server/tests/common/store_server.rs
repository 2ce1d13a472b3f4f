//! An in-process server that keeps a handle on its store, for the tests
//! that inject store faults (`fault-injection`: stall, read-only, page cap)
//! while clients work: the commit stall, the slow disk and the full disk.

use std::net::SocketAddr;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;
use vsculpt_server::config::Config;
use vsculpt_server::server::{Server, ServerError};
use vsculpt_server::shutdown::Shutdown;
use vsculpt_server::store::{DesignRecord, Store};

use crate::common::ws::Client;

/// A running server, its store and its first design.
pub struct StoreServer {
    pub addr: SocketAddr,
    pub store: Arc<Store>,
    pub admin: String,
    pub design: DesignRecord,
    pub shutdown: Shutdown,
    pub serving: tokio::task::JoinHandle<Result<(), ServerError>>,
}

impl StoreServer {
    /// Starts the server on `data` (no web client) with the working state
    /// written `persist_delay` after an edit.
    pub async fn start(data: &Path, persist_delay: Duration) -> Self {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let mut config = Config::new(data.to_path_buf(), data.join("no-web-client"));
        config.persist_delay = persist_delay;
        let shutdown = Shutdown::new();
        let server = Server::start(listener, config, shutdown.clone())
            .await
            .unwrap();
        let addr = server.local_addr();
        let store = server.hub().store().clone();
        let admin = server.admin_token().to_string();
        let design = server.designs().unwrap()[0].clone();
        let serving = tokio::spawn(server.run());
        Self {
            addr,
            store,
            admin,
            design,
            shutdown,
            serving,
        }
    }

    /// An editor of the first design, joined as `name`.
    pub async fn connect(&self, name: &str) -> Client {
        Client::connect(self.addr, self.design.id, &self.design.tokens.editor, name).await
    }

    /// Triggers shutdown and waits until the server has stopped cleanly
    /// (its final working-state write included).
    pub async fn stop(self) {
        self.shutdown.trigger();
        self.serving.await.unwrap().unwrap();
    }
}
