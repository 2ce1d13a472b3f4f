//! The paper's demo body (paper 002, figures 7 and 10): the cube [−1, 1]³
//! as a tricubic 5 × 5 × 7 lattice whose morph target is the spool made
//! from it (the kernel's `body::demo`), scaled to model units (mm). At
//! t = 0 it is the cube, at t = 1 the spool; the frames between are the
//! metamorphosis.

use super::body_part::{BodyPart, LatticeDoc};
use super::error::{CommandError, ErrorKind};
use vsculpt_kernel::body::{BSplineVolume, demo};

/// Model units per unit of the kernel's demo (the cube is 60 mm wide).
pub const SPOOL_SCALE: f64 = 30.0;

fn scaled(vol: &BSplineVolume) -> LatticeDoc {
    let mut l = LatticeDoc::from_volume(vol);
    for p in &mut l.points {
        for c in p.iter_mut() {
            *c *= SPOOL_SCALE;
        }
    }
    l
}

/// The cube-to-spool body part (validated).
pub fn spool_part() -> Result<BodyPart, CommandError> {
    let spool = demo::spool()
        .map_err(|e| CommandError::new(ErrorKind::InvalidValue, format!("spool: {e}")))?;
    let part = BodyPart {
        lattice: scaled(&demo::cube()),
        morph_target: Some(scaled(&spool)),
        icons: Vec::new(),
    };
    part.validate()?;
    Ok(part)
}
