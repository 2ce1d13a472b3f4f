//! Eigen-decomposition of a symmetric 3 × 3 matrix by cyclic Jacobi
//! rotations (allocation-free): plane fits take the eigenvector of the
//! smallest eigenvalue of a covariance as the plane's normal.

use glam::{DMat3, DVec3};

/// Eigenvalues (ascending) and unit eigenvectors of the symmetric `m`.
#[allow(clippy::needless_range_loop)] // rotations index rows and columns together
pub fn sym3_eigen(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let mut a = [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z],
    ];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let diag = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-300 || off <= 1e-17 * diag {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() <= 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let vals = [a[idx[0]][idx[0]], a[idx[1]][idx[1]], a[idx[2]][idx[2]]];
    let vecs = idx.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]).normalize());
    (vals, vecs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonalises_a_rotated_diagonal_matrix() {
        let r = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let d = DMat3::from_diagonal(DVec3::new(3.0, -1.0, 0.5));
        let m = r * d * r.transpose();
        let (vals, vecs) = sym3_eigen(m);
        assert!((vals[0] + 1.0).abs() < 1e-12 && (vals[1] - 0.5).abs() < 1e-12);
        assert!((vals[2] - 3.0).abs() < 1e-12);
        for (l, v) in vals.iter().zip(vecs) {
            assert!((m * v - v * *l).length() < 1e-12);
        }
    }
}
