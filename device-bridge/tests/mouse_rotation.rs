//! The 3D mouse's rotation axes and calibration, from bytes written here from the
//! published formats (never the bridge's encoders):
//! * HID reports of a SpaceNavigator / SpaceMouse Wireless: report 1 (x, y, z) and
//!   report 2 (rx, ry, rz), or one 13-byte report 1 with all six, each a signed
//!   16-bit little-endian count. The axes are the USB HID Usage Tables' (HUT 1.12
//!   §4.2, Generic Desktop X, Y, Z, Rx, Ry, Rz): X grows left → right, Y far → near,
//!   Z high → low, rotations by the right-hand rule about those axes. The bridge's
//!   frame is x right, y up, z towards the user, so a HID vector v reads
//!   (vx, −vz, vy) — a proper rotation, so twists map like pushes.
//! * spacenavd events: eight i32 `[0, x, y, z, rx, ry, rz, period]` with x right,
//!   y up, z away from the user; libspnav's `spnav_posrot_moveobj` (src/util.c)
//!   moves an object by `(x, y, −z)` and turns it about `(rx, ry, −rz)`.
//!
//! And what rotation does: twisting the cap turns a selected normal icon's normal
//! about the scene axis at `menu.rotation_speed`, and leaves a position icon alone.

use glam::{DQuat, DVec3};
use vsculpt_bridge::config::{Config, DeviceConfig, DeviceKind, build_decoder};
use vsculpt_bridge::device::{Reading, Sample, SourceId, Timestamp};
use vsculpt_bridge::interaction::{
    Command, IconKind, IconRole, IconState, IconView, Interaction, NORMAL_LEVER,
};

/// A signed 16-bit count, little-endian, as a HID report carries it.
fn le(v: i16) -> [u8; 2] {
    [(v as u16 & 0xff) as u8, (v as u16 >> 8) as u8]
}

/// HID report `id` carrying `values` (three or six counts).
fn report(id: u8, values: &[i16]) -> Vec<u8> {
    let mut r = vec![id];
    for v in values {
        r.extend(le(*v));
    }
    r
}

/// A spacenavd motion event: eight native-endian i32.
fn spnav_motion(v: [i32; 6]) -> Vec<u8> {
    let words = [0, v[0], v[1], v[2], v[3], v[4], v[5], 16];
    let mut out = Vec::with_capacity(32);
    for w in words {
        out.extend(w.to_ne_bytes());
    }
    out
}

/// A HID vector (HUT axes) in the bridge's frame.
fn hut_to_bridge(v: DVec3) -> DVec3 {
    // columns: HID X = right, HID Y = towards the user, HID Z = down
    let m = glam::DMat3::from_cols(
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.0, -1.0, 0.0),
    );
    assert_eq!(m.determinant(), 1.0);
    m * v
}

fn motions(kind: DeviceKind, id: Option<(u16, u16)>, chunks: &[Vec<u8>]) -> Vec<(DVec3, DVec3)> {
    let mut d = DeviceConfig::new("mouse", kind);
    d.spacemouse.deadzone = [0.0; 6];
    d.spacenavd.deadzone = [0.0; 6];
    decode(&d, id, chunks)
}

fn decode(d: &DeviceConfig, id: Option<(u16, u16)>, chunks: &[Vec<u8>]) -> Vec<(DVec3, DVec3)> {
    let mut dec = build_decoder(SourceId(0), d);
    if let Some(id) = id {
        dec.set_identity(id);
    }
    let mut out = Vec::new();
    for c in chunks {
        dec.feed(c, Timestamp(0), &mut out);
    }
    out.into_iter()
        .filter_map(|s| match s.reading {
            Reading::Motion {
                translation,
                rotation,
            } => Some((translation, rotation)),
            _ => None,
        })
        .collect()
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-12
}

#[test]
fn hid_rotation_axes_follow_the_hid_usage_frame() {
    const SPACENAVIGATOR: (u16, u16) = (0x046d, 0xc626);
    // each axis alone, at half deflection (175 of 350), in the split reports
    for axis in 0..6 {
        let mut v = [0i16; 6];
        v[axis] = 175;
        let chunks = [report(1, &v[..3]), report(2, &v[3..])];
        let got = motions(DeviceKind::SpacemouseHid, Some(SPACENAVIGATOR), &chunks);
        let (t, r) = *got.last().unwrap();
        let hid = |o: usize| DVec3::new(v[o] as f64, v[o + 1] as f64, v[o + 2] as f64) / 350.0;
        assert!(
            close(t, hut_to_bridge(hid(0))),
            "axis {axis}: translation {t}"
        );
        assert!(close(r, hut_to_bridge(hid(3))), "axis {axis}: rotation {r}");
    }
    // a twist of the cap clockwise seen from above is +Rz (about "down", right-hand
    // rule): in the bridge's frame a negative turn about y (up)
    let got = motions(
        DeviceKind::SpacemouseHid,
        Some(SPACENAVIGATOR),
        &[report(2, &[0, 0, 350])],
    );
    assert!(close(got[0].1, DVec3::new(0.0, -1.0, 0.0)), "{:?}", got[0]);
    // the 13-byte report of a SpaceMouse Wireless carries all six the same way
    let v = [-100i16, 50, 200, 300, -20, 70];
    let got = motions(
        DeviceKind::SpacemouseHid,
        Some((0x256f, 0xc62e)),
        &[report(1, &v)],
    );
    let hid = |o: usize| DVec3::new(v[o] as f64, v[o + 1] as f64, v[o + 2] as f64) / 350.0;
    assert!(close(got[0].0, hut_to_bridge(hid(0))), "{:?}", got[0]);
    assert!(close(got[0].1, hut_to_bridge(hid(3))), "{:?}", got[0]);
}

#[test]
fn spacenavd_rotation_is_libspnavs_object_rotation() {
    let got = motions(
        DeviceKind::Spacenavd,
        None,
        &[
            spnav_motion([0, 0, 0, 35, 70, 105]),
            spnav_motion([-70, 140, 350, -350, 0, -175]),
        ],
    );
    // libspnav: translation (x, y, −z), rotation axis (rx, ry, −rz)
    assert!(close(got[0].0, DVec3::ZERO));
    assert!(close(got[0].1, DVec3::new(0.1, 0.2, -0.3)), "{:?}", got[0]);
    assert!(close(got[1].0, DVec3::new(-0.2, 0.4, -1.0)), "{:?}", got[1]);
    assert!(close(got[1].1, DVec3::new(-1.0, 0.0, 0.5)), "{:?}", got[1]);
}

#[test]
fn calibration_from_the_config_file_applies_per_axis() {
    let toml = r#"
        [[device]]
        name = "mouse"
        kind = "spacenavd"
        spacenavd = { full_scale = 400.0, deadzone = [0.1, 0.0, 0.0, 0.0, 0.5, 0.0], axis_scale = [1.0, 2.0, 1.0, 0.0, 1.0, 1.0], axis_signs = [1.0, 1.0, -1.0, 1.0, 1.0, -1.0] }
    "#;
    let c = Config::parse(toml).unwrap();
    let d = &c.devices[0];
    let got = decode(
        d,
        None,
        &[
            // x inside its dead zone (40 of 400 = 0.1), y doubled, z pulled towards
            // the user (−z in spacenavd) and sign-flipped; rx off; ry below its
            // dead zone of 0.5; rz at −0.25 of full scale (→ +0.25, then sign −1)
            spnav_motion([40, 100, -200, 400, 180, -100]),
            // x just past its dead zone ramps from 0: (0.2 − 0.1) / 0.9; ry at
            // 0.75: (0.75 − 0.5) / 0.5
            spnav_motion([80, 0, 0, 0, 300, 0]),
            // beyond full scale clamps to 1 before the gain
            spnav_motion([0, 800, 0, 0, 0, 0]),
        ],
    );
    assert!(close(got[0].0, DVec3::new(0.0, 0.5, -0.5)), "{:?}", got[0]);
    assert!(close(got[0].1, DVec3::new(0.0, 0.0, -0.25)), "{:?}", got[0]);
    assert!(
        close(got[1].0, DVec3::new(0.1 / 0.9, 0.0, 0.0)),
        "{:?}",
        got[1]
    );
    assert!(close(got[1].1, DVec3::new(0.0, 0.5, 0.0)), "{:?}", got[1]);
    assert!(close(got[2].0, DVec3::new(0.0, 2.0, 0.0)), "{:?}", got[2]);
    // the default dead zone (0.05 of full scale) holds a resting cap's drift at 0
    let c = Config::parse("[[device]]\nname = \"m\"\nkind = \"spacenavd\"\n").unwrap();
    let got = decode(
        &c.devices[0],
        None,
        &[spnav_motion([3, -10, 17, -4, 8, 12])],
    );
    assert_eq!(got[0], (DVec3::ZERO, DVec3::ZERO));
    // bad calibrations are refused with the setting's name
    for bad in [
        "deadzone = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
        "axis_scale = [-1.0, 1.0, 1.0, 1.0, 1.0, 1.0]",
        "axis_signs = [0.5, 1.0, 1.0, 1.0, 1.0, 1.0]",
    ] {
        let text = format!(
            "[[device]]\nname = \"m\"\nkind = \"spacemouse_hid\"\nspacemouse = {{ {bad} }}\n"
        );
        let e = Config::parse(&text).unwrap_err().to_string();
        let key = bad.split(' ').next().unwrap();
        assert!(e.contains(key), "{e}");
    }
}

fn normal_icon(id: u64, at: DVec3, normal: DVec3) -> IconView {
    IconView {
        part: 1,
        id,
        position: at,
        target: normal,
        role: IconRole::Constraint,
        kind: IconKind::Normal,
        state: IconState::Passive,
    }
}

/// Feeds spacenavd event bytes, each at its time (µs), through the decoder and the
/// interaction; returns the commands.
fn twist(i: &mut Interaction, d: &DeviceConfig, events: &[(u64, Vec<u8>)]) -> Vec<Command> {
    let mut dec = build_decoder(SourceId(0), d);
    let mut out = Vec::new();
    for (t, bytes) in events {
        let mut samples: Vec<Sample> = Vec::new();
        dec.feed(bytes, Timestamp(*t), &mut samples);
        for s in &samples {
            i.handle(s, &mut out);
        }
    }
    out
}

#[test]
fn twisting_the_cap_turns_a_selected_normal_and_leaves_a_position_alone() {
    let toml = r#"
        [[device]]
        name = "mouse"
        kind = "spacenavd"
        [menu]
        rotation_speed = 2.0
        [rates]
        drag_hz = 1000.0
    "#;
    let config = Config::parse(toml).unwrap();
    let at = DVec3::new(10.0, 20.0, 30.0);
    let n0 = DVec3::new(0.0, 0.0, 1.0);
    let mut i = Interaction::new(&config);
    i.set_surface_area(4.0);
    i.set_icons([normal_icon(7, at, n0)]);
    // button 2 selects the next icon (the default menu)
    let press = |b: i32| {
        let mut e = Vec::new();
        for w in [1, b, 1, 0, 0, 0, 0, 0] {
            e.extend(w.to_ne_bytes());
        }
        e
    };
    let d = &config.devices[0];
    // ry = 175 of 350 is half a twist about up (y); the dead zone of 0.05 ramps it
    // to (0.5 − 0.05) / 0.95; ten events 10 ms apart after the first (which only
    // starts the clock) make 0.1 s
    let mut events = vec![(0, press(2))];
    for k in 0..=10u64 {
        events.push((1_000_000 + k * 10_000, spnav_motion([0, 0, 0, 0, 175, 0])));
    }
    events.push((1_200_000, spnav_motion([0; 6])));
    let out = twist(&mut i, d, &events);
    assert_eq!(
        out.first(),
        Some(&Command::Grab {
            icon: 7,
            sensor: "mouse".into()
        })
    );
    let last_drag = out
        .iter()
        .rev()
        .find_map(|c| match c {
            Command::Drag { icon: 7, target } => Some(*target),
            _ => None,
        })
        .expect("a drag of the normal");
    let angle = 2.0 * (0.45 / 0.95) * 0.1;
    let expected = DQuat::from_rotation_y(angle) * n0;
    let pointed = (last_drag - at).normalize();
    assert!(
        (pointed - expected).length() < 1e-12,
        "pointed {pointed}, expected {expected}"
    );
    // the server reads the drag as the point the normal points to from the icon:
    // a lever of NORMAL_LEVER surface sizes (√4 = 2)
    assert!(((last_drag - at).length() - NORMAL_LEVER * 2.0).abs() < 1e-9);
    assert!(matches!(out.last(), Some(Command::Release { icon: 7, .. })));

    // a position icon selected: a twist alone sends nothing
    let mut i = Interaction::new(&config);
    i.set_icons([IconView {
        part: 1,
        kind: IconKind::Position,
        target: at,
        ..normal_icon(8, at, n0)
    }]);
    let out = twist(&mut i, d, &events);
    assert!(out.is_empty(), "{out:?}");
}
