//! Shape operations of paper §4 built from primitives: round corners on a box
//! (Fig. 8) and shape mapping of an equal density surface onto a box face or a
//! cylinder (Figs. 10–12). Smooth blending (Fig. 9) needs no helper: a plane-based
//! primitive with a [`super::Connecting`] profile is its non-uniform reducing factor.
//!
//! Round corners — the reading chosen and the radius it predicts. Inside a uniform
//! solid eq. (4) gives E = Σ F, so a negative density primitive removes exactly the
//! region where it is non-zero: its influence range. Read literally, a negative
//! pipe on a box edge removes a cylinder about the edge: a concave cove of radius
//! equal to its influence range. The convex round of Fig. 8 is a "part of a pipe"
//! read as a sector shell: a pipe with reference radius ρ whose axis is inset by ρ
//! from both faces, clipped to the quarter facing the edge, hollow inside ρ. It
//! removes the points of the edge wedge farther than ρ from the axis, so the edge
//! becomes a circular arc of radius exactly ρ, tangent to both faces — provided the
//! influence range covers the wedge's far corner, range ≥ (√2 − 1) ρ. The vertices
//! take an octant of a negative ball shell of reference radius ρ (range ≥ (√3 − 1) ρ).
//! The result is the box's points within ρ of the box shrunk by ρ: a rounded box.

use super::density::{DensityPrimitive, DensityShape, HalfSpace, Sheet};
use super::error::{DsmError, positive};
use super::geometric::{GeometricPrimitive, GeometricShape};
use super::model::Group;
use super::placement::Placement;
use super::surface::EqualDensitySurface;
use glam::{DMat3, DVec2, DVec3};

/// A group holding a box of half extents `half` whose 12 edges and 8 vertices are
/// rounded to radius `radius` by negative sector-shell pipes and octant ball shells.
pub fn rounded_box(
    half: DVec3,
    placement: Placement,
    radius: f64,
    de: f64,
) -> Result<Group, DsmError> {
    positive("round radius", radius)?;
    positive("D_e", de)?;
    if radius >= half.min_element() {
        return Err(DsmError::BadParameter {
            name: "round radius",
            value: radius,
            why: "must be below the smallest half extent",
        });
    }
    let bx = GeometricPrimitive::new(GeometricShape::Box { half }, placement)?;
    let inner = half - DVec3::splat(radius);
    let (a, d, range) = (1.0 / radius, -de, radius);
    let r = placement.rotation();
    let t = placement.translation();
    let keep_pos = |axis: DVec3| HalfSpace {
        normal: -axis,
        offset: 0.0,
    };
    let mut density = Vec::new();
    // Edges: along each axis k, the 4 edges at signs (s1, s2) of the two others.
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        for (s1, s2) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
            let mut centre = DVec3::ZERO;
            centre[i] = s1 * inner[i];
            centre[j] = s2 * inner[j];
            let mut ex = DVec3::ZERO;
            ex[i] = s1;
            let mut ey = DVec3::ZERO;
            ey[j] = s2;
            let ez = ex.cross(ey);
            let local = Placement::new(r * DMat3::from_cols(ex, ey, ez), t + r * centre)?;
            let p = DensityPrimitive::new(
                DensityShape::Pipe {
                    radius,
                    half_length: inner[k],
                },
                local,
                d,
                a,
            )?
            .with_range(range)?
            .clipped(keep_pos(DVec3::X))
            .clipped(keep_pos(DVec3::Y));
            density.push(p);
        }
    }
    // Vertices: an octant of a ball shell at each inner corner.
    for s in 0..8 {
        let sg = DVec3::new(
            if s & 1 == 0 { 1.0 } else { -1.0 },
            if s & 2 == 0 { 1.0 } else { -1.0 },
            if s & 4 == 0 { 1.0 } else { -1.0 },
        );
        let local = Placement::new(r, t + r * (inner * sg))?;
        let mut p = DensityPrimitive::new(DensityShape::Sphere { radius }, local, d, a)?
            .with_range(range)?;
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            p = p.clipped(HalfSpace {
                normal: -axis * sg,
                offset: 0.0,
            });
        }
        density.push(p);
    }
    Ok(Group {
        geometric: vec![bx],
        density,
        incorporated: Vec::new(),
    })
}

/// The plane-based primitive that maps `surface`, over [lo, hi] of its (u, v), onto
/// the +z face of a box with half extents `half` placed at `placement`: the
/// reference plane is the face, u and v run along the box's local x and y from the
/// face centre. The face then carries the relief h(u, v) (and its mirror lies
/// inside the box).
pub fn map_onto_box_top(
    surface: &EqualDensitySurface,
    lo: DVec2,
    hi: DVec2,
    half: DVec3,
    placement: Placement,
) -> Result<DensityPrimitive, DsmError> {
    let face = Placement::new(
        placement.rotation(),
        placement.to_world(DVec3::new(0.0, 0.0, half.z)),
    )?;
    surface.primitive(lo, hi, face)
}

/// The cylinder-mapped primitive carrying `surface` over [lo, hi] of (u, v) = (R θ, z)
/// on the cylinder of radius R about the local z axis of `placement`: the radial
/// relief is h(u, v) (eq. 12 with r = |ρ − R|).
pub fn map_onto_cylinder(
    surface: &EqualDensitySurface,
    lo: DVec2,
    hi: DVec2,
    radius: f64,
    placement: Placement,
) -> Result<DensityPrimitive, DsmError> {
    let sheet = Sheet {
        distribution: surface.distribution.clone(),
        lo,
        hi,
        connect: surface.connect.clone(),
    };
    DensityPrimitive::new(
        DensityShape::CylinderMap {
            radius,
            sheet: Box::new(sheet),
        },
        placement,
        1.0,
        surface.reducing,
    )
}
