//! Why a product edit was refused. A refused edit changes nothing.

use thiserror::Error;

use super::{BindingId, JoinId, PartId, PartKind};
use crate::design::DesignError;

/// Why a product edit was refused; the product is left as it was.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum ProductError {
    /// No part with that id.
    #[error("no part {0:?}")]
    UnknownPart(PartId),
    /// A part with that id exists already.
    #[error("part {0:?} exists already")]
    DuplicatePart(PartId),
    /// The part is not of the kind the edit needs.
    #[error("part {part:?} is not a {expected:?} part")]
    WrongKind {
        /// The part.
        part: PartId,
        /// The kind the edit needs.
        expected: PartKind,
    },
    /// No join with that id.
    #[error("no join {0:?}")]
    UnknownJoin(JoinId),
    /// A join with that id exists already.
    #[error("join {0:?} exists already")]
    DuplicateJoin(JoinId),
    /// No binding with that id.
    #[error("no binding {0:?}")]
    UnknownBinding(BindingId),
    /// A binding with that id exists already.
    #[error("binding {0:?} exists already")]
    DuplicateBinding(BindingId),
    /// The two edges (or the curve and the surface line) cannot be held
    /// together exactly: different degree, number of control points or
    /// knots (up to reversal and an affine reparameterisation), or a
    /// degenerate edge. The message says which.
    #[error("incompatible: {0}")]
    Incompatible(String),
    /// The part's own edit or solve failed.
    #[error(transparent)]
    Design(#[from] DesignError),
}
