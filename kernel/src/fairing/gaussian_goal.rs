//! The fairing step's fit toward a Gaussian-curvature goal: the quadric
//! z = f + d u + e v + a u² + b uv + c v² fitted by least squares to a
//! point's neighbours (local coordinates, axes at their pseudo-centroid)
//! with Gaussian curvature K = goal at the origin, whose height f there is
//! where the point should be — the counterpart of
//! [`super::quadric::goal_weights`] for mean-curvature goals.
//!
//! K = H² − δ² (H the mean curvature, δ = (k₁ − k₂)/2 the anisotropy), so
//! the fit is the mean-curvature fit whose goal H satisfies
//! H = s·√(K + δ²) with δ that fit's own anisotropy: a scalar fixed point,
//! found by re-solving the (linear) mean-constrained fit with
//! H ← s·√max(K + δ(H)², 0), the slopes of the last fit in its constraint,
//! until H no longer changes (a few passes: the anisotropy of a fit hardly
//! depends on its mean curvature). The last pass's fit then has K = goal
//! to round-off, and its height is linear in the neighbours' heights
//! (f = Σ α_j z_j + β, the weights the global sweep needs).
//!
//! A Gaussian goal does not say which way the surface bends; the branch
//! is s = +1 — the fit bends away from the normal, as a unit sphere with
//! outward normals (H = K = 1) — for K ≥ 0, and the sign of the ring's
//! own unconstrained fit for K < 0 (a saddle bends both ways). Where
//! K < 0 and the ring is less anisotropic than −K needs (δ² < −K), the
//! fit goes to H = 0, the nearest it can get with that anisotropy: such
//! goals are approached, not met, where the boundary does not shape the
//! saddle.
//!
//! A run starts with umbilic sweeps ([`WARM_UP_MOVE`]).
//!
//! (A direct constraint 4ac − b² = K w⁴ met by Newton steps from the
//! ring's unconstrained fit was tried first: on the perturbed octant the
//! unconstrained 1-ring fits are noisy enough — curvature ≈ 7 against the
//! goal's 1 — that Newton landed on the other branch at some points and
//! the sweeps diverged; a single linearisation per pass had left the
//! fixed point 0.19 RMS off K = 1.)

use glam::DVec3;

use super::quadric::{goal_normal_equations, kkt_weights, mean_gaussian, solve_dense};

/// Passes of the fixed point in H at most per fit.
pub const MAX_PASSES: usize = 16;

/// A run toward Gaussian goals starts with umbilic sweeps (δ taken as 0:
/// the mean-curvature goal s·√max(K, 0)) until a sweep moves no point by
/// more than this fraction of the mesh's size: on a noisy mesh the 1-ring
/// fits' anisotropy is noise (δ ≈ 7 against K = 1 on the octant perturbed
/// by half its spacing) and taken at face value it bulges the first sweep
/// far off (a move of 2 on the unit octant, then divergence).
pub const WARM_UP_MOVE: f64 = 1e-3;

/// The fit (f, d, e, a, b, c, multiplier) with mean curvature `h` at the
/// origin, the constraint linearised at slopes (d0, e0), and the KKT
/// matrix and constraint value used.
fn mean_fit(
    base: &([f64; 49], [f64; 7]),
    (d0, e0): (f64, f64),
    h: f64,
) -> Option<([f64; 7], [f64; 49], f64)> {
    let (mut m, mut r) = *base;
    let w2 = 1.0 + d0 * d0 + e0 * e0;
    let g = [1.0 + e0 * e0, -d0 * e0, 1.0 + d0 * d0];
    for k in 0..3 {
        m[(3 + k) * 7 + 6] = g[k];
        m[6 * 7 + 3 + k] = g[k];
    }
    let rhs = -h * w2 * w2.sqrt();
    r[6] = rhs;
    let kkt = m;
    if !solve_dense(&mut m, &mut r, 7) {
        return None;
    }
    Some((r, kkt, rhs))
}

/// The branch sign for goal `k`: +1 for K ≥ 0; for K < 0 the sign of the
/// mean curvature of the ring's fit without a curvature constraint (a
/// light ridge on a, b, c keeps it solvable).
fn branch(base: &([f64; 49], [f64; 7]), k: f64) -> f64 {
    if k >= 0.0 {
        return 1.0;
    }
    let (mut m, mut r) = *base;
    m[48] = 1.0;
    let trace: f64 = (3..6).map(|i| m[i * 7 + i]).sum();
    for i in 3..6 {
        m[i * 7 + i] += 1e-9 * trace.max(1e-300);
    }
    if !solve_dense(&mut m, &mut r, 7) {
        return 1.0;
    }
    let (h, _) = mean_gaussian(r[1], r[2], r[3], r[4], r[5]);
    if h < 0.0 { -1.0 } else { 1.0 }
}

/// The fit of the neighbours (local coordinates, at least 4) with
/// Gaussian curvature `goal` at the origin as weights: f = Σ_j α_j z_j + β
/// for the neighbours' heights z_j (their u, v fixed). With `umbilic`, the
/// warm-up's fit: mean curvature s·√max(K, 0), one pass. Fills `alpha`,
/// returns β; `None` for a singular fit.
pub fn gaussian_goal_weights(
    neighbours: &[DVec3],
    goal: f64,
    umbilic: bool,
    alpha: &mut Vec<f64>,
) -> Option<f64> {
    if neighbours.len() < 4 || !goal.is_finite() {
        return None;
    }
    let base = goal_normal_equations(neighbours);
    let s = branch(&base, goal);
    let mut h = s * goal.max(0.0).sqrt();
    let mut slopes = (0.0, 0.0);
    let mut last = None;
    for _ in 0..MAX_PASSES {
        let (x, kkt, rhs) = mean_fit(&base, slopes, h)?;
        last = Some((kkt, rhs));
        if umbilic {
            break;
        }
        let (hf, kf) = mean_gaussian(x[1], x[2], x[3], x[4], x[5]);
        let spread = (hf * hf - kf).max(0.0);
        let next = s * (goal + spread).max(0.0).sqrt();
        let moved = (next - h).abs() + (x[1] - slopes.0).abs() + (x[2] - slopes.1).abs();
        h = next;
        slopes = (x[1], x[2]);
        if moved <= 1e-14 * (1.0 + h.abs()) {
            break;
        }
    }
    // The last pass's fit as weights.
    let (kkt, rhs) = last?;
    kkt_weights(kkt, neighbours, rhs, alpha)
}
