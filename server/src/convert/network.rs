//! Network parts between the wire (`vsculpt_protocol::network`) and the
//! design (`design::part::NetworkPart`, `design::network_engine`): decoding
//! a network shape and `network_edit`, encoding a network with its
//! meetings and faces for snapshots, `part_created` and `network_changed`;
//! a fairing job's `fairing_progress` and `fairing_ended`.

use crate::design::fairing_job::{JobEnded, JobOutcome, JobProgress};
use crate::design::network_engine::{
    DEFAULT_FAIRING_ITERATIONS, FairingDoc, GoalDoc, MeasureDoc, NetworkEditDoc, NetworkView,
};
use crate::design::part::{CurveDoc, NetworkPart};
use axum::extract::ws::Utf8Bytes;
use vsculpt_protocol as wire;
use vsculpt_protocol::ServerMessage;
use vsculpt_protocol::network::{
    FaceSide, FairingGoal, FairingOutcome, FairingProgress, FairnessMeasure, Meeting, NetworkData,
    NetworkEdit, NetworkFace, RibbonHandles,
};

fn curve_from_wire(c: &wire::CurveData) -> CurveDoc {
    CurveDoc {
        degree: c.knots.degree as usize,
        knots: c.knots.knots.clone(),
        points: c.points.clone(),
    }
}

fn curve_to_wire(c: &CurveDoc) -> wire::CurveData {
    wire::CurveData {
        knots: wire::Knots {
            degree: c.degree as u32,
            knots: c.knots.clone(),
        },
        points: c.points.clone(),
    }
}

/// A wire network as a new part's body (meetings, faces and faired faces
/// are the server's and ignored).
pub fn network_from_wire(n: &NetworkData) -> NetworkPart {
    NetworkPart {
        curves: n.curves.iter().map(curve_from_wire).collect(),
        tolerance: n.tolerance,
        up: n.up,
        faired: Vec::new(),
        ribbons: Default::default(),
        icons: Vec::new(),
    }
}

/// A network with its meetings and faces on the wire.
pub fn network_to_wire(v: &NetworkView) -> NetworkData {
    NetworkData {
        curves: v.part.curves.iter().map(curve_to_wire).collect(),
        tolerance: v.part.tolerance,
        up: v.part.up,
        meetings: v
            .meetings
            .iter()
            .map(|(p, inc)| Meeting {
                point: *p,
                curves: inc.iter().map(|&(c, t)| (c as u32, t)).collect(),
            })
            .collect(),
        faces: v
            .faces
            .iter()
            .map(|sides| NetworkFace {
                sides: sides
                    .iter()
                    .map(|&(curve, t_start, t_end)| FaceSide {
                        curve: curve as u32,
                        t_start,
                        t_end,
                    })
                    .collect(),
            })
            .collect(),
        faired: v.part.faired.iter().map(|f| f.face as u32).collect(),
        ribbons: v
            .ribbons
            .iter()
            .map(|sides| {
                sides
                    .iter()
                    .map(|&(scale, twist)| RibbonHandles { scale, twist })
                    .collect()
            })
            .collect(),
        tuning: v.tuning.clone(),
    }
}

/// A `network_edit` as the engine's edit (defaults filled in).
pub fn edit_from_wire(e: &NetworkEdit) -> NetworkEditDoc {
    match e {
        NetworkEdit::MovePoint { curve, index, xyz } => NetworkEditDoc::MovePoint {
            curve: *curve as usize,
            index: *index as usize,
            xyz: *xyz,
        },
        NetworkEdit::DragPoint { curve, t, xyz } => NetworkEditDoc::DragPoint {
            curve: *curve as usize,
            t: *t,
            xyz: *xyz,
        },
        NetworkEdit::AddCurve { curve } => NetworkEditDoc::AddCurve(curve_from_wire(curve)),
        NetworkEdit::RemoveCurve { curve } => NetworkEditDoc::RemoveCurve(*curve as usize),
        NetworkEdit::SetRibbon {
            face,
            side,
            scale,
            twist,
        } => NetworkEditDoc::SetRibbon {
            face: *face as usize,
            side: *side as usize,
            scale: *scale,
            twist: *twist,
        },
        NetworkEdit::SetTuning { face, handles } => NetworkEditDoc::SetTuning {
            face: *face as usize,
            handles: handles.clone(),
        },
        NetworkEdit::Fair(f) => NetworkEditDoc::Fair(FairingDoc {
            face: f.face as usize,
            measure: match f.measure {
                FairnessMeasure::Mean => MeasureDoc::Mean,
                FairnessMeasure::Gaussian => MeasureDoc::Gaussian,
                FairnessMeasure::MaxPrincipal => MeasureDoc::MaxPrincipal,
                FairnessMeasure::MinPrincipal => MeasureDoc::MinPrincipal,
            },
            goal: match f.goal {
                FairingGoal::Constant(g) => GoalDoc::Constant(g),
                FairingGoal::FromBoundary => GoalDoc::FromBoundary,
            },
            relaxation: f.relaxation.unwrap_or(1.0),
            tolerance: f.tolerance.unwrap_or(1e-10),
            max_iterations: f
                .max_iterations
                .map_or(DEFAULT_FAIRING_ITERATIONS, |n| n as usize),
        }),
    }
}

/// A fairing job's progress as the wire has it (in `fairing_progress` and
/// a snapshot's `fairing`).
pub fn fairing_progress(p: &JobProgress) -> FairingProgress {
    FairingProgress {
        part: p.part,
        face: p.face as u32,
        client: p.client,
        iteration: p.iteration as u32,
        max_iterations: p.max_iterations as u32,
        max_move: p.max_move,
        threshold: p.threshold,
        fraction: p.fraction,
    }
}

/// A fairing job's progress on the wire.
pub fn fairing_progress_to_wire(p: &JobProgress) -> Utf8Bytes {
    super::text(&ServerMessage::FairingProgress(fairing_progress(p)))
}

/// A fairing job's end on the wire.
pub fn fairing_ended_to_wire(e: &JobEnded) -> Utf8Bytes {
    super::text(&ServerMessage::FairingEnded {
        part: e.part,
        face: e.face as u32,
        client: e.client,
        outcome: match e.outcome {
            JobOutcome::Applied => FairingOutcome::Applied,
            JobOutcome::Cancelled => FairingOutcome::Cancelled,
            JobOutcome::Discarded => FairingOutcome::Discarded,
            JobOutcome::Failed => FairingOutcome::Failed,
        },
        iterations: e.iterations as u32,
        converged: e.converged,
        message: e.message.clone(),
    })
}
