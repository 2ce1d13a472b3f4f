//! Icon entities (paper 003): constraints and loads attached to a surface —
//! point, curve and region anchors × load, position, derivative (R, V, R2,
//! V2, RV) and normal roles, in the states driving, passive and sleeping —
//! and how each becomes equations or loads of a [`crate::solve::Problem`].

mod distributed;
mod entity;
mod group;
mod id;
mod identity;
mod kind;
mod rows;
mod sampling;
mod state;

pub use distributed::load_row;
pub use entity::{Icon, IconSpec, centroid};
pub use group::icon_group;
pub use id::{IconId, SensorId};
pub use identity::{Identity, curve_identity};
pub use kind::{Anchor, Derivative, Edge, Role};
pub use rows::{curve_row, surface_row};
pub use sampling::{AnchorError, capture, held_points, placement, samples};
pub use state::IconState;
