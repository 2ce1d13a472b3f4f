//! The `vsculpt-server` binary: parse the command line, set up logging
//! (tracing to stderr), bind, print the start banner to stdout (the one
//! deliberate write to stdout: API.md §4 fixes its lines so scripts and
//! tests can parse them), and serve until Ctrl-C or SIGTERM.

use clap::Parser;
use std::io::Write;
use std::process::ExitCode;
use vsculpt_server::config::{Cli, Config};
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::{Shutdown, os_signal};

#[tokio::main]
async fn main() -> ExitCode {
    let cli = Cli::parse();
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "info,tower_http=warn".into()),
        )
        .init();
    let listener = match tokio::net::TcpListener::bind(cli.listen).await {
        Ok(l) => l,
        Err(e) => {
            tracing::error!("cannot listen on {}: {e}", cli.listen);
            return ExitCode::FAILURE;
        }
    };
    let shutdown = Shutdown::new();
    let server = match Server::start(listener, Config::from(&cli), shutdown.clone()).await {
        Ok(s) => s,
        Err(e) => {
            tracing::error!("cannot start: {e}");
            return ExitCode::FAILURE;
        }
    };
    match server.links() {
        Ok(banner) => {
            let mut out = std::io::stdout().lock();
            let _ = out.write_all(banner.as_bytes());
            let _ = out.flush();
        }
        Err(e) => tracing::error!("cannot list designs: {e}"),
    }
    let trigger = shutdown;
    tokio::spawn(async move {
        os_signal().await;
        trigger.trigger();
    });
    match server.run().await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!("server failed: {e}");
            ExitCode::FAILURE
        }
    }
}
