//! The quadric error function of dual contouring: the point minimising
//! Σ (n_i · (x − p_i))² over a cell's Hermite samples (p_i, n_i), solved about the
//! samples' mass point with a truncated eigendecomposition (eigenvalues below 1/10 of
//! the largest are dropped), as in Schaefer & Warren's dual contouring notes.

use glam::{DMat3, DVec3};

/// Accumulated Hermite samples of one cell.
#[derive(Clone, Copy, Debug)]
pub struct Qef {
    ata: DMat3,
    atb: DVec3,
    mass: DVec3,
    normal_sum: DVec3,
    count: u32,
}

/// The minimiser and the number of directions it is constrained in (1 = smooth
/// surface, 2 = an edge, 3 = a corner).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QefSolution {
    /// The point.
    pub point: DVec3,
    /// Rank kept.
    pub rank: u32,
    /// The mass point of the samples.
    pub mass_point: DVec3,
    /// The sum of the unit normals.
    pub normal_sum: DVec3,
}

impl Default for Qef {
    fn default() -> Self {
        // Not derived: glam's DMat3::default() is the identity.
        Self {
            ata: DMat3::ZERO,
            atb: DVec3::ZERO,
            mass: DVec3::ZERO,
            normal_sum: DVec3::ZERO,
            count: 0,
        }
    }
}

impl Qef {
    /// Adds a sample on the surface with unit normal n.
    pub fn add(&mut self, p: DVec3, n: DVec3) {
        let o = DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        self.ata += o;
        self.atb += n * n.dot(p);
        self.mass += p;
        self.normal_sum += n;
        self.count += 1;
    }

    /// The minimiser (None without samples).
    pub fn solve(&self) -> Option<QefSolution> {
        if self.count == 0 {
            return None;
        }
        let m = self.mass / self.count as f64;
        let rhs = self.atb - self.ata * m;
        let (vals, vecs) = symmetric_eigen(self.ata);
        let top = vals.iter().copied().fold(0.0, f64::max);
        let mut x = m;
        let mut rank = 0;
        for (i, &val) in vals.iter().enumerate() {
            if val > 0.1 * top && val > 0.0 {
                let v = vecs.col(i);
                x += v * (v.dot(rhs) / val);
                rank += 1;
            }
        }
        Some(QefSolution {
            point: x,
            rank,
            mass_point: m,
            normal_sum: self.normal_sum,
        })
    }
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3 × 3 matrix by cyclic Jacobi.
pub fn symmetric_eigen(mut a: DMat3) -> ([f64; 3], DMat3) {
    let mut v = DMat3::IDENTITY;
    for _ in 0..32 {
        let off = a.x_axis.y.abs() + a.x_axis.z.abs() + a.y_axis.z.abs();
        if off < 1e-300 || off < 1e-15 * (a.x_axis.x.abs() + a.y_axis.y.abs() + a.z_axis.z.abs()) {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = a.col(q)[p];
            if apq == 0.0 {
                continue;
            }
            let app = a.col(p)[p];
            let aqq = a.col(q)[q];
            let theta = (aqq - app) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            let mut j = DMat3::IDENTITY;
            j.col_mut(p)[p] = c;
            j.col_mut(q)[q] = c;
            j.col_mut(q)[p] = s;
            j.col_mut(p)[q] = -s;
            a = j.transpose() * a * j;
            v *= j;
        }
    }
    ([a.x_axis.x, a.y_axis.y, a.z_axis.z], v)
}
