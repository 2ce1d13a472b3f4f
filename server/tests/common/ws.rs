//! A WebSocket test client (tokio-tungstenite 0.29, the same tungstenite
//! as axum) speaking protocol v2: hello, requests with `req` numbers,
//! waiting for a given message type, decoding geometry frames.

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use std::net::SocketAddr;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_protocol::GeometryFrame;

pub type Stream =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// What arrived.
#[derive(Debug)]
pub enum Got {
    Text(Value),
    Frame(GeometryFrame),
    /// A mesh frame (kind 3: a dsm part).
    Mesh(vsculpt_protocol::MeshFrame),
    Closed,
}

pub struct Client {
    pub ws: Stream,
    pub welcome: Value,
    pub snapshot: Value,
    next_req: u64,
}

pub const WAIT: Duration = Duration::from_secs(10);

/// Opens a raw socket to `/ws`.
pub async fn raw(addr: SocketAddr) -> Stream {
    tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap()
        .0
}

pub fn hello(design: u64, token: &str, name: &str) -> Value {
    if name.is_empty() {
        // The shortest hello: the optional fields left out.
        return json!({
            "type": "hello",
            "protocol": vsculpt_protocol::PROTOCOL_VERSION,
            "token": token,
            "design": design
        });
    }
    json!({
        "type": "hello",
        "protocol": vsculpt_protocol::PROTOCOL_VERSION,
        "token": token,
        "design": design,
        "client_name": name,
        "client_kind": "tool"
    })
}

/// Reads the next message as it came; panics when none comes within WAIT or the socket fails.
pub async fn next_message(ws: &mut Stream) -> Message {
    tokio::time::timeout(WAIT, ws.next())
        .await
        .expect("no message")
        .expect("closed")
        .expect("socket error")
}

/// Reads the next message (text parsed as JSON, binary decoded as a frame).
pub async fn next(ws: &mut Stream) -> Got {
    loop {
        let m = tokio::time::timeout(WAIT, ws.next())
            .await
            .expect("no message within 10 s");
        match m {
            None | Some(Err(_)) => return Got::Closed,
            Some(Ok(Message::Text(t))) => {
                return Got::Text(serde_json::from_str(t.as_str()).unwrap());
            }
            Some(Ok(Message::Binary(b)))
                if b.get(4) == Some(&vsculpt_protocol::mesh_frame::KIND_MESH) =>
            {
                return Got::Mesh(vsculpt_protocol::MeshFrame::decode(&b).expect("bad mesh frame"));
            }
            // A body part's frames (kind 4) are read by tests/body.rs itself.
            Some(Ok(Message::Binary(b)))
                if b.len() > 4 && b[4] == vsculpt_protocol::body_frame::KIND_BODY =>
            {
                continue;
            }
            Some(Ok(Message::Binary(b))) => {
                return Got::Frame(GeometryFrame::decode(&b).expect("bad geometry frame"));
            }
            Some(Ok(Message::Close(_))) => return Got::Closed,
            Some(Ok(_)) => continue,
        }
    }
}

impl Client {
    /// Connects and says hello; panics unless welcomed.
    pub async fn connect(addr: SocketAddr, design: u64, token: &str, name: &str) -> Self {
        match Self::try_connect(addr, design, token, name).await {
            Ok(c) => c,
            Err(e) => panic!("not welcomed: {e}"),
        }
    }

    /// Connects and says hello; the error message if refused.
    pub async fn try_connect(
        addr: SocketAddr,
        design: u64,
        token: &str,
        name: &str,
    ) -> Result<Self, Value> {
        let mut ws = raw(addr).await;
        ws.send(Message::text(hello(design, token, name).to_string()))
            .await
            .unwrap();
        let welcome = match next(&mut ws).await {
            Got::Text(v) if v["type"] == "welcome" => v,
            Got::Text(v) => return Err(v),
            other => panic!("unexpected {other:?}"),
        };
        let snapshot = match next(&mut ws).await {
            Got::Text(v) if v["type"] == "snapshot" => v,
            other => panic!("expected a snapshot, got {other:?}"),
        };
        Ok(Self {
            ws,
            welcome,
            snapshot,
            next_req: 1,
        })
    }

    pub fn client_id(&self) -> u64 {
        self.welcome["client_id"].as_u64().unwrap()
    }

    pub async fn send(&mut self, v: Value) {
        self.ws.send(Message::text(v.to_string())).await.unwrap();
    }

    pub async fn send_text(&mut self, s: &str) {
        self.ws.send(Message::text(s.to_string())).await.unwrap();
    }

    pub async fn next(&mut self) -> Got {
        next(&mut self.ws).await
    }

    /// The next text message of type `ty`, skipping others.
    pub async fn wait_for(&mut self, ty: &str) -> Value {
        loop {
            match self.next().await {
                Got::Text(v) if v["type"] == ty => return v,
                Got::Closed => panic!("closed while waiting for {ty}"),
                _ => {}
            }
        }
    }

    /// The next geometry frame, skipping text.
    pub async fn frame(&mut self) -> GeometryFrame {
        loop {
            match self.next().await {
                Got::Frame(f) => return f,
                Got::Closed => panic!("closed while waiting for a frame"),
                _ => {}
            }
        }
    }

    /// The next mesh frame of part `part` with revision > `after`, skipping
    /// text and other frames.
    pub async fn mesh_of_after(&mut self, part: u64, after: u64) -> vsculpt_protocol::MeshFrame {
        loop {
            match self.next().await {
                Got::Mesh(m) if m.part == part && m.revision > after => return m,
                Got::Closed => panic!("closed while waiting for a mesh frame"),
                _ => {}
            }
        }
    }

    /// The next frame with revision > `after`.
    pub async fn frame_after(&mut self, after: u64) -> GeometryFrame {
        loop {
            let f = self.frame().await;
            if f.revision > after {
                return f;
            }
        }
    }

    /// The next geometry frame of part `part`, skipping text and other
    /// parts' frames.
    pub async fn frame_of(&mut self, part: u64) -> GeometryFrame {
        loop {
            let f = self.frame().await;
            if f.part == part {
                return f;
            }
        }
    }

    /// The next frame of part `part` with revision > `after`.
    pub async fn frame_of_after(&mut self, part: u64, after: u64) -> GeometryFrame {
        loop {
            let f = self.frame_of(part).await;
            if f.revision > after {
                return f;
            }
        }
    }

    /// The frame of the drag just sent: the frame of `part` whose revision
    /// is the one its `icon_feedback` names (either may come first).
    pub async fn frame_of_drag(&mut self, part: u64) -> GeometryFrame {
        let mut want = None;
        let mut got: Option<GeometryFrame> = None;
        loop {
            match self.next().await {
                Got::Text(v) if v["type"] == "icon_feedback" => {
                    want = v["revision"].as_u64();
                }
                Got::Frame(f) if f.part == part => got = Some(f),
                Got::Closed => panic!("closed"),
                _ => {}
            }
            if let (Some(w), Some(f)) = (want, &got)
                && f.revision >= w
            {
                assert_eq!(f.revision, w, "the editor skipped the frame of its drag");
                return got.unwrap();
            }
        }
    }

    /// The geometry frames a join sends, one per surface or curve part of the snapshot, by
    /// part id (in the snapshot's order).
    pub async fn join_frames(&mut self) -> Vec<GeometryFrame> {
        // Surface and curve parts send geometry frames; body, DSM and
        // network parts send their own kinds (read by their tests).
        let ids: Vec<u64> = self.snapshot["parts"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|p| matches!(p["shape"]["kind"].as_str(), Some("surface" | "curve")))
            .map(|p| p["id"].as_u64().unwrap())
            .collect();
        let mut got: Vec<GeometryFrame> = Vec::new();
        while got.len() < ids.len() {
            let f = self.frame().await;
            assert!(ids.contains(&f.part), "a frame of unknown part {}", f.part);
            assert!(
                got.iter().all(|g| g.part != f.part),
                "two join frames of part {}",
                f.part
            );
            got.push(f);
        }
        got.sort_by_key(|f| ids.iter().position(|i| *i == f.part));
        got
    }

    /// Sends `msg` with a fresh `req` and returns the reply carrying it —
    /// `ack`, `error`, or a query's answer (`design_created`, `versions`,
    /// `designs`, `pong`); other messages are skipped (events carry no
    /// `req`).
    pub async fn request(&mut self, mut msg: Value) -> Value {
        let req = self.next_req;
        self.next_req += 1;
        msg["req"] = json!(req);
        self.send(msg).await;
        loop {
            match self.next().await {
                Got::Text(v) if v["req"] == json!(req) => return v,
                Got::Closed => panic!("closed while waiting for reply to {req}"),
                _ => {}
            }
        }
    }

    /// Creates a load icon at (u, v) on `part` and grabs it for a drag: its id.
    pub async fn grab_load_icon(&mut self, part: u64, u: f64, v: f64) -> u64 {
        let created = self
            .request(json!({"type": "create_icon", "part": part,
                "spec": {"anchor": {"kind": "point", "u": u, "v": v}, "role": {"kind": "load"}}}))
            .await;
        assert_eq!(created["type"], "ack", "{created}");
        let icon = created["icon"].as_u64().unwrap();
        self.ok(json!({"type": "drag_start", "part": part, "icon": icon}))
            .await;
        icon
    }

    /// `request` that must be acked.
    pub async fn ok(&mut self, msg: Value) {
        let r = self.request(msg.clone()).await;
        assert_eq!(r["type"], "ack", "{msg} → {r}");
    }

    /// `request` that must fail with `code`.
    pub async fn refused(&mut self, msg: Value, code: &str) {
        let r = self.request(msg.clone()).await;
        assert_eq!(r["type"], "error", "{msg} → {r}");
        assert_eq!(r["code"], code, "{msg} → {r}");
    }

    /// Round trip proving the connection and server are alive.
    pub async fn ping(&mut self) {
        self.send(json!({"type": "ping"})).await;
        self.wait_for("pong").await;
    }
}
