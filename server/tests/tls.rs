//! Optional TLS (`--tls-cert`/`--tls-key`): with a self-signed certificate
//! generated here (rcgen), a client that trusts it gets the page over
//! HTTPS and joins a design over `wss://`; the banner gives `https://` and
//! `wss://` links; a client that does not trust the certificate, or speaks
//! plain HTTP to the TLS port, gets nothing; a key that does not match the
//! certificate stops the start with a clear error.

mod common;

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use std::sync::Arc;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_rustls::TlsConnector;
use tokio_rustls::rustls::pki_types::{CertificateDer, ServerName};
use tokio_rustls::rustls::{self, ClientConfig, RootCertStore};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_server::config::Config;
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;
use vsculpt_server::tls::TlsFiles;

struct Cert {
    files: TlsFiles,
    der: CertificateDer<'static>,
}

/// A self-signed certificate for `localhost` and 127.0.0.1, written as PEM
/// into `dir`.
fn self_signed(dir: &std::path::Path, tag: &str) -> Cert {
    let key = rcgen::KeyPair::generate().unwrap();
    let params =
        rcgen::CertificateParams::new(vec!["localhost".to_string(), "127.0.0.1".to_string()])
            .unwrap();
    let cert = params.self_signed(&key).unwrap();
    let files = TlsFiles {
        cert: dir.join(format!("{tag}-cert.pem")),
        key: dir.join(format!("{tag}-key.pem")),
    };
    std::fs::write(&files.cert, cert.pem()).unwrap();
    std::fs::write(&files.key, key.serialize_pem()).unwrap();
    Cert {
        files,
        der: cert.der().clone(),
    }
}

fn client_config(trusted: &CertificateDer<'static>) -> Arc<ClientConfig> {
    let mut roots = RootCertStore::empty();
    roots.add(trusted.clone()).unwrap();
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    Arc::new(
        ClientConfig::builder_with_provider(provider)
            .with_safe_default_protocol_versions()
            .unwrap()
            .with_root_certificates(roots)
            .with_no_client_auth(),
    )
}

async fn tls_connect(
    addr: std::net::SocketAddr,
    config: Arc<ClientConfig>,
) -> std::io::Result<tokio_rustls::client::TlsStream<TcpStream>> {
    let tcp = TcpStream::connect(addr).await?;
    TlsConnector::from(config)
        .connect(ServerName::try_from("localhost").unwrap(), tcp)
        .await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn wss_and_https_work_with_a_trusted_self_signed_certificate() {
    let data = tempfile::tempdir().unwrap();
    let certs = tempfile::tempdir().unwrap();
    let cert = self_signed(certs.path(), "good");
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut config = Config::new(data.path().to_path_buf(), data.path().join("no-web"));
    config.tls = Some(cert.files.clone());
    let shutdown = Shutdown::new();
    let server = Server::start(listener, config, shutdown.clone())
        .await
        .unwrap();
    let addr = server.local_addr();
    let banner = server.links().unwrap();
    assert!(
        banner.starts_with(&format!("vsculpt-server listening on https://{addr}\n")),
        "{banner}"
    );
    let device_line = banner.lines().find(|l| l.contains(" device: ")).unwrap();
    assert!(
        device_line.contains(&format!("wss://{addr}/ws?")),
        "{banner}"
    );
    assert!(
        !banner.contains("http://") && !banner.contains("ws://"),
        "{banner}"
    );
    let editor_line = banner.lines().find(|l| l.contains(" editor: ")).unwrap();
    let token = editor_line.split("token=").nth(1).unwrap().to_string();
    let design: u64 = editor_line
        .split("design=")
        .nth(1)
        .unwrap()
        .split('&')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let task = tokio::spawn(server.run());

    // HTTPS: /healthz answers.
    let trusted = client_config(&cert.der);
    let mut s = tls_connect(addr, trusted.clone()).await.unwrap();
    s.write_all(b"GET /healthz HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")
        .await
        .unwrap();
    let mut reply = String::new();
    s.read_to_string(&mut reply).await.unwrap();
    assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");

    // WSS: hello → welcome → snapshot → geometry frames.
    let s = tls_connect(addr, trusted.clone()).await.unwrap();
    let (mut ws, _) =
        tokio_tungstenite::client_async(format!("wss://localhost:{}/ws", addr.port()), s)
            .await
            .unwrap();
    let hello = json!({"type": "hello", "protocol": vsculpt_protocol::PROTOCOL_VERSION, "token": token, "design": design});
    ws.send(Message::text(hello.to_string())).await.unwrap();
    let mut kinds = Vec::new();
    let mut frames = 0;
    while frames == 0 {
        match ws.next().await.unwrap().unwrap() {
            Message::Text(t) => {
                let v: Value = serde_json::from_str(t.as_str()).unwrap();
                kinds.push(v["type"].as_str().unwrap().to_string());
            }
            Message::Binary(b) => {
                vsculpt_protocol::GeometryFrame::decode(&b).unwrap();
                frames += 1;
            }
            _ => {}
        }
    }
    assert_eq!(kinds[..2], ["welcome", "snapshot"]);
    ws.send(Message::text(json!({"type": "ping", "req": 7}).to_string()))
        .await
        .unwrap();
    loop {
        if let Message::Text(t) = ws.next().await.unwrap().unwrap() {
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            if v["type"] == "pong" {
                assert_eq!(v["req"], 7);
                break;
            }
        }
    }

    // A client trusting another certificate refuses the server.
    let other = self_signed(certs.path(), "other");
    assert!(tls_connect(addr, client_config(&other.der)).await.is_err());

    // Plain WebSocket to the TLS port: no upgrade.
    let plain = tokio_tungstenite::connect_async(format!("ws://{addr}/ws")).await;
    assert!(plain.is_err());

    // The server still serves trusting clients after the failures.
    let mut s = tls_connect(addr, trusted).await.unwrap();
    s.write_all(b"GET /healthz HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")
        .await
        .unwrap();
    let mut reply = String::new();
    s.read_to_string(&mut reply).await.unwrap();
    assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");

    drop(ws);
    shutdown.trigger();
    task.await.unwrap().unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_key_that_does_not_match_the_certificate_stops_the_start() {
    let data = tempfile::tempdir().unwrap();
    let certs = tempfile::tempdir().unwrap();
    let a = self_signed(certs.path(), "a");
    let b = self_signed(certs.path(), "b");
    for (files, what) in [
        (
            TlsFiles {
                cert: a.files.cert.clone(),
                key: b.files.key.clone(),
            },
            "TLS configuration",
        ),
        (
            TlsFiles {
                cert: a.files.key.clone(),
                key: a.files.key.clone(),
            },
            "no certificate",
        ),
        (
            TlsFiles {
                cert: certs.path().join("missing.pem"),
                key: a.files.key.clone(),
            },
            "missing.pem",
        ),
    ] {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let mut config = Config::new(data.path().to_path_buf(), data.path().join("no-web"));
        config.tls = Some(files);
        let err = match Server::start(listener, config, Shutdown::new()).await {
            Ok(_) => panic!("started with a bad TLS configuration"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(what), "{err}");
    }
}
