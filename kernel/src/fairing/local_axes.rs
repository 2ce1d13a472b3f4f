//! Local axes at a mesh point (paper 004 §5): the tangent plane fitted to
//! the point and its neighbours by least squares — its normal is the
//! eigenvector of the smallest eigenvalue of their covariance, oriented to
//! agree with a reference normal — with x and y spanning the plane; and the
//! pseudo-centroid (§6): the mean of the neighbours, towards whose normal
//! line a point is moved so that points do not bunch.

use glam::{DMat3, DVec3};

use super::eigen3::sym3_eigen;

/// An orthonormal frame at a point: z along the normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalAxes {
    /// The frame's origin.
    pub origin: DVec3,
    /// In the tangent plane.
    pub x: DVec3,
    /// In the tangent plane, z × x.
    pub y: DVec3,
    /// The normal.
    pub z: DVec3,
}

impl LocalAxes {
    /// Coordinates of `p` in the frame.
    pub fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.x), d.dot(self.y), d.dot(self.z))
    }
}

/// The plane fitted to `points` (at least 3), its normal oriented along
/// `reference`, with its origin at `origin`.
pub fn fit_axes(
    origin: DVec3,
    points: impl Iterator<Item = DVec3> + Clone,
    reference: DVec3,
) -> LocalAxes {
    let (mut sum, mut k) = (DVec3::ZERO, 0usize);
    for p in points.clone() {
        sum += p;
        k += 1;
    }
    let mean = sum / k.max(1) as f64;
    let mut cov = DMat3::ZERO;
    for p in points {
        let d = p - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let (_, vecs) = sym3_eigen(cov);
    let mut z = vecs[0];
    if z.dot(reference) < 0.0 {
        z = -z;
    }
    let x = z.any_orthonormal_vector();
    LocalAxes {
        origin,
        x,
        y: z.cross(x),
        z,
    }
}

/// The pseudo-centroid: the mean of the neighbours.
pub fn pseudo_centroid(neighbours: impl Iterator<Item = DVec3>) -> DVec3 {
    let (mut s, mut k) = (DVec3::ZERO, 0usize);
    for p in neighbours {
        s += p;
        k += 1;
    }
    s / k.max(1) as f64
}
