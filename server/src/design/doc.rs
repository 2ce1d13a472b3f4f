//! The design document: everything that defines a design (name, parts with
//! their shapes, materials and icons, relations) as plain serde data. It is what the store persists (as
//! JSON: the working state and every version), what undo keeps and what a
//! joining client receives. Validation of untrusted values (finite numbers,
//! (u, v) inside the domain, sizes) happens here, before the kernel sees them.

use super::error::{CommandError, ErrorKind};
use super::part::{CurveDoc, PartBody, PartDoc, RelationDoc, RelationKind};
use crate::cad::IgesSurface;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Format version of the persisted document (1: one surface per design,
/// read by [`super::legacy`]; 2: parts).
pub const DOC_FORMAT: u32 = 2;

fn invalid(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// A B-spline surface: degrees, full knot vectors, control points row-major
/// (`i * nv + j`, `i` along u).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurfaceDoc {
    /// Degree in u.
    pub u_degree: usize,
    /// Degree in v.
    pub v_degree: usize,
    /// Knots in u.
    pub u_knots: Vec<f64>,
    /// Knots in v.
    pub v_knots: Vec<f64>,
    /// Control points along u.
    pub nu: usize,
    /// Control points along v.
    pub nv: usize,
    /// Control points.
    pub points: Vec<[f64; 3]>,
}

impl SurfaceDoc {
    /// The parameter domain ((u0, u1), (v0, v1)).
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (
            (self.u_knots[self.u_degree], self.u_knots[self.nu]),
            (self.v_knots[self.v_degree], self.v_knots[self.nv]),
        )
    }

    /// Whether (u, v) lies in the domain.
    pub fn contains(&self, u: f64, v: f64) -> bool {
        let ((u0, u1), (v0, v1)) = self.domain();
        u.is_finite() && v.is_finite() && u >= u0 && u <= u1 && v >= v0 && v <= v1
    }

    /// Structural checks (sizes, finiteness); knot rules are the kernel's.
    pub fn validate(&self) -> Result<(), CommandError> {
        if self.u_degree == 0 || self.v_degree == 0 || self.u_degree > 7 || self.v_degree > 7 {
            return Err(invalid("degrees must be between 1 and 7"));
        }
        if self.nu <= self.u_degree || self.nv <= self.v_degree {
            return Err(invalid("too few control points for the degree"));
        }
        if self.nu > 400 || self.nv > 400 {
            return Err(invalid("at most 400 control points per direction"));
        }
        if self.points.len() != self.nu * self.nv {
            return Err(invalid("control point count does not match nu × nv"));
        }
        if self.u_knots.len() != self.nu + self.u_degree + 1
            || self.v_knots.len() != self.nv + self.v_degree + 1
        {
            return Err(invalid("knot count does not match"));
        }
        let finite = self
            .u_knots
            .iter()
            .chain(&self.v_knots)
            .all(|x| x.is_finite())
            && self.points.iter().flatten().all(|x| x.is_finite());
        if !finite {
            return Err(invalid("non-finite knot or control point"));
        }
        let ((u0, u1), (v0, v1)) = self.domain();
        if u1 <= u0 || v1 <= v0 {
            return Err(invalid("empty parameter domain"));
        }
        Ok(())
    }

    /// Control points as vectors.
    pub fn dpoints(&self) -> Vec<DVec3> {
        self.points.iter().map(|&p| DVec3::from(p)).collect()
    }

    /// As IGES data.
    pub fn to_iges(&self) -> IgesSurface {
        IgesSurface {
            u_degree: self.u_degree,
            v_degree: self.v_degree,
            u_knots: self.u_knots.clone(),
            v_knots: self.v_knots.clone(),
            nu: self.nu,
            nv: self.nv,
            points: self.dpoints(),
        }
    }

    /// From IGES data.
    pub fn from_iges(s: &IgesSurface) -> Self {
        Self {
            u_degree: s.u_degree,
            v_degree: s.v_degree,
            u_knots: s.u_knots.clone(),
            v_knots: s.v_knots.clone(),
            nu: s.nu,
            nv: s.nv,
            points: s.points.iter().map(|p| p.to_array()).collect(),
        }
    }
}

/// The thin-plate material (paper 003): stretch α and bend β weights.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialDoc {
    /// α11.
    pub alpha11: f64,
    /// α12.
    pub alpha12: f64,
    /// α22.
    pub alpha22: f64,
    /// β11.
    pub beta11: f64,
    /// β12.
    pub beta12: f64,
    /// β22.
    pub beta22: f64,
}

impl Default for MaterialDoc {
    /// The kernel's default: mostly bending, a little stretch.
    fn default() -> Self {
        Self {
            alpha11: 0.01,
            alpha12: 0.0,
            alpha22: 0.01,
            beta11: 1.0,
            beta12: 1.0,
            beta22: 1.0,
        }
    }
}

impl MaterialDoc {
    /// Finite, non-negative weights.
    pub fn validate(&self) -> Result<(), CommandError> {
        let all = [
            self.alpha11,
            self.alpha12,
            self.alpha22,
            self.beta11,
            self.beta12,
            self.beta22,
        ];
        if all.iter().any(|x| !x.is_finite()) {
            return Err(invalid("material weights must be finite"));
        }
        if [
            self.alpha11,
            self.alpha22,
            self.beta11,
            self.beta12,
            self.beta22,
        ]
        .iter()
        .any(|&x| x < 0.0)
        {
            return Err(invalid("material weights must not be negative"));
        }
        Ok(())
    }
}

/// A clamped B-spline curve in the surface's (u, v) domain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UvCurveDoc {
    /// Degree.
    pub degree: usize,
    /// Knots (points + degree + 1).
    pub knots: Vec<f64>,
    /// Control points as (u, v).
    pub points: Vec<[f64; 2]>,
}

impl UvCurveDoc {
    /// The curve's point at its mid-parameter, where its icon's handle is
    /// (the kernel's `Anchor::handle_uv`); the middle control point when the
    /// curve is not a valid B-spline (validation refuses it elsewhere).
    pub fn mid_point(&self) -> [f64; 2] {
        let fallback = self
            .points
            .get(self.points.len() / 2)
            .copied()
            .unwrap_or([0.0; 2]);
        let Ok(knots) = vsculpt_kernel::bspline::KnotVector::new(self.degree, self.knots.clone())
        else {
            return fallback;
        };
        let points = self
            .points
            .iter()
            .map(|p| glam::DVec3::new(p[0], p[1], 0.0))
            .collect();
        match vsculpt_kernel::bspline::BSplineCurve::new(knots, points) {
            Ok(c) => {
                let (a, b) = c.domain();
                let p = c.point(0.5 * (a + b));
                [p.x, p.y]
            }
            Err(_) => fallback,
        }
    }
}

/// Where an icon sits on the surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AnchorDoc {
    /// A point at (u, v).
    Point {
        /// u.
        u: f64,
        /// v.
        v: f64,
    },
    /// A curve in the (u, v) domain.
    Curve {
        /// The curve.
        curve: UvCurveDoc,
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
        /// Deformation asked inside (true) or outside the region.
        inside: bool,
    },
    /// A boundary edge of a surface part (unit domain), held by one
    /// position constraint (`clamped`: also its tangent plane). Added with
    /// issue 15; documents without edges load as before.
    Edge {
        /// Which edge.
        edge: EdgeSideDoc,
        /// Position and tangent plane (true) or position only.
        clamped: bool,
    },
    /// A point of a curve part at parameter t.
    Param {
        /// t.
        t: f64,
    },
    /// A stretch of a curve part.
    Span {
        /// Start.
        t0: f64,
        /// End.
        t1: f64,
    },
}

impl AnchorDoc {
    /// A representative (u, v): the point, the curve's middle control point,
    /// the region's centre or the edge's middle.
    pub fn centre(&self) -> [f64; 2] {
        match self {
            AnchorDoc::Point { u, v } => [*u, *v],
            AnchorDoc::Curve { curve } => curve.mid_point(),
            AnchorDoc::Region { u0, v0, u1, v1, .. } => [(u0 + u1) / 2.0, (v0 + v1) / 2.0],
            AnchorDoc::Edge { edge, .. } => {
                let [a, b] = edge.ends();
                [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
            }
            AnchorDoc::Param { t } => [*t, 0.0],
            AnchorDoc::Span { t0, t1 } => [(t0 + t1) / 2.0, 0.0],
        }
    }

    /// Whether the anchor belongs on a curve part (`param`, `span`).
    pub fn on_curve(&self) -> bool {
        matches!(self, AnchorDoc::Param { .. } | AnchorDoc::Span { .. })
    }

    /// Checks the anchor is a curve anchor with parameters inside `curve`'s
    /// domain.
    pub fn validate_on_curve(&self, curve: &CurveDoc) -> Result<(), CommandError> {
        let ts = match self {
            AnchorDoc::Param { t } => vec![*t],
            AnchorDoc::Span { t0, t1 } => {
                if t0 == t1 {
                    return Err(invalid("a span needs two different parameters"));
                }
                vec![*t0, *t1]
            }
            _ => {
                return Err(invalid(
                    "an icon on a curve part is anchored by `param` or `span`",
                ));
            }
        };
        for t in ts {
            if !curve.contains(t) {
                let (a, b) = curve.domain();
                return Err(CommandError::new(
                    ErrorKind::OutOfDomain,
                    format!("t = {t} is outside the curve's domain [{a}, {b}]"),
                ));
            }
        }
        Ok(())
    }

    /// Every (u, v) the anchor uses (a curve's control points lie in the
    /// domain iff its convex hull does, which bounds the curve).
    pub fn params(&self) -> Vec<[f64; 2]> {
        match self {
            AnchorDoc::Point { u, v } => vec![[*u, *v]],
            AnchorDoc::Curve { curve } => curve.points.clone(),
            AnchorDoc::Region { u0, v0, u1, v1, .. } => vec![[*u0, *v0], [*u1, *v1]],
            AnchorDoc::Edge { edge, .. } => edge.ends().to_vec(),
            AnchorDoc::Param { .. } | AnchorDoc::Span { .. } => Vec::new(),
        }
    }

    /// Checks every parameter is finite and inside `surface`'s domain.
    pub fn validate(&self, surface: &SurfaceDoc) -> Result<(), CommandError> {
        if self.on_curve() {
            return Err(invalid(
                "an icon on a surface part is anchored by `point`, `curve`, `region` or `edge`",
            ));
        }
        if let AnchorDoc::Curve { curve } = self {
            if !(2..=256).contains(&curve.points.len()) {
                return Err(invalid("a curve icon needs 2 to 256 (u, v) control points"));
            }
            if curve.degree == 0 || curve.knots.len() != curve.points.len() + curve.degree + 1 {
                return Err(invalid("curve knots do not match its degree and points"));
            }
            if curve.knots.iter().any(|k| !k.is_finite()) {
                return Err(invalid("curve knots must be finite"));
            }
        }
        for [u, v] in self.params() {
            if !u.is_finite() || !v.is_finite() {
                return Err(invalid("icon parameters must be finite"));
            }
            if !surface.contains(u, v) {
                let ((u0, u1), (v0, v1)) = surface.domain();
                return Err(CommandError::new(
                    ErrorKind::OutOfDomain,
                    format!(
                        "(u, v) = ({u}, {v}) is outside the domain [{u0}, {u1}] × [{v0}, {v1}]"
                    ),
                ));
            }
        }
        if let AnchorDoc::Region { u0, v0, u1, v1, .. } = self
            && (u0 == u1 || v0 == v1)
        {
            return Err(invalid("a region needs two corners differing in u and v"));
        }
        Ok(())
    }
}

/// A boundary edge of the unit parameter domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeSideDoc {
    /// u = 0.
    UMin,
    /// u = 1.
    UMax,
    /// v = 0.
    VMin,
    /// v = 1.
    VMax,
}

impl EdgeSideDoc {
    /// The edge's two ends in the unit parameter square.
    pub fn ends(self) -> [[f64; 2]; 2] {
        match self {
            EdgeSideDoc::UMin => [[0.0, 0.0], [0.0, 1.0]],
            EdgeSideDoc::UMax => [[1.0, 0.0], [1.0, 1.0]],
            EdgeSideDoc::VMin => [[0.0, 0.0], [1.0, 0.0]],
            EdgeSideDoc::VMax => [[0.0, 1.0], [1.0, 1.0]],
        }
    }
}

/// Which derivative a derivative constraint fixes (paper 003's labels).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DerivativeDoc {
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

/// What an icon does (paper 003's icon kinds).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum IconRoleDoc {
    /// A load pulling the surface.
    Load,
    /// A position constraint w = target.
    Position,
    /// A derivative constraint (the derivative = target).
    Derivative {
        /// Which derivative.
        which: DerivativeDoc,
    },
    /// Normal constraint: the surface normal is the target direction.
    Normal,
}

/// An icon's state (paper 003).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IconStateDoc {
    /// Bound to a sensor or pointer; moving it drives the deformation.
    Driving,
    /// Holds (constraint) or follows the surface (load).
    Passive,
    /// No effect; follows the surface.
    Sleeping,
}

/// One icon.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IconDoc {
    /// Id, unique within the design.
    pub id: u64,
    /// Where it sits.
    pub anchor: AnchorDoc,
    /// What it does.
    pub role: IconRoleDoc,
    /// Its state.
    pub state: IconStateDoc,
    /// Where it is on the surface (a curve's or region's centre).
    pub xyz: [f64; 3],
    /// Its target: a position, a derivative vector or a normal direction
    /// (for a load, the point its handle pulls to).
    pub target: [f64; 3],
    /// Sensors bound to it.
    #[serde(default)]
    pub sensors: Vec<String>,
}

impl IconDoc {
    /// The state the kernel holds this icon in when its part is built
    /// from the document: a bound sensor drives it; a drag does not
    /// survive a rebuild (driving without a sensor is passive).
    pub fn kernel_state(&self) -> IconStateDoc {
        if !self.sensors.is_empty() {
            return IconStateDoc::Driving;
        }
        match self.state {
            IconStateDoc::Driving => IconStateDoc::Passive,
            other => other,
        }
    }
}

/// A whole design: a product of parts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DesignDoc {
    /// Document format version ([`DOC_FORMAT`]).
    pub format: u32,
    /// Name.
    pub name: String,
    /// The parts, in the order clients list them.
    pub parts: Vec<PartDoc>,
    /// Relations between parts.
    #[serde(default)]
    pub relations: Vec<RelationDoc>,
    /// The id the next icon gets (icon ids are unique across parts).
    pub next_icon: u64,
    /// The id the next part gets.
    pub next_part: u64,
    /// The id the next relation gets.
    pub next_relation: u64,
}

impl DesignDoc {
    /// Serialised for the store.
    pub fn to_bytes(&self) -> Vec<u8> {
        // Serialising plain data with finite floats cannot fail.
        serde_json::to_vec(self).unwrap_or_default()
    }

    /// Parsed from the store: this format, or format 1 (one surface per
    /// design) read as a one-part design.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CommandError> {
        #[derive(Deserialize)]
        struct Format {
            format: u32,
        }
        let unreadable = |e: serde_json::Error| {
            CommandError::new(ErrorKind::Storage, format!("stored design unreadable: {e}"))
        };
        let f: Format = serde_json::from_slice(bytes).map_err(unreadable)?;
        match f.format {
            DOC_FORMAT => serde_json::from_slice(bytes).map_err(unreadable),
            1 => Ok(super::legacy::upgrade(
                serde_json::from_slice(bytes).map_err(unreadable)?,
            )),
            other => Err(CommandError::new(
                ErrorKind::Storage,
                format!("stored design has format {other}, expected {DOC_FORMAT}"),
            )),
        }
    }

    /// The part with `id`.
    pub fn part(&self, id: u64) -> Option<&PartDoc> {
        self.parts.iter().find(|p| p.id == id)
    }

    /// The part with `id`, mutable.
    pub fn part_mut(&mut self, id: u64) -> Option<&mut PartDoc> {
        self.parts.iter_mut().find(|p| p.id == id)
    }

    /// The icon with `id` and the part it is on.
    pub fn icon(&self, id: u64) -> Option<(&PartDoc, &IconDoc)> {
        self.parts
            .iter()
            .find_map(|p| p.body.icons().iter().find(|i| i.id == id).map(|i| (p, i)))
    }

    /// Every icon of every part.
    pub fn icons(&self) -> impl Iterator<Item = &IconDoc> {
        self.parts.iter().flat_map(|p| p.body.icons())
    }

    /// The relations that involve part `part`.
    pub fn relations_of(&self, part: u64) -> impl Iterator<Item = &RelationDoc> {
        self.relations
            .iter()
            .filter(move |r| r.kind.parts().contains(&part))
    }

    /// The parts solved together with `part`: itself and every part
    /// reachable through joins and bindings, in id order.
    pub fn group_of(&self, part: u64) -> Vec<u64> {
        let mut group = vec![part];
        let mut k = 0;
        while k < group.len() {
            let p = group[k];
            for r in self.relations_of(p) {
                for q in r.kind.parts() {
                    if !group.contains(&q) {
                        group.push(q);
                    }
                }
            }
            k += 1;
        }
        group.sort_unstable();
        group
    }

    /// Full validation of untrusted content: every part, unique ids and
    /// names, relations naming parts (and icons) that exist.
    pub fn validate(&self) -> Result<(), CommandError> {
        if self.parts.len() > super::part::MAX_PARTS {
            return Err(invalid(format!(
                "a design holds at most {} parts",
                super::part::MAX_PARTS
            )));
        }
        let mut ids = std::collections::BTreeSet::new();
        let mut names = std::collections::BTreeSet::new();
        let mut icons = std::collections::BTreeSet::new();
        for p in &self.parts {
            if !ids.insert(p.id) || !names.insert(p.name.as_str()) {
                return Err(invalid("part ids and names must be unique"));
            }
            if !super::part::is_colour(&p.colour) {
                return Err(invalid("a part's colour is #rrggbb"));
            }
            p.body.validate()?;
            for i in p.body.icons() {
                if !icons.insert(i.id) {
                    return Err(invalid("icon ids must be unique across parts"));
                }
            }
        }
        for r in &self.relations {
            for q in r.kind.parts() {
                if !ids.contains(&q) {
                    return Err(invalid(format!("relation {} names no part {q}", r.id)));
                }
            }
            if let RelationKind::Join { ratio, .. } = r.kind
                && !(ratio.is_finite() && ratio > 0.0)
            {
                return Err(invalid(format!("relation {} has a bad ratio", r.id)));
            }
            if let RelationKind::Ffd { body, rest, .. } = &r.kind {
                let Some(PartBody::Body(b)) = self.part(*body).map(|p| &p.body) else {
                    return Err(invalid(format!(
                        "relation {}: part {body} is not a body",
                        r.id
                    )));
                };
                if let Some(rest) = rest {
                    rest.volume()?;
                    if rest.degrees != b.lattice.degrees || rest.knots != b.lattice.knots {
                        return Err(invalid(format!(
                            "relation {}: its rest lattice does not fit body {body}",
                            r.id
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// A one-part design holding `body`, named `name` (its part is called
    /// `part_name`).
    pub fn single(name: &str, part_name: &str, body: PartBody) -> Self {
        let next_icon = body.icons().iter().map(|i| i.id + 1).max().unwrap_or(1);
        Self {
            format: DOC_FORMAT,
            name: name.to_string(),
            parts: vec![PartDoc {
                id: 1,
                name: part_name.to_string(),
                visible: true,
                locked: false,
                colour: super::part::PALETTE[0].to_string(),
                body,
            }],
            relations: Vec::new(),
            next_icon,
            next_part: 2,
            next_relation: 1,
        }
    }
}

/// A finite point or an `InvalidValue` error.
pub fn finite_point(p: [f64; 3]) -> Result<DVec3, CommandError> {
    if p.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from(p))
    } else {
        Err(CommandError::new(
            ErrorKind::NotFinite,
            "coordinates must be finite (no NaN or ∞)",
        ))
    }
}

#[cfg(test)]
mod handle_tests {
    use super::*;

    /// A curve icon's handle is on the curve: for the quadratic Bézier
    /// through (0.2, 0.3), (0.5, 0.9), (0.8, 0.3) the mid-parameter point is
    /// ¼·P0 + ½·P1 + ¼·P2 = (0.5, 0.6), not the middle control point.
    #[test]
    fn a_curve_handle_is_its_mid_parameter_point() {
        let curve = UvCurveDoc {
            degree: 2,
            knots: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            points: vec![[0.2, 0.3], [0.5, 0.9], [0.8, 0.3]],
        };
        let [u, v] = AnchorDoc::Curve { curve }.centre();
        assert!(
            (u - 0.5).abs() < 1e-15 && (v - 0.6).abs() < 1e-15,
            "({u}, {v})"
        );
        let broken = UvCurveDoc {
            degree: 2,
            knots: vec![0.0, 1.0],
            points: vec![[0.1, 0.2], [0.3, 0.4]],
        };
        assert_eq!(AnchorDoc::Curve { curve: broken }.centre(), [0.3, 0.4]);
    }
}
