//! A fake VRPN server on loopback: accepts TCP clients, exchanges cookies,
//! announces its senders and types, then streams `vrpn_Tracker Pos_Quat` messages
//! for every sensor at a fixed period.

use crate::device::vrpn::{
    COOKIE_LEN, POS_QUAT, SENDER_DESCRIPTION, TYPE_DESCRIPTION, cookie, encode_description,
    encode_message, encode_pos_quat,
};
use glam::{DQuat, DVec3};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// Type id the fake server gives Pos_Quat (any id works; clients map names).
const POS_QUAT_ID: i32 = 7;

struct State {
    poses: Vec<(DVec3, DQuat)>,
    clients: Vec<TcpStream>,
}

/// The fake server.
pub struct FakeVrpnServer {
    addr: SocketAddr,
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

fn greet(mut s: TcpStream, device: &str) -> std::io::Result<TcpStream> {
    s.set_read_timeout(Some(Duration::from_secs(2)))?;
    let mut theirs = [0u8; COOKIE_LEN];
    s.read_exact(&mut theirs)?;
    if !theirs.starts_with(crate::device::vrpn::MAGIC_PREFIX) {
        return Err(std::io::Error::other("client cookie mismatch"));
    }
    let mut hello = cookie().to_vec();
    hello.extend(encode_description(SENDER_DESCRIPTION, 0, "Other"));
    hello.extend(encode_description(SENDER_DESCRIPTION, 1, device));
    hello.extend(encode_description(
        TYPE_DESCRIPTION,
        3,
        "vrpn_Tracker Velocity",
    ));
    hello.extend(encode_description(TYPE_DESCRIPTION, POS_QUAT_ID, POS_QUAT));
    s.write_all(&hello)?;
    s.set_nodelay(true)?;
    Ok(s)
}

impl FakeVrpnServer {
    /// Serves `sensors` sensors of device `device` on 127.0.0.1 (a free port), every `period`.
    pub fn start(device: &str, sensors: usize, period: Duration) -> std::io::Result<Self> {
        let listener = TcpListener::bind("127.0.0.1:0")?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let state = Arc::new(Mutex::new(State {
            poses: vec![(DVec3::ZERO, DQuat::IDENTITY); sensors],
            clients: Vec::new(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (st, sp, dev) = (state.clone(), stop.clone(), device.to_owned());
        let accept = std::thread::spawn(move || {
            while !sp.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((s, _)) => {
                        let _ = s.set_nonblocking(false);
                        if let Ok(s) = greet(s, &dev) {
                            st.lock().unwrap_or_else(|e| e.into_inner()).clients.push(s);
                        }
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
            }
        });
        let (st, sp) = (state.clone(), stop.clone());
        let stream = std::thread::spawn(move || {
            let mut t = 0u32;
            while !sp.load(Ordering::SeqCst) {
                std::thread::sleep(period);
                t = t.wrapping_add(1);
                let mut g = st.lock().unwrap_or_else(|e| e.into_inner());
                let mut msgs = Vec::new();
                for (i, (p, q)) in g.poses.iter().enumerate() {
                    let payload = encode_pos_quat(i as i32, p.to_array(), [q.x, q.y, q.z, q.w]);
                    msgs.extend(encode_message(t, 0, 1, POS_QUAT_ID, &payload));
                }
                g.clients.retain_mut(|c| c.write_all(&msgs).is_ok());
            }
        });
        Ok(Self {
            addr,
            state,
            stop,
            threads: vec![accept, stream],
        })
    }

    /// The listening address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Sets a sensor's pose.
    pub fn set_pose(&self, sensor: usize, position: DVec3, orientation: DQuat) {
        let mut g = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = g.poses.get_mut(sensor) {
            *p = (position, orientation);
        }
    }

    /// Number of connected clients.
    pub fn clients(&self) -> usize {
        self.state
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clients
            .len()
    }

    /// Drops every client (the server restarting).
    pub fn drop_clients(&self) {
        self.state
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clients
            .clear();
    }
}

impl Drop for FakeVrpnServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}
