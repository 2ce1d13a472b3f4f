//! A Density Spatial Model part on the wire (paper 001): shape groups of
//! primitives, eq. (7)'s add/subtract per group, passing-points nets, and
//! the edits a client sends to reshape one (`dsm_edit`).
//!
//! Every number is checked here ([`DsmData::validate`], [`DsmEdit::validate`]):
//! finite, within ±[`MAX_MAGNITUDE`](crate::limits::MAX_MAGNITUDE), lengths,
//! densities and reducing factors positive where the model needs them, and
//! at most [`MAX_DSM_PRIMITIVES`] primitives, [`MAX_DSM_GROUPS`] groups and
//! [`MAX_NET_NODES`] net nodes per side. What needs the part (ids, group
//! indices) the server checks.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::{ErrorCode, ProtocolError};
use crate::limits::MAX_MAGNITUDE;
use crate::types::Vec3;

/// Most primitives in one DSM part.
pub const MAX_DSM_PRIMITIVES: usize = 256;
/// Most shape groups in one DSM part.
pub const MAX_DSM_GROUPS: usize = 32;
/// Most nodes along either side of a passing-points net.
pub const MAX_NET_NODES: usize = 32;
/// Mesh resolutions a DSM part may ask for: cells along the longest side.
pub const DSM_CELLS: std::ops::RangeInclusive<u32> = 8..=256;

/// A DSM part's shape: D_e, the mesh resolution and its groups in order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DsmData {
    /// The presentation density D_e (> 0).
    pub de: f64,
    /// Mesh resolution: cells along the longest side of the shape's bounds.
    pub cells: u32,
    /// Shape groups (eqs. 3–6), in order: a group incorporates only earlier ones.
    pub groups: Vec<DsmGroup>,
}

/// How a group's equal density solid enters the object (eq. 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DsmOp {
    /// Added to the object.
    Add,
    /// Subtracted from it.
    Subtract,
    /// Only incorporated into later groups, not drawn by itself.
    None,
}

/// A shape group: primitives that fuse with each other only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DsmGroup {
    /// How its solid enters the object.
    pub op: DsmOp,
    /// Indices of earlier groups whose solids it incorporates (eq. 3).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub incorporated: Vec<u32>,
    /// Its primitives.
    pub primitives: Vec<DsmPrimitive>,
}

/// One primitive: a stable id within the part, where it is, and what it is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DsmPrimitive {
    /// Stable id within the part (the handle edits name).
    pub id: u64,
    /// Its centre (a net: the origin of its reference plane).
    pub at: Vec3,
    /// Its local z axis (revolution axis, pipe direction, a net's plane
    /// normal); +z when omitted. Need not be unit length, must not be zero.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<Vec3>,
    /// What it is.
    pub shape: DsmPrimitiveShape,
}

/// The kinds of primitive (paper §2): geometric ones of uniform density ±D_e,
/// and density ones F = D·exp(−a·r).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum DsmPrimitiveShape {
    /// Rectangular solid with half extents along local x, y, z.
    Box {
        /// Half extents (> 0).
        half: Vec3,
        /// Density −D_e instead of +D_e.
        #[serde(default)]
        negative: bool,
    },
    /// Capped cylinder about the local z axis.
    Cylinder {
        /// Radius (> 0).
        radius: f64,
        /// Half height (> 0).
        half_height: f64,
        /// Density −D_e.
        #[serde(default)]
        negative: bool,
    },
    /// Sphere.
    Sphere {
        /// Radius (> 0).
        radius: f64,
        /// Density −D_e.
        #[serde(default)]
        negative: bool,
    },
    /// Sphere-based density primitive D·exp(−a·r).
    DensitySphere {
        /// D (any sign, not zero).
        density: f64,
        /// a (> 0).
        reducing: f64,
    },
    /// Pipe-based density primitive about a segment of `length` along the axis,
    /// centred at `at`.
    DensityPipe {
        /// Segment length (> 0).
        length: f64,
        /// D (any sign, not zero).
        density: f64,
        /// a (> 0).
        reducing: f64,
    },
    /// Plane-based primitive whose equal density surface passes through a
    /// regular passing-points net (the inverse transformation, eqs. 8–11).
    Net {
        /// Nodes along u (3 ..= 32).
        nu: u32,
        /// Nodes along v (3 ..= 32).
        nv: u32,
        /// Node spacing along u and v (> 0); node (i, j) is at
        /// (i·du, j·dv) − the net's half extent, so the net is centred on `at`.
        spacing: [f64; 2],
        /// Heights above the reference plane (> 0), row by row (j·nu + i).
        heights: Vec<f64>,
        /// The plane-based primitive's reducing factor a_i (> 0).
        reducing: f64,
    },
}

/// One edit of a DSM part (`dsm_edit`): each names a primitive by id.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum DsmEdit {
    /// Adds a primitive to group `group` (`group` = the number of groups
    /// appends a new added group).
    AddPrimitive {
        /// The group index.
        group: u32,
        /// The primitive (its id must be new in the part).
        primitive: DsmPrimitive,
    },
    /// Removes a primitive.
    RemovePrimitive {
        /// The primitive.
        id: u64,
    },
    /// Moves a primitive's centre.
    MovePrimitive {
        /// The primitive.
        id: u64,
        /// Its new centre.
        at: Vec3,
    },
    /// Replaces a primitive's shape (resize; the type may not change).
    ResizePrimitive {
        /// The primitive.
        id: u64,
        /// Its new shape, of the same type.
        shape: DsmPrimitiveShape,
    },
    /// Sets a density primitive's D and a.
    SetDensity {
        /// The primitive.
        id: u64,
        /// D (any sign, not zero).
        density: f64,
        /// a (> 0).
        reducing: f64,
    },
    /// Moves a primitive to another group.
    ChangeGroup {
        /// The primitive.
        id: u64,
        /// The group index (the number of groups appends a new added group).
        group: u32,
    },
    /// Drags one node of a net primitive to a new height (a net node drag).
    DragNode {
        /// The net primitive.
        id: u64,
        /// The node (j·nu + i).
        node: u32,
        /// Its new height above the reference plane (> 0).
        height: f64,
    },
}

fn err(code: ErrorCode, message: String) -> ProtocolError {
    ProtocolError::new(code, message)
}

fn number(name: &str, x: f64) -> Result<(), ProtocolError> {
    if !x.is_finite() {
        return Err(err(ErrorCode::NotFinite, format!("{name} is not finite")));
    }
    if x.abs() > MAX_MAGNITUDE {
        return Err(err(
            ErrorCode::OutOfRange,
            format!("{name} = {x} exceeds ±{MAX_MAGNITUDE}"),
        ));
    }
    Ok(())
}

fn positive(name: &str, x: f64) -> Result<(), ProtocolError> {
    number(name, x)?;
    if x <= 0.0 {
        return Err(err(
            ErrorCode::OutOfRange,
            format!("{name} = {x} must be positive"),
        ));
    }
    Ok(())
}

fn nonzero(name: &str, x: f64) -> Result<(), ProtocolError> {
    number(name, x)?;
    if x == 0.0 {
        return Err(err(ErrorCode::OutOfRange, format!("{name} must not be 0")));
    }
    Ok(())
}

fn vec3(name: &str, v: &Vec3) -> Result<(), ProtocolError> {
    v.iter().try_for_each(|&x| number(name, x))
}

impl DsmPrimitiveShape {
    /// The `type` tag on the wire.
    pub fn type_name(&self) -> &'static str {
        match self {
            Self::Box { .. } => "box",
            Self::Cylinder { .. } => "cylinder",
            Self::Sphere { .. } => "sphere",
            Self::DensitySphere { .. } => "density_sphere",
            Self::DensityPipe { .. } => "density_pipe",
            Self::Net { .. } => "net",
        }
    }

    /// Checks its numbers and sizes.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        match self {
            Self::Box { half, .. } => half.iter().try_for_each(|&h| positive("half", h)),
            Self::Cylinder {
                radius,
                half_height,
                ..
            } => {
                positive("radius", *radius)?;
                positive("half_height", *half_height)
            }
            Self::Sphere { radius, .. } => positive("radius", *radius),
            Self::DensitySphere { density, reducing } => {
                nonzero("density", *density)?;
                positive("reducing", *reducing)
            }
            Self::DensityPipe {
                length,
                density,
                reducing,
            } => {
                positive("length", *length)?;
                nonzero("density", *density)?;
                positive("reducing", *reducing)
            }
            Self::Net {
                nu,
                nv,
                spacing,
                heights,
                reducing,
            } => {
                for (name, n) in [("nu", *nu), ("nv", *nv)] {
                    if !(3..=MAX_NET_NODES as u32).contains(&n) {
                        return Err(err(
                            ErrorCode::OutOfRange,
                            format!("{name} = {n} must be in 3..={MAX_NET_NODES}"),
                        ));
                    }
                }
                positive("spacing", spacing[0])?;
                positive("spacing", spacing[1])?;
                if heights.len() != (*nu * *nv) as usize {
                    return Err(err(
                        ErrorCode::OutOfRange,
                        format!(
                            "a {nu} × {nv} net needs {} heights, got {}",
                            nu * nv,
                            heights.len()
                        ),
                    ));
                }
                heights.iter().try_for_each(|&h| positive("height", h))?;
                positive("reducing", *reducing)
            }
        }
    }
}

impl DsmPrimitive {
    /// Checks its numbers.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        vec3("at", &self.at)?;
        if let Some(a) = &self.axis {
            vec3("axis", a)?;
            if a.iter().all(|&x| x == 0.0) {
                return Err(err(ErrorCode::OutOfRange, "axis is zero".into()));
            }
        }
        self.shape.validate()
    }
}

impl DsmData {
    /// Checks numbers, sizes, ids (unique) and group references (earlier only).
    pub fn validate(&self) -> Result<(), ProtocolError> {
        positive("de", self.de)?;
        if !DSM_CELLS.contains(&self.cells) {
            return Err(err(
                ErrorCode::OutOfRange,
                format!("cells = {} must be in {DSM_CELLS:?}", self.cells),
            ));
        }
        if self.groups.len() > MAX_DSM_GROUPS {
            return Err(err(
                ErrorCode::TooLarge,
                format!("{} groups, limit {MAX_DSM_GROUPS}", self.groups.len()),
            ));
        }
        let count: usize = self.groups.iter().map(|g| g.primitives.len()).sum();
        if count > MAX_DSM_PRIMITIVES {
            return Err(err(
                ErrorCode::TooLarge,
                format!("{count} primitives, limit {MAX_DSM_PRIMITIVES}"),
            ));
        }
        let mut ids = std::collections::HashSet::new();
        for (k, g) in self.groups.iter().enumerate() {
            if let Some(&m) = g.incorporated.iter().find(|&&m| m as usize >= k) {
                return Err(err(
                    ErrorCode::OutOfRange,
                    format!("group {k} incorporates group {m}: only earlier groups"),
                ));
            }
            for p in &g.primitives {
                p.validate()?;
                if !ids.insert(p.id) {
                    return Err(err(
                        ErrorCode::OutOfRange,
                        format!("primitive id {} appears twice", p.id),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The primitive with this id, with its group index.
    pub fn primitive(&self, id: u64) -> Option<(usize, &DsmPrimitive)> {
        self.groups
            .iter()
            .enumerate()
            .find_map(|(k, g)| g.primitives.iter().find(|p| p.id == id).map(|p| (k, p)))
    }
}

impl DsmEdit {
    /// Checks its numbers (what needs the part, the server checks).
    pub fn validate(&self) -> Result<(), ProtocolError> {
        match self {
            Self::AddPrimitive { primitive, .. } => primitive.validate(),
            Self::MovePrimitive { at, .. } => vec3("at", at),
            Self::ResizePrimitive { shape, .. } => shape.validate(),
            Self::SetDensity {
                density, reducing, ..
            } => {
                nonzero("density", *density)?;
                positive("reducing", *reducing)
            }
            Self::DragNode { height, .. } => positive("height", *height),
            Self::RemovePrimitive { .. } | Self::ChangeGroup { .. } => Ok(()),
        }
    }
}
