//! The WebSocket endpoint `/ws`: upgrade, then one task per connection
//! ([`connection`]) that authenticates the hello, joins the design's actor
//! and runs a reader and a writer ([`writer`]: latest-wins geometry,
//! ordered events, resync on lag; [`rate`]: per-client message limits;
//! [`pace`]: a send rate matched to a client's link).

pub mod connection;
pub mod join_geometry;
pub mod pace;
pub mod rate;
pub mod writer;

use crate::app::AppState;
use axum::extract::{Query, State, WebSocketUpgrade};
use axum::response::Response;
use std::collections::HashMap;

/// Hard cap on one WebSocket message; anything between the configured
/// application limit and this gets an error reply and the connection stays
/// up, beyond it the connection is closed by the WebSocket layer.
pub const HARD_MESSAGE_LIMIT: usize = 16 * 1024 * 1024;

/// `GET /ws`: upgrades to a WebSocket.
pub async fn upgrade(
    ws: WebSocketUpgrade,
    State(state): State<AppState>,
    Query(query): Query<HashMap<String, String>>,
) -> Response {
    ws.max_message_size(HARD_MESSAGE_LIMIT)
        .max_frame_size(HARD_MESSAGE_LIMIT)
        .on_upgrade(move |socket| connection::run(socket, state, query))
}
