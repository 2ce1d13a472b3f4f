//! Finding a design by one of its tokens through indexes, so a request's
//! token check costs a few B-tree lookups however many designs exist,
//! instead of loading every design row. The row found is confirmed with
//! the constant-time comparison of [`super::Tokens::role_of`].

use super::{DesignRecord, Role, Store, StoreError};
use rusqlite::OptionalExtension;

/// The indexes the lookup uses (created if missing; cheap when present).
pub const TOKEN_INDEXES: &str = "
CREATE INDEX IF NOT EXISTS designs_editor_token ON designs (editor_token);
CREATE INDEX IF NOT EXISTS designs_viewer_token ON designs (viewer_token);
CREATE INDEX IF NOT EXISTS designs_device_token ON designs (device_token);
";

/// The lookup: one indexed probe per token column.
pub const TOKEN_LOOKUP: &str = "
SELECT id, name, created_ms, editor_token, viewer_token, device_token FROM designs
    WHERE editor_token = ?1 AND deleted = 0
UNION ALL
SELECT id, name, created_ms, editor_token, viewer_token, device_token FROM designs
    WHERE viewer_token = ?1 AND deleted = 0
UNION ALL
SELECT id, name, created_ms, editor_token, viewer_token, device_token FROM designs
    WHERE device_token = ?1 AND deleted = 0
LIMIT 1
";

impl Store {
    /// Creates the token indexes if this database has none yet.
    pub fn ensure_token_indexes(&self) -> Result<(), StoreError> {
        self.conn().execute_batch(TOKEN_INDEXES)?;
        Ok(())
    }

    /// The live design `token` belongs to, with the role it grants.
    pub fn design_by_token(&self, token: &str) -> Result<Option<(DesignRecord, Role)>, StoreError> {
        if token.is_empty() {
            return Ok(None);
        }
        let conn = self.conn();
        let rec = conn
            .query_row(TOKEN_LOOKUP, [token], Self::row_to_record)
            .optional()?;
        Ok(rec.and_then(|r| r.tokens.role_of(token).map(|role| (r, role))))
    }
}
