//! Parts of a product and the relations between them.
//!
//! A design is a product made of named parts, each of one kind (today a
//! B-spline `surface` or a deformable `curve`, paper 003), each with its own
//! material, icons, visibility, colour and lock. Relations tie parts
//! together: a `join` holds two surface edges together with position (G0)
//! or tangent-plane (G1) continuity; a `binding` makes a surface follow a
//! curve part along one of its parameter lines. A new kind of part is one new variant of
//! [`PartShape`] (and of [`PartMaterial`] where it needs its own material);
//! a new relation one new variant of [`RelationSpec`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::types::{Icon, Knots, Material, SurfaceData, Vec3};

/// A clamped B-spline curve in model space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CurveData {
    /// Degree and knots (control points + degree + 1 of them).
    pub knots: Knots,
    /// The control points.
    pub points: Vec<Vec3>,
}

/// A part's geometry, tagged by its kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PartShape {
    /// A tensor-product B-spline surface sculpted under the thin-plate
    /// energy (paper 003, eq. 2).
    Surface {
        /// The surface.
        surface: SurfaceData,
    },
    /// A deformable B-spline curve (paper 003, eq. 1).
    Curve {
        /// The curve.
        curve: CurveData,
    },
    /// A Density Spatial Model shape (paper 001): primitives in shape
    /// groups, meshed by the server and sent as mesh frames (kind 3).
    Dsm {
        /// The shape.
        dsm: crate::dsm::DsmData,
    },
    /// A styling-curve network (paper 004): B-spline curves whose faces the
    /// server fills with n-sided patches, sent as mesh frames (kind 3).
    Network {
        /// The network.
        network: crate::network::NetworkData,
    },
    /// A Coons body (paper 002): a B-spline volume shaped by its control
    /// lattice, drawn from body frames (kind 4). It has no material or icons.
    Body {
        /// The body (boxed: two lattices are large, most shapes small).
        body: Box<crate::body::BodyData>,
    },
}

impl PartShape {
    /// The kind's name as it appears on the wire (`"surface"`, `"curve"`).
    pub fn kind(&self) -> PartKind {
        match self {
            PartShape::Surface { .. } => PartKind::Surface,
            PartShape::Curve { .. } => PartKind::Curve,
            PartShape::Dsm { .. } => PartKind::Dsm,
            PartShape::Network { .. } => PartKind::Network,
            PartShape::Body { .. } => PartKind::Body,
        }
    }
}

/// The kinds of part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PartKind {
    /// A B-spline surface.
    Surface,
    /// A deformable curve.
    Curve,
    /// A Density Spatial Model shape.
    Dsm,
    /// A styling-curve network.
    Network,
    /// A Coons body.
    Body,
}

/// The material of a curve part (paper 003, eq. 1): stretch α and bend β.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CurveMaterial {
    /// Stretch (weight of |c'|²).
    pub alpha: f64,
    /// Bend (weight of |c''|²).
    pub beta: f64,
}

/// A part's material: six coefficients for a surface, two for a curve. The
/// JSON carries no tag; the fields say which.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum PartMaterial {
    /// A surface's thin-plate material.
    Surface(Material),
    /// A curve's material.
    Curve(CurveMaterial),
}

/// One part as clients see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Part {
    /// Stable id within the design.
    pub id: u64,
    /// Its name (unique within the design).
    pub name: String,
    /// Drawn or hidden.
    pub visible: bool,
    /// A locked part refuses edits and drags (code `locked`).
    pub locked: bool,
    /// Display colour, `#rrggbb`.
    pub colour: String,
    /// Its material.
    pub material: PartMaterial,
    /// Its icons (icon ids are unique across the design).
    pub icons: Vec<Icon>,
    /// Its geometry. In a `snapshot` to a client that joined with
    /// `geometry_first`, the control points are empty (`[]`): geometry
    /// frames carry them.
    pub shape: PartShape,
}

/// What a new part should be.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    /// Its name (unique within the design).
    pub name: String,
    /// Its geometry.
    pub shape: PartShape,
    /// Its material; the kind's default when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<PartMaterial>,
    /// Its colour, `#rrggbb`; one chosen by the server when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour: Option<String>,
}

/// A boundary edge of a surface part, named by the parameter held fixed
/// along it (`u_min`: u = u0, running along v).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Edge {
    /// u = u0.
    UMin,
    /// u = u1.
    UMax,
    /// v = v0.
    VMin,
    /// v = v1.
    VMax,
}

/// An edge of a part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EdgeRef {
    /// The part.
    pub part: u64,
    /// Which edge.
    pub edge: Edge,
}

/// How two joined edges meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Continuity {
    /// Position: the edges coincide.
    G0,
    /// Position and tangent plane: the normals agree along the seam.
    G1,
}

/// What a relation ties together.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RelationSpec {
    /// Two surface edges held together by the solver; pulling either part
    /// (or the seam) moves both.
    Join {
        /// The first edge.
        a: EdgeRef,
        /// The second edge.
        b: EdgeRef,
        /// G0 or G1.
        continuity: Continuity,
        /// Whether `b` runs against `a` (its parameter reversed).
        #[serde(default)]
        reversed: bool,
    },
    /// A surface follows a curve part along one of its parameter lines:
    /// editing the curve edits the surface along it (paper 003: "curve icon
    /// edited by editing the curve"), held as an identity along the whole
    /// line. The curve needs the line's degree, control-point count and
    /// knots (up to reversal and an affine change of parameter).
    Binding {
        /// The curve part (it drives).
        curve: u64,
        /// The surface part (it follows).
        surface: u64,
        /// The surface's parameter line: `{"u": 0.5}` (u = 0.5, running
        /// along v) or `{"v": 0.25}`.
        line: IsoLine,
        /// Whether the curve runs against the line's parameter.
        #[serde(default)]
        reversed: bool,
    },
    /// Free-form deformation (paper 002): a surface, curve or DSM part
    /// embedded in a body part follows the body's lattice. Refused when
    /// any control point (DSM: mesh vertex) lies outside the body. A
    /// B-spline part's control points are moved (an approximation of the
    /// deformed surface); a DSM part's mesh vertices are mapped exactly.
    /// Removing the relation (or the body) unbinds.
    Ffd {
        /// The body part (it deforms).
        body: u64,
        /// The bound part (it follows).
        part: u64,
    },
}

/// A parameter line of a surface part.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum IsoLine {
    /// u = this value, running along v.
    U(f64),
    /// v = this value, running along u.
    V(f64),
}

/// A relation as clients see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Relation {
    /// Stable id within the design.
    pub id: u64,
    /// What it ties together.
    #[serde(flatten)]
    pub spec: RelationSpec,
}

/// Whether `s` is a display colour `#rrggbb`.
pub fn is_colour(s: &str) -> bool {
    s.len() == 7 && s.starts_with('#') && s[1..].bytes().all(|b| b.is_ascii_hexdigit())
}
