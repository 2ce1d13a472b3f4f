//! Nothing closes silently and nothing is dropped silently: a text message
//! that is not UTF-8 and a frame over the hard limit get an error message
//! and the matching close code (1007, 1009); a refused drag frame without a
//! `req` still comes back as an error; a hello of a future protocol version
//! (with fields this version does not know) and a version-1 hello get
//! `bad_version`.

mod common;

use common::TestServer;
use common::ws::{self, Client};
use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use tokio::io::AsyncWriteExt;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::protocol::frame::Frame;
use tokio_tungstenite::tungstenite::protocol::frame::coding::{Data, OpCode};

/// Reads until the server closes: the text messages and the close code.
async fn until_close(s: &mut ws::Stream) -> (Vec<Value>, Option<u16>) {
    let mut texts = Vec::new();
    loop {
        let m = tokio::time::timeout(ws::WAIT, s.next())
            .await
            .expect("the server neither answered nor closed");
        match m {
            Some(Ok(Message::Text(t))) => texts.push(serde_json::from_str(t.as_str()).unwrap()),
            Some(Ok(Message::Close(c))) => return (texts, c.map(|c| u16::from(c.code))),
            Some(Ok(_)) => {}
            None | Some(Err(_)) => return (texts, None),
        }
    }
}

fn last_error(texts: &[Value]) -> &Value {
    texts
        .iter()
        .rev()
        .find(|v| v["type"] == "error")
        .unwrap_or_else(|| panic!("no error message among {texts:?}"))
}

fn plain(s: &mut ws::Stream) -> &mut tokio::net::TcpStream {
    match s.get_mut() {
        tokio_tungstenite::MaybeTlsStream::Plain(t) => t,
        _ => unreachable!("a plain ws:// connection"),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn invalid_utf8_gets_an_error_and_close_1007() {
    let server = TestServer::start(common::data_dir("close-utf8")).await;
    let d = server.demo().clone();
    // After the hello.
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    let bad = Frame::message(vec![b'{', 0xff, 0xfe, b'}'], OpCode::Data(Data::Text), true);
    c.ws.send(Message::Frame(bad.clone())).await.unwrap();
    let (texts, code) = until_close(&mut c.ws).await;
    assert_eq!(last_error(&texts)["code"], "malformed");
    assert!(
        last_error(&texts)["message"]
            .as_str()
            .unwrap()
            .contains("UTF-8")
    );
    assert_eq!(code, Some(1007));
    // As the first message.
    let mut s = ws::raw(server.addr).await;
    s.send(Message::Frame(bad)).await.unwrap();
    let (texts, code) = until_close(&mut s).await;
    assert_eq!(last_error(&texts)["code"], "malformed");
    assert_eq!(code, Some(1007));
    // The server is fine.
    let mut c = Client::connect(server.addr, d.id, &d.viewer, "v").await;
    c.ping().await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_frame_over_the_hard_limit_gets_an_error_and_close_1009() {
    let server = TestServer::start(common::data_dir("close-big")).await;
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    // A masked binary frame header announcing 17 MiB (RFC 6455 §5.2),
    // written by hand; the payload never follows.
    let len: u64 = 17 << 20;
    let mut header = vec![0x82, 0x80 | 127];
    header.extend_from_slice(&len.to_be_bytes());
    header.extend_from_slice(&[1, 2, 3, 4]);
    plain(&mut c.ws).write_all(&header).await.unwrap();
    let (texts, code) = until_close(&mut c.ws).await;
    let e = last_error(&texts);
    assert_eq!(e["code"], "too_large");
    assert!(e["message"].as_str().unwrap().contains("17825792"), "{e}");
    assert_eq!(code, Some(1009));
    let mut c = Client::connect(server.addr, d.id, &d.viewer, "v").await;
    c.ping().await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn refused_drags_without_req_come_back() {
    let server = TestServer::start(common::data_dir("drag-refused")).await;
    let d = server.demo().clone();
    let mut a = Client::connect(server.addr, d.id, &d.editor, "a").await;
    let mut b = Client::connect(server.addr, d.id, &d.editor, "b").await;
    let icon = common::parts::icons(&a.snapshot, 1)[0]["id"]
        .as_u64()
        .unwrap();
    // An unknown icon.
    b.send(json!({"type": "drag", "part": 1, "icon": 999, "xyz": [0.0, 0.0, 1.0]}))
        .await;
    let e = b.wait_for("error").await;
    assert_eq!(e["code"], "unknown_icon", "{e}");
    assert!(e.get("req").is_none());
    // An icon another editor holds.
    a.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    b.send(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [0.0, 0.0, 1.0]}))
        .await;
    let e = b.wait_for("error").await;
    assert_eq!(e["code"], "conflict", "{e}");
    // A burst of refused frames is answered by at least one error and the
    // connection stays up.
    for k in 0..50 {
        b.send(json!({"type": "drag", "part": 1, "icon": 999, "xyz": [0.0, 0.0, k as f64]}))
            .await;
    }
    assert_eq!(b.wait_for("error").await["code"], "unknown_icon");
    b.ping().await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_future_protocol_version_gets_bad_version() {
    let server = TestServer::start(common::data_dir("future-version")).await;
    let d = server.demo().clone();
    // A hello of the next version as a future client might write it: other
    // fields, none of this version's optional ones.
    let future = vsculpt_protocol::PROTOCOL_VERSION + 1;
    let hello = json!({"type": "hello", "protocol": future, "token": d.editor, "design": d.id,
        "session": {"resume": "abc"}, "capabilities": ["deltas"]});
    let mut s = ws::raw(server.addr).await;
    s.send(Message::text(hello.to_string())).await.unwrap();
    let (texts, code) = until_close(&mut s).await;
    assert_eq!(last_error(&texts)["code"], "bad_version", "{texts:?}");
    assert_eq!(code, Some(1008));
    // Version 1 (one surface per design) is gone: its hello is refused too.
    assert_eq!(vsculpt_protocol::PROTOCOL_VERSION, 2);
    let mut old = ws::hello(d.id, &d.editor, "v1");
    old["protocol"] = json!(1);
    let mut s = ws::raw(server.addr).await;
    s.send(Message::text(old.to_string())).await.unwrap();
    let (texts, code) = until_close(&mut s).await;
    assert_eq!(last_error(&texts)["code"], "bad_version", "{texts:?}");
    assert_eq!(code, Some(1008));
    server.stop().await;
}
