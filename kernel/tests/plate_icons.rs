//! A Kirchhoff plate built from icons only (issue 15, Tests): a flat unit
//! square whose four edges are held by edge icons (clamped: position and
//! tangent plane; simply supported: position), pulled by a load icon — a
//! region load over the whole plate (uniform) or a point load at the centre
//! — dragged through `Design`, at 8, 16, 32, 64 and 128 spans.
//!
//! Independent truths:
//! * at every grid, the same discrete system solved here by a banded
//!   Cholesky (natural order, no library; one refinement step), with the
//!   held control points found here (the outer one or two rows of control
//!   points of each edge) and the load vector from the icon's row: the
//!   kernel's centre deflection must agree to 1e-8;
//! * the plate series. With α = 0 and β11 = β12 = β22 = 1 the energy's
//!   Euler–Lagrange equation is Δ²w = f (Kirchhoff, D = 1, ν = 0; see
//!   `distributed_load.rs`). Simply supported: Navier's double series,
//!   summed here. Clamped: S. Timoshenko and S. Woinowsky-Krieger, *Theory
//!   of Plates and Shells*, 2nd ed., McGraw-Hill 1959, tables 35 and 38
//!   (square plate, centre): uniform load w = 0.00126 q a⁴/D, central point
//!   load w = 0.00560 P a²/D (3 figures). The discrete answers must approach
//!   them as the grid refines.

use glam::DVec3;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::{Anchor, Edge, IconSpec, IconState, Role, load_row, surface_row};

/// A Kirchhoff plate of unit rigidity (the rest term only keeps an
/// unconstrained surface bounded; its effect here is ~1e-7 relative).
fn plate_material() -> SurfaceMaterial {
    SurfaceMaterial {
        alpha11: 0.0,
        alpha12: 0.0,
        alpha22: 0.0,
        beta11: 1.0,
        beta12: 1.0,
        beta22: 1.0,
        rest: 1e-4,
    }
}

/// Lower-banded symmetric positive definite matrix, row-major: row i holds
/// columns i − b ..= i.
struct Banded {
    n: usize,
    b: usize,
    a: Vec<f64>,
}

impl Banded {
    fn at(&mut self, i: usize, j: usize) -> &mut f64 {
        debug_assert!(j <= i && i - j <= self.b);
        &mut self.a[i * (self.b + 1) + (j + self.b - i)]
    }

    fn get(&self, i: usize, j: usize) -> f64 {
        if j > i || i - j > self.b {
            return 0.0;
        }
        self.a[i * (self.b + 1) + (j + self.b - i)]
    }

    /// In-place Cholesky A = L Lᵀ (L in the same band).
    fn cholesky(&mut self) {
        let (n, b) = (self.n, self.b);
        let w = b + 1;
        for i in 0..n {
            let lo = i.saturating_sub(b);
            for j in lo..=i {
                // Σ_k L[i][k] L[j][k] over k in max(lo, j − b) .. j.
                let k0 = lo.max(j.saturating_sub(b));
                let mut s = 0.0;
                for k in k0..j {
                    s += self.a[i * w + (k + b - i)] * self.a[j * w + (k + b - j)];
                }
                let v = self.a[i * w + (j + b - i)] - s;
                self.a[i * w + (j + b - i)] = if i == j {
                    assert!(v > 0.0, "not positive definite at {i}");
                    v.sqrt()
                } else {
                    v / self.a[j * w + b]
                };
            }
        }
    }

    /// x = (L Lᵀ)⁻¹ r.
    fn solve(&self, r: &[f64]) -> Vec<f64> {
        let (n, b) = (self.n, self.b);
        let mut y = r.to_vec();
        for i in 0..n {
            let dot: f64 = (i.saturating_sub(b)..i)
                .map(|k| self.get(i, k) * y[k])
                .sum();
            y[i] = (y[i] - dot) / self.get(i, i);
        }
        for i in (0..n).rev() {
            let dot: f64 = (i + 1..(i + b + 1).min(n))
                .map(|k| self.get(k, i) * y[k])
                .sum();
            y[i] = (y[i] - dot) / self.get(i, i);
        }
        y
    }
}

/// K_ff x = rhs_f over the free control points (scattered back, zero at the
/// held ones), by a banded Cholesky and one step of iterative refinement
/// with the sparse K.
fn banded_free_solve(k: &Stiffness, held: &[bool], rhs: &[f64], nv: usize) -> Vec<f64> {
    let n = k.dim();
    let free: Vec<usize> = (0..n).filter(|&c| !held[c]).collect();
    let mut at = vec![usize::MAX; n];
    for (f, &c) in free.iter().enumerate() {
        at[c] = f;
    }
    // Bicubic: control points couple within 3 steps in each direction.
    let b = 3 * nv + 3;
    let m = free.len();
    let mut band = Banded {
        n: m,
        b,
        a: vec![0.0; m * (b + 1)],
    };
    let lower = k.lower();
    let (cp, ri, v) = (
        lower.symbolic().col_ptr(),
        lower.symbolic().row_idx(),
        lower.val(),
    );
    for c in 0..n {
        for e in cp[c]..cp[c + 1] {
            let r = ri[e];
            let (fr, fc) = (at[r], at[c]);
            if fr == usize::MAX || fc == usize::MAX {
                continue;
            }
            let (i, j) = if fr >= fc { (fr, fc) } else { (fc, fr) };
            *band.at(i, j) += v[e];
        }
    }
    // K_ff x with the full (symmetric) band, for the refinement step.
    let apply = |band_a: &Banded, x: &[f64]| -> Vec<f64> {
        let mut y = vec![0.0; m];
        for i in 0..m {
            for j in i.saturating_sub(b)..=i {
                let a = band_a.get(i, j);
                y[i] += a * x[j];
                if i != j {
                    y[j] += a * x[i];
                }
            }
        }
        y
    };
    let original = Banded {
        n: m,
        b,
        a: band.a.clone(),
    };
    band.cholesky();
    let r: Vec<f64> = free.iter().map(|&c| rhs[c]).collect();
    let mut x = band.solve(&r);
    let kx = apply(&original, &x);
    let residual: Vec<f64> = r.iter().zip(&kx).map(|(a, b)| a - b).collect();
    for (xi, d) in x.iter_mut().zip(band.solve(&residual)) {
        *xi += d;
    }
    let mut out = vec![0.0; n];
    for (f, &c) in free.iter().enumerate() {
        out[c] = x[f];
    }
    out
}

/// The control points an edge icon holds, found here from the grid: the
/// outer row of each edge, and the next one when clamped.
fn held_here(nu: usize, nv: usize, clamped: bool) -> Vec<bool> {
    let rows = if clamped { 2 } else { 1 };
    (0..nu * nv)
        .map(|c| {
            let (i, j) = (c / nv, c % nv);
            i < rows || j < rows || i >= nu - rows || j >= nv - rows
        })
        .collect()
}

/// Per (clamped, point): the kernel's centre deflection per unit of total
/// load and the banded solve's, on `spans` × `spans` spans.
fn deflections(spans: usize, clamped: bool) -> [(f64, f64); 2] {
    let n = spans + 3;
    let surface = BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap();
    let material = plate_material();
    let k = Stiffness::surface(surface.u_knots(), surface.v_knots(), &material).unwrap();
    let held = held_here(n, n, clamped);
    let centre = surface_row(&surface, 0.5, 0.5, 0, 0);
    let mut out = [(0.0, 0.0); 2];
    for (slot, point) in [false, true].into_iter().enumerate() {
        let mut d = Design::new(surface.clone(), material).unwrap();
        d.set_adaptive_spring(false);
        for edge in [Edge::UMin, Edge::UMax, Edge::VMin, Edge::VMax] {
            d.add_icon(IconSpec {
                anchor: Anchor::Edge { edge, clamped },
                role: Role::Position,
                state: IconState::Passive,
                target: None,
            })
            .unwrap();
        }
        let anchor = if point {
            Anchor::Point { u: 0.5, v: 0.5 }
        } else {
            Anchor::Region {
                u0: 0.0,
                v0: 0.0,
                u1: 1.0,
                v1: 1.0,
                inside: true,
            }
        };
        let load = d
            .add_icon(IconSpec {
                anchor: anchor.clone(),
                role: Role::Load,
                state: IconState::Passive,
                target: None,
            })
            .unwrap();
        d.solve().unwrap();
        let before = d.surface().clone();
        let grab = d.icon(load).unwrap().xyz;
        d.drag_start(load).unwrap();
        let pull = 1e-3;
        let r = d.drag(load, grab + DVec3::Z * pull).unwrap();
        assert_eq!(
            r.report.warning, None,
            "{spans} clamped {clamped} point {point}"
        );
        // The load's total force: κ · pull, spread by the icon's row (whose
        // weights sum to 1 for a point, to the area 1 for the plate).
        let row = load_row(&anchor, &surface);
        let total: f64 = row.weights.iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "load row total {total}");
        let force = d.spring().stiffness() * pull;
        let kernel = (centre.apply(d.surface().points()) - centre.apply(before.points())).z / force;
        // The edges did not move.
        for (c, &h) in held.iter().enumerate() {
            if h {
                let off = (d.surface().points()[c] - before.points()[c]).length();
                assert!(off <= 1e-12, "{spans}: held point {c} moved {off:e}");
            }
        }
        let mut rhs = vec![0.0; n * n];
        for (&i, &w) in row.indices.iter().zip(&row.weights) {
            rhs[i] += w;
        }
        let x = banded_free_solve(&k, &held, &rhs, n);
        let banded: f64 = centre
            .indices
            .iter()
            .zip(&centre.weights)
            .map(|(&i, &w)| w * x[i])
            .sum();
        out[slot] = (kernel, banded);
    }
    out
}

/// Navier's series for the centre of a simply supported unit square plate,
/// D = 1: uniform unit load, and unit point load at the centre.
fn navier() -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let (mut uniform, mut point) = (0.0, 0.0);
    for m in (1..4001).step_by(2) {
        for n in (1..4001).step_by(2) {
            let (m_, n_) = (m as f64, n as f64);
            let q = (m_ * m_ + n_ * n_).powi(2);
            let sign = if ((m + n) / 2 - 1) % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            uniform += sign / (m_ * n_ * q);
            point += 1.0 / q;
        }
    }
    (16.0 / pi.powi(6) * uniform, 4.0 / pi.powi(4) * point)
}

#[test]
fn a_plate_of_edge_and_load_icons_converges_to_plate_theory_at_8_to_128_spans() {
    let (ss_uniform, ss_point) = navier();
    assert!((ss_uniform - 0.00406).abs() < 5e-6, "{ss_uniform}");
    assert!((ss_point - 0.01160).abs() < 5e-6, "{ss_point}");
    for clamped in [false, true] {
        // (exact, relative tolerance at 128 spans) for uniform, point.
        let exact = if clamped {
            // The tables' 3 figures: ±0.4 % and ±0.1 %.
            [(0.00126, 5e-3), (0.00560, 3e-3)]
        } else {
            [(ss_uniform, 1e-5), (ss_point, 1e-3)]
        };
        let mut last = [f64::INFINITY; 2];
        for spans in [8, 16, 32, 64, 128] {
            let got = deflections(spans, clamped);
            for (slot, ((kernel, banded), (want, _))) in got.iter().zip(exact).enumerate() {
                let what = format!(
                    "clamped {clamped} {} spans {spans}",
                    ["uniform", "point"][slot]
                );
                assert!(
                    (kernel - banded).abs() <= 1e-8 * banded.abs(),
                    "{what}: kernel {kernel:e} banded {banded:e}"
                );
                let error = (kernel - want).abs() / want;
                eprintln!("{what}: {kernel:.7e} (plate theory {want:.5e}) rel {error:.2e}");
                // Against the series: the error falls with refinement down
                // to the floor the rest term sets (~3e-7: rest · w against
                // Δ²w ≈ 4π⁴ w).
                if !clamped {
                    assert!(
                        error < last[slot] || error < 1e-6,
                        "{what}: {error:e} after {:e}",
                        last[slot]
                    );
                }
                last[slot] = error;
            }
        }
        for (slot, (_, tol)) in exact.iter().enumerate() {
            assert!(
                last[slot] < *tol,
                "clamped {clamped} slot {slot}: {}",
                last[slot]
            );
        }
    }
}
