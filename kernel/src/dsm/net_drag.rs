//! A net node dragged at interactive rates: the inverse transformation (eqs.
//! 8–11) re-solved per frame by reusing the factorisation taken when the drag
//! started.
//!
//! Moving node d changes h_d, so eq. (8) changes a_dk only for k = d and the
//! nodes that have d among their surrounding nodes — at most 9 columns S of C on
//! a regular net — and the right-hand side only in row d. With C = C₀ + U Eᵀ
//! (U = C[:, S] − C₀[:, S], E the unit columns of S), the Sherman–Morrison–Woodbury
//! identity gives
//!
//! X = Y − Z (I + Eᵀ Z)⁻¹ Eᵀ Y,  Y = C₀⁻¹ b,  Z = C₀⁻¹ U,
//!
//! |S| + 1 triangular solve pairs against C₀'s LU and one |S| × |S| system per
//! frame, instead of a new n × n factorisation. Every frame's solution is checked
//! at the charged nodes; where the update has lost accuracy (|h(u_j, v_j) − h_j|
//! above `tolerance`, e.g. a drag far from where it started), the frame is
//! solved from scratch and that factorisation becomes the new C₀.

use super::distribution::{Charge, Distribution};
use super::error::DsmError;
use super::inverse::{
    InverseOptions, InverseReport, PassingPointsNet, inverse_transform, reducing_factor,
};
use super::surface::EqualDensitySurface;
use faer::Mat;
use faer::linalg::solvers::PartialPivLu;
use faer::prelude::Solve;

/// One node of a net being dragged.
pub struct NetDrag {
    net: PassingPointsNet,
    opts: InverseOptions,
    node: usize,
    interior: Vec<usize>,
    /// Interior (column) indices whose reducing factor depends on h_node.
    cols: Vec<usize>,
    c0: Mat<f64>,
    lu: PartialPivLu<f64>,
    start: InverseReport,
    /// Largest |h(u_j, v_j) − h_j| accepted from the update.
    pub tolerance: f64,
    /// Frames solved from scratch since the drag started (after the first).
    pub refactorised: usize,
}

/// What one drag frame found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragStep {
    /// max |h(u_j, v_j) − h_j| over the charged nodes.
    pub max_residual: f64,
    /// Whether this frame was solved from scratch.
    pub refactorised: bool,
}

impl NetDrag {
    /// Starts dragging `node` of `net`: one full inverse transformation (its
    /// report, with the condition, is [`Self::start_report`]).
    pub fn start(
        net: PassingPointsNet,
        opts: InverseOptions,
        node: usize,
    ) -> Result<(Self, EqualDensitySurface), DsmError> {
        if node >= net.nodes().len() {
            return Err(DsmError::DegenerateNet("no such node"));
        }
        let (surface, report) = inverse_transform(&net, &opts)?;
        let interior: Vec<usize> = (0..net.nodes().len())
            .filter(|&i| !net.is_peripheral(i))
            .collect();
        let cols = interior
            .iter()
            .enumerate()
            .filter(|&(_, &k)| k == node || net.neighbours(k).contains(&node))
            .map(|(c, _)| c)
            .collect();
        let c0 = matrix(&net, &opts, &interior);
        let lu = c0.partial_piv_lu();
        let tolerance = 1e-9 * net.size();
        Ok((
            Self {
                net,
                opts,
                node,
                interior,
                cols,
                c0,
                lu,
                start: report,
                tolerance,
                refactorised: 0,
            },
            surface,
        ))
    }

    /// The full report of the drag's first solve.
    pub fn start_report(&self) -> &InverseReport {
        &self.start
    }

    /// The net as dragged so far.
    pub fn net(&self) -> &PassingPointsNet {
        &self.net
    }

    /// Moves the node to height h and solves; on error nothing changes.
    pub fn set_height(&mut self, h: f64) -> Result<(EqualDensitySurface, DragStep), DsmError> {
        let old = self.net.nodes()[self.node].z;
        self.net.set_height(self.node, h)?;
        match self.solve() {
            Ok(out) => Ok(out),
            Err(e) => {
                self.net.set_height(self.node, old)?;
                Err(e)
            }
        }
    }

    fn solve(&mut self) -> Result<(EqualDensitySurface, DragStep), DsmError> {
        let n = self.interior.len();
        let m = self.cols.len();
        let a_i = self.opts.reducing;
        let nodes = self.net.nodes();
        let ad: Vec<f64> = self
            .interior
            .iter()
            .map(|&k| reducing_factor(&self.net, k, a_i, self.opts.a_min))
            .collect();
        let rhs = Mat::<f64>::from_fn(n, 1, |j, _| {
            self.opts.de * (a_i * nodes[self.interior[j]].z).exp() - self.opts.base
        });
        let u = Mat::<f64>::from_fn(n, m, |j, c| {
            let k = self.cols[c];
            let (pj, pk) = (nodes[self.interior[j]], nodes[self.interior[k]]);
            (-ad[k] * (pj.truncate() - pk.truncate()).length_squared()).exp() - self.c0[(j, k)]
        });
        let y = self.lu.solve(&rhs);
        let z = self.lu.solve(&u);
        let small = Mat::<f64>::from_fn(m, m, |a, b| {
            z[(self.cols[a], b)] + if a == b { 1.0 } else { 0.0 }
        });
        let ys = Mat::<f64>::from_fn(m, 1, |a, _| y[(self.cols[a], 0)]);
        let w = small.partial_piv_lu().solve(&ys);
        let x: Vec<f64> = (0..n)
            .map(|j| y[(j, 0)] - (0..m).map(|c| z[(j, c)] * w[(c, 0)]).sum::<f64>())
            .collect();
        if x.iter().all(|v| v.is_finite()) {
            let surface = self.surface(&x, &ad)?;
            let r = self.residual(&surface);
            if r <= self.tolerance {
                return Ok((
                    surface,
                    DragStep {
                        max_residual: r,
                        refactorised: false,
                    },
                ));
            }
        }
        // The update lost accuracy: solve from scratch and restart from here.
        let (surface, report) = inverse_transform(&self.net, &self.opts)?;
        self.c0 = matrix(&self.net, &self.opts, &self.interior);
        self.lu = self.c0.partial_piv_lu();
        self.refactorised += 1;
        Ok((
            surface,
            DragStep {
                max_residual: report.max_residual,
                refactorised: true,
            },
        ))
    }

    fn surface(&self, x: &[f64], ad: &[f64]) -> Result<EqualDensitySurface, DsmError> {
        let nodes = self.net.nodes();
        let charges = self
            .interior
            .iter()
            .zip(x.iter().zip(ad))
            .map(|(&k, (&strength, &reducing))| Charge {
                at: nodes[k].truncate(),
                strength,
                reducing,
            })
            .collect();
        Ok(EqualDensitySurface {
            distribution: Distribution::new(self.opts.base, charges, self.opts.de, self.opts.tau)?,
            reducing: self.opts.reducing,
            de: self.opts.de,
            connect: None,
        })
    }

    fn residual(&self, s: &EqualDensitySurface) -> f64 {
        let nodes = self.net.nodes();
        self.interior
            .iter()
            .map(|&j| {
                s.height(nodes[j].truncate())
                    .map_or(f64::INFINITY, |h| (h - nodes[j].z).abs())
            })
            .fold(0.0, f64::max)
    }
}

/// Row-scaled eq. (9)'s matrix C_jk = exp(−a_dk ρ_jk²) over the interior nodes.
fn matrix(net: &PassingPointsNet, opts: &InverseOptions, interior: &[usize]) -> Mat<f64> {
    let ad: Vec<f64> = interior
        .iter()
        .map(|&k| reducing_factor(net, k, opts.reducing, opts.a_min))
        .collect();
    let nodes = net.nodes();
    Mat::<f64>::from_fn(interior.len(), interior.len(), |j, k| {
        let (pj, pk) = (nodes[interior[j]], nodes[interior[k]]);
        (-ad[k] * (pj.truncate() - pk.truncate()).length_squared()).exp()
    })
}
