//! Fairing a network part's face runs as a job off the design's actor
//! (paper 004 §8 through the real server): another client's drag on a
//! surface part gets its frames while the job runs (ordering: frames
//! between the job's progress and its end, no timing); a cancel changes
//! nothing (the design's document byte for byte); a second fair of the
//! same face is refused; a completed job's faired points (goals in mean
//! and in Gaussian curvature) equal the synchronous kernel run's on the
//! same face to 1e-12, its boundary unmoved, and undo restores the
//! unfaired face; a face whose curve moves while it is faired gets a
//! discarded job; a deleted part cancels its job.
//!
//! A "long" fairing here is one of the bottle's five-sided face with a
//! relaxation of 0.001 (each sweep takes 0.1 % of its step): tens of
//! thousands of sweeps to converge, far more than the few requests a test
//! sends while it runs; tests that need it to end cancel it.

mod common;

use common::http::{get, request};
use common::parts::{SHELL, load_icon};
use common::ws::{Client, Got};
use common::{TestServer, data_dir};
use serde_json::{Value, json};
use vsculpt_server::design::network_engine::{
    FairingDoc, GoalDoc, MeasureDoc, NetworkEditDoc, NetworkEngine,
};
use vsculpt_server::design::part::PartBody;

/// The demo design with the bottle network added as a part: (editor
/// client, network part id, five-sided face).
struct Setup {
    server: TestServer,
    data: std::path::PathBuf,
    design: u64,
    editor: String,
    part: u64,
    five: u64,
}

async fn setup(name: &str) -> Setup {
    let data = data_dir(name);
    let server = TestServer::start(data.clone()).await;
    let body = json!({"name": "bottle", "template": "bottle"}).to_string();
    let r = request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&server.admin),
        body.as_bytes(),
    )
    .await;
    assert_eq!(r.status, 201, "{}", r.text());
    let v = r.json();
    let bottle = Client::connect(
        server.addr,
        v["id"].as_u64().unwrap(),
        v["tokens"]["editor"].as_str().unwrap(),
        "bottle",
    )
    .await;
    let mut network = bottle.snapshot["parts"][0]["shape"]["network"].clone();
    let five = network["faces"]
        .as_array()
        .unwrap()
        .iter()
        .position(|f| f["sides"].as_array().unwrap().len() == 5)
        .unwrap() as u64;
    for k in ["meetings", "faces", "faired"] {
        network.as_object_mut().unwrap().remove(k);
    }
    let demo = server.demo();
    let (design, editor) = (demo.id, demo.editor.clone());
    let mut a = Client::connect(server.addr, design, &editor, "setup").await;
    let r = a
        .request(json!({"type": "create_part", "spec": {"name": "bottle",
            "shape": {"kind": "network", "network": network}}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let part = r["part"].as_u64().unwrap();
    Setup {
        server,
        data,
        design,
        editor,
        part,
        five,
    }
}

impl Setup {
    async fn client(&self, name: &str) -> Client {
        Client::connect(self.server.addr, self.design, &self.editor, name).await
    }

    /// The design's document as the HTTP API gives it (its JSON text and
    /// the network part's body).
    async fn doc(&self) -> (String, PartBody) {
        let r = get(
            self.server.addr,
            &format!("/api/designs/{}", self.design),
            Some(&self.editor),
        )
        .await;
        assert_eq!(r.status, 200, "{}", r.text());
        let v = r.json();
        let part = v["design"]["parts"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["id"] == json!(self.part))
            .unwrap()
            .clone();
        (
            v["design"].to_string(),
            serde_json::from_value(part["body"].clone()).unwrap(),
        )
    }

    fn long_fair(&self) -> Value {
        json!({"type": "network_edit", "part": self.part, "edit": {"op": "fair",
            "face": self.five, "measure": "mean", "goal": "from_boundary",
            "relaxation": 0.001, "tolerance": 1e-14, "max_iterations": 100_000}})
    }

    async fn stop(self) {
        self.server.stop().await;
        let _ = std::fs::remove_dir_all(&self.data);
    }
}

/// Sends `msg` with request number `req` without waiting for its answer.
async fn send_req(c: &mut Client, mut msg: Value, req: u64) {
    msg["req"] = json!(req);
    c.send(msg).await;
}

/// The next text message of type `ty` about face `face` of `part`.
async fn job_message(c: &mut Client, ty: &str, part: u64, face: u64) -> Value {
    loop {
        let v = c.wait_for(ty).await;
        if v["part"] == json!(part) && v["face"] == json!(face) {
            return v;
        }
    }
}

/// The answer to request `req` (skipping everything else).
async fn answer(c: &mut Client, req: u64) -> Value {
    loop {
        if let Got::Text(v) = c.next().await
            && v["req"] == json!(req)
        {
            return v;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_drag_on_a_surface_part_gets_frames_while_a_fairing_runs() {
    let s = setup("fairing-job-drag").await;
    let mut a = s.client("ann").await;
    let mut b = s.client("bob").await;
    let (icon, xyz) = load_icon(&b.snapshot);
    send_req(&mut a, s.long_fair(), 900).await;
    let started = job_message(&mut b, "fairing_progress", s.part, s.five).await;
    assert_eq!(started["iteration"], 0, "{started}");
    assert_eq!(started["client"], json!(a.client_id()));
    assert_eq!(started["max_iterations"], 100_000);

    // Bob drags the shell's load icon: its frames come while the job runs.
    b.ok(json!({"type": "drag_start", "part": SHELL, "icon": icon}))
        .await;
    let mut frames = 0;
    let mut progress_after_frames = None;
    for step in 1..=3 {
        b.send(json!({"type": "drag", "part": SHELL, "icon": icon,
            "xyz": [xyz[0], xyz[1], xyz[2] + 0.5 * step as f64]}))
            .await;
    }
    while progress_after_frames.is_none() {
        match b.next().await {
            Got::Frame(f) if f.part == SHELL => frames += 1,
            Got::Text(v) if v["type"] == "fairing_ended" => {
                panic!("the job ended before the drag's frames (got {frames}): {v}")
            }
            Got::Text(v)
                if v["type"] == "fairing_progress"
                    && frames > 0
                    && v["iteration"].as_u64().unwrap() > 0 =>
            {
                progress_after_frames = Some(v)
            }
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
    let p = progress_after_frames.unwrap();
    assert!(frames >= 1);
    let fraction = p["fraction"].as_f64().unwrap();
    assert!((0.0..1.0).contains(&fraction), "{p}");
    assert!(p["max_move"].as_f64().unwrap() > p["threshold"].as_f64().unwrap());
    b.ok(json!({"type": "drag_end", "part": SHELL, "icon": icon}))
        .await;

    // Bob (another editor) cancels Ann's job; Ann's fair is answered then.
    b.ok(json!({"type": "cancel_fairing", "part": s.part, "face": s.five}))
        .await;
    let ended = job_message(&mut b, "fairing_ended", s.part, s.five).await;
    assert_eq!(ended["outcome"], "cancelled", "{ended}");
    let r = answer(&mut a, 900).await;
    assert_eq!(r["type"], "error", "{r}");
    assert_eq!(r["code"], "conflict", "{r}");
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancel_changes_nothing_and_a_second_request_is_refused() {
    let s = setup("fairing-job-cancel").await;
    let mut a = s.client("ann").await;
    let mut v = Client::connect(
        s.server.addr,
        s.design,
        &s.server.demo().viewer.clone(),
        "viewer",
    )
    .await;
    let (before, _) = s.doc().await;
    send_req(&mut a, s.long_fair(), 900).await;
    // The viewer sees the job's progress, and may not cancel it.
    let started = job_message(&mut v, "fairing_progress", s.part, s.five).await;
    assert_eq!(started["iteration"], 0);
    let running = loop {
        let p = job_message(&mut v, "fairing_progress", s.part, s.five).await;
        if p["iteration"].as_u64().unwrap() > 0 {
            break p;
        }
    };
    assert!(running["fraction"].as_f64().unwrap() >= 0.0);
    v.refused(
        json!({"type": "cancel_fairing", "part": s.part, "face": s.five}),
        "forbidden",
    )
    .await;

    // A second fair of the same face (even another kind of run) is refused.
    let mut second = s.long_fair();
    second["edit"]["max_iterations"] = json!(5);
    let r = a.request(second).await;
    assert_eq!(r["type"], "error", "{r}");
    assert_eq!(r["code"], "conflict", "{r}");
    assert!(
        r["message"]
            .as_str()
            .unwrap()
            .contains("already being faired"),
        "{r}"
    );
    // Cancelling a face with no job is refused too.
    a.refused(
        json!({"type": "cancel_fairing", "part": s.part, "face": (s.five + 1) % 6}),
        "out_of_range",
    )
    .await;

    a.ok(json!({"type": "cancel_fairing", "part": s.part, "face": s.five}))
        .await;
    let r = answer(&mut a, 900).await;
    assert_eq!(r["code"], "conflict", "{r}");
    assert!(r["message"].as_str().unwrap().contains("cancelled"), "{r}");
    let ended = job_message(&mut v, "fairing_ended", s.part, s.five).await;
    assert_eq!(ended["outcome"], "cancelled", "{ended}");
    assert!(ended["iterations"].as_u64().unwrap() >= 1, "{ended}");
    let (after, _) = s.doc().await;
    assert_eq!(after, before, "a cancelled fairing changed the design");
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_finished_job_equals_the_synchronous_run_and_undo_restores_the_face() {
    let s = setup("fairing-job-result").await;
    let mut a = s.client("ann").await;
    let mut b = s.client("bob").await;
    let (before, body) = s.doc().await;
    let PartBody::Network(part) = body else {
        panic!("not a network")
    };
    // Goals in mean and in Gaussian curvature (from the boundary's).
    for (measure, name) in [
        (MeasureDoc::Mean, "mean"),
        (MeasureDoc::Gaussian, "gaussian"),
    ] {
        let doc = FairingDoc {
            face: s.five as usize,
            measure,
            goal: GoalDoc::FromBoundary,
            relaxation: 1.0,
            tolerance: 1e-10,
            max_iterations: 40,
        };
        // The synchronous run of the same fairing on the same part.
        let mut engine = NetworkEngine::build(&part).unwrap();
        engine.apply(&NetworkEditDoc::Fair(doc)).unwrap();
        let sync = engine.to_part().faired;
        assert_eq!(sync.len(), 1);

        let r = a
            .request(
                json!({"type": "network_edit", "part": s.part, "edit": {"op": "fair",
                "face": s.five, "measure": name, "goal": "from_boundary", "max_iterations": 40}}),
            )
            .await;
        assert_eq!(r["type"], "ack", "{name}: {r}");
        let ended = job_message(&mut b, "fairing_ended", s.part, s.five).await;
        assert_eq!(ended["outcome"], "applied", "{name}: {ended}");
        assert_eq!(ended["iterations"], json!(sync[0].iterations));
        let (_, body) = s.doc().await;
        let PartBody::Network(faired) = body else {
            panic!("not a network")
        };
        assert_eq!(faired.faired.len(), 1);
        let (got, want) = (&faired.faired[0], &sync[0]);
        assert_eq!(got.face, want.face);
        assert_eq!(got.points.len(), want.points.len());
        let worst = got
            .points
            .iter()
            .zip(&want.points)
            .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-12,
            "{name}: job and synchronous run differ by {worst}"
        );
        // The run moved the interior (the comparison can fail), not the
        // boundary.
        let input = NetworkEngine::build(&part)
            .unwrap()
            .fairing_input(&doc)
            .unwrap();
        let (mut moved, mut moved_boundary) = (0.0f64, 0.0f64);
        for ((p, q), on) in got.points.iter().zip(&input.points).zip(&input.boundary) {
            let d = glam::DVec3::from(*p).distance(*q);
            if *on {
                moved_boundary = moved_boundary.max(d);
            } else {
                moved = moved.max(d);
            }
        }
        println!(
            "{name}: {} sweeps, interior moved up to {moved:.3e}",
            sync[0].iterations
        );
        assert!(
            moved > 1e-4,
            "{name}: fairing moved the interior by {moved}"
        );
        assert_eq!(moved_boundary, 0.0, "{name}: fairing moved the boundary");

        // One undo restores the unfaired face, byte for byte.
        a.ok(json!({"type": "undo"})).await;
        let (undone, _) = s.doc().await;
        assert_eq!(undone, before);
    }
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_face_changed_while_it_is_faired_discards_the_result() {
    let s = setup("fairing-job-stale").await;
    let mut a = s.client("ann").await;
    let mut b = s.client("bob").await;
    let (_, body) = s.doc().await;
    let PartBody::Network(part) = body else {
        panic!("not a network")
    };
    // A curve of the five-sided face: its control point away from meetings.
    let sides = &b.snapshot["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == json!(s.part))
        .unwrap()["shape"]["network"]["faces"][s.five as usize]["sides"];
    let curve = sides[0]["curve"].as_u64().unwrap() as usize;
    let (t0, t1) = (
        sides[0]["t_start"].as_f64().unwrap(),
        sides[0]["t_end"].as_f64().unwrap(),
    );
    let mut fair = s.long_fair();
    fair["edit"]["max_iterations"] = json!(500);
    send_req(&mut a, fair, 900).await;
    job_message(&mut b, "fairing_progress", s.part, s.five).await;
    // Drag the middle of the face's first side outwards while it runs.
    let c = vsculpt_server::design::network_engine::kernel_curve(&part.curves[curve]).unwrap();
    let t = 0.5 * (t0 + t1);
    let to = c.point(t) * 1.05;
    b.ok(json!({"type": "network_edit", "part": s.part,
        "edit": {"op": "drag_point", "curve": curve, "t": t, "xyz": to.to_array()}}))
        .await;
    let (dragged, _) = s.doc().await;
    let ended = job_message(&mut b, "fairing_ended", s.part, s.five).await;
    assert_eq!(ended["outcome"], "discarded", "{ended}");
    let r = answer(&mut a, 900).await;
    assert_eq!(r["code"], "conflict", "{r}");
    assert!(r["message"].as_str().unwrap().contains("discarded"), "{r}");
    let (after, _) = s.doc().await;
    assert_eq!(after, dragged, "a discarded result changed the design");
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn deleting_the_part_cancels_its_job() {
    let s = setup("fairing-job-delete").await;
    let mut a = s.client("ann").await;
    send_req(&mut a, s.long_fair(), 900).await;
    job_message(&mut a, "fairing_progress", s.part, s.five).await;
    a.ok(json!({"type": "delete_part", "part": s.part})).await;
    let ended = job_message(&mut a, "fairing_ended", s.part, s.five).await;
    assert_eq!(ended["outcome"], "cancelled", "{ended}");
    assert!(
        ended["message"].as_str().unwrap().contains("deleted"),
        "{ended}"
    );
    let r = answer(&mut a, 900).await;
    assert_eq!(r["code"], "conflict", "{r}");
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_joining_while_a_job_runs_finds_it_in_its_snapshot() {
    let s = setup("fairing-job-join").await;
    let mut a = s.client("ann").await;
    assert!(
        a.snapshot.get("fairing").is_none(),
        "no job runs yet: {}",
        a.snapshot["fairing"]
    );
    send_req(&mut a, s.long_fair(), 900).await;
    // Wait until the job has done sweeps, so the snapshot has more to say
    // than the start.
    let seen = loop {
        let p = job_message(&mut a, "fairing_progress", s.part, s.five).await;
        if p["iteration"].as_u64().unwrap() > 0 {
            break p;
        }
    };

    // Cy joins now: its snapshot lists the job, at least as far on as the
    // progress Ann saw before Cy joined.
    let c = s.client("cy").await;
    let jobs = c.snapshot["fairing"].as_array().expect("fairing listed");
    assert_eq!(jobs.len(), 1, "{}", c.snapshot["fairing"]);
    let j = &jobs[0];
    assert_eq!(j["part"], json!(s.part), "{j}");
    assert_eq!(j["face"], json!(s.five), "{j}");
    assert_eq!(j["client"], json!(a.client_id()), "{j}");
    assert_eq!(j["max_iterations"], 100_000, "{j}");
    assert!(
        j["iteration"].as_u64().unwrap() >= seen["iteration"].as_u64().unwrap(),
        "{j} is behind {seen}"
    );
    let fraction = j["fraction"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&fraction), "{j}");
    assert!(j["max_move"].as_f64().unwrap() > 0.0, "{j}");

    // Once the job ended (cancelled), a joiner's snapshot lists none.
    a.ok(json!({"type": "cancel_fairing", "part": s.part, "face": s.five}))
        .await;
    let r = answer(&mut a, 900).await;
    assert_eq!(r["code"], "conflict", "{r}");
    let d = s.client("dee").await;
    assert!(
        d.snapshot.get("fairing").is_none(),
        "{}",
        d.snapshot["fairing"]
    );
    s.stop().await;
}
