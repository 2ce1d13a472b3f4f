//! The TCP transport of the real server: every accepted connection has
//! TCP_NODELAY set, so a small reply or geometry frame is sent at once
//! instead of waiting up to a delayed-ACK period behind Nagle's algorithm.
//! The option is read back from the server's own accepted socket (found
//! among this process's file descriptors by its address pair), not inferred
//! from timing.

mod common;

use common::TestServer;
use common::ws::Client;
use std::net::SocketAddr;

/// The `TCP_NODELAY` setting of this process's socket whose local address
/// is `local` and peer address is `peer`, if there is one.
#[cfg(target_os = "linux")]
fn nodelay_of_socket(local: SocketAddr, peer: SocketAddr) -> Option<bool> {
    use std::os::fd::{BorrowedFd, RawFd};
    for entry in std::fs::read_dir("/proc/self/fd").ok()?.flatten() {
        let Ok(fd) = entry.file_name().to_string_lossy().parse::<RawFd>() else {
            continue;
        };
        let is_socket = std::fs::read_link(entry.path())
            .map(|l| l.to_string_lossy().starts_with("socket:"))
            .unwrap_or(false);
        if !is_socket {
            continue;
        }
        // SAFETY: the descriptor was listed as open a moment ago; it is only
        // duplicated (the duplicate is closed on drop), never closed itself.
        let borrowed = unsafe { BorrowedFd::borrow_raw(fd) };
        let Ok(owned) = borrowed.try_clone_to_owned() else {
            continue;
        };
        let tcp = std::net::TcpStream::from(owned);
        if tcp.local_addr().ok() == Some(local) && tcp.peer_addr().ok() == Some(peer) {
            return tcp.nodelay().ok();
        }
    }
    None
}

#[cfg(target_os = "linux")]
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn accepted_connections_have_tcp_nodelay() {
    let server = TestServer::start(common::data_dir("nodelay")).await;
    let d = server.demo().clone();
    let c = Client::connect(server.addr, d.id, &d.viewer, "probe").await;
    let client_side = match c.ws.get_ref() {
        tokio_tungstenite::MaybeTlsStream::Plain(tcp) => tcp.local_addr().unwrap(),
        _ => unreachable!("a plain ws:// connection"),
    };
    let nodelay = nodelay_of_socket(server.addr, client_side)
        .expect("the server's end of the connection is in this process");
    assert!(nodelay, "the accepted socket must have TCP_NODELAY set");
    drop(c);
    server.stop().await;
}
