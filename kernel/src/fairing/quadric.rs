//! Local quadric fits (paper 004 §7): in a point's local axes the
//! neighbours are fitted by least squares with
//! z = f + d u + e v + a u² + b uv + c v², and the curvatures follow from the
//! Monge patch's fundamental forms (E = 1 + d², F = de, G = 1 + e²,
//! L = 2a/w, M = b/w, N = 2c/w, w = √(1 + d² + e²)).
//!
//! **Sign convention**: curvatures are positive where the surface bends
//! away from its normal, so a sphere with outward normals has H = 1/R and
//! K = 1/R² (H = (k1 + k2)/2, k1 ≥ k2).
//!
//! * [`curvatures`] estimates at a point (f = 0: the fit passes through it),
//!   from the neighbours given; over a 2-ring it adds the cubic terms (the
//!   default, chosen by measurement: `tests/fairing_curvature.rs`).
//! * [`goal_height`] is the fairing step: the fit of the neighbours alone
//!   constrained to the goal mean curvature, whose height f at the origin
//!   is where the point should be; [`measure_goal_weights`] the same as
//!   weights, toward a mean- or Gaussian-curvature goal.

use glam::DVec3;

use super::local_axes::LocalAxes;

/// Which curvature measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    /// H = (k1 + k2)/2.
    Mean,
    /// K = k1 k2.
    Gaussian,
    /// k1, the larger principal curvature.
    MaxPrincipal,
    /// k2, the smaller principal curvature.
    MinPrincipal,
}

/// Curvatures at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Curvatures {
    /// Mean curvature.
    pub mean: f64,
    /// Gaussian curvature.
    pub gaussian: f64,
    /// Larger principal curvature.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// The fitted surface's unit normal.
    pub normal: DVec3,
}

impl Curvatures {
    /// The value of `m`.
    pub fn get(&self, m: Measure) -> f64 {
        match m {
            Measure::Mean => self.mean,
            Measure::Gaussian => self.gaussian,
            Measure::MaxPrincipal => self.k1,
            Measure::MinPrincipal => self.k2,
        }
    }
}

/// Solves the n × n system `a x = b` in place (row-major `a`) by Gaussian
/// elimination with partial pivoting; false if singular.
pub fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap_or(col);
        if a[piv * n + col].abs() < 1e-300 {
            return false;
        }
        if piv != col {
            for k in 0..n {
                a.swap(col * n + k, piv * n + k);
            }
            b.swap(col, piv);
        }
        for r in col + 1..n {
            let f = a[r * n + col] / a[col * n + col];
            if f != 0.0 {
                for k in col..n {
                    a[r * n + k] -= f * a[col * n + k];
                }
                b[r] -= f * b[col];
            }
        }
    }
    for r in (0..n).rev() {
        let mut s = b[r];
        for k in r + 1..n {
            s -= a[r * n + k] * b[k];
        }
        b[r] = s / a[r * n + r];
    }
    b.iter().all(|x| x.is_finite())
}

/// The mean and Gaussian curvature at the origin of the Monge patch
/// z = d u + e v + a u² + b uv + c v² (bending away from the normal
/// positive).
pub(crate) fn mean_gaussian(d: f64, e: f64, a: f64, b: f64, c: f64) -> (f64, f64) {
    let w2 = 1.0 + d * d + e * e;
    let w = w2.sqrt();
    let hm = (a * (1.0 + e * e) - b * d * e + c * (1.0 + d * d)) / (w2 * w);
    let km = (4.0 * a * c - b * b) / (w2 * w2);
    (-hm, km)
}

/// Curvatures from the Monge coefficients (d, e, a, b, c) in `axes`.
fn monge(axes: &LocalAxes, d: f64, e: f64, a: f64, b: f64, c: f64) -> Curvatures {
    let (mean, gaussian) = mean_gaussian(d, e, a, b, c);
    let disc = (mean * mean - gaussian).max(0.0).sqrt();
    Curvatures {
        mean,
        gaussian,
        k1: mean + disc,
        k2: mean - disc,
        normal: (axes.z - axes.x * d - axes.y * e).normalize(),
    }
}

/// Curvatures at `axes.origin` (a mesh point) from the polynomial through
/// it fitted to `neighbours` (world positions, at least 5): a quadric
/// z = d u + e v + a u² + b uv + c v², or with `cubic` (and at least 12
/// neighbours) that plus the four cubic terms — which absorb the third-order
/// part of the surface over a wide ring instead of letting it bias a, b, c.
pub fn curvatures(
    axes: &LocalAxes,
    neighbours: impl Iterator<Item = DVec3> + Clone,
    cubic: bool,
) -> Option<Curvatures> {
    let count = neighbours.clone().count();
    let k = if cubic && count >= 12 { 9 } else { 5 };
    if count < 5 {
        return None;
    }
    let mut m = [0.0; 81];
    let mut r = [0.0; 9];
    for p in neighbours {
        let q = axes.local(p);
        let (u, v) = (q.x, q.y);
        let row = [
            u,
            v,
            u * u,
            u * v,
            v * v,
            u * u * u,
            u * u * v,
            u * v * v,
            v * v * v,
        ];
        for i in 0..k {
            for j in 0..k {
                m[i * k + j] += row[i] * row[j];
            }
            r[i] += row[i] * q.z;
        }
    }
    if !solve_dense(&mut m[..k * k], &mut r[..k], k) {
        return None;
    }
    Some(monge(axes, r[0], r[1], r[2], r[3], r[4]))
}

/// Light holds in the goal fits' normal equations `m` (row stride
/// `stride`, unknowns f, d, e, a, b, c first) for `count` neighbours whose
/// largest squared distance from the origin is `scale`: on the slopes d, e
/// (the local axes make the true slopes small), which keeps rings of fewer
/// than six neighbours solvable; and for four neighbours on the twist b
/// too: four points in a cross aligned with the axes have uv = 0 at every
/// point, so nothing else fixes b (the height at the origin does not
/// depend on it there).
pub(crate) fn hold_small_rings(m: &mut [f64], stride: usize, count: usize, scale: f64) {
    let hold = if count < 6 { 1e-3 } else { 1e-9 } * scale;
    m[stride + 1] += hold;
    m[2 * stride + 2] += hold;
    if count < 5 {
        m[4 * stride + 4] += 1e-3 * scale * scale;
    }
}

/// The height f at the origin of the quadric fitted to `neighbours`
/// (local coordinates; at least 4) whose mean curvature at the origin is
/// `goal`; `None` for a singular fit. The constraint
/// a(1 + e²) − b d e + c(1 + d²) = −goal·w³ is linear in (a, b, c) with the
/// slopes (d, e) of the previous pass (two passes, the first with d = e = 0).
/// It also fixes a + c, which a ring of points on a circle leaves free.
pub fn goal_height(neighbours: &[DVec3], goal: f64) -> Option<f64> {
    if neighbours.len() < 4 {
        return None;
    }
    // Unknowns x = (f, d, e, a, b, c) and the constraint's multiplier.
    let mut ata = [0.0; 36];
    let mut atz = [0.0; 6];
    let mut scale = 0.0f64;
    for q in neighbours {
        let row = [1.0, q.x, q.y, q.x * q.x, q.x * q.y, q.y * q.y];
        for i in 0..6 {
            for j in 0..6 {
                ata[i * 6 + j] += row[i] * row[j];
            }
            atz[i] += row[i] * q.z;
        }
        scale = scale.max(q.x * q.x + q.y * q.y);
    }
    hold_small_rings(&mut ata, 6, neighbours.len(), scale);
    let (mut d0, mut e0) = (0.0, 0.0);
    let mut f = 0.0;
    for _ in 0..2 {
        let w2: f64 = 1.0 + d0 * d0 + e0 * e0;
        let g = [1.0 + e0 * e0, -d0 * e0, 1.0 + d0 * d0];
        let mut m = [0.0; 49];
        let mut r = [0.0; 7];
        for i in 0..6 {
            for j in 0..6 {
                m[i * 7 + j] = ata[i * 6 + j];
            }
            r[i] = atz[i];
        }
        for k in 0..3 {
            m[(3 + k) * 7 + 6] = g[k];
            m[6 * 7 + 3 + k] = g[k];
        }
        r[6] = -goal * w2 * w2.sqrt();
        if !solve_dense(&mut m, &mut r, 7) {
            return None;
        }
        f = r[0];
        (d0, e0) = (r[1], r[2]);
    }
    Some(f)
}

/// The fit of [`goal_height`] as weights: f = Σ_j α_j z_j + β for the
/// neighbours' heights z_j (their u, v fixed). Fills `alpha`, returns β.
pub fn goal_weights(neighbours: &[DVec3], goal: f64, alpha: &mut Vec<f64>) -> Option<f64> {
    // Slopes from the fit itself (as goal_height's second pass).
    let (mut d0, mut e0) = (0.0, 0.0);
    if let Some((d, e)) = goal_slopes(neighbours, goal) {
        (d0, e0) = (d, e);
    }
    let (mut m, _) = goal_normal_equations(neighbours);
    let w2: f64 = 1.0 + d0 * d0 + e0 * e0;
    let g = [1.0 + e0 * e0, -d0 * e0, 1.0 + d0 * d0];
    for k in 0..3 {
        m[(3 + k) * 7 + 6] = g[k];
        m[6 * 7 + 3 + k] = g[k];
    }
    kkt_weights(m, neighbours, -goal * w2 * w2.sqrt(), alpha)
}

/// The normal equations of a goal fit of `neighbours` (local coordinates):
/// the 7 × 7 matrix of the unknowns f, d, e, a, b, c (the constraint's row
/// and column left zero) with the holds of [`hold_small_rings`], and the
/// right-hand side (the constraint's entry zero).
pub(crate) fn goal_normal_equations(neighbours: &[DVec3]) -> ([f64; 49], [f64; 7]) {
    let mut m = [0.0; 49];
    let mut r = [0.0; 7];
    let mut scale = 0.0f64;
    for q in neighbours {
        let row = [1.0, q.x, q.y, q.x * q.x, q.x * q.y, q.y * q.y];
        for i in 0..6 {
            for j in 0..6 {
                m[i * 7 + j] += row[i] * row[j];
            }
            r[i] += row[i] * q.z;
        }
        scale = scale.max(q.x * q.x + q.y * q.y);
    }
    hold_small_rings(&mut m, 7, neighbours.len(), scale);
    (m, r)
}

/// A goal fit's height at the origin as weights of the neighbours'
/// heights, from its KKT matrix `kkt` and constraint value `rhs`:
/// y = K⁻¹ e_f (K symmetric), then f = yᵀ [Aᵀ z; rhs] = Σ_j α_j z_j + β.
/// Fills `alpha`, returns β; `None` for a singular matrix.
pub(crate) fn kkt_weights(
    mut kkt: [f64; 49],
    neighbours: &[DVec3],
    rhs: f64,
    alpha: &mut Vec<f64>,
) -> Option<f64> {
    let mut y = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    if !solve_dense(&mut kkt, &mut y, 7) {
        return None;
    }
    alpha.clear();
    alpha.extend(neighbours.iter().map(|q| {
        let row = [1.0, q.x, q.y, q.x * q.x, q.x * q.y, q.y * q.y];
        (0..6).map(|k| y[k] * row[k]).sum::<f64>()
    }));
    Some(y[6] * rhs)
}

/// The goal-constrained fit as weights (f = Σ_j α_j z_j + β, see
/// [`goal_weights`]) for a goal in `measure`: mean curvature
/// ([`goal_weights`]) or Gaussian curvature
/// ([`super::gaussian_goal::gaussian_goal_weights`], its warm-up's fit with
/// `warm_up`); `None` for a singular fit or a measure fairing does not take
/// (the principal curvatures).
pub fn measure_goal_weights(
    measure: Measure,
    neighbours: &[DVec3],
    goal: f64,
    warm_up: bool,
    alpha: &mut Vec<f64>,
) -> Option<f64> {
    match measure {
        Measure::Mean => goal_weights(neighbours, goal, alpha),
        Measure::Gaussian => {
            super::gaussian_goal::gaussian_goal_weights(neighbours, goal, warm_up, alpha)
        }
        Measure::MaxPrincipal | Measure::MinPrincipal => None,
    }
}

/// The slopes (d, e) of the goal-constrained fit with flat slopes assumed.
fn goal_slopes(neighbours: &[DVec3], goal: f64) -> Option<(f64, f64)> {
    let (mut m, mut r) = goal_normal_equations(neighbours);
    for k in 0..3 {
        let g = [1.0, 0.0, 1.0][k];
        m[(3 + k) * 7 + 6] = g;
        m[6 * 7 + 3 + k] = g;
    }
    r[6] = -goal;
    if !solve_dense(&mut m, &mut r, 7) {
        return None;
    }
    Some((r[1], r[2]))
}
