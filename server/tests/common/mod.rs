//! Shared test harness: start the real server in-process on an ephemeral
//! port (or as a child process), parse its banner, talk HTTP and WebSocket.

#![allow(dead_code)]

pub mod http;
pub mod parts;
pub mod random;
pub mod store_server;
pub mod ws;

use std::net::SocketAddr;
use std::path::PathBuf;
use vsculpt_server::config::Config;
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;

/// The tokens of one design as the banner printed them.
#[derive(Clone, Debug)]
pub struct DesignLinks {
    pub id: u64,
    pub name: String,
    pub editor: String,
    pub viewer: String,
    pub device: String,
}

/// Parses the banner of API.md §4.
pub fn parse_banner(text: &str) -> (SocketAddr, Vec<DesignLinks>) {
    let mut addr = None;
    let mut designs: Vec<DesignLinks> = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("vsculpt-server listening on http://") {
            addr = Some(rest.trim().parse().unwrap());
            continue;
        }
        let Some(rest) = line.strip_prefix("design ") else {
            continue;
        };
        let (id, rest) = rest.split_once(' ').unwrap();
        let id: u64 = id.parse().unwrap();
        let q1 = rest.find('"').unwrap();
        let q2 = rest.rfind('"').unwrap();
        let name = rest[q1 + 1..q2].to_string();
        let (kind, url) = rest[q2 + 2..].split_once(": ").unwrap();
        let token = url.split("token=").nth(1).unwrap().to_string();
        assert!(url.contains(&format!("design={id}")));
        let entry = match designs.iter_mut().find(|d| d.id == id) {
            Some(e) => e,
            None => {
                designs.push(DesignLinks {
                    id,
                    name,
                    editor: String::new(),
                    viewer: String::new(),
                    device: String::new(),
                });
                designs.last_mut().unwrap()
            }
        };
        match kind {
            "editor" => {
                assert!(url.starts_with("http://"));
                entry.editor = token
            }
            "viewer" => {
                assert!(url.starts_with("http://"));
                entry.viewer = token
            }
            "device" => {
                assert!(url.starts_with("ws://") && url.contains("/ws?"));
                entry.device = token
            }
            other => panic!("unknown link kind {other}"),
        }
    }
    (addr.expect("no listening line"), designs)
}

/// A fresh, empty data directory, under cargo's scratch folder for
/// integration tests (`CARGO_TARGET_TMPDIR`, inside the target directory),
/// never the system's temp folder: a test that stops early leaves nothing
/// behind outside the build.
pub fn data_dir(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("vsculpt-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An in-process server.
pub struct TestServer {
    pub addr: SocketAddr,
    pub designs: Vec<DesignLinks>,
    pub admin: String,
    pub shutdown: Shutdown,
    pub task: tokio::task::JoinHandle<()>,
}

impl TestServer {
    /// Starts a server on 127.0.0.1:0 over `data` (web client from `web`).
    pub async fn start_with(data: PathBuf, web: PathBuf) -> Self {
        Self::start_configured(data, web, |_| {}).await
    }

    /// Starts a server whose configuration `adjust` changes first.
    pub async fn start_configured(
        data: PathBuf,
        web: PathBuf,
        adjust: impl FnOnce(&mut Config),
    ) -> Self {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let mut config = Config::new(data, web);
        config.persist_delay = std::time::Duration::from_millis(100);
        adjust(&mut config);
        let shutdown = Shutdown::new();
        let server = Server::start(listener, config, shutdown.clone())
            .await
            .unwrap();
        let (addr, designs) = parse_banner(&server.links().unwrap());
        assert_eq!(addr, server.local_addr());
        let admin = server.admin_token().to_string();
        let task = tokio::spawn(async move {
            server.run().await.unwrap();
        });
        Self {
            addr,
            designs,
            admin,
            shutdown,
            task,
        }
    }

    /// Starts a server over `data` with no web client installed.
    pub async fn start(data: PathBuf) -> Self {
        let web = data.join("no-web-client");
        Self::start_with(data, web).await
    }

    /// The demo design.
    pub fn demo(&self) -> &DesignLinks {
        &self.designs[0]
    }

    /// Triggers shutdown and waits for the server to stop.
    pub async fn stop(self) {
        self.shutdown.trigger();
        tokio::time::timeout(std::time::Duration::from_secs(10), self.task)
            .await
            .expect("server did not stop")
            .unwrap();
    }
}

/// A server as a child process (for restart and kill -9 tests).
pub struct ChildServer {
    pub child: std::process::Child,
    pub addr: SocketAddr,
    pub designs: Vec<DesignLinks>,
}

impl ChildServer {
    /// Starts the binary over `data`; `designs` is how many designs the
    /// banner will list (it is read up to the last of their lines).
    pub fn start(data: &std::path::Path, designs: usize) -> Self {
        use std::io::BufRead;
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_vsculpt-server"))
            .args(["--listen", "127.0.0.1:0", "--data"])
            .arg(data)
            .args(["--web-dir"])
            .arg(data.join("no-web-client"))
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let mut reader = std::io::BufReader::new(stdout);
        let mut banner = String::new();
        for _ in 0..2 + 3 * designs {
            let mut line = String::new();
            assert!(
                reader.read_line(&mut line).unwrap() > 0,
                "banner ended early: {banner}"
            );
            banner.push_str(&line);
        }
        // Keep draining stdout so the child never blocks on a full pipe.
        std::thread::spawn(move || {
            let mut sink = String::new();
            while reader.read_line(&mut sink).map(|n| n > 0).unwrap_or(false) {
                sink.clear();
            }
        });
        let (addr, designs) = parse_banner(&banner);
        Self {
            child,
            addr,
            designs,
        }
    }

    /// SIGTERM, then wait for a clean exit.
    pub fn terminate(mut self) -> std::process::ExitStatus {
        let pid = self.child.id() as i32;
        unsafe_kill(pid, 15);
        let start = std::time::Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return status;
            }
            assert!(
                start.elapsed().as_secs() < 15,
                "server did not exit on SIGTERM"
            );
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }

    /// SIGKILL (kill -9).
    pub fn kill9(mut self) {
        self.child.kill().unwrap();
        let _ = self.child.wait();
    }
}

fn unsafe_kill(pid: i32, sig: i32) {
    let status = std::process::Command::new("kill")
        .arg(format!("-{sig}"))
        .arg(pid.to_string())
        .status()
        .unwrap();
    assert!(status.success());
}
