//! Icon entities: constraints and loads attached to a surface or curve, and
//! how each becomes constraint equations or loads of a [`crate::solve::Problem`].

mod rows;

pub use rows::{curve_row, surface_row};
