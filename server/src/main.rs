//! The `vsculpt-server` binary: parse the command line, set up logging that
//! cannot hurt the service (see `vsculpt-logging`), bind, print the start
//! banner to stdout (the one deliberate write to stdout: API.md §4 fixes its
//! lines so scripts and tests can parse them), and serve until SIGTERM or
//! Ctrl-C — the first ends the process within [`SHUTDOWN_DEADLINE`] (after
//! flushing every design that can be flushed), a second at once.

use clap::Parser;
use std::io::Write;
use std::process::ExitCode;
use std::time::Duration;
use vsculpt_server::config::{Cli, Config, Maintenance};
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::{Shutdown, watch_os_signals};

/// Longest time from the first signal to the end of the process.
const SHUTDOWN_DEADLINE: Duration = Duration::from_millis(2700);
/// How long the logs get to drain at exit.
const LOG_FLUSH: Duration = Duration::from_millis(200);

/// Writes a line to stderr, ignoring a closed or failing stderr.
fn say(line: &str) {
    let _ = writeln!(std::io::stderr(), "vsculpt-server: {line}");
}

/// Runs `backup` or `restore`; one line on stdout on success.
fn maintain(data: &std::path::Path, job: Maintenance) -> ExitCode {
    use vsculpt_server::store::backup::{backup, restore};
    let (done, what) = match &job {
        Maintenance::Backup { out, force } => (backup(data, out, *force), "backed up"),
        Maintenance::Restore {
            backup: file,
            force,
        } => (restore(file, data, *force), "restored"),
    };
    match done {
        Ok(c) => {
            let _ = writeln!(
                std::io::stdout(),
                "{what} {} designs, {} versions",
                c.designs,
                c.versions
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            say(&e.to_string());
            ExitCode::FAILURE
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(job) = cli.command.clone() {
        return maintain(&cli.data, job);
    }
    let logging = match vsculpt_logging::init(&cli.log, "info,tower_http=warn") {
        Ok(l) => std::sync::Arc::new(l),
        Err(e) => {
            say(&e.to_string());
            return ExitCode::from(2);
        }
    };
    let rt = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            say(&format!("cannot start the runtime: {e}"));
            return ExitCode::FAILURE;
        }
    };
    let shutdown = Shutdown::new();
    let flusher = logging.clone();
    if let Err(e) = watch_os_signals(shutdown.clone(), SHUTDOWN_DEADLINE, move || {
        flusher.flush(LOG_FLUSH);
    }) {
        say(&format!("cannot watch signals: {e}"));
        return ExitCode::FAILURE;
    }
    let code = rt.block_on(serve(cli, shutdown));
    // Anything still running (a writer stuck on a dead disk) is abandoned.
    rt.shutdown_timeout(Duration::from_millis(200));
    logging.flush(LOG_FLUSH);
    code
}

async fn serve(cli: Cli, shutdown: Shutdown) -> ExitCode {
    let listener = match tokio::net::TcpListener::bind(cli.listen).await {
        Ok(l) => l,
        Err(e) => {
            tracing::error!("cannot listen on {}: {e}", cli.listen);
            say(&format!("cannot listen on {}: {e}", cli.listen));
            return ExitCode::FAILURE;
        }
    };
    let server = match Server::start(listener, Config::from(&cli), shutdown).await {
        Ok(s) => s,
        Err(e) => {
            tracing::error!("cannot start: {e}");
            say(&format!("cannot start: {e}"));
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
    match server.run().await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!("server failed: {e}");
            ExitCode::FAILURE
        }
    }
}
