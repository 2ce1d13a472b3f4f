//! vsculpt-server: the headless sculpting service. It owns every design
//! (one actor task each, holding the kernel state), serves the web client,
//! fans geometry out to WebSocket clients, persists designs and versions in
//! an embedded SQLite store and exchanges surfaces as IGES and meshes.
//!
//! The binary (`src/main.rs`) only parses the command line and prints the
//! banner; everything else lives here so tests and benches can start a real
//! server in-process ([`server::Server`], [`server::serve`]).

pub mod app;
pub mod cad;
pub mod config;
pub mod convert;
pub mod design;
pub mod export;
pub mod metrics;
pub mod origin;
pub mod permissions;
pub mod rejection;
pub mod server;
pub mod shutdown;
pub mod store;
pub mod tls;
pub mod web;
pub mod ws;
