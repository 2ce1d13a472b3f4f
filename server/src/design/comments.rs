//! A design's review comments at run time: the threads its actor holds (a
//! comment and its replies), who may do what with them, and each request
//! checked against the design before it is written to the store.
//!
//! Rights. Tokens name a party, not a person (every holder of the viewer
//! link is "the customer"), so the author's side is what can be checked:
//!
//! * editors and viewers comment and reply; devices (the bridge) may not;
//! * an editor resolves, reopens and deletes any comment or reply;
//! * a viewer resolves, reopens and deletes only comments and replies
//!   written through a viewer link;
//! * the text of a comment or reply may be changed by whoever may delete
//!   it: its author's side or an editor.
//!
//! Comments are not edits: they never enter undo/redo, and undo, revert or
//! restore leave them alone.

use super::error::{CommandError, ErrorKind};
use super::model::DesignModel;
use crate::store::{CommentRecord, DesignId, NewComment, Role, Store, StoreError};
use std::collections::BTreeMap;
use std::sync::Arc;

/// What a client asks of the comments.
#[derive(Clone, Debug, PartialEq)]
pub enum CommentOp {
    /// Pin a new comment.
    Add {
        /// The part.
        part: u64,
        /// (u, v) on a surface part.
        uv: Option<[f64; 2]>,
        /// The model-space point (replaced by S(u, v) when `uv` is given).
        xyz: Option<[f64; 3]>,
        /// What it says.
        text: String,
    },
    /// Reply to a comment (a reply to a reply joins its comment's thread).
    Reply {
        /// The comment.
        comment: u64,
        /// What it says.
        text: String,
    },
    /// Resolve or reopen a comment.
    Resolve {
        /// The comment (a reply: its comment).
        comment: u64,
        /// Resolved or open.
        resolved: bool,
    },
    /// Delete a comment with its replies, or one reply.
    Delete {
        /// The comment's or reply's id.
        comment: u64,
    },
    /// Replace the text of a comment or reply.
    Edit {
        /// The comment's or reply's id.
        comment: u64,
        /// The new text.
        text: String,
    },
}

/// A comment with its replies, oldest first.
#[derive(Clone, Debug, PartialEq)]
pub struct CommentThread {
    /// The comment.
    pub head: CommentRecord,
    /// Its replies.
    pub replies: Vec<CommentRecord>,
}

/// What a comment request changed, for every client.
#[derive(Clone, Debug, PartialEq)]
pub enum CommentChange {
    /// A new comment.
    Added(CommentThread),
    /// A thread changed (a reply added, edited or deleted, resolved or
    /// reopened, a text edited).
    Changed(CommentThread),
    /// A comment was deleted with its replies.
    Deleted(u64),
}

/// A checked request, ready for the store.
#[derive(Clone, Debug)]
pub enum Write {
    /// Store a comment or reply.
    Add(NewComment),
    /// Set a comment's resolution.
    Resolve {
        /// The comment.
        comment: u64,
        /// Who resolved it; `None`: reopened.
        by: Option<String>,
    },
    /// Delete a comment (with its replies) or a reply.
    Delete {
        /// The id.
        comment: u64,
    },
    /// Replace a comment's or reply's text.
    Edit {
        /// The id.
        comment: u64,
        /// The new text.
        text: String,
    },
}

/// What the store did.
#[derive(Clone, Debug)]
pub enum Written {
    /// The stored comment or reply.
    Added(CommentRecord),
    /// A comment's resolution was stored.
    Resolved {
        /// The comment.
        comment: u64,
        /// Who resolved it.
        by: Option<String>,
    },
    /// A comment or reply was deleted.
    Deleted {
        /// The id.
        comment: u64,
    },
    /// A comment's or reply's text was replaced.
    Edited {
        /// The id.
        comment: u64,
        /// The new text.
        text: String,
        /// When it was stored, ms since the Unix epoch.
        at: i64,
    },
}

impl Write {
    /// Writes to the store (blocking: call on the blocking pool).
    pub fn run(self, store: &Store, design: DesignId) -> Result<Written, StoreError> {
        Ok(match self {
            Write::Add(c) => Written::Added(store.add_comment(design, &c)?),
            Write::Resolve { comment, by } => {
                if !store.resolve_comment(design, comment, by.as_deref())? {
                    return Err(StoreError::UnknownComment(design, comment));
                }
                Written::Resolved { comment, by }
            }
            Write::Delete { comment } => {
                if !store.delete_comment(design, comment)? {
                    return Err(StoreError::UnknownComment(design, comment));
                }
                Written::Deleted { comment }
            }
            Write::Edit { comment, text } => {
                let Some(at) = store.edit_comment(design, comment, &text)? else {
                    return Err(StoreError::UnknownComment(design, comment));
                };
                Written::Edited { comment, text, at }
            }
        })
    }
}

/// Whether `role` may comment and reply.
pub fn may_comment(role: Role) -> bool {
    matches!(role, Role::Editor | Role::Viewer)
}

/// Whether `role` may resolve, reopen or delete what was written through
/// a `written_by` link.
pub fn may_moderate(role: Role, written_by: Role) -> bool {
    match role {
        Role::Editor => true,
        Role::Viewer => written_by == Role::Viewer,
        Role::Device => false,
    }
}

fn unknown(comment: u64) -> CommandError {
    CommandError::new(
        ErrorKind::InvalidValue,
        format!("no comment {comment} in this design"),
    )
}

fn forbidden(role: Role, what: &str) -> CommandError {
    CommandError::new(
        ErrorKind::Forbidden,
        format!("a {} may not {what}", format!("{role:?}").to_lowercase()),
    )
}

/// The comments of one design, as its actor holds them.
#[derive(Clone, Debug)]
pub struct CommentBook {
    threads: BTreeMap<u64, CommentThread>,
    /// Most comments and replies in all.
    limit: usize,
    /// The threads oldest first, shared with snapshots.
    view: Arc<Vec<CommentThread>>,
}

impl CommentBook {
    /// The book of the stored rows (oldest first), holding at most `limit`
    /// comments and replies.
    pub fn new(rows: Vec<CommentRecord>, limit: usize) -> Self {
        let mut threads: BTreeMap<u64, CommentThread> = BTreeMap::new();
        for r in rows {
            match r.comment.parent {
                None => {
                    threads.insert(
                        r.id,
                        CommentThread {
                            head: r,
                            replies: Vec::new(),
                        },
                    );
                }
                Some(p) => {
                    if let Some(t) = threads.get_mut(&p) {
                        t.replies.push(r);
                    }
                }
            }
        }
        let mut book = Self {
            threads,
            limit,
            view: Arc::default(),
        };
        book.refresh();
        book
    }

    fn refresh(&mut self) {
        self.view = Arc::new(self.threads.values().cloned().collect());
    }

    /// Every thread, oldest first.
    pub fn view(&self) -> Arc<Vec<CommentThread>> {
        self.view.clone()
    }

    /// Comments and replies in all.
    pub fn count(&self) -> usize {
        self.threads.values().map(|t| 1 + t.replies.len()).sum()
    }

    /// The thread a comment or reply belongs to, and the record itself.
    fn find(&self, id: u64) -> Option<(&CommentThread, &CommentRecord)> {
        if let Some(t) = self.threads.get(&id) {
            return Some((t, &t.head));
        }
        self.threads
            .values()
            .find_map(|t| t.replies.iter().find(|r| r.id == id).map(|r| (t, r)))
    }

    fn room(&self) -> Result<(), CommandError> {
        if self.count() >= self.limit {
            return Err(CommandError::new(
                ErrorKind::TooLarge,
                format!(
                    "the design holds {} comments and replies, its limit: delete some first",
                    self.limit
                ),
            ));
        }
        Ok(())
    }

    /// Checks `op` by a client of `role` named `author` against the design
    /// (`model`, written on version `version`): what to write, or why not.
    /// Nothing changes here.
    pub fn check(
        &self,
        op: CommentOp,
        role: Role,
        author: &str,
        version: u64,
        model: &DesignModel,
    ) -> Result<Write, CommandError> {
        match op {
            CommentOp::Add {
                part,
                uv,
                xyz,
                text,
            } => {
                if !may_comment(role) {
                    return Err(forbidden(role, "comment"));
                }
                if model.doc().part(part).is_none() {
                    return Err(CommandError::new(
                        ErrorKind::UnknownPart,
                        format!("no part {part}"),
                    ));
                }
                let xyz = match uv {
                    Some([u, v]) => Some(model.surface_point(part, u, v)?.to_array()),
                    None => Some(xyz.ok_or_else(|| {
                        CommandError::new(ErrorKind::InvalidValue, "an anchor needs (u, v) or xyz")
                    })?),
                };
                if xyz.is_some_and(|p| p.iter().any(|x| !x.is_finite())) {
                    return Err(CommandError::new(ErrorKind::NotFinite, "xyz is not finite"));
                }
                self.room()?;
                Ok(Write::Add(NewComment {
                    parent: None,
                    part,
                    uv,
                    xyz,
                    text,
                    author: author.to_string(),
                    access: role,
                    version,
                }))
            }
            CommentOp::Reply { comment, text } => {
                if !may_comment(role) {
                    return Err(forbidden(role, "reply to comments"));
                }
                let (thread, _) = self.find(comment).ok_or_else(|| unknown(comment))?;
                self.room()?;
                Ok(Write::Add(NewComment {
                    parent: Some(thread.head.id),
                    part: thread.head.comment.part,
                    uv: None,
                    xyz: None,
                    text,
                    author: author.to_string(),
                    access: role,
                    version,
                }))
            }
            CommentOp::Resolve { comment, resolved } => {
                let (thread, _) = self.find(comment).ok_or_else(|| unknown(comment))?;
                if !may_moderate(role, thread.head.comment.access) {
                    return Err(forbidden(
                        role,
                        "resolve or reopen a comment written through an editor link",
                    ));
                }
                Ok(Write::Resolve {
                    comment: thread.head.id,
                    by: resolved.then(|| author.to_string()),
                })
            }
            CommentOp::Delete { comment } => {
                let (_, record) = self.find(comment).ok_or_else(|| unknown(comment))?;
                if !may_moderate(role, record.comment.access) {
                    return Err(forbidden(
                        role,
                        "delete a comment or reply written through an editor link",
                    ));
                }
                Ok(Write::Delete { comment })
            }
            CommentOp::Edit { comment, text } => {
                let (_, record) = self.find(comment).ok_or_else(|| unknown(comment))?;
                if !may_moderate(role, record.comment.access) {
                    return Err(forbidden(
                        role,
                        "edit a comment or reply written through an editor link",
                    ));
                }
                Ok(Write::Edit { comment, text })
            }
        }
    }

    /// Takes in what the store wrote: the id it created (a comment or
    /// reply) and the change for every client.
    pub fn apply(&mut self, written: Written) -> (Option<u64>, Option<CommentChange>) {
        let out = match written {
            Written::Added(r) => {
                let id = r.id;
                match r.comment.parent {
                    None => {
                        let t = CommentThread {
                            head: r,
                            replies: Vec::new(),
                        };
                        self.threads.insert(id, t.clone());
                        (Some(id), Some(CommentChange::Added(t)))
                    }
                    Some(p) => match self.threads.get_mut(&p) {
                        Some(t) => {
                            t.replies.push(r);
                            (Some(id), Some(CommentChange::Changed(t.clone())))
                        }
                        None => (Some(id), None),
                    },
                }
            }
            Written::Resolved { comment, by } => match self.threads.get_mut(&comment) {
                Some(t) => {
                    t.head.resolved_by = by;
                    (None, Some(CommentChange::Changed(t.clone())))
                }
                None => (None, None),
            },
            Written::Deleted { comment } => {
                if self.threads.remove(&comment).is_some() {
                    (None, Some(CommentChange::Deleted(comment)))
                } else {
                    let t = self
                        .threads
                        .values_mut()
                        .find(|t| t.replies.iter().any(|r| r.id == comment));
                    match t {
                        Some(t) => {
                            t.replies.retain(|r| r.id != comment);
                            (None, Some(CommentChange::Changed(t.clone())))
                        }
                        None => (None, None),
                    }
                }
            }
            Written::Edited { comment, text, at } => {
                let t = self
                    .threads
                    .values_mut()
                    .find(|t| t.head.id == comment || t.replies.iter().any(|r| r.id == comment));
                match t {
                    Some(t) => {
                        for r in std::iter::once(&mut t.head).chain(t.replies.iter_mut()) {
                            if r.id == comment {
                                r.comment.text.clone_from(&text);
                                r.edited_ms = Some(at);
                            }
                        }
                        (None, Some(CommentChange::Changed(t.clone())))
                    }
                    None => (None, None),
                }
            }
        };
        self.refresh();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rights_follow_the_link_a_comment_was_written_through() {
        assert!(may_comment(Role::Editor) && may_comment(Role::Viewer));
        assert!(!may_comment(Role::Device));
        assert!(may_moderate(Role::Editor, Role::Viewer));
        assert!(may_moderate(Role::Editor, Role::Editor));
        assert!(may_moderate(Role::Viewer, Role::Viewer));
        assert!(!may_moderate(Role::Viewer, Role::Editor));
        assert!(!may_moderate(Role::Device, Role::Viewer));
    }
}
