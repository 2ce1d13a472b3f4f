//! The parts of a design document and the relations between them, as plain
//! serde data (what the store persists and undo keeps). A part is one shape
//! model with its own material and icons — today a B-spline surface or a
//! deformable curve (paper 003); a new kind is one new [`PartBody`] variant.
//! Validation of untrusted values happens here, before the kernel sees them.

use super::doc::{IconDoc, MaterialDoc, SurfaceDoc};
use super::error::{CommandError, ErrorKind};
use serde::{Deserialize, Serialize};

fn invalid(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// Most parts in one design.
pub const MAX_PARTS: usize = 64;
/// Most relations in one design.
pub const MAX_RELATIONS: usize = 256;
/// Most control points of a curve part.
pub const MAX_CURVE_POINTS: usize = 1024;

/// A clamped B-spline curve in model space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveDoc {
    /// Degree.
    pub degree: usize,
    /// Knots (points + degree + 1).
    pub knots: Vec<f64>,
    /// Control points.
    pub points: Vec<[f64; 3]>,
}

impl CurveDoc {
    /// The parameter domain (t0, t1).
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    /// Whether `t` lies in the domain.
    pub fn contains(&self, t: f64) -> bool {
        let (a, b) = self.domain();
        t.is_finite() && t >= a && t <= b
    }

    /// Structural checks (sizes, finiteness); knot rules are the kernel's.
    pub fn validate(&self) -> Result<(), CommandError> {
        if self.degree == 0 || self.degree > 7 {
            return Err(invalid("curve degree must be between 1 and 7"));
        }
        if self.points.len() <= self.degree {
            return Err(invalid("too few control points for the curve's degree"));
        }
        if self.points.len() > MAX_CURVE_POINTS {
            return Err(invalid(format!(
                "a curve part has at most {MAX_CURVE_POINTS} control points"
            )));
        }
        if self.knots.len() != self.points.len() + self.degree + 1 {
            return Err(invalid("curve knot count does not match"));
        }
        let finite = self.knots.iter().all(|x| x.is_finite())
            && self.points.iter().flatten().all(|x| x.is_finite());
        if !finite {
            return Err(invalid("non-finite knot or control point"));
        }
        Ok(())
    }
}

/// A curve's material (paper 003, eq. 1): stretch α and bend β.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveMaterialDoc {
    /// Stretch.
    pub alpha: f64,
    /// Bend.
    pub beta: f64,
}

impl Default for CurveMaterialDoc {
    /// The kernel's default: α = 0.01, β = 1.
    fn default() -> Self {
        Self {
            alpha: 0.01,
            beta: 1.0,
        }
    }
}

impl CurveMaterialDoc {
    /// Finite, non-negative weights.
    pub fn validate(&self) -> Result<(), CommandError> {
        if !self.alpha.is_finite() || !self.beta.is_finite() {
            return Err(invalid("material weights must be finite"));
        }
        if self.alpha < 0.0 || self.beta < 0.0 {
            return Err(invalid("material weights must not be negative"));
        }
        Ok(())
    }
}

/// A surface part: the surface, its material and icons.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurfacePart {
    /// The surface.
    pub surface: SurfaceDoc,
    /// Material.
    pub material: MaterialDoc,
    /// Icons.
    pub icons: Vec<IconDoc>,
    /// The spring coefficient κ the drags calibrated (kernel default when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
    /// The size S the spring's stiffness κS scales with: the surface's
    /// area when its kernel design was first made (absent: the area of the
    /// stored shape). Kept so a reload pulls as the live design did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spring_size: Option<f64>,
}

/// A curve part: the curve, its material and icons (anchored `param` or
/// `span`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvePart {
    /// The curve.
    pub curve: CurveDoc,
    /// Material.
    pub material: CurveMaterialDoc,
    /// Icons.
    pub icons: Vec<IconDoc>,
    /// The spring coefficient κ the drags calibrated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
}

/// A face of a network part whose patch a fairing run replaced by its
/// faired point mesh (the patch's samples at the engine's resolution,
/// interior points moved, boundary points untouched).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FairedFaceDoc {
    /// The face (in the order the network finds its faces).
    pub face: usize,
    /// The faired points, one per sample of the face's mesh.
    pub points: Vec<[f64; 3]>,
    /// Sweeps the run took.
    pub iterations: usize,
    /// Whether it converged.
    pub converged: bool,
}

/// Most a side's ribbon scale handle may be (and 1 / this the least).
pub const MAX_RIBBON_SCALE: f64 = 10.0;

/// The designer's ribbon handles of a network part (paper 004 §5): a side's
/// scale (the cross-boundary derivative's length, times
/// 1 + (scale − 1) sin(πs) along the side) and an edge's twist (the tangent
/// plane along the edge turned about the curve by twist·sin(πu); both faces
/// on the edge follow, so they stay G1). Edge indices are the kernel's
/// (derived from the curves, so they are the same whenever the part is
/// built); only handles that differ from the default are kept.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RibbonHandlesDoc {
    /// (face, side, scale) with scale ≠ 1.
    #[serde(default)]
    pub scales: Vec<(usize, usize, f64)>,
    /// (edge, twist in radians) with twist ≠ 0.
    #[serde(default)]
    pub twists: Vec<(usize, f64)>,
    /// (face, its n + 1 tuning handles: centre, then corners) for faces
    /// with a non-zero handle.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tuning: Vec<(usize, Vec<[f64; 3]>)>,
}

impl RibbonHandlesDoc {
    /// No handle moved.
    pub fn is_empty(&self) -> bool {
        self.scales.is_empty() && self.twists.is_empty() && self.tuning.is_empty()
    }

    /// Finite values in range (indices are the kernel's to check).
    pub fn validate(&self) -> Result<(), CommandError> {
        for &(f, s, x) in &self.scales {
            check_scale(x).map_err(|m| invalid(format!("face {f} side {s}: {m}")))?;
        }
        for &(e, t) in &self.twists {
            check_twist(t).map_err(|m| invalid(format!("edge {e}: {m}")))?;
        }
        for (f, h) in &self.tuning {
            if h.iter().flatten().any(|x| !x.is_finite()) {
                return Err(invalid(format!("face {f}: tuning handles must be finite")));
            }
        }
        Ok(())
    }
}

/// Whether `x` is a ribbon scale handle: finite, in
/// [1/[`MAX_RIBBON_SCALE`], [`MAX_RIBBON_SCALE`]].
pub fn check_scale(x: f64) -> Result<(), String> {
    if x.is_finite() && (1.0 / MAX_RIBBON_SCALE..=MAX_RIBBON_SCALE).contains(&x) {
        Ok(())
    } else {
        Err(format!(
            "ribbon scale {x} must be finite and in [{}, {MAX_RIBBON_SCALE}]",
            1.0 / MAX_RIBBON_SCALE
        ))
    }
}

/// Whether `t` is a twist handle: finite, |t| < π/2 radians.
pub fn check_twist(t: f64) -> Result<(), String> {
    if t.is_finite() && t.abs() < std::f64::consts::FRAC_PI_2 {
        Ok(())
    } else {
        Err(format!(
            "ribbon twist {t} must be finite and |twist| < π/2 radians"
        ))
    }
}

/// A styling-curve network part (paper 004): its curves, the tolerance
/// within which they meet, the side its patches face and the faces faired.
/// Meetings and faces are derived (by the kernel) and not stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetworkPart {
    /// The styling curves.
    pub curves: Vec<CurveDoc>,
    /// Curves closer than this meet.
    pub tolerance: f64,
    /// The side the normals face.
    pub up: [f64; 3],
    /// Faired faces (dropped when a curve of the face changes).
    #[serde(default)]
    pub faired: Vec<FairedFaceDoc>,
    /// Ribbon handles that differ from the compatible ribbon (scale 1,
    /// twist 0); reset when the curves' faces are re-derived.
    #[serde(default, skip_serializing_if = "RibbonHandlesDoc::is_empty")]
    pub ribbons: RibbonHandlesDoc,
    /// Icons: none yet (a network is edited by its curves); always empty.
    #[serde(default)]
    pub icons: Vec<IconDoc>,
}

/// Most curves of a network part.
pub const MAX_NETWORK_CURVES: usize = 64;

impl NetworkPart {
    /// Structural checks (counts, finiteness); whether the curves meet and
    /// enclose faces is the kernel's (see `network_engine`).
    pub fn validate(&self) -> Result<(), CommandError> {
        if self.curves.is_empty() || self.curves.len() > MAX_NETWORK_CURVES {
            return Err(invalid(format!(
                "a network part has 1 to {MAX_NETWORK_CURVES} curves, not {}",
                self.curves.len()
            )));
        }
        for c in &self.curves {
            c.validate()?;
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(invalid("network tolerance must be finite and > 0"));
        }
        if !self.up.iter().all(|x| x.is_finite()) || self.up == [0.0; 3] {
            return Err(invalid("network `up` must be finite and non-zero"));
        }
        if !self.icons.is_empty() {
            return Err(invalid("a network part has no icons"));
        }
        if self
            .faired
            .iter()
            .any(|f| f.points.iter().flatten().any(|x| !x.is_finite()))
        {
            return Err(invalid("non-finite faired point"));
        }
        self.ribbons.validate()?;
        Ok(())
    }
}

/// A part's shape model, by kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PartBody {
    /// A B-spline surface (paper 003, eq. 2).
    Surface(SurfacePart),
    /// A deformable curve (paper 003, eq. 1).
    Curve(CurvePart),
    /// A styling-curve network filled with n-sided patches (paper 004).
    Network(NetworkPart),
    /// A Density Spatial Model shape (paper 001; `dsm_engine`).
    Dsm(super::dsm_engine::DsmPart),
    /// A Coons body (paper 002): a B-spline volume shaped by its lattice.
    Body(super::body_part::BodyPart),
}

impl PartBody {
    /// The part's icons.
    pub fn icons(&self) -> &[IconDoc] {
        match self {
            PartBody::Surface(s) => &s.icons,
            PartBody::Curve(c) => &c.icons,
            PartBody::Network(n) => &n.icons,
            PartBody::Dsm(d) => &d.icons,
            PartBody::Body(b) => &b.icons,
        }
    }

    /// The part's icons, mutable.
    pub fn icons_mut(&mut self) -> &mut Vec<IconDoc> {
        match self {
            PartBody::Surface(s) => &mut s.icons,
            PartBody::Curve(c) => &mut c.icons,
            PartBody::Network(n) => &mut n.icons,
            PartBody::Dsm(d) => &mut d.icons,
            PartBody::Body(b) => &mut b.icons,
        }
    }

    /// The kind's name (`"surface"`, `"curve"`, `"network"`, `"dsm"`, `"body"`).
    pub fn kind(&self) -> &'static str {
        match self {
            PartBody::Surface(_) => "surface",
            PartBody::Curve(_) => "curve",
            PartBody::Network(_) => "network",
            PartBody::Dsm(_) => "dsm",
            PartBody::Body(_) => "body",
        }
    }

    /// Every control point (none for a network part — its curves hold
    /// them — nor for a DSM part).
    pub fn points(&self) -> &[[f64; 3]] {
        match self {
            PartBody::Surface(s) => &s.surface.points,
            PartBody::Curve(c) => &c.curve.points,
            PartBody::Network(_) | PartBody::Dsm(_) => &[],
            PartBody::Body(b) => &b.lattice.points,
        }
    }

    /// Full validation of untrusted content: geometry, material, every
    /// icon's anchor inside the part's domain.
    pub fn validate(&self) -> Result<(), CommandError> {
        match self {
            PartBody::Surface(s) => {
                s.surface.validate()?;
                s.material.validate()?;
                for i in &s.icons {
                    i.anchor.validate(&s.surface)?;
                }
            }
            PartBody::Curve(c) => {
                c.curve.validate()?;
                c.material.validate()?;
                for i in &c.icons {
                    i.anchor.validate_on_curve(&c.curve)?;
                }
            }
            PartBody::Network(n) => n.validate()?,
            PartBody::Dsm(d) => d.validate()?,
            PartBody::Body(b) => b.validate()?,
        }
        if self
            .icons()
            .iter()
            .any(|i| i.xyz.iter().chain(&i.target).any(|x| !x.is_finite()))
        {
            return Err(invalid("icon coordinates must be finite"));
        }
        Ok(())
    }
}

/// One part of a design.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartDoc {
    /// Id, unique within the design.
    pub id: u64,
    /// Name, unique within the design.
    pub name: String,
    /// Drawn or hidden.
    pub visible: bool,
    /// A locked part refuses edits and drags.
    pub locked: bool,
    /// Display colour `#rrggbb`.
    pub colour: String,
    /// Its shape model.
    pub body: PartBody,
}

/// A boundary edge of a surface part (the parameter held fixed along it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeDoc {
    /// u = u0.
    UMin,
    /// u = u1.
    UMax,
    /// v = v0.
    VMin,
    /// v = v1.
    VMax,
}

/// How joined edges meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContinuityDoc {
    /// Position.
    G0,
    /// Position and tangent plane.
    G1,
}

/// What a relation ties together.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RelationKind {
    /// Two surface edges held together by the solver.
    Join {
        /// First part.
        a: u64,
        /// Its edge.
        edge_a: EdgeDoc,
        /// Second part.
        b: u64,
        /// Its edge.
        edge_b: EdgeDoc,
        /// G0 or G1.
        continuity: ContinuityDoc,
        /// `b` runs against `a`.
        reversed: bool,
        /// The G1 ratio fixed when the join was made (the kernel's
        /// `Join::ratio`), so a rebuild is exact; 1 for G0.
        ratio: f64,
    },
    /// A surface follows a curve part along one of its parameter lines.
    Binding {
        /// The curve part.
        curve: u64,
        /// The surface part.
        surface: u64,
        /// The line.
        line: IsoLineDoc,
        /// The curve runs against the line.
        reversed: bool,
    },
    /// A part embedded in a body part follows its lattice (free-form
    /// deformation, paper 002; see `ffd_binding`).
    Ffd {
        /// The body part.
        body: u64,
        /// The bound surface, curve or DSM part.
        part: u64,
        /// A DSM part's rest lattice: the body's lattice when it was bound
        /// (its mesh, derived from its DSM data, is deformed from this
        /// state). Absent for a surface or curve part, whose stored
        /// control points are moved at each lattice change.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rest: Option<super::body_part::LatticeDoc>,
    },
}

/// A parameter line of a surface.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IsoLineDoc {
    /// u = value, along v.
    U(f64),
    /// v = value, along u.
    V(f64),
}

impl RelationKind {
    /// The parts it ties.
    pub fn parts(&self) -> [u64; 2] {
        match self {
            RelationKind::Join { a, b, .. } => [*a, *b],
            RelationKind::Binding { curve, surface, .. } => [*curve, *surface],
            RelationKind::Ffd { body, part, .. } => [*body, *part],
        }
    }
}

/// A relation between parts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RelationDoc {
    /// Id, unique within the design.
    pub id: u64,
    /// What it ties.
    pub kind: RelationKind,
}

/// The colours new parts get, in turn (distinguishable on the studio's
/// grey background and for the common colour-vision deficiencies).
pub const PALETTE: [&str; 8] = [
    "#c8ccd4", "#5b8bd9", "#e0914a", "#5fb37c", "#c46fc0", "#d9c24a", "#4ab8c4", "#d96a6a",
];

/// Whether `s` is `#rrggbb`.
pub fn is_colour(s: &str) -> bool {
    s.len() == 7 && s.starts_with('#') && s[1..].bytes().all(|b| b.is_ascii_hexdigit())
}
