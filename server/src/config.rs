//! Server configuration: the command line (clap) and the limits the
//! WebSocket and REST layers enforce.

use clap::Parser;
use std::net::SocketAddr;
use std::path::PathBuf;

/// `vsculpt-server` command line.
#[derive(Clone, Debug, Parser)]
#[command(
    name = "vsculpt-server",
    version,
    about = "The vsculpt sculpting service"
)]
pub struct Cli {
    /// Address to listen on (`127.0.0.1:0` picks a free port).
    #[arg(long, default_value = "127.0.0.1:7878")]
    pub listen: SocketAddr,
    /// Data directory (the embedded database lives here).
    #[arg(long, default_value = "./data", global = true)]
    pub data: PathBuf,
    /// The web client's folder (index.html, src/, node_modules/).
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../web-client"))]
    pub web_dir: PathBuf,
    /// Do not create the demo design on first start.
    #[arg(long)]
    pub no_demo: bool,
    /// Most vertices one mesh export (OBJ, STL, glTF) may have; the
    /// tessellation is coarsened to fit.
    #[arg(long, default_value_t = crate::export::DEFAULT_MAX_EXPORT_VERTICES)]
    pub export_max_vertices: usize,
    /// A web origin (e.g. `https://review.example.com`) besides the
    /// server's own whose pages may use the API and WebSocket; repeatable.
    #[arg(long = "allow-origin")]
    pub allow_origin: Vec<String>,
    /// Serve HTTPS and WSS with this PEM certificate chain (needs
    /// `--tls-key`).
    #[arg(long, requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// The PEM private key of `--tls-cert`.
    #[arg(long, requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// Logging: `--log-file PATH` (rotated daily), `--log-format text|json`.
    #[command(flatten)]
    pub log: vsculpt_logging::LogArgs,
    /// Instead of serving: back up or restore the data directory.
    #[command(subcommand)]
    pub command: Option<Maintenance>,
}

/// Data-directory maintenance (`vsculpt-server backup|restore`).
#[derive(Clone, Debug, clap::Subcommand)]
pub enum Maintenance {
    /// Copy the database of `--data` (a server may be running on it) into
    /// OUT as one consistent snapshot.
    Backup {
        /// The backup file to write.
        out: PathBuf,
        /// Overwrite OUT if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Make BACKUP the database of `--data` (no server may be running on it).
    Restore {
        /// A file written by `backup`.
        backup: PathBuf,
        /// Replace an existing database in `--data`.
        #[arg(long)]
        force: bool,
    },
}

/// Everything the server needs to run.
#[derive(Clone, Debug)]
pub struct Config {
    /// Data directory.
    pub data_dir: PathBuf,
    /// Web client folder.
    pub web_dir: PathBuf,
    /// Create the demo design when the store has no design.
    pub demo: bool,
    /// Largest WebSocket message accepted (bytes); larger ones get an error.
    pub max_message_bytes: usize,
    /// Largest HTTP request body (IGES import), bytes.
    pub max_body_bytes: usize,
    /// Delay after a change before the working state is written.
    pub persist_delay: std::time::Duration,
    /// Vertex budget of one mesh export.
    pub export_max_vertices: usize,
    /// Origins besides the server's own allowed to call `/ws` and the API.
    pub allowed_origins: Vec<String>,
    /// Set `TCP_NODELAY` on accepted connections (always, except in the
    /// latency bench's same-run baseline).
    pub tcp_nodelay: bool,
    /// Serve over TLS with these files (plain HTTP when `None`).
    pub tls: Option<crate::tls::TlsFiles>,
    /// Most review comments and replies one design may hold.
    pub max_comments: usize,
}

impl Config {
    /// Defaults for `data_dir`, serving `web_dir`.
    pub fn new(data_dir: PathBuf, web_dir: PathBuf) -> Self {
        Self {
            data_dir,
            web_dir,
            demo: true,
            max_message_bytes: 256 * 1024,
            max_body_bytes: 16 * 1024 * 1024,
            persist_delay: std::time::Duration::from_millis(500),
            export_max_vertices: crate::export::DEFAULT_MAX_EXPORT_VERTICES,
            allowed_origins: Vec::new(),
            tcp_nodelay: true,
            tls: None,
            max_comments: vsculpt_protocol::limits::MAX_COMMENTS_PER_DESIGN,
        }
    }
}

impl From<&Cli> for Config {
    fn from(cli: &Cli) -> Self {
        let mut c = Config::new(cli.data.clone(), cli.web_dir.clone());
        c.demo = !cli.no_demo;
        c.export_max_vertices = cli.export_max_vertices;
        c.allowed_origins = cli.allow_origin.clone();
        if let (Some(cert), Some(key)) = (&cli.tls_cert, &cli.tls_key) {
            c.tls = Some(crate::tls::TlsFiles {
                cert: cert.clone(),
                key: key.clone(),
            });
        }
        c
    }
}
