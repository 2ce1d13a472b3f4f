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

/// What `--help` says about the configuration file.
pub const CONFIG_HELP: &str = "\
Configuration: a TOML file (--config FILE, else ./vsculpt-bridge.toml when it exists).
Every setting is shown, with its default, in vsculpt-bridge.example.toml next to this
program's sources; `vsculpt-bridge check-config FILE` validates a file and prints the
effective settings. Sections and keys:
  [server]       url (the server's \"device:\" link), token, design
  [calibration]  translation, rotation (x, y, z, w), scale
  [[device]]     name, kind (flock | fastrak | cyberglove | spacemouse_hid | spacenavd | vrpn),
                 port, baud, address (VRPN: Tracker0@host[:port] or Tracker0@tcp://host:port),
                 settle_ms, poll_hz, and per kind flock = {…}, fastrak = {…},
                 cyberglove = {…}, spacemouse = {…}, spacenavd = {…}, vrpn = {…};
                 3D mice full_scale, deadzone, axis_scale, axis_signs (x y z rx ry rz);
                 trackers also gate = {max_speed, max_acceleration, noise,
                 max_angular_speed, angular_noise, confirm, max_gap}
  [[hand]]       name, tracker, sensor, glove, reach, calibration = {open, closed}
  [menu]         device, buttons, speed, rotation_speed
  [rates]        drag_hz";

/// vsculpt device bridge: 3D mice, 6-DOF trackers and data gloves driving icons.
#[derive(Debug, Parser)]
#[command(name = "vsculpt-bridge", version, after_help = CONFIG_HELP)]
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
    /// Validate a configuration file and print the effective settings (defaults
    /// filled in, tokens hidden); exit code 2 when it is not valid.
    CheckConfig {
        /// The TOML file.
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

/// The effective settings of `c` as TOML, with the server token hidden.
pub fn effective_settings(c: &Config) -> String {
    let mut c = c.clone();
    if let Some((head, tail)) = c.server.url.split_once("token=") {
        let rest = tail.find('&').map_or("", |i| &tail[i..]);
        c.server.url = format!("{head}token=<hidden>{rest}");
    }
    if c.server.token.is_some() {
        c.server.token = Some("<hidden>".into());
    }
    c.to_toml()
}

fn check_config(file: &Path) -> ExitCode {
    match Config::load(file) {
        Ok(c) => {
            println!(
                "# {}: valid — {} device(s), {} hand(s); effective settings:",
                file.display(),
                c.devices.len(),
                c.hands.len()
            );
            print!("{}", effective_settings(&c));
            ExitCode::SUCCESS
        }
        Err(e) => {
            say(&format!("{}: {e}", file.display()));
            ExitCode::from(2)
        }
    }
}

/// Runs the command line with `wire` as the protocol mapping.
pub fn main(wire: Arc<dyn Wire>) -> ExitCode {
    let args = Args::parse();
    if let Some(Action::CheckConfig { file }) = &args.command {
        return check_config(file);
    }
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
    let rt = match crate::bridge::runtime() {
        Ok(rt) => rt,
        Err(e) => {
            say(&format!("cannot start the runtime: {e}"));
            return ExitCode::FAILURE;
        }
    };
    let result = rt.block_on(async {
        match args.command.unwrap_or(Action::Run) {
            Action::Run | Action::CheckConfig { .. } => run_live(config, wire, None, stop_signal())
                .await
                .map(|_| ()),
            Action::Record { file } => run_live(config, wire, Some(&file), stop_signal())
                .await
                .map(|_| ()),
            Action::Replay { file, speed } => {
                if !(speed.is_finite() && speed > 0.0) {
                    return Err(
                        RecordingError::Format("--speed must be a positive number".into()).into(),
                    );
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
