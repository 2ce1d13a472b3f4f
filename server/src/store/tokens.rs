//! Access tokens: unguessable random strings (256 bits from the operating
//! system's generator, hex-encoded) and the role each grants on a design.

use serde::{Deserialize, Serialize};

/// What a token lets its holder do on one design.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// May change everything: icons, material, commits, versions.
    Editor,
    /// Sees everything live, changes no geometry; writes review comments
    /// (`design::comments`).
    Viewer,
    /// A device bridge: drives icons (drag, samples), may not commit.
    Device,
}

impl Role {
    /// Whether this role may change the design's shape or icons.
    pub fn can_edit(self) -> bool {
        matches!(self, Role::Editor | Role::Device)
    }

    /// Whether this role may commit, revert, restore or delete.
    pub fn can_manage(self) -> bool {
        matches!(self, Role::Editor)
    }
}

/// The three tokens of one design.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tokens {
    /// Editor token.
    pub editor: String,
    /// Viewer token.
    pub viewer: String,
    /// Device-bridge token.
    pub device: String,
}

impl Tokens {
    /// Three fresh random tokens.
    pub fn generate() -> Result<Self, getrandom::Error> {
        Ok(Self {
            editor: random_token()?,
            viewer: random_token()?,
            device: random_token()?,
        })
    }

    /// The role `token` grants, compared in constant time per token.
    pub fn role_of(&self, token: &str) -> Option<Role> {
        if constant_time_eq(token, &self.editor) {
            Some(Role::Editor)
        } else if constant_time_eq(token, &self.viewer) {
            Some(Role::Viewer)
        } else if constant_time_eq(token, &self.device) {
            Some(Role::Device)
        } else {
            None
        }
    }
}

/// A 64-character hex token from 32 bytes of OS randomness.
pub fn random_token() -> Result<String, getrandom::Error> {
    let mut buf = [0u8; 32];
    getrandom::fill(&mut buf)?;
    Ok(buf.iter().map(|b| format!("{b:02x}")).collect())
}

fn constant_time_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}
