//! Value types that messages carry: surfaces, materials, icons, versions,
//! designs and presence. Vectors are `[f64; 3]` (JSON arrays), ids are u64.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A point or vector in model space.
pub type Vec3 = [f64; 3];

/// A clamped B-spline knot vector with its degree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Knots {
    /// The degree (≥ 1).
    pub degree: u32,
    /// All knots (control points + degree + 1 of them).
    pub knots: Vec<f64>,
}

/// A tensor-product B-spline surface: knots and a row-major control grid
/// (`index = i * nv + j`, i along u).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceData {
    /// Knots along u (nu control points).
    pub u: Knots,
    /// Knots along v (nv control points).
    pub v: Knots,
    /// Control points along u.
    pub nu: u32,
    /// Control points along v.
    pub nv: u32,
    /// nu · nv control points.
    pub points: Vec<Vec3>,
}

/// A curve in the surface's (u,v) domain: a clamped B-spline whose control
/// points are (u, v) pairs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UvCurve {
    /// Degree and knots.
    pub knots: Knots,
    /// Control points as (u, v).
    pub points: Vec<[f64; 2]>,
}

/// The thin-plate material: stretch α and bend β coefficients.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Stretch along u.
    pub alpha11: f64,
    /// Stretch coupling (w_u · w_v).
    pub alpha12: f64,
    /// Stretch along v.
    pub alpha22: f64,
    /// Bend along u.
    pub beta11: f64,
    /// Twist (w_uv).
    pub beta12: f64,
    /// Bend along v.
    pub beta22: f64,
}

/// Where an icon sits on its part: `point`, `curve`, `region` and `edge` on
/// a surface, `param` and `span` on a curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Anchor {
    /// A point at (u, v).
    Point {
        /// Parameter u.
        u: f64,
        /// Parameter v.
        v: f64,
    },
    /// A curve on the surface.
    Curve {
        /// The curve in the (u,v) domain.
        curve: UvCurve,
    },
    /// A parameter rectangle from two corners.
    Region {
        /// First corner u.
        u0: f64,
        /// First corner v.
        v0: f64,
        /// Second corner u.
        u1: f64,
        /// Second corner v.
        v1: f64,
        /// Deformation asked inside the region (true) or outside it (false).
        inside: bool,
    },
    /// A boundary edge of a surface part (unit parameter domain), held in
    /// one position constraint: `simply_supported` holds the edge curve,
    /// `clamped` also the tangent plane across it.
    Edge {
        /// Which edge.
        edge: EdgeSide,
        /// How it is held.
        mode: EdgeMode,
    },
    /// A point of a curve part at parameter t.
    Param {
        /// The curve parameter.
        t: f64,
    },
    /// A stretch of a curve part, from t0 to t1.
    Span {
        /// Start parameter.
        t0: f64,
        /// End parameter.
        t1: f64,
    },
}

/// A boundary edge of a surface's parameter domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EdgeSide {
    /// u = u_min.
    UMin,
    /// u = u_max.
    UMax,
    /// v = v_min.
    VMin,
    /// v = v_max.
    VMax,
}

/// How an edge icon holds its edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EdgeMode {
    /// Position and tangent plane.
    Clamped,
    /// Position only.
    SimplySupported,
}

/// Which derivative a derivative constraint fixes (paper 003's labels).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
pub enum Derivative {
    /// w_u.
    R,
    /// w_v.
    V,
    /// w_uu.
    R2,
    /// w_vv.
    V2,
    /// w_uv.
    RV,
}

/// What an icon does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Role {
    /// A load: dragging it applies a spring force.
    Load,
    /// The surface passes through the icon's target.
    Position,
    /// A derivative of the surface equals the icon's target vector.
    Derivative {
        /// Which derivative.
        which: Derivative,
    },
    /// The surface normal at the icon equals the icon's direction.
    Normal,
}

/// An icon's state (paper 003).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum IconState {
    /// Bound to a sensor or a pointer; moving it drives the deformation.
    Driving,
    /// Not bound; a constraint still holds, a load follows the surface.
    Passive,
    /// Drawn grey; no effect.
    Sleeping,
}

/// One icon as clients see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Icon {
    /// Stable id within the design.
    pub id: u64,
    /// Where it sits.
    pub anchor: Anchor,
    /// What it does.
    pub role: Role,
    /// Driving, passive or sleeping.
    pub state: IconState,
    /// Its current position on the surface (for curves and regions, their centre).
    pub xyz: Vec3,
    /// Its target: a position, a derivative vector or a normal direction.
    pub target: Vec3,
    /// Sensors bound to it.
    pub sensors: Vec<String>,
    /// The client dragging it, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holder: Option<u64>,
}

/// What a new icon should be.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct IconSpec {
    /// Where it sits.
    pub anchor: Anchor,
    /// What it does.
    pub role: Role,
    /// Its initial state (passive when omitted).
    #[serde(default = "passive")]
    pub state: IconState,
    /// Its target; the surface's current value when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<Vec3>,
}

fn passive() -> IconState {
    IconState::Passive
}

/// A committed version of a design.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VersionInfo {
    /// 1, 2, 3, … per design.
    pub version: u64,
    /// Commit time, milliseconds since the Unix epoch.
    pub time_ms: u64,
    /// Who committed it.
    pub author: String,
    /// The commit message.
    pub message: String,
}

/// A design in a listing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignInfo {
    /// Its id.
    pub id: u64,
    /// Its name.
    pub name: String,
    /// Number of committed versions.
    pub versions: u64,
}

/// What a connection may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Access {
    /// May edit.
    Editor,
    /// Sees everything live, changes nothing.
    Viewer,
    /// A device bridge: drags and device samples.
    Device,
}

/// What kind of program a client is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ClientKind {
    /// The web client.
    Browser,
    /// The device bridge.
    Bridge,
    /// A script or test (the default).
    #[default]
    Tool,
}

/// The three access tokens of a design (256 random bits each, hex).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignTokens {
    /// Full access.
    pub editor: String,
    /// Sees everything, changes nothing.
    pub viewer: String,
    /// A device bridge: drags, sensors, role and state of icons.
    pub device: String,
}

/// Where a client's view camera is, so that others can follow it (a
/// customer following the designer's view). Model coordinates, the design's
/// up axis is +z for every client.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// The eye position.
    pub eye: Vec3,
    /// The point looked at (the orbit centre); differs from `eye`.
    pub target: Vec3,
    /// The vertical field of view in degrees, in (0, 180).
    pub fov: f64,
}

/// One connected client, for presence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PresenceEntry {
    /// Its client id.
    pub client: u64,
    /// Its name.
    pub name: String,
    /// Its access.
    pub access: Access,
    /// The icon it is dragging, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holding: Option<u64>,
    /// Where its pointer or hand is, if it says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pointer: Option<Vec3>,
    /// Where its view camera is, if it says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<Camera>,
}

/// A device's condition, as the bridge reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DeviceCondition {
    /// Open and streaming.
    Connected,
    /// Gone; the bridge is trying to reopen it.
    Disconnected,
    /// Open but misbehaving (e.g. lost sync).
    Error,
}
