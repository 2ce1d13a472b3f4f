//! Anderson acceleration of the global fairing sweeps ([`super::implicit`]).
//!
//! A sweep is a fixed-point map x ↦ G(x) of the interior positions (the
//! frozen equations' solution at the frames fitted at x). Plain sweeps take
//! x ← x + ω f with the residual f = G(x) − x and converge linearly (about
//! 0.4 per sweep on the sphere octants). Anderson's method (type II, depth
//! m) keeps the last m differences ΔX, ΔF of positions and residuals and
//! steps from the combination of them that best cancels the current
//! residual: γ = argmin ‖f − ΔF γ‖₂, x ← x + ω f − (ΔX + ω ΔF) γ.
//! A fixed point of G is a fixed point of the accelerated iteration and
//! vice versa (f = 0 there), so the run ends where plain sweeps end; the
//! convergence test still measures the plain residual f of every sweep.
//!
//! Safeguards: the least-squares problem is solved from its m × m normal
//! equations with a relative ridge of 1e-12; a singular system, a
//! non-finite γ or a residual that grew more than [`RESTART_GROWTH`] times
//! over the last sweep clears the history (the step is then the plain one).

use super::quadric::solve_dense;

/// A residual this many times the last one restarts the history.
pub const RESTART_GROWTH: f64 = 2.0;

/// How the sweeps are stepped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Acceleration {
    /// x ← x + ω f (the paper's scheme, solved globally).
    Plain,
    /// Anderson acceleration with this depth (≥ 1; 0 is plain).
    Anderson(usize),
}

impl Default for Acceleration {
    /// Anderson acceleration of depth 5: the same fixed point as plain
    /// steps in 13 sweeps instead of 22 on the octants
    /// (`tests/fairing_anderson.rs`, `benches/fairing.rs`) and in no more
    /// sweeps on every face of the bottle demo (`tests/fairing_bottle.rs`).
    /// (It was not the default while the page's fairing of the bottle did
    /// not finish: the cause was not the acceleration but the fit at a
    /// quad face's centre, whose four neighbours in a cross left the twist
    /// term free — a singular fit that ended the job; see
    /// [`super::quadric::hold_small_rings`].)
    fn default() -> Self {
        Acceleration::Anderson(5)
    }
}

/// The state of an accelerated iteration over vectors of a fixed length.
#[derive(Clone, Debug, Default)]
pub struct Anderson {
    depth: usize,
    /// The previous iterate and residual.
    last: Option<(Vec<f64>, Vec<f64>)>,
    /// Oldest first: (Δx, Δf) of consecutive iterates.
    diffs: Vec<(Vec<f64>, Vec<f64>)>,
    /// Times the history was cleared by a safeguard.
    pub restarts: usize,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Anderson {
    /// An iteration keeping `depth` differences (0: plain steps).
    pub fn new(depth: usize) -> Self {
        Self {
            depth,
            ..Self::default()
        }
    }

    /// The depth it was made with.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// The next iterate from the current one `x` and its residual
    /// `f` = G(x) − x, with mixing `omega`; written into `x`.
    pub fn step(&mut self, x: &mut [f64], f: &[f64], omega: f64) {
        if self.depth == 0 {
            for (xi, fi) in x.iter_mut().zip(f) {
                *xi += omega * fi;
            }
            return;
        }
        if let Some((x0, f0)) = self.last.take() {
            let grew = dot(f, f) > RESTART_GROWTH * RESTART_GROWTH * dot(&f0, &f0);
            if grew {
                self.diffs.clear();
                self.restarts += 1;
            } else {
                let dx: Vec<f64> = x.iter().zip(&x0).map(|(a, b)| a - b).collect();
                let df: Vec<f64> = f.iter().zip(&f0).map(|(a, b)| a - b).collect();
                if self.diffs.len() == self.depth {
                    self.diffs.remove(0);
                }
                self.diffs.push((dx, df));
            }
        }
        self.last = Some((x.to_vec(), f.to_vec()));
        let gamma = self.coefficients(f);
        if gamma.is_none() && !self.diffs.is_empty() {
            self.diffs.clear();
            self.restarts += 1;
        }
        for (i, (xi, fi)) in x.iter_mut().zip(f).enumerate() {
            *xi += omega * fi;
            if let Some(g) = &gamma {
                for (gk, (dx, df)) in g.iter().zip(&self.diffs) {
                    *xi -= gk * (dx[i] + omega * df[i]);
                }
            }
        }
    }

    /// γ minimising ‖f − ΔF γ‖₂, or `None` (no history, or a singular or
    /// non-finite solve).
    fn coefficients(&self, f: &[f64]) -> Option<Vec<f64>> {
        let m = self.diffs.len();
        if m == 0 {
            return None;
        }
        let mut gram = vec![0.0; m * m];
        let mut rhs = vec![0.0; m];
        for i in 0..m {
            for j in 0..=i {
                let g = dot(&self.diffs[i].1, &self.diffs[j].1);
                gram[i * m + j] = g;
                gram[j * m + i] = g;
            }
            rhs[i] = dot(&self.diffs[i].1, f);
        }
        let trace: f64 = (0..m).map(|i| gram[i * m + i]).sum();
        if !(trace > 0.0 && trace.is_finite()) {
            return None;
        }
        for i in 0..m {
            gram[i * m + i] += 1e-12 * trace;
        }
        if !solve_dense(&mut gram, &mut rhs, m) {
            return None;
        }
        Some(rhs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// G(x) = A x + b with a contraction A (spectral radius 0.9): plain
    /// steps need ~200 iterations to 1e-9; Anderson's, on a 6-dimensional
    /// linear map with depth 6, reach it in a handful (it is GMRES there).
    #[test]
    fn accelerates_a_slow_linear_contraction_to_its_fixed_point() {
        let n = 6;
        let a = |x: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let diag = 0.9 - 0.1 * i as f64;
                    let next = if i + 1 < n { 0.05 * x[i + 1] } else { 0.0 };
                    diag * x[i] + next + 1.0
                })
                .collect()
        };
        let run = |depth: usize| {
            let mut it = Anderson::new(depth);
            let mut x = vec![0.0; n];
            for k in 1..=1000 {
                let g = a(&x);
                let f: Vec<f64> = g.iter().zip(&x).map(|(g, x)| g - x).collect();
                if f.iter().fold(0.0f64, |m, v| m.max(v.abs())) < 1e-9 {
                    return (k, x);
                }
                it.step(&mut x, &f, 1.0);
            }
            (1000, x)
        };
        let (plain, xp) = run(0);
        let (fast, xa) = run(6);
        assert!(plain > 150, "plain took {plain}");
        assert!(fast < 20, "Anderson took {fast}");
        for (p, q) in xp.iter().zip(&xa) {
            assert!((p - q).abs() < 1e-7, "{p} vs {q}");
        }
    }
}
