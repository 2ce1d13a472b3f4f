//! The command line: `vsculpt-bridge [--config FILE] [--server URL] [--list | run |
//! record FILE | replay FILE [--speed X]]`. `main.rs` only calls [`main`].

use crate::bridge::{run_live, run_replay};
use crate::config::Config;
use crate::link::Wire;
use crate::listing;
use crate::recording::RecordingError;
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

/// Default configuration file, used when present and no `--config` is given.
pub const DEFAULT_CONFIG: &str = "vsculpt-bridge.toml";

/// vsculpt device bridge: 3D mice, 6-DOF trackers and data gloves driving icons.
#[derive(Debug, Parser)]
#[command(name = "vsculpt-bridge", version)]
pub struct Args {
    /// TOML configuration (default: ./vsculpt-bridge.toml when it exists).
    #[arg(long, short)]
    pub config: Option<PathBuf>,
    /// Server device URL (overrides the configuration), as the server prints it.
    #[arg(long)]
    pub server: Option<String>,
    /// List HID devices, serial ports, spacenavd and VRPN sources, then exit.
    #[arg(long)]
    pub list: bool,
    /// Logging: `--log-file PATH` (rotated daily), `--log-format text|json`.
    #[command(flatten)]
    pub log: vsculpt_logging::LogArgs,
    /// What to do (default: run).
    #[command(subcommand)]
    pub command: Option<Action>,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Action {
    /// Run the configured devices against the server.
    Run,
    /// Run, and keep every raw device frame with its timestamp in FILE.
    Record {
        /// Recording to write.
        file: PathBuf,
    },
    /// Feed a recording back through the same parsers to the server.
    Replay {
        /// Recording to read.
        file: PathBuf,
        /// Playback speed (1 = real time).
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
    },
}

fn load_config(args: &Args) -> Result<Config, String> {
    let mut c = match &args.config {
        Some(p) => Config::load(p).map_err(|e| e.to_string())?,
        None if Path::new(DEFAULT_CONFIG).exists() => {
            Config::load(Path::new(DEFAULT_CONFIG)).map_err(|e| e.to_string())?
        }
        None => Config::default(),
    };
    if let Some(url) = &args.server {
        c.server.url = url.clone();
    }
    Ok(c)
}

/// Resolves on Ctrl-C or SIGTERM.
async fn stop_signal() {
    let ctrl_c = async {
        if tokio::signal::ctrl_c().await.is_err() {
            std::future::pending::<()>().await;
        }
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {}
        _ = term => {}
    }
    tracing::info!("stopping");
}

/// Writes a line to stderr, ignoring a closed or failing stderr.
fn say(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "vsculpt-bridge: {line}");
}

/// Runs the command line with `wire` as the protocol mapping.
pub fn main(wire: Arc<dyn Wire>) -> ExitCode {
    let args = Args::parse();
    let logging = match vsculpt_logging::init(&args.log, "info") {
        Ok(l) => l,
        Err(e) => {
            say(&e.to_string());
            return ExitCode::from(2);
        }
    };
    let code = run(args, wire);
    logging.flush(std::time::Duration::from_millis(200));
    code
}

fn run(args: Args, wire: Arc<dyn Wire>) -> ExitCode {
    let config = match load_config(&args) {
        Ok(c) => c,
        Err(e) => {
            say(&e);
            return ExitCode::from(2);
        }
    };
    if args.list {
        use std::io::Write;
        let _ = write!(
            std::io::stdout(),
            "{}",
            listing::probe(Some(&config)).render()
        );
        return ExitCode::SUCCESS;
    }
    let rt = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            say(&format!("cannot start the runtime: {e}"));
            return ExitCode::FAILURE;
        }
    };
    let result = rt.block_on(async {
        match args.command.unwrap_or(Action::Run) {
            Action::Run => run_live(config, wire, None, stop_signal())
                .await
                .map(|_| ()),
            Action::Record { file } => run_live(config, wire, Some(&file), stop_signal())
                .await
                .map(|_| ()),
            Action::Replay { file, speed } => {
                if !(speed.is_finite() && speed > 0.0) {
                    return Err(RecordingError::Format(
                        "--speed must be a positive number".into(),
                    ));
                }
                run_replay(config, wire, &file, speed, stop_signal())
                    .await
                    .map(|n| {
                        tracing::info!(samples = n, "replay finished");
                    })
            }
        }
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            say(&e.to_string());
            ExitCode::FAILURE
        }
    }
}
