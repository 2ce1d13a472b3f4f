//! Review comments: a pin anchored to a point on a part (a surface part by
//! its parameters (u, v), any part by a model-space point), with its text,
//! author, the design version it was written on, whether it is resolved,
//! and a thread of replies. Comments are not geometry: they are stored with
//! the design, survive restarts and never enter undo/redo.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::{ErrorCode, ProtocolError};
use crate::limits::MAX_COMMENT_BYTES;
use crate::types::{Access, Vec3};

/// Where a pin sits on its part. A client gives (u, v) on a surface part —
/// the server then computes `xyz` on the current surface, and clients draw
/// the pin at the surface point S(u, v) of the shape they show — or `xyz`
/// alone on any part (a curve, a network, a DSM or a body part, whose
/// surface has no single (u, v)). Comments from the server always carry
/// `xyz`: the point where the pin was placed, on the shape of the time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CommentAnchor {
    /// Parameter u (with `v`; surface parts only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u: Option<f64>,
    /// Parameter v (with `u`; surface parts only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v: Option<f64>,
    /// The model-space point; when (u, v) is given the server replaces it by
    /// S(u, v).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub xyz: Option<Vec3>,
}

/// One reply in a comment's thread.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CommentReply {
    /// Its id (comments and replies share one id space per design).
    pub id: u64,
    /// What it says.
    pub text: String,
    /// Who wrote it (the writer's `client_name`).
    pub author: String,
    /// Through which link it was written (editor or viewer).
    pub access: Access,
    /// When, milliseconds since the Unix epoch.
    pub time_ms: u64,
    /// When its text was last changed (`edit_comment`), milliseconds since
    /// the Unix epoch; absent if it never was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edited_ms: Option<u64>,
    /// The design version it was written on (see [`Comment::version`]).
    pub version: u64,
}

/// A comment pinned to a point of a part, with its replies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Comment {
    /// Its id, stable within the design.
    pub id: u64,
    /// The part it is pinned to (it stays when the part is deleted).
    pub part: u64,
    /// Where the pin is.
    pub anchor: CommentAnchor,
    /// What it says.
    pub text: String,
    /// Who wrote it (the writer's `client_name`).
    pub author: String,
    /// Through which link it was written: the customer's viewer link or
    /// the designer's editor link.
    pub access: Access,
    /// When, milliseconds since the Unix epoch.
    pub time_ms: u64,
    /// When its text was last changed (`edit_comment`), milliseconds since
    /// the Unix epoch; absent if it never was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edited_ms: Option<u64>,
    /// The design version it was written on: the version last committed,
    /// restored or reverted to when it was written (0: before the first
    /// commit). The comment may be about uncommitted changes made since.
    pub version: u64,
    /// Whether someone marked it resolved.
    pub resolved: bool,
    /// Who resolved it (absent while open).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolved_by: Option<String>,
    /// Its replies, oldest first.
    #[serde(default)]
    pub replies: Vec<CommentReply>,
}

/// A comment's or reply's text: not blank, at most [`MAX_COMMENT_BYTES`]
/// bytes of UTF-8, no control characters but line breaks and tabs.
pub fn validate_text(text: &str) -> Result<(), ProtocolError> {
    if text.trim().is_empty() {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "the comment text is empty",
        ));
    }
    if text.len() > MAX_COMMENT_BYTES {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            format!(
                "the comment text is {} bytes, limit {MAX_COMMENT_BYTES}",
                text.len()
            ),
        ));
    }
    if text
        .chars()
        .any(|c| c.is_control() && c != '\n' && c != '\t')
    {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "the comment text contains control characters (only line breaks and tabs may appear)",
        ));
    }
    Ok(())
}

impl CommentAnchor {
    /// Checks the anchor without the design: (u, v) both or neither, at
    /// least one of (u, v) and `xyz`, every number finite and within
    /// ±[`MAX_MAGNITUDE`](crate::limits::MAX_MAGNITUDE). The server checks the part and the domain.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        match (self.u, self.v) {
            (Some(u), Some(v)) => {
                crate::validate::number("anchor.u", u)?;
                crate::validate::number("anchor.v", v)?;
            }
            (None, None) => {
                if self.xyz.is_none() {
                    return Err(ProtocolError::new(
                        ErrorCode::OutOfRange,
                        "a comment anchor needs (u, v) or xyz",
                    ));
                }
            }
            _ => {
                return Err(ProtocolError::new(
                    ErrorCode::OutOfRange,
                    "a comment anchor gives u and v together",
                ));
            }
        }
        if let Some(p) = self.xyz {
            for (k, x) in p.into_iter().enumerate() {
                crate::validate::number(&format!("anchor.xyz[{k}]"), x)?;
            }
        }
        Ok(())
    }

    /// The (u, v) pair, if given.
    pub fn uv(&self) -> Option<(f64, f64)> {
        self.u.zip(self.v)
    }
}
