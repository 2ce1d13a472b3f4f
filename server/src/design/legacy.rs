//! Documents written before parts (format 1: one surface, its material and
//! icons per design) and their upgrade to a one-part design. Stores, undo
//! histories and committed versions written by older servers load through
//! here; the server always writes the current format.

use super::doc::{DOC_FORMAT, DesignDoc, IconDoc, MaterialDoc, SurfaceDoc};
use super::part::{PALETTE, PartBody, PartDoc, SurfacePart};
use serde::Deserialize;

/// A format-1 document, field for field as format 1 wrote it.
#[derive(Clone, Debug, Deserialize)]
pub struct DesignDocV1 {
    /// The design's name.
    pub name: String,
    /// The surface.
    pub surface: SurfaceDoc,
    /// Material.
    pub material: MaterialDoc,
    /// Icons.
    pub icons: Vec<IconDoc>,
    /// The id the next icon gets.
    pub next_icon: u64,
    /// The calibrated spring coefficient.
    #[serde(default)]
    pub kappa: Option<f64>,
}

/// The name the single part of an upgraded design gets.
pub const UPGRADED_PART_NAME: &str = "surface";

/// `old` as a design of one surface part (id 1) with the same surface,
/// material, icons (same ids) and spring calibration.
pub fn upgrade(old: DesignDocV1) -> DesignDoc {
    DesignDoc {
        format: DOC_FORMAT,
        name: old.name,
        parts: vec![PartDoc {
            id: 1,
            name: UPGRADED_PART_NAME.to_string(),
            visible: true,
            locked: false,
            colour: PALETTE[0].to_string(),
            body: PartBody::Surface(SurfacePart {
                surface: old.surface,
                material: old.material,
                icons: old.icons,
                kappa: old.kappa,
                spring_size: None,
            }),
        }],
        relations: Vec::new(),
        next_icon: old.next_icon,
        next_part: 2,
        next_relation: 1,
    }
}
