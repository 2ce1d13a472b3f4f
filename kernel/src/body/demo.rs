//! The paper's examples as kernel constructors: the cube, the spool made
//! from it (figure 7), the cube-to-spool metamorphosis (figure 10) and a
//! five-body chair (figure 9). The paper gives no numbers; these are ours.
//!
//! * **Cube**: [−1, 1]³, tricubic, 5 × 5 × 7 control points at the Greville
//!   abscissae (so x(u, v, w) is the affine map onto the cube).
//! * **Spool**: the cube's lattice with every layer k (along w, i.e. z)
//!   rounded — a square layer point (x, y) goes to the disc point
//!   r_k (x √(1 − y²/2), y √(1 − x²/2)) — with radii r = (1.5, 1.5, 0.7,
//!   0.7, 0.7, 1.5, 1.5): the two outer layers at each end are the flanges
//!   (their distance is the flange thickness, §3 "top and bottom points also
//!   define the thickness"), the middle ones the waist. Only the six faces
//!   are taken from that lattice; the spool is the Coons body 2 of those
//!   faces, so its interior follows the Boolean sum.
//! * **Chair**: five tricubic Bézier bodies — front and rear seat halves, a
//!   tapered pedestal under each, a backrest leaning back on the rear half
//!   — joined face to face (C0), with the seat dipped by moving shared
//!   points through the lattice.

use glam::{DVec2, DVec3};

use super::lattice::BodyLattice;
use super::morph::{Morph, Path};
use super::{BSplineVolume, Body2, BodyError, Dir, Face};

/// The flange and waist radii per layer of the spool (7 layers along w).
pub const SPOOL_RADII: [f64; 7] = [1.5, 1.5, 0.7, 0.7, 0.7, 1.5, 1.5];

/// The cube [−1, 1]³ as a tricubic volume with 5 × 5 × 7 control points.
pub fn cube() -> BSplineVolume {
    BSplineVolume::affine(
        DVec3::splat(-1.0),
        [DVec3::X * 2.0, DVec3::Y * 2.0, DVec3::Z * 2.0],
        [3, 3, 3],
        [5, 5, 7],
    )
    .expect("valid sizes")
}

/// The square-to-disc map of the spool (Fong's elliptical grid mapping).
fn to_disc(p: DVec2) -> DVec2 {
    DVec2::new(
        p.x * (1.0 - 0.5 * p.y * p.y).sqrt(),
        p.y * (1.0 - 0.5 * p.x * p.x).sqrt(),
    )
}

/// The spool of figure 7 as a Coons body 2 (see the module doc).
pub fn spool_body() -> Result<Body2, BodyError> {
    let mut lattice = cube();
    let pts: Vec<DVec3> = (0..lattice.points().len())
        .map(|idx| {
            let p = lattice.points()[idx];
            let k = lattice.ijk(idx)[2];
            let d = to_disc(DVec2::new(p.x, p.y)) * SPOOL_RADII[k];
            DVec3::new(d.x, d.y, p.z)
        })
        .collect();
    lattice.set_points(pts)?;
    Body2::from_volume_faces(&lattice)
}

/// The spool of figure 7 as a B-spline volume (the exact conversion of
/// [`spool_body`]).
pub fn spool() -> Result<BSplineVolume, BodyError> {
    spool_body()?.to_volume()
}

/// The metamorphosis of figure 10, cube to spool, with the eased path.
pub fn cube_to_spool() -> Result<Morph, BodyError> {
    Morph::new(&cube(), &spool()?, Path::Eased)
}

fn block(origin: DVec3, size: DVec3) -> BSplineVolume {
    BSplineVolume::affine(
        origin,
        [DVec3::X * size.x, DVec3::Y * size.y, DVec3::Z * size.z],
        [3, 3, 3],
        [4, 4, 4],
    )
    .expect("valid sizes")
}

/// Body indices of [`chair`].
pub mod chair_part {
    /// Front half of the seat.
    pub const SEAT_FRONT: usize = 0;
    /// Rear half of the seat.
    pub const SEAT_REAR: usize = 1;
    /// Pedestal under the front half.
    pub const PEDESTAL_FRONT: usize = 2;
    /// Pedestal under the rear half.
    pub const PEDESTAL_REAR: usize = 3;
    /// Backrest on the rear half.
    pub const BACK: usize = 4;
}

/// The five-body chair of figure 9 (x: depth, front at 0; y: width; z: up).
pub fn chair() -> Result<BodyLattice, BodyError> {
    use chair_part::*;
    let seat = DVec3::new(0.5, 1.0, 0.1);
    let mut bodies = vec![
        block(DVec3::new(0.0, 0.0, 0.45), seat),
        block(DVec3::new(0.5, 0.0, 0.45), seat),
        block(DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.5, 1.0, 0.45)),
        block(DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.5, 1.0, 0.45)),
        block(DVec3::new(0.5, 0.0, 0.55), DVec3::new(0.5, 1.0, 0.75)),
    ];
    // Pedestals taper toward the floor.
    for (b, cx) in [(PEDESTAL_FRONT, 0.25), (PEDESTAL_REAR, 0.75)] {
        let v = &mut bodies[b];
        for idx in 0..v.points().len() {
            let k = v.ijk(idx)[2];
            let s = [0.35, 0.6, 0.9, 1.0][k];
            let p = v.points()[idx];
            v.set_point(
                idx,
                DVec3::new(cx + (p.x - cx) * s, 0.5 + (p.y - 0.5) * s, p.z),
            )?;
        }
    }
    // The backrest thins and leans back with height.
    {
        let v = &mut bodies[BACK];
        for idx in 0..v.points().len() {
            let k = v.ijk(idx)[2];
            if k == 0 {
                continue;
            }
            let h = k as f64 / 3.0;
            let p = v.points()[idx];
            let x = 0.85 + (p.x - 0.85) * (1.0 - 0.6 * h) + 0.2 * h * h;
            v.set_point(idx, DVec3::new(x, p.y, p.z))?;
        }
    }
    let mut lattice = BodyLattice::new(bodies);
    let end = |dir| Face { dir, end: true };
    let start = |dir| Face { dir, end: false };
    lattice.join(SEAT_FRONT, end(Dir::U), SEAT_REAR, start(Dir::U), 1e-12)?;
    lattice.join(
        PEDESTAL_FRONT,
        end(Dir::W),
        SEAT_FRONT,
        start(Dir::W),
        1e-12,
    )?;
    lattice.join(PEDESTAL_REAR, end(Dir::W), SEAT_REAR, start(Dir::W), 1e-12)?;
    lattice.join(SEAT_REAR, end(Dir::W), BACK, start(Dir::W), 1e-12)?;
    // Dip the seat: inner top points of both halves down 3 cm (the rear
    // half's top is the backrest's bottom: moved in both).
    for b in [SEAT_FRONT, SEAT_REAR] {
        for i in 1..3 {
            for j in 1..3 {
                let v = &lattice.bodies()[b];
                let idx = v.index(i, j, 3);
                let p = v.points()[idx] - DVec3::Z * 0.03;
                lattice.set_point(b, idx, p)?;
            }
        }
    }
    Ok(lattice)
}
