//! Review comments between the server's threads (`design::comments`) and
//! the wire's `Comment`.

use crate::design::comments::{CommentChange, CommentThread};
use crate::store::CommentRecord;
use vsculpt_protocol as wire;
use vsculpt_protocol::ServerMessage;

fn reply_to_wire(r: &CommentRecord) -> wire::CommentReply {
    wire::CommentReply {
        id: r.id,
        text: r.comment.text.clone(),
        author: r.comment.author.clone(),
        access: super::access(r.comment.access),
        time_ms: r.time_ms.max(0) as u64,
        edited_ms: r.edited_ms.map(|t| t.max(0) as u64),
        version: r.comment.version,
    }
}

/// A comment with its replies as clients see it.
pub fn thread_to_wire(t: &CommentThread) -> wire::Comment {
    let h = &t.head;
    wire::Comment {
        id: h.id,
        part: h.comment.part,
        anchor: wire::CommentAnchor {
            u: h.comment.uv.map(|[u, _]| u),
            v: h.comment.uv.map(|[_, v]| v),
            xyz: h.comment.xyz,
        },
        text: h.comment.text.clone(),
        author: h.comment.author.clone(),
        access: super::access(h.comment.access),
        time_ms: h.time_ms.max(0) as u64,
        edited_ms: h.edited_ms.map(|t| t.max(0) as u64),
        version: h.comment.version,
        resolved: h.resolved_by.is_some(),
        resolved_by: h.resolved_by.clone(),
        replies: t.replies.iter().map(reply_to_wire).collect(),
    }
}

/// `comment_added`, `comment_changed` or `comment_deleted`.
pub fn change_to_wire(c: &CommentChange) -> ServerMessage {
    match c {
        CommentChange::Added(t) => ServerMessage::CommentAdded {
            comment: thread_to_wire(t),
        },
        CommentChange::Changed(t) => ServerMessage::CommentChanged {
            comment: thread_to_wire(t),
        },
        CommentChange::Deleted(id) => ServerMessage::CommentDeleted { comment: *id },
    }
}
