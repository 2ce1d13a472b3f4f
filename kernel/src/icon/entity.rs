//! The icon entity: id, anchor, role, state, position, target and sensors.
//!
//! Every icon has a *handle* ([`Anchor::handle_uv`]): the point, a curve's
//! mid-parameter point (held exactly: the first row of its identity), a
//! region's centre. Targets, by role:
//!
//! * position: where the handle's surface point must go. A point icon holds
//!   w(u,v) = target; a curve or an inside region holds its whole shape,
//!   translated by `target − handle` (the handle's surface point when the
//!   shape was captured); an outside region holds the rest of the surface
//!   where it is (its target is not used and cannot be set);
//! * derivative: the vector w_u, w_v, w_uu, w_vv or w_uv must equal;
//! * normal: the unit normal N;
//! * load: the hand end of the load's spring. A *driving* load pulls with
//!   k·(target − handle); a passive or sleeping load carries no force. A new
//!   load's spring is attached where the surface is (target = handle).

use glam::DVec3;

use super::{Anchor, IconId, IconState, Role, SensorId};
use crate::solve::ScalarRow;

/// What a new icon should be.
#[derive(Clone, Debug, PartialEq)]
pub struct IconSpec {
    /// Where it sits.
    pub anchor: Anchor,
    /// What it does.
    pub role: Role,
    /// Its state.
    pub state: IconState,
    /// Its target; `None` takes the surface's current value, so a new
    /// constraint holds the shape as it is and a new load pulls nothing.
    pub target: Option<DVec3>,
}

/// An icon attached to a design's surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Icon {
    /// Its id.
    pub id: IconId,
    /// Where it sits.
    pub anchor: Anchor,
    /// What it does.
    pub role: Role,
    /// Driving, passive or sleeping.
    pub state: IconState,
    /// Sensors bound to it.
    pub sensors: Vec<SensorId>,
    /// Its position on the surface (the surface point at its handle),
    /// recomputed after every solve.
    pub xyz: DVec3,
    /// Its target (see the module doc).
    pub target: DVec3,
    /// The held shape: for a position constraint, the positions its samples
    /// must keep (shifted by `target − handle`). One point per sample of the
    /// anchor; a curve's position constraint then one value per row of its
    /// identity ([`super::Identity`]).
    pub shape: Vec<DVec3>,
    /// The surface point at the handle when `shape` was captured: where a
    /// load's spring is attached, and what a position constraint's target is
    /// measured from.
    pub handle: DVec3,
    pub(crate) samples: Vec<(f64, f64)>,
    /// A curve's translation-free identity rows ([`super::Identity`]).
    pub(crate) identity: Vec<ScalarRow>,
}

impl Icon {
    /// The (u,v) samples where the icon touches the surface.
    pub fn samples(&self) -> &[(f64, f64)] {
        &self.samples
    }

    /// The (u,v) of the icon's handle (see [`Anchor::handle_uv`]).
    pub fn handle_uv(&self) -> (f64, f64) {
        self.anchor.handle_uv()
    }

    /// Whether the icon acts on the shape now: a constraint unless sleeping,
    /// a load only while driving (paper 003, Table 1).
    pub fn is_active(&self) -> bool {
        match self.state {
            IconState::Sleeping => false,
            IconState::Passive => self.role.is_constraint(),
            IconState::Driving => true,
        }
    }
}

/// The mean of a set of points (zero for none).
pub fn centroid(points: &[DVec3]) -> DVec3 {
    if points.is_empty() {
        return DVec3::ZERO;
    }
    points.iter().copied().sum::<DVec3>() / points.len() as f64
}
