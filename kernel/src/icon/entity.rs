//! The icon entity: id, anchor, role, state, position, target and sensors.
//!
//! Targets, by role: a position constraint's target is the point the surface
//! must pass through (for curves and regions: where the centroid of the held
//! shape must go); a derivative constraint's target is the vector
//! w_u, w_v, w_uu, w_vv or w_uv must equal; a normal constraint's target is
//! the unit normal N; a load's target is the point its spring is pulled to
//! (the load's force is k·(target − attachment)).

use glam::DVec3;

use super::{Anchor, IconId, IconState, Role, SensorId};

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
    /// Its position on the surface (the centroid of its samples), recomputed
    /// after every solve.
    pub xyz: DVec3,
    /// Its target (see the module doc).
    pub target: DVec3,
    /// The held shape: for a constraint, the positions its samples must keep
    /// (shifted by `target − centroid(shape)`); for a load, where its springs
    /// are attached. One point per sample of the anchor.
    pub shape: Vec<DVec3>,
    pub(crate) samples: Vec<(f64, f64)>,
}

impl Icon {
    /// The (u,v) samples where the icon touches the surface.
    pub fn samples(&self) -> &[(f64, f64)] {
        &self.samples
    }

    /// The centroid of the held shape.
    pub fn shape_centroid(&self) -> DVec3 {
        centroid(&self.shape)
    }

    /// The (u,v) of the icon's handle: the point, the middle sample of a
    /// curve, the centre of a region.
    pub fn handle_uv(&self) -> (f64, f64) {
        match &self.anchor {
            Anchor::Point { u, v } => (*u, *v),
            Anchor::Curve(_) => self.samples[self.samples.len() / 2],
            Anchor::Region { u0, v0, u1, v1, .. } => (0.5 * (u0 + u1), 0.5 * (v0 + v1)),
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
