//! A product: a design made of many parts — surfaces and curves today,
//! room for every shape model of the papers — and the relations between
//! them.
//!
//! * [`Part`] — one shape of one kind (a [`crate::design::Design`] surface
//!   or a [`crate::curve_design::CurveDesign`] curve), keyed by [`PartId`].
//!   A new kind is one new variant (here, in [`PartSnapshot`] and in the
//!   few `match`es of `part.rs` and `model.rs`).
//! * [`Product`] — the parts, edits and drags forwarded to them, and which
//!   parts each changed ([`ChangedParts`]). A part with no relation is
//!   solved exactly as alone.
//! * [`Join`] — two surface edges held together, G0 or G1, by linear
//!   constraints between the parts' control points (`join.rs`).
//! * [`Binding`] — a curve part a surface follows along a parameter line
//!   (`binding.rs`).
//! * Groups of joined and bound surfaces are solved jointly over a
//!   block-diagonal stiffness (`group.rs`).

pub mod binding;
mod changed;
mod compat;
mod edge;
mod error;
mod group;
pub mod join;
mod model;
mod part;

pub use binding::{Binding, BindingId, BindingSpec, IsoLine, iso_curve};
pub use changed::ChangedParts;
pub use compat::map_parameter;
pub use edge::Edge;
pub use error::ProductError;
pub use join::{Continuity, Join, JoinId, JoinSpec};
pub use model::{Edited, PartDrag, Product, RemovedPart};
pub use part::{Part, PartId, PartKind, PartSnapshot};
