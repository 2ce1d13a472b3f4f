//! The registry of running design actors: starts an actor on first use from
//! the store's working state, hands out handles, deletes designs and stops
//! every actor (flushing its working state) at shutdown.

use super::actor::{self, DesignHandle, Request};
use super::error::{CommandError, ErrorKind};
use super::model::DesignDoc;
use crate::metrics::Metrics;
use crate::store::{DesignId, DesignRecord, Store};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::Mutex;

/// Every running design actor of one server.
pub struct Hub {
    store: Arc<Store>,
    metrics: Arc<Metrics>,
    persist_delay: Duration,
    running: Mutex<HashMap<DesignId, DesignHandle>>,
}

fn storage(e: impl std::fmt::Display) -> CommandError {
    CommandError::new(ErrorKind::Storage, e.to_string())
}

impl Hub {
    /// A hub over `store`.
    pub fn new(store: Arc<Store>, metrics: Arc<Metrics>, persist_delay: Duration) -> Self {
        Self {
            store,
            metrics,
            persist_delay,
            running: Mutex::new(HashMap::new()),
        }
    }

    /// The store.
    pub fn store(&self) -> &Arc<Store> {
        &self.store
    }

    /// The handle of design `id`, starting its actor when needed.
    pub async fn open(&self, id: DesignId) -> Result<DesignHandle, CommandError> {
        let mut running = self.running.lock().await;
        if let Some(h) = running.get(&id)
            && !h.is_closed()
        {
            return Ok(h.clone());
        }
        let store = self.store.clone();
        let loaded = tokio::task::spawn_blocking(move || -> Result<_, CommandError> {
            if store.design(id).map_err(storage)?.is_none() {
                return Err(CommandError::new(
                    ErrorKind::UnknownDesign,
                    format!("design {id} does not exist"),
                ));
            }
            Ok((
                store.working(id).map_err(storage)?,
                store.versions(id).map_err(storage)?,
            ))
        })
        .await
        .map_err(storage)??;
        let (working, versions) = loaded;
        let bytes = working.ok_or_else(|| {
            CommandError::new(
                ErrorKind::Storage,
                format!("design {id} has no working state"),
            )
        })?;
        let doc = DesignDoc::from_bytes(&bytes)?;
        let handle = actor::spawn(
            id,
            doc,
            versions,
            self.store.clone(),
            self.metrics.clone(),
            self.persist_delay,
        )?;
        running.insert(id, handle.clone());
        Ok(handle)
    }

    /// Creates a design from `doc` (stored, with version 1 = `doc`).
    pub async fn create(&self, doc: DesignDoc, author: &str) -> Result<DesignRecord, CommandError> {
        let store = self.store.clone();
        let author = author.to_string();
        tokio::task::spawn_blocking(move || {
            // Validate by building the model once (CPU work: off the async
            // threads, like the store writes).
            super::model::DesignModel::load(&doc)?;
            let bytes = doc.to_bytes();
            let rec = store.create_design(&doc.name, &bytes).map_err(storage)?;
            store
                .commit(rec.id, &author, "created", &bytes)
                .map_err(storage)?;
            Ok(rec)
        })
        .await
        .map_err(storage)?
    }

    /// Deletes design `id`: clients are told, its actor stops.
    pub async fn delete(&self, id: DesignId) -> Result<(), CommandError> {
        let store = self.store.clone();
        tokio::task::spawn_blocking(move || store.delete_design(id))
            .await
            .map_err(storage)?
            .map_err(|e| CommandError::new(ErrorKind::UnknownDesign, e.to_string()))?;
        if let Some(h) = self.running.lock().await.remove(&id) {
            let _ = h.send(Request::Delete).await;
        }
        Ok(())
    }

    /// Stops every actor, flushing working states.
    pub async fn stop_all(&self) {
        let handles: Vec<DesignHandle> =
            self.running.lock().await.drain().map(|(_, h)| h).collect();
        for h in handles {
            h.stop().await;
        }
    }
}
