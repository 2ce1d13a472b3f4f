//! Review comments in the store (schema version 2): one row per comment or
//! reply (a reply names its comment in `parent`; deleting a comment
//! deletes its replies), tied to the design and to the design version it
//! was written on. Each write is its own durable transaction, like a
//! commit: a comment is on disk before anyone is told of it.

use super::{DesignId, Role, Store, StoreError};
use rusqlite::{OptionalExtension, params};

/// Schema version 2: the comments table.
pub(super) const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS comments (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    design_id   INTEGER NOT NULL REFERENCES designs(id),
    parent      INTEGER REFERENCES comments(id) ON DELETE CASCADE,
    part        INTEGER NOT NULL,
    u           REAL,
    v           REAL,
    x           REAL,
    y           REAL,
    z           REAL,
    text        TEXT    NOT NULL,
    author      TEXT    NOT NULL,
    access      TEXT    NOT NULL,
    time_ms     INTEGER NOT NULL,
    version     INTEGER NOT NULL,
    resolved_by TEXT,
    resolved_ms INTEGER
);
CREATE INDEX IF NOT EXISTS comments_by_design ON comments(design_id, id);
";

/// A comment or reply to store.
#[derive(Clone, Debug, PartialEq)]
pub struct NewComment {
    /// The comment replied to (`None`: a new comment).
    pub parent: Option<u64>,
    /// The part it is pinned to (a reply: its comment's part).
    pub part: u64,
    /// (u, v) on a surface part.
    pub uv: Option<[f64; 2]>,
    /// The model-space point (a reply: none).
    pub xyz: Option<[f64; 3]>,
    /// What it says.
    pub text: String,
    /// Who wrote it.
    pub author: String,
    /// Through which link.
    pub access: Role,
    /// The design version it was written on.
    pub version: u64,
}

/// Schema version 3: when a comment's text was last edited.
pub(super) const SCHEMA_EDITED: &str = "ALTER TABLE comments ADD COLUMN edited_ms INTEGER;";

/// A stored comment or reply.
#[derive(Clone, Debug, PartialEq)]
pub struct CommentRecord {
    /// Its id (unique in the store).
    pub id: u64,
    /// What was stored.
    pub comment: NewComment,
    /// When, ms since the Unix epoch.
    pub time_ms: i64,
    /// When its text was last edited, ms since the Unix epoch (`None`:
    /// never).
    pub edited_ms: Option<i64>,
    /// Who resolved it (a comment; `None` while open).
    pub resolved_by: Option<String>,
}

fn access_text(r: Role) -> &'static str {
    match r {
        Role::Editor => "editor",
        Role::Viewer => "viewer",
        Role::Device => "device",
    }
}

fn access_of(s: &str) -> Role {
    match s {
        "editor" => Role::Editor,
        "device" => Role::Device,
        _ => Role::Viewer,
    }
}

fn row_to_record(r: &rusqlite::Row<'_>) -> rusqlite::Result<CommentRecord> {
    let opt = |i: usize| r.get::<_, Option<f64>>(i);
    let (u, v) = (opt(3)?, opt(4)?);
    let (x, y, z) = (opt(5)?, opt(6)?, opt(7)?);
    Ok(CommentRecord {
        id: r.get::<_, i64>(0)? as u64,
        comment: NewComment {
            parent: r.get::<_, Option<i64>>(1)?.map(|p| p as u64),
            part: r.get::<_, i64>(2)? as u64,
            uv: u.zip(v).map(|(u, v)| [u, v]),
            xyz: match (x, y, z) {
                (Some(x), Some(y), Some(z)) => Some([x, y, z]),
                _ => None,
            },
            text: r.get(8)?,
            author: r.get(9)?,
            access: access_of(&r.get::<_, String>(10)?),
            version: r.get::<_, i64>(12)? as u64,
        },
        time_ms: r.get(11)?,
        resolved_by: r.get(13)?,
        edited_ms: r.get(14)?,
    })
}

const COLUMNS: &str = "id, parent, part, u, v, x, y, z, text, author, access, time_ms, version, resolved_by, edited_ms";

impl Store {
    /// Stores a comment or reply of live design `id` (a reply's parent must
    /// be a comment of that design, not a reply).
    pub fn add_comment(&self, id: DesignId, c: &NewComment) -> Result<CommentRecord, StoreError> {
        let time_ms = super::now_ms();
        let mut conn = self.conn();
        let tx = conn.transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)?;
        super::live_design(&tx, id)?;
        if let Some(p) = c.parent {
            let head: Option<i64> = tx
                .query_row(
                    "SELECT id FROM comments WHERE id = ?1 AND design_id = ?2 AND parent IS NULL",
                    params![p as i64, id as i64],
                    |r| r.get(0),
                )
                .optional()?;
            if head.is_none() {
                return Err(StoreError::UnknownComment(id, p));
            }
        }
        let [u, v] = c.uv.map_or([None, None], |[u, v]| [Some(u), Some(v)]);
        let [x, y, z] = c
            .xyz
            .map_or([None, None, None], |[x, y, z]| [Some(x), Some(y), Some(z)]);
        tx.execute(
            "INSERT INTO comments (design_id, parent, part, u, v, x, y, z, text, author, access, time_ms, version)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13)",
            params![
                id as i64,
                c.parent.map(|p| p as i64),
                c.part as i64,
                u,
                v,
                x,
                y,
                z,
                c.text,
                c.author,
                access_text(c.access),
                time_ms,
                c.version as i64
            ],
        )?;
        let new_id = tx.last_insert_rowid() as u64;
        tx.commit()?;
        Ok(CommentRecord {
            id: new_id,
            comment: c.clone(),
            time_ms,
            edited_ms: None,
            resolved_by: None,
        })
    }

    /// Every comment and reply of design `id`, oldest first.
    pub fn comments(&self, id: DesignId) -> Result<Vec<CommentRecord>, StoreError> {
        let conn = self.conn();
        let mut stmt = conn.prepare(&format!(
            "SELECT {COLUMNS} FROM comments WHERE design_id = ?1 ORDER BY id"
        ))?;
        let rows = stmt.query_map(params![id as i64], row_to_record)?;
        Ok(rows.collect::<Result<Vec<_>, _>>()?)
    }

    /// Marks comment `comment` of design `id` resolved by `by`, or open
    /// (`None`); false when there is no such comment.
    pub fn resolve_comment(
        &self,
        id: DesignId,
        comment: u64,
        by: Option<&str>,
    ) -> Result<bool, StoreError> {
        let n = self.conn().execute(
            "UPDATE comments SET resolved_by = ?3, resolved_ms = ?4
             WHERE design_id = ?1 AND id = ?2 AND parent IS NULL",
            params![id as i64, comment as i64, by, by.map(|_| super::now_ms())],
        )?;
        Ok(n == 1)
    }

    /// Replaces the text of comment or reply `comment` of design `id` and
    /// stamps the edit; the time stamped (ms since the Unix epoch), or
    /// `None` when there is no such row.
    pub fn edit_comment(
        &self,
        id: DesignId,
        comment: u64,
        text: &str,
    ) -> Result<Option<i64>, StoreError> {
        let at = super::now_ms();
        let n = self.conn().execute(
            "UPDATE comments SET text = ?3, edited_ms = ?4 WHERE design_id = ?1 AND id = ?2",
            params![id as i64, comment as i64, text, at],
        )?;
        Ok((n == 1).then_some(at))
    }

    /// Deletes comment or reply `comment` of design `id` (a comment with its
    /// replies); false when there is no such row.
    pub fn delete_comment(&self, id: DesignId, comment: u64) -> Result<bool, StoreError> {
        let n = self.conn().execute(
            "DELETE FROM comments WHERE design_id = ?1 AND id = ?2",
            params![id as i64, comment as i64],
        )?;
        Ok(n == 1)
    }
}
