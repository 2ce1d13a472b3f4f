//! vsculpt-logging: the logging of the vsculpt daemons (server and device
//! bridge), built so that logging can never hurt the service.
//!
//! * Lines go through a [`LossyWriter`]: a bounded queue and one writer
//!   thread. A closed stderr (a log reader that went away: `… | head`, a
//!   closed terminal, a restarted log shipper), a full disk or a stuck pipe
//!   drops lines — counted, see [`dropped_lines`] — and never blocks, fails or
//!   panics the task that logged.
//! * `--log-file PATH` writes to `PATH.YYYY-MM-DD` in PATH's directory,
//!   a new file every day (UTC), keeping the last [`KEEP_DAYS`] files.
//! * `--log-format json` writes one JSON object per line (timestamp, level,
//!   target, fields) for log shippers; `text` (the default) is for people.
//! * `RUST_LOG` filters as usual.

mod lossy;

pub use lossy::{LossyWriter, QUEUE_LINES};

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::Duration;
use thiserror::Error;
use tracing_subscriber::layer::SubscriberExt;
use tracing_subscriber::util::SubscriberInitExt;
use tracing_subscriber::{EnvFilter, Layer, Registry};

/// Rotated log files kept (one per day).
pub const KEEP_DAYS: usize = 31;

/// How log lines are written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LogFormat {
    /// Human-readable lines.
    #[default]
    Text,
    /// One JSON object per line.
    Json,
}

/// The logging options both daemons take on their command line.
#[derive(Clone, Debug, Default, PartialEq, Eq, clap::Args)]
pub struct LogArgs {
    /// Write logs to PATH.YYYY-MM-DD (a new file each day) instead of stderr.
    #[arg(long, value_name = "PATH", global = true)]
    pub log_file: Option<PathBuf>,
    /// Log line format.
    #[arg(long, value_enum, default_value_t = LogFormat::Text, global = true)]
    pub log_format: LogFormat,
}

/// Why logging could not be set up.
#[derive(Debug, Error)]
pub enum LogError {
    /// The log file (or its directory) cannot be created.
    #[error("log file {path}: {message}")]
    File {
        /// The `--log-file` given.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// The writer thread could not be started.
    #[error("cannot start the log writer: {0}")]
    Thread(#[from] std::io::Error),
    /// A global subscriber was already installed.
    #[error("logging is already set up")]
    AlreadySet,
}

static DROPPED: OnceLock<Arc<AtomicU64>> = OnceLock::new();

fn counter() -> Arc<AtomicU64> {
    DROPPED.get_or_init(|| Arc::new(AtomicU64::new(0))).clone()
}

/// Log lines dropped since start (reader gone, sink failing, queue full).
pub fn dropped_lines() -> u64 {
    DROPPED.get().map_or(0, |c| c.load(Ordering::Relaxed))
}

/// The installed logging; keep it to flush at exit.
#[derive(Debug)]
pub struct Logging {
    writer: LossyWriter,
}

impl Logging {
    /// Writes out what is queued, waiting at most `timeout`; false when the
    /// sink did not take it in time (the lines stay queued or are dropped).
    pub fn flush(&self, timeout: Duration) -> bool {
        self.writer.flush(timeout)
    }

    /// Lines dropped so far.
    pub fn dropped(&self) -> u64 {
        self.writer.dropped()
    }
}

fn rolling_file(path: &Path) -> Result<Box<dyn std::io::Write + Send>, LogError> {
    let err = |message: String| LogError::File {
        path: path.to_path_buf(),
        message,
    };
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .filter(|n| !n.is_empty())
        .ok_or_else(|| err("needs a file name".into()))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| err(e.to_string()))?;
    let appender = tracing_appender::rolling::RollingFileAppender::builder()
        .rotation(tracing_appender::rolling::Rotation::DAILY)
        .filename_prefix(name)
        .max_log_files(KEEP_DAYS)
        .build(&dir)
        .map_err(|e| err(e.to_string()))?;
    Ok(Box::new(appender))
}

/// Builds the writer for `args`: stderr or the rotated file, behind a
/// [`LossyWriter`] counting into the process-wide [`dropped_lines`].
pub fn writer(args: &LogArgs) -> Result<LossyWriter, LogError> {
    let sink: Box<dyn std::io::Write + Send> = match &args.log_file {
        Some(p) => rolling_file(p)?,
        None => Box::new(std::io::stderr()),
    };
    Ok(LossyWriter::spawn(sink, QUEUE_LINES, counter())?)
}

/// Installs the global subscriber: `args`' sink and format, filtered by
/// `RUST_LOG` or else `default_filter` (e.g. `"info"`).
pub fn init(args: &LogArgs, default_filter: &str) -> Result<Logging, LogError> {
    let writer = writer(args)?;
    let ansi = args.log_file.is_none()
        && args.log_format == LogFormat::Text
        && std::io::IsTerminal::is_terminal(&std::io::stderr());
    let filter =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default_filter));
    let layer: Box<dyn Layer<Registry> + Send + Sync> = match args.log_format {
        LogFormat::Text => tracing_subscriber::fmt::layer()
            .with_writer(writer.clone())
            .with_ansi(ansi)
            .log_internal_errors(false)
            .boxed(),
        LogFormat::Json => tracing_subscriber::fmt::layer()
            .json()
            .with_writer(writer.clone())
            .log_internal_errors(false)
            .boxed(),
    };
    tracing_subscriber::registry()
        .with(layer)
        .with(filter)
        .try_init()
        .map_err(|_| LogError::AlreadySet)?;
    Ok(Logging { writer })
}
