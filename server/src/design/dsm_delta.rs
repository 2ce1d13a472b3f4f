//! Mesh deltas (protocol kind 8, `/ws?mesh_delta=1`): a part's new mesh
//! frame as the changes from the frame published before it, for the clients
//! that hold that one. A DSM part's mesher re-meshes only where an edit
//! reaches and its frames keep their quantisation cube while the model's
//! bounds hold ([`super::dsm_engine::grid_cube`]), so during a drag most of
//! a frame is runs of the previous one.
//!
//! The delta is made once per published frame (every client that gets it
//! gets the same bytes) and checked before it is offered: applied to the
//! previous frame, it must give the new frame's bytes exactly, or no delta
//! is made and every client gets the whole frame.

use super::deflated_frame::DeflatedFrame;
use axum::body::Bytes;
use vsculpt_protocol::mesh_delta::MeshDelta;
use vsculpt_protocol::mesh_frame::{KIND_MESH, MESH_HEADER_BYTES, MeshFrame};

/// A part's frame as a mesh delta from the frame of revision `base`.
#[derive(Clone, Debug)]
pub struct MeshDeltaFrame {
    /// The revision of the part's frame the delta applies to.
    pub base: u64,
    /// The encoded [`MeshDelta`].
    pub frame: Bytes,
    /// `frame` deflated, for the clients that asked (`deflate=1`).
    pub deflated: DeflatedFrame,
}

/// Whether `bytes` is a mesh frame (kind 3) with a header.
fn is_mesh(bytes: &[u8]) -> bool {
    bytes.len() >= MESH_HEADER_BYTES && bytes[4] == KIND_MESH
}

/// The new frame `next` as a delta from the part's frame `previous` of
/// revision `base`, when both are mesh frames on the same cube and the
/// delta is shorter than `next` and gives it back byte for byte.
pub fn mesh_delta(base: u64, previous: &[u8], next: &[u8]) -> Option<MeshDeltaFrame> {
    // Origin and step (bytes 40–55) differ: no delta, and no decoding.
    if !is_mesh(previous) || !is_mesh(next) || previous[40..56] != next[40..56] {
        return None;
    }
    let old = MeshFrame::decode(previous).ok()?;
    let new = MeshFrame::decode(next).ok()?;
    if old.revision != base {
        return None;
    }
    let delta = MeshDelta::between(&old, &new)?;
    let made = delta.apply(&old).ok()?.encode().ok()?;
    if made != next {
        tracing::warn!(
            part = new.part,
            revision = new.revision,
            "a mesh delta did not give its frame back; sending the whole frame"
        );
        return None;
    }
    Some(MeshDeltaFrame {
        base,
        frame: Bytes::from(delta.encode().ok()?),
        deflated: DeflatedFrame::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::dsm_engine::{DsmEngine, DsmPart};
    use vsculpt_protocol::dsm::{DsmData, DsmEdit};

    fn frame(engine: &DsmEngine, rev: u64) -> Bytes {
        engine.frame(1, 5, rev, false).unwrap()
    }

    #[test]
    fn a_moved_button_of_the_handset_is_a_short_delta_that_gives_the_frame_back() {
        let demo = super::super::demo::handset_dsm();
        let mut engine = DsmEngine::default();
        engine.insert(5, &DsmPart::new(demo.clone())).unwrap();
        let before = frame(&engine, 1);
        // The lanyard hole (the subtracted cylinder), moved a little.
        let id = demo.groups[1].primitives[0].id;
        let at = demo.groups[1].primitives[0].at;
        // Sideways: the box's bounding ball, not the hole's, bounds the model in y.
        let edit = DsmEdit::MovePrimitive {
            id,
            at: [at[0], at[1] + 0.01, at[2]],
        };
        let moved: DsmData = super::super::dsm_engine::apply_edit(&demo, &edit).unwrap();
        engine.insert(5, &DsmPart::new(moved)).unwrap();
        let after = frame(&engine, 2);
        let d = mesh_delta(1, &before, &after).expect("a delta");
        assert!(d.frame.len() < after.len());
        let applied = MeshDelta::decode(&d.frame)
            .unwrap()
            .apply(&MeshFrame::decode(&before).unwrap())
            .unwrap();
        assert_eq!(applied.encode().unwrap(), after.to_vec());
        // Not from a frame of another revision, nor to a non-mesh frame.
        assert!(mesh_delta(2, &before, &after).is_none());
        assert!(mesh_delta(1, &before, &after[..40]).is_none());
    }
}
