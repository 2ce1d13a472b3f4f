//! The paper's demo body (paper 002, figures 7 and 10): the cube [−1, 1]³
//! as a tricubic 5 × 5 × 7 lattice whose morph target is the spool made
//! from it (the kernel's `body::demo`), scaled to model units (mm). At
//! t = 0 it is the cube, at t = 1 the spool; the frames between are the
//! metamorphosis. The first-start demo design places it beside the mouse
//! ([`DEMO_SPOOL_AT`]).

use super::body_part::{BodyPart, LatticeDoc};
use super::error::{CommandError, ErrorKind};
use vsculpt_kernel::body::{BSplineVolume, demo};

/// Model units per unit of the kernel's demo (the cube is 60 mm wide).
pub const SPOOL_SCALE: f64 = 30.0;

/// Where the first-start demo design puts the spool's centre (mm): beside
/// the mouse (x ∈ [−60, 60], |y| ≤ 45), so the flanges (radius 45 mm) keep
/// 45 mm clear of it: the body spans x ∈ [105, 195].
pub const DEMO_SPOOL_AT: [f64; 3] = [150.0, 0.0, 0.0];

fn scaled(vol: &BSplineVolume, at: [f64; 3]) -> LatticeDoc {
    let mut l = LatticeDoc::from_volume(vol);
    for p in &mut l.points {
        for (c, o) in p.iter_mut().zip(at) {
            *c = *c * SPOOL_SCALE + o;
        }
    }
    l
}

/// The cube-to-spool body part centred at the origin (validated).
pub fn spool_part() -> Result<BodyPart, CommandError> {
    spool_part_at([0.0; 3])
}

/// The cube-to-spool body part centred at `at` (validated).
pub fn spool_part_at(at: [f64; 3]) -> Result<BodyPart, CommandError> {
    let spool = demo::spool()
        .map_err(|e| CommandError::new(ErrorKind::InvalidValue, format!("spool: {e}")))?;
    let part = BodyPart {
        lattice: scaled(&demo::cube(), at),
        morph_target: Some(scaled(&spool, at)),
        icons: Vec::new(),
    };
    part.validate()?;
    Ok(part)
}
