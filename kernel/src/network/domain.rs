//! The patch domain: a regular n-gon inscribed in the unit circle, its
//! Wachspress coordinates λ_j and the side parameters of the side-based
//! (Kato) patch, after Salvi & Várady's notation:
//!
//! * vertex V_j = (cos(2πj/n + π/2 − π/n), sin(…)), counter-clockwise; side i
//!   runs from V_i to V_{i+1};
//! * λ_j = w_j / Σ w, w_j = Π_{k ∉ {j−1, j}} A_k(p), A_k(p) the area of the
//!   triangle (p, V_k, V_{k+1}) — the Wachspress weights with the two
//!   vanishing areas cancelled, so they are polynomials, finite on the
//!   boundary (the constant corner-triangle factor is the same for every j of
//!   a regular polygon and cancels);
//! * side parameter s_i = λ_{i+1} / (λ_i + λ_{i+1}) ∈ [0, 1] along side i,
//!   distance parameter d_i = 1 − λ_i − λ_{i+1}, zero exactly on side i and
//!   equal to s_{i+1} on side i+1 (and 1 − s_{i−1} on side i−1).

use glam::DVec2;

use super::jet::Scalar;

/// A regular n-gon domain (n ≥ 3).
#[derive(Clone, Debug, PartialEq)]
pub struct Domain {
    vertices: Vec<DVec2>,
}

/// Side-based parameters of one domain point.
#[derive(Clone, Debug, PartialEq)]
pub struct SideParams<S> {
    /// Wachspress coordinates λ_j.
    pub lambda: Vec<S>,
    /// s_i per side.
    pub s: Vec<S>,
    /// d_i per side.
    pub d: Vec<S>,
}

impl Domain {
    /// The regular `n`-gon (n ≥ 3; the caller checks).
    pub fn regular(n: usize) -> Self {
        let phase = std::f64::consts::FRAC_PI_2 - std::f64::consts::PI / n as f64;
        let vertices = (0..n)
            .map(|j| {
                let a = phase + std::f64::consts::TAU * j as f64 / n as f64;
                DVec2::new(a.cos(), a.sin())
            })
            .collect();
        Self { vertices }
    }

    /// Number of sides.
    pub fn sides(&self) -> usize {
        self.vertices.len()
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices
    }

    /// The point at parameter s ∈ [0, 1] along side i.
    pub fn side_point(&self, i: usize, s: f64) -> DVec2 {
        let n = self.sides();
        self.vertices[i].lerp(self.vertices[(i + 1) % n], s)
    }

    /// Whether `p` is inside the polygon or on its boundary (to `eps`).
    pub fn contains(&self, p: DVec2, eps: f64) -> bool {
        let n = self.sides();
        (0..n).all(|k| {
            let (a, b) = (self.vertices[k], self.vertices[(k + 1) % n]);
            (b - a).perp_dot(p - a) >= -eps
        })
    }

    /// The domain vertex `p` coincides with (to 1e-14), if any.
    pub fn corner_at(&self, p: DVec2) -> Option<usize> {
        self.vertices
            .iter()
            .position(|v| (*v - p).length() <= 1e-14)
    }

    /// λ, s and d at the point (x, y) (not a domain vertex).
    pub fn params<S: Scalar>(&self, x: S, y: S) -> SideParams<S> {
        let n = self.sides();
        // A_k(p) = ½ (V_k − p) × (V_{k+1} − p), linear in p.
        let area: Vec<S> = (0..n)
            .map(|k| {
                let (a, b) = (self.vertices[k], self.vertices[(k + 1) % n]);
                let (ax, ay) = (S::cst(a.x) - x, S::cst(a.y) - y);
                let (bx, by) = (S::cst(b.x) - x, S::cst(b.y) - y);
                (ax * by - ay * bx) * S::cst(0.5)
            })
            .collect();
        let w: Vec<S> = (0..n)
            .map(|j| {
                let mut prod = S::cst(1.0);
                for (k, a) in area.iter().enumerate() {
                    if k != j && k != (j + n - 1) % n {
                        prod = prod * *a;
                    }
                }
                prod
            })
            .collect();
        let total = w.iter().fold(S::cst(0.0), |acc, x| acc + *x);
        let lambda: Vec<S> = w.iter().map(|x| *x / total).collect();
        let mut s = Vec::with_capacity(n);
        let mut d = Vec::with_capacity(n);
        for i in 0..n {
            let (li, lj) = (lambda[i], lambda[(i + 1) % n]);
            let sum = li + lj;
            // s_i is 0/0 only where λ_i = λ_{i+1} = 0 (far from side i), where
            // side i's blend is zero: any finite value serves.
            s.push(if sum.val() > 1e-300 {
                lj / sum
            } else {
                S::cst(0.5)
            });
            d.push(S::cst(1.0) - sum);
        }
        SideParams { lambda, s, d }
    }
}
