//! Gauss–Legendre quadrature: n nodes integrate polynomials of degree
//! 2n − 1 exactly, which makes integrals of B-spline products exact when
//! taken span by span.

/// Nodes and weights of the n-point Gauss–Legendre rule on [−1, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The n-point rule (n ≥ 1), nodes by Newton iteration on the Legendre
    /// polynomial P_n to machine precision.
    pub fn new(n: usize) -> Self {
        let n = n.max(1);
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            // Tricomi's initial guess for the i-th root.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            dp = if d != 0.0 { d } else { dp };
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Self { nodes, weights }
    }

    /// The smallest rule exact for polynomials of degree `degree`.
    pub fn exact_for(degree: usize) -> Self {
        Self::new(degree / 2 + 1)
    }

    /// Nodes and weights mapped to [a, b], as (t, w) pairs.
    pub fn on(&self, a: f64, b: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(move |(&x, &w)| (mid + half * x, half * w))
    }

    /// The number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false: a rule has at least one node.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// P_n(x) and P_n'(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    let p = if n == 0 { 1.0 } else { p1 };
    let d = if n == 0 {
        0.0
    } else {
        n as f64 * (x * p1 - p0) / (x * x - 1.0)
    };
    (p, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        for n in 1..=8 {
            let g = GaussLegendre::new(n);
            for deg in 0..2 * n {
                let got: f64 = g.on(0.5, 2.0).map(|(t, w)| w * t.powi(deg as i32)).sum();
                let exact =
                    (2f64.powi(deg as i32 + 1) - 0.5f64.powi(deg as i32 + 1)) / (deg as f64 + 1.0);
                assert!(
                    (got - exact).abs() < 1e-12 * exact.abs().max(1.0),
                    "n={n} deg={deg}"
                );
            }
        }
    }

    #[test]
    fn is_not_exact_beyond_its_degree() {
        let g = GaussLegendre::new(2);
        let got: f64 = g.on(0.0, 1.0).map(|(t, w)| w * t.powi(4)).sum();
        assert!((got - 0.2).abs() > 1e-4);
    }
}
