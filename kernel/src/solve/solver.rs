//! The constrained solver: minimises δᵀKδ − 2δ·b subject to C(P_ref + δ) = d
//! (see [`super::problem`]) by the Schur complement over a prefactored K.
//!
//! With Y = K⁻¹Cᵀ and S = C K⁻¹ Cᵀ:
//!
//! ```text
//! δ0 = K⁻¹ b,   λ = S⁺ (C δ0 + C P_ref − d),   δ = δ0 − Y λ
//! ```
//!
//! Every load and every equation is built from a [`ScalarRow`] a_c, so all
//! of K⁻¹b and Y are combinations of the columns Z = K⁻¹[a_c], cached by
//! row (and kept a while after their row leaves). A load's column is solved
//! when its row first comes; an equation row's is left pending: its
//! entries of G are taken from the existing columns (K⁻¹ is symmetric) and
//! from forward halves L⁻¹Pa kept on their elimination-tree reach (see
//! `Factor::forward_sparse`, and `Factor::forward_batch` for many rows at
//! once: a curve across 81 × 159 brings 415), with no full solve. A few
//! pending columns (at most `SOLVED_WHEN_READ`) are solved in one batch when
//! the shape next moves; with more, nothing reads Z: a solve or a drag
//! response takes δ = K̃⁻¹(Σ w_c a_c) by one solve of the combined rows
//! (see `Solver::z_is_whole`). S is
//! assembled from the small Gram matrix G = Aᵀ Z. S⁻¹ is a
//! Cholesky inverse when S is provably well conditioned, else a
//! pseudo-inverse by symmetric eigendecomposition: redundant equations
//! (eigenvalues below 1e-12 of the largest) are dropped and contradictory
//! ones get the least-squares compromise in the S-norm; the residual
//! |C P − d| is reported, never NaN.
//!
//! Pins (a vector equation on one control point) are not rows of C: the
//! factor is of K with them eliminated (see [`Stiffness::with_pinned`]),
//! their values enter as a moved reference. A change of the pinned set (a
//! region or edge icon added, removed or switched) keeps the factor of the
//! old set when the change is small and well conditioned: S over the new
//! pinned set is built through it (see `pin_update`: forward halves of the
//! changed points' columns, a small dense R, the columns kept over the old
//! factor), with no refactor and no full sparse solve, so an edit that
//! holds the shape where it is (proved by `still_optimal`) costs no
//! refactor at all. The refactor is deferred to [`Solver::settle_pins`]: a
//! host calls it when idle, and a solve that must move the shape or the
//! first frame of a grab calls it first (measured: solving through the
//! update cost more than refactoring, see kernel/README.md). When S is not
//! provably well
//! conditioned, the vector equations whose rows lie in K's pattern are
//! folded into the factor (K + Σ ρ a aᵀ, see `Folded`).
//!
//! A full solve is refined to convergence (see `refined_deltas`), and skipped when the
//! last solution still meets the new problem's optimality conditions (see
//! `still_optimal`).
//!
//! A drag frame moves one group's input t (targets and forces, see
//! [`super::problem`]); δ is affine in t, δ(t) = δ_base + R t, so the first
//! drag of a group computes R (three N-vectors of DVec3, coupled across
//! coordinates when projected equations exist) and every later frame costs
//! 3N multiply-adds: no sparse solve, no allocation.

use std::collections::{HashMap, VecDeque};
use std::sync::Arc;

use faer::Mat;
use glam::DVec3;

use super::factor::{Factor, Forward};
use super::pin_update::PinUpdate;

use super::{Equation, Group, GroupKey, Problem, ScalarRow, SolveError};
use crate::energy::Stiffness;

/// How the solver obtained its drag responses so far (see
/// [`Solver::response_counts`]): what a grab cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ResponseCounts {
    /// Responses computed (a first grab, another group grabbed, or the
    /// first grab after the problem's structure changed).
    pub computed: u64,
    /// Refinement steps taken by any solve or response (each a projection
    /// and, when the stationarity residual asks, a batched sparse solve).
    pub refinement_steps: u64,
}

/// What a solve achieved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveReport {
    /// max |C P − d| over all scalar equations (0 when there are none).
    pub constraint_residual: f64,
    /// How many scalar equations were redundant or contradictory (dropped
    /// eigen-directions of S).
    pub rank_deficiency: usize,
    /// The number of scalar equations.
    pub equations: usize,
    /// Set when the answer does not meet every equation: see [`SolveWarning`].
    pub warning: Option<SolveWarning>,
}

/// Why an `Ok` answer does not meet every equation to tolerance
/// ([`RESIDUAL_TOLERANCE`] of the shape's size).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolveWarning {
    /// The equations are dependent to working precision (S numerically
    /// singular: `dropped` eigen-directions below 1e-12 of the largest, or a
    /// control point pinned more than once) and their targets disagree: the
    /// answer is the least-squares compromise and `residual` is
    /// max |C P − d|. Genuinely contradictory constraints (the same point
    /// held at two places) end here.
    Dependent {
        /// Dropped eigen-directions of S.
        dropped: usize,
        /// max |C P − d|.
        residual: f64,
    },
}

/// A solve whose equations are independent (nothing dropped) must meet each
/// to this fraction of the shape's size (max(|P|, |d|, 1), or the size of
/// the loads' unconstrained pull ‖K⁻¹b‖ when larger: the answer cancels
/// against it); otherwise it is [`SolveError::Inexact`], never `Ok`.
pub const RESIDUAL_TOLERANCE: f64 = 1e-9;

/// One term α · (a_col applied to coordinate k).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Term {
    k: usize,
    col: usize,
    coef: f64,
}

/// One scalar equation.
#[derive(Clone, Debug)]
struct ScalarEq {
    terms: Vec<Term>,
    target: f64,
    group: usize,
    /// The coordinate of the drag input that shifts this equation's target.
    shift: Option<usize>,
}

/// A vector equation on one control point: `weight · P[index] = target`.
#[derive(Clone, Debug)]
struct PinEq {
    index: usize,
    weight: f64,
    target: DVec3,
    group: usize,
}

/// A vector equation's row folded into the factor: K̃ = K + ρ a aᵀ. The
/// term ρ (a·δ − r)² it stands for is zero wherever the equation holds, so
/// it changes no answer, only the multipliers (λ = μ + ρ a·δ); but it lifts
/// the directions of S = C K̃⁻¹ Cᵀ that the soft modes of K (a small `rest`,
/// the affine modes) made huge, so S stays well conditioned however many
/// equations there are (S̃ = (S⁻¹ + ρ)⁻¹ for one row).
#[derive(Clone, Debug, PartialEq)]
struct Folded {
    row: ScalarRow,
    rho: f64,
}

impl Folded {
    /// ρ = the mean diagonal of K over the row's points / |a|²: a penalty
    /// as stiff as the surface there.
    fn new(row: &ScalarRow, k: &Stiffness) -> Self {
        let diag: f64 = row.indices.iter().map(|&i| k.diagonal(i)).sum::<f64>()
            / row.indices.len().max(1) as f64;
        let norm2: f64 = row.weights.iter().map(|w| w * w).sum();
        Self {
            row: row.clone(),
            rho: if norm2 > 0.0 { diag / norm2 } else { 0.0 },
        }
    }
}

fn same_folds(a: &[Folded], b: &[Folded]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.row == y.row)
}

/// K + Σ ρ a aᵀ over `folded` (whose rows lie in K's pattern).
fn fold(k: &Stiffness, folded: &[Folded]) -> Stiffness {
    let mut out = k.clone();
    for f in folded {
        out.add_outer(&f.row.indices, &f.row.weights, f.rho);
    }
    out
}

/// A pinned control point and its equations (`pins[eqs]`). Pinned more
/// than once, it takes the least-squares value Σ w d / Σ w².
#[derive(Clone, Debug)]
struct PinPoint {
    index: usize,
    eqs: std::ops::Range<usize>,
}

#[derive(Clone, Debug)]
struct LoadCol {
    col: usize,
    force: DVec3,
    gain: f64,
    group: usize,
}

/// Bit-exact key of a row, for caching its column of Z.
type RowKey = (Vec<usize>, Vec<u64>);

fn row_key(r: &ScalarRow) -> RowKey {
    (
        r.indices.clone(),
        r.weights.iter().map(|w| w.to_bits()).collect(),
    )
}

/// The cached response of one group to its drag input.
#[derive(Debug)]
struct Response {
    /// The dragged group's key.
    key: GroupKey,
    kind: ResponseKind,
}

/// δ(t) − δ(0) = R t. Without projected equations every coordinate answers
/// alone and alike, so R = ρ ⊗ I with one scalar field ρ: a third of the
/// memory traffic per frame.
#[derive(Debug)]
enum ResponseKind {
    Uniform(Vec<f64>),
    Coupled([Vec<DVec3>; 3]),
}

impl ResponseKind {
    fn new(r: [Vec<DVec3>; 3]) -> Self {
        let scale = r
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
        let tol = 1e-12 * scale.max(1e-300);
        let uniform = (0..r[0].len()).all(|i| {
            let (a, b, c) = (r[0][i], r[1][i], r[2][i]);
            a.y.abs() <= tol
                && a.z.abs() <= tol
                && b.x.abs() <= tol
                && b.z.abs() <= tol
                && c.x.abs() <= tol
                && c.y.abs() <= tol
                && (a.x - b.y).abs() <= tol
                && (a.x - c.z).abs() <= tol
        });
        if uniform {
            ResponseKind::Uniform(r[0].iter().map(|v| v.x).collect())
        } else {
            ResponseKind::Coupled(r)
        }
    }
}

/// The solution with every drag input at zero, for one reference shape.
#[derive(Debug)]
struct Base {
    reference: Vec<DVec3>,
    /// reference + δ(0).
    start: Vec<DVec3>,
}

/// The largest coordinate magnitude of a shape (at least 1).
fn max_extent(points: &[DVec3]) -> f64 {
    points
        .iter()
        .fold(1.0f64, |m, p| m.max(p.abs().max_element()))
}

/// One column z = K⁻¹a of Z, shared between problems, and ‖z‖∞.
#[derive(Clone, Debug)]
struct Column {
    values: Arc<[f64]>,
    norm: f64,
}

impl Column {
    fn new(values: &[f64]) -> Self {
        Self {
            norm: values.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            values: values.into(),
        }
    }

    /// A column not solved yet (see [`Solver::pending`]): no values.
    fn pending() -> Self {
        Self {
            values: Arc::from(Vec::new()),
            norm: f64::NAN,
        }
    }

    /// Whether the column is not solved yet.
    fn is_pending(&self) -> bool {
        self.norm.is_nan()
    }
}

/// |w| ‖z‖∞ per coordinate: how far weight `w` on column `col` reaches the
/// shape. A pending column's norm is not known: any non-zero weight on it
/// reaches without bound (the conservative answer: refine, count as
/// pulling).
fn column_reach(w: DVec3, col: &Column) -> DVec3 {
    if col.is_pending() {
        DVec3::select(w.cmpeq(DVec3::ZERO), DVec3::ZERO, DVec3::INFINITY)
    } else {
        w.abs() * col.norm
    }
}

/// The last full solve, for [`Solver::still_optimal`].
#[derive(Debug)]
struct LastSolve {
    reference: Vec<DVec3>,
    out: Vec<DVec3>,
    problem: Problem,
    /// Per group: Σ |λ_e| · ‖K⁻¹ a_e‖∞, how far its multipliers move the shape.
    pull: HashMap<GroupKey, f64>,
}

/// Solves the problem icons hand it, fast enough for drag frames.
#[derive(Debug)]
pub struct Solver {
    /// The stiffness K the energy is measured with.
    stiffness: Stiffness,
    /// K with the pinned control points eliminated (see
    /// [`Stiffness::with_pinned`]), factored.
    factor: Factor,
    /// The pinned control points of the problem: eliminated from the
    /// unknowns (by the factor, or by `update`).
    pinned: Vec<bool>,
    /// Which control points `factor` has eliminated.
    factored: Vec<bool>,
    /// When `pinned` differs from `factored`: the change held over the
    /// factor of `factored`, its refactor deferred (see [`PinUpdate`],
    /// [`Self::settle_pins`]).
    update: Option<PinUpdate>,
    /// Whether a problem was set since the factor was made (see
    /// [`Self::repin`]).
    served: bool,
    /// Equations folded into the factor (see [`Folded`]).
    folded: Vec<Folded>,
    /// K + Σ ρ a aᵀ over `folded`: the matrix the factor eliminates the
    /// pins from, and the one residuals are measured with.
    augmented: Stiffness,
    /// The pin equations of the problem, sorted by control point.
    pins: Vec<PinEq>,
    /// The pinned control points: index and the range of their equations
    /// in `pins`.
    pin_points: Vec<PinPoint>,
    /// Redundant pin equations (a point pinned more than once), ×3.
    pin_redundant: usize,
    problem: Problem,
    /// The rows of the equations that are not pins and of the loads, whole.
    rows: Vec<ScalarRow>,
    /// The same rows without their pinned control points: what Z is made of.
    free_rows: Vec<ScalarRow>,
    /// Z = K⁻¹[a_c], one column per row. Columns are shared, not copied,
    /// when a new problem keeps a row: a constraint change costs only the
    /// new rows' solves.
    z: Vec<Column>,
    /// Columns of rows that left the problem, kept for when they come back
    /// (an icon switched off and on again, an undo): oldest first, at most
    /// [`RETIRED_BYTES`] of them. Valid until the stiffness changes.
    retired: VecDeque<(RowKey, Column)>,
    /// Columns of Z not solved yet (placeholders in `z`): new equation rows
    /// whose entries of G came from existing columns and forward halves.
    /// A few (see [`SOLVED_WHEN_READ`]) are solved in one batch by
    /// [`Self::solve_pending`] before anything reads them; more stay
    /// pending (see [`Self::z_is_whole`]): a new icon, even a curve's
    /// hundreds of rows, costs no full sparse solve.
    pending: Vec<usize>,
    /// The forward halves L⁻¹Pa of the pending columns' rows (from the
    /// Gram's forward solves): a pending column costs only the backward half.
    pending_forward: Vec<Forward>,
    g: Vec<f64>,
    eqs: Vec<ScalarEq>,
    loads: Vec<LoadCol>,
    s_pinv: Vec<f64>,
    /// Whether `s_pinv` is S's exact inverse (the Cholesky path or a
    /// checked block update of it), not a pseudo-inverse.
    s_exact: bool,
    rank_deficiency: usize,
    base: Option<Base>,
    response: Option<Response>,
    last: Option<LastSolve>,
    counts: ResponseCounts,
    /// Solve every new row's column of Z in full at a problem change (the
    /// path before issue 15), see [`Solver::set_eager_columns`].
    eager_columns: bool,
}

impl Solver {
    /// Factors `stiffness` (symbolic and numeric); the problem starts empty.
    pub fn new(stiffness: Stiffness) -> Result<Self, SolveError> {
        let factor = Factor::new(stiffness.clone())?;
        Ok(Self {
            pinned: vec![false; stiffness.dim()],
            factored: vec![false; stiffness.dim()],
            update: None,
            served: false,
            folded: Vec::new(),
            augmented: stiffness.clone(),
            stiffness,
            factor,
            pins: Vec::new(),
            pin_points: Vec::new(),
            pin_redundant: 0,
            problem: Problem::default(),
            rows: Vec::new(),
            free_rows: Vec::new(),
            z: Vec::new(),
            retired: VecDeque::new(),
            pending: Vec::new(),
            pending_forward: Vec::new(),
            g: Vec::new(),
            eqs: Vec::new(),
            loads: Vec::new(),
            s_pinv: Vec::new(),
            s_exact: false,
            rank_deficiency: 0,
            base: None,
            response: None,
            last: None,
            counts: ResponseCounts::default(),
            eager_columns: false,
        })
    }

    /// Whether a problem change solves every new row's column of Z = K̃⁻¹Cᵀ
    /// in full (`true`: the path before issue 15, one full sparse solve
    /// per row) instead of leaving equation rows pending with their block
    /// of G from forward halves (`false`, the default). A reference for
    /// tests that compare the two; it applies from the next problem change.
    #[doc(hidden)]
    pub fn set_eager_columns(&mut self, eager: bool) {
        self.eager_columns = eager;
    }

    /// The number of control points.
    pub fn dim(&self) -> usize {
        self.factor.dim()
    }

    /// How many right-hand sides the factor has solved for so far (new
    /// constraint columns, refinement steps): what a problem change cost.
    pub fn columns_solved(&self) -> u64 {
        self.factor.columns_solved()
    }

    /// How many drag responses were computed so far and how many
    /// refinement steps every solve took: a diagnostic, as
    /// [`Self::columns_solved`].
    pub fn response_counts(&self) -> ResponseCounts {
        self.counts
    }

    /// The stiffness K (the factor holds K with the pinned control points
    /// eliminated).
    pub fn stiffness(&self) -> &Stiffness {
        &self.stiffness
    }

    /// Refactors for a new stiffness (numeric only when the pattern is
    /// unchanged) and recomputes the problem's columns. On error nothing changes.
    pub fn refactor(&mut self, stiffness: Stiffness) -> Result<(), SolveError> {
        if stiffness.dim() != self.dim() {
            let mut fresh = Solver::new(stiffness)?;
            fresh.set_problem(self.problem.clone())?;
            *self = fresh;
            return Ok(());
        }
        // Factor::refactor keeps the old factor when it fails.
        let old = std::mem::replace(&mut self.stiffness, stiffness);
        let old_folded = self.folded.clone();
        let folded: Vec<Folded> = old_folded
            .iter()
            .map(|f| Folded::new(&f.row, &self.stiffness))
            .collect();
        if let Err(e) = self.rebuild_factor(self.pinned.clone(), folded) {
            self.stiffness = old;
            return Err(e);
        }
        let problem = std::mem::take(&mut self.problem);
        if let Err(e) = self.set_problem(problem.clone()) {
            // Only reachable if the problem was valid before and S fails now:
            // go back to the old stiffness so nothing changes.
            self.stiffness = old;
            self.rebuild_factor(self.pinned.clone(), old_folded)?;
            self.set_problem(problem)?;
            return Err(e);
        }
        Ok(())
    }

    /// Drops every cached column of Z (they belong to the old factor).
    fn forget_columns(&mut self) {
        self.clear_rows();
        self.retired.clear();
    }

    /// Drops the rows of the current problem and what was computed from
    /// them (columns of Z, pending rows and their forward halves, the drag
    /// response); the retired columns stay.
    fn clear_rows(&mut self) {
        self.rows.clear();
        self.free_rows.clear();
        self.z.clear();
        self.pending.clear();
        self.pending_forward.clear();
        self.response = None;
    }

    /// Takes the pinned set `pinned` over the current factor (see
    /// [`PinUpdate`]) instead of refactoring: `false` (nothing changed) when
    /// that is not possible or would cost more than the refactor. The
    /// columns of the factor's own operator are kept (`retired`) for when
    /// the pinned set goes back to the factor's (free) or for the update's
    /// Gram entries.
    fn repin(&mut self, pinned: &[bool]) -> bool {
        if !self.served {
            // A fresh solver's first pins: its factor has served nothing
            // yet, so the refactor is the lasting choice.
            return false;
        }
        let update = if pinned == self.factored.as_slice() {
            None
        } else {
            match PinUpdate::new(&self.factor, &self.augmented, &self.factored, pinned) {
                Some(u) => Some(u),
                None => return false,
            }
        };
        if self.update.is_none() {
            // The current columns are the factor's own: keep them.
            let all: Vec<Column> = Vec::new();
            self.retire(&all);
        }
        self.clear_rows();
        self.g.clear();
        self.s_exact = false;
        self.update = update;
        self.pinned = pinned.to_vec();
        true
    }

    /// Whether a change of the pinned set is held over the factor of an
    /// earlier set, its refactor deferred (see [`Self::settle_pins`]).
    pub fn pins_pending(&self) -> bool {
        self.update.is_some()
    }

    /// Refactors for the current pinned set when a change of it is held
    /// over the factor of an earlier one (a numeric refactorisation and the
    /// problem's columns: the cost a pin change deferred). [`Self::solve`]
    /// (when the shape must move) and [`Self::drag`] call it first; a host
    /// may call it when idle so that neither pays. `Ok(false)` when nothing
    /// was pending. On error nothing changes.
    pub fn settle_pins(&mut self) -> Result<bool, SolveError> {
        if self.update.is_none() {
            return Ok(false);
        }
        let pinned = self.pinned.clone();
        let folded = self.folded.clone();
        let old_factored = self.factored.clone();
        // The same K and problem: the last answer stays the proof of
        // `still_optimal` (a refactor forgets it).
        let last = self.last.take();
        self.rebuild_factor(pinned, folded)?;
        self.last = last;
        let problem = std::mem::take(&mut self.problem);
        if let Err(e) = self.set_problem(problem.clone()) {
            // Back to the earlier factor and the update over it.
            let folded = self.folded.clone();
            let pinned = self.pinned.clone();
            self.rebuild_factor(old_factored, folded)?;
            self.repin(&pinned);
            self.set_problem(problem)?;
            return Err(e);
        }
        Ok(true)
    }

    /// The current problem.
    pub fn problem(&self) -> &Problem {
        &self.problem
    }

    /// Takes a new problem: validates it, reuses the columns of rows seen
    /// before, solves for the new ones in one batch, assembles S and its
    /// pseudo-inverse. On error nothing changes.
    pub fn set_problem(&mut self, problem: Problem) -> Result<(), SolveError> {
        let n = self.dim();
        validate(&problem, n)?;
        if self.same_structure(&problem) {
            // Only targets and forces changed: keep everything else.
            self.take_targets(problem);
            return Ok(());
        }
        // Pins: a vector equation on one control point fixes it. They are
        // eliminated from the unknowns (the factor is of K_ff), not
        // answered through S: any number of them, exactly.
        let mut pins: Vec<PinEq> = Vec::new();
        for (gi, group) in problem.groups.iter().enumerate() {
            for eq in &group.equations {
                if let Equation::Vector { row, target } = eq
                    && let ([index], [weight]) = (row.indices.as_slice(), row.weights.as_slice())
                    && *weight != 0.0
                {
                    pins.push(PinEq {
                        index: *index,
                        weight: *weight,
                        target: *target,
                        group: gi,
                    });
                }
            }
        }
        pins.sort_by_key(|p| p.index);
        let mut pin_points: Vec<PinPoint> = Vec::new();
        for (e, p) in pins.iter().enumerate() {
            match pin_points.last_mut() {
                Some(last) if last.index == p.index => last.eqs.end = e + 1,
                _ => pin_points.push(PinPoint {
                    index: p.index,
                    eqs: e..e + 1,
                }),
            }
        }
        let pin_redundant = 3 * (pins.len() - pin_points.len());
        let mut pinned = vec![false; n];
        for p in &pin_points {
            pinned[p.index] = true;
        }
        let is_pin = |eq: &Equation| matches!(eq, Equation::Vector { row, .. } if is_pin_row(row));
        // Columns: one per equation row and per load row, deduplicated.
        let mut rows: Vec<ScalarRow> = Vec::new();
        let mut index: HashMap<RowKey, usize> = HashMap::new();
        let mut col_of = |r: &ScalarRow, rows: &mut Vec<ScalarRow>| -> usize {
            *index.entry(row_key(r)).or_insert_with(|| {
                rows.push(r.clone());
                rows.len() - 1
            })
        };
        let mut eqs = Vec::new();
        let mut loads = Vec::new();
        for (gi, group) in problem.groups.iter().enumerate() {
            for eq in group.equations.iter().filter(|eq| !is_pin(eq)) {
                match eq {
                    Equation::Vector { row, target } => {
                        let col = col_of(row, &mut rows);
                        for k in 0..3 {
                            eqs.push(ScalarEq {
                                terms: vec![Term { k, col, coef: 1.0 }],
                                target: target[k],
                                group: gi,
                                shift: Some(k),
                            });
                        }
                    }
                    Equation::Projected {
                        row,
                        direction,
                        target,
                    } => {
                        let col = col_of(row, &mut rows);
                        eqs.push(ScalarEq {
                            terms: (0..3)
                                .filter(|&k| direction[k] != 0.0)
                                .map(|k| Term {
                                    k,
                                    col,
                                    coef: direction[k],
                                })
                                .collect(),
                            target: *target,
                            group: gi,
                            shift: None,
                        });
                    }
                }
            }
            for load in &group.loads {
                let col = col_of(&load.row, &mut rows);
                loads.push(LoadCol {
                    col,
                    force: load.force,
                    gain: load.drag_gain,
                    group: gi,
                });
            }
        }
        let free_rows: Vec<ScalarRow> = rows
            .iter()
            .map(|r| {
                let (indices, weights) = r
                    .indices
                    .iter()
                    .zip(&r.weights)
                    .filter(|(i, _)| !pinned[**i])
                    .map(|(i, w)| (*i, *w))
                    .unzip();
                ScalarRow { indices, weights }
            })
            .collect();
        // Equations whose rows lie in K's pattern can be folded into the
        // factor (see `fold`): the ones that are neither pins nor projected.
        let foldable: Vec<Folded> = {
            let mut seen = std::collections::HashSet::new();
            eqs.iter()
                .filter(|e| e.shift.is_some())
                .filter_map(|e| {
                    let col = e.terms[0].col;
                    let row = &free_rows[col];
                    (seen.insert(col) && !row.indices.is_empty() && self.stiffness.holds(row))
                        .then(|| Folded::new(row, &self.stiffness))
                })
                .collect()
        };
        let old = (self.pinned.clone(), self.folded.clone());
        // Keep the folded set while every folded row is still an equation
        // (a new point icon, a switched one: no refactor); refold when one
        // left, or when S asks for it below.
        let still_folded = {
            let keys: std::collections::HashSet<RowKey> =
                foldable.iter().map(|f| row_key(&f.row)).collect();
            self.folded.iter().all(|f| keys.contains(&row_key(&f.row)))
        };
        let mut fold = if self.folded.is_empty() {
            Vec::new()
        } else if still_folded {
            self.folded.clone()
        } else {
            foldable.clone()
        };
        let mut refactored = false;
        let (z, pending, forward, g, s_pinv, rank_deficiency, s_exact) = loop {
            if same_folds(&fold, &self.folded) && pinned != self.pinned && self.repin(&pinned) {
                refactored = true;
            } else if pinned != self.pinned || !same_folds(&fold, &self.folded) {
                if let Err(e) = self.rebuild_factor(pinned.clone(), fold.clone()) {
                    if refactored {
                        self.restore_factor(old);
                    }
                    return Err(e);
                }
                refactored = true;
            }
            let (z, pending, forward, g, s) = if self.update.is_some() {
                self.schur_updated(&rows, &free_rows, &eqs)
            } else {
                self.schur(&rows, &free_rows, &eqs, &loads)
            };
            // Same factor: S⁻¹ by block updates of the current one when
            // they are exact enough, else from scratch.
            let updated = if refactored {
                None
            } else {
                self.updated_inverse(&rows, &eqs, &s)
            };
            // When S is not provably well conditioned the equations are
            // folded and S formed again: the eigendecomposition of this S
            // would be thrown away (on 81 × 159 a curve's 1245 equations
            // cost ~50 ms of it), so only the Cholesky path is tried.
            let may_fold = !same_folds(&fold, &foldable);
            let inverse =
                match updated {
                    Some(kept) => Ok(kept),
                    None if may_fold => Ok(cholesky_inverse(&s)
                        .map_or_else(|| (Vec::new(), 0, false), |p| (p, 0, true))),
                    None => pseudo_inverse(&s),
                };
            match inverse {
                Ok((_, _, false)) if !same_folds(&fold, &foldable) => {
                    // S is ill-conditioned over K: fold the equations into
                    // the factor and try again.
                    fold = foldable.clone();
                }
                Ok((p, dropped, exact)) => break (z, pending, forward, g, p, dropped, exact),
                Err(e) => {
                    if refactored {
                        self.restore_factor(old);
                    }
                    return Err(e);
                }
            }
        };
        // A drag response depends on the equations' and loads' structure
        // (rows, columns, gains, pins), not on their targets and forces: a
        // new problem of the same structure (a drag started, a load's spring
        // re-attached) keeps it.
        let same_structure = !refactored
            && self.eqs.len() == eqs.len()
            && self.loads.len() == loads.len()
            && self.pins.len() == pins.len()
            && self
                .pins
                .iter()
                .zip(&pins)
                .all(|(a, b)| a.index == b.index && a.weight == b.weight && a.group == b.group)
            && self
                .eqs
                .iter()
                .zip(&eqs)
                .all(|(a, b)| a.terms == b.terms && a.group == b.group && a.shift == b.shift)
            && self
                .loads
                .iter()
                .zip(&loads)
                .all(|(a, b)| a.col == b.col && a.gain == b.gain && a.group == b.group)
            && self.z.len() == z.len()
            && self
                .z
                .iter()
                .zip(&z)
                .all(|(a, b)| Arc::ptr_eq(&a.values, &b.values));
        let response = self.response.take().filter(|_| same_structure);
        if self.update.is_none() {
            // Columns of an update's operator are not the factor's own.
            self.retire(&z);
        }
        self.problem = problem;
        self.rows = rows;
        self.free_rows = free_rows;
        self.z = z;
        self.pending = pending;
        self.pending_forward = forward;
        self.g = g;
        self.eqs = eqs;
        self.loads = loads;
        self.s_pinv = s_pinv;
        self.s_exact = s_exact;
        self.rank_deficiency = rank_deficiency + pin_redundant;
        self.pinned = pinned;
        self.pins = pins;
        self.pin_points = pin_points;
        self.pin_redundant = pin_redundant;
        self.base = None;
        self.response = response;
        self.served = true;
        Ok(())
    }

    /// The current rows by key (their columns of Z and G) and which of
    /// them are still pending: what a problem change can keep.
    fn cached_rows(&self) -> (HashMap<RowKey, usize>, Vec<bool>) {
        let old = self
            .rows
            .iter()
            .enumerate()
            .map(|(c, r)| (row_key(r), c))
            .collect();
        let mut was_pending = vec![false; self.z.len()];
        for &c in &self.pending {
            was_pending[c] = true;
        }
        (old, was_pending)
    }

    /// Z = K̃⁻¹[free rows] (cached columns reused, the rest in one batched
    /// solve), G = Aᵀ Z and S over the scalar equations. A few new rows
    /// that are only equations (no load) are left pending (returned) when
    /// the factor gives their block of G by forward solves: their entries
    /// against solved columns are a_newᵀ z_c (K⁻¹ is symmetric). Rows
    /// still pending keep their forward halves, and G's entries between
    /// rows the current problem has too are copied, not recomputed.
    fn schur(
        &mut self,
        rows: &[ScalarRow],
        free_rows: &[ScalarRow],
        eqs: &[ScalarEq],
        loads: &[LoadCol],
    ) -> Schur {
        let n = self.dim();
        // Z: reuse cached columns, solve for the rest in one batch.
        let (old, was_pending) = self.cached_rows();
        let mut z: Vec<Option<Column>> = rows
            .iter()
            .map(|r| {
                let key = row_key(r);
                match old.get(&key) {
                    Some(&oc) if was_pending[oc] => None,
                    Some(&oc) => Some(self.z[oc].clone()),
                    None => self
                        .retired
                        .iter()
                        .find(|(k, _)| *k == key)
                        .map(|(_, col)| col.clone()),
                }
            })
            .collect();
        let missing: Vec<usize> = (0..rows.len()).filter(|&c| z[c].is_none()).collect();
        let mut is_load = vec![false; rows.len()];
        for l in loads {
            is_load[l.col] = true;
        }
        // The forward halves of rows still pending are kept (same factor:
        // a refactor forgets the pending columns); only new rows need one.
        let carried: HashMap<usize, &Forward> = if self.pending_forward.len() == self.pending.len()
        {
            self.pending
                .iter()
                .copied()
                .zip(&self.pending_forward)
                .collect()
        } else {
            HashMap::new()
        };
        let carried_of = |c: usize| {
            old.get(&row_key(&rows[c]))
                .and_then(|oc| carried.get(oc).copied())
        };
        // New equation rows are left pending (their block of G from forward
        // halves on the elimination-tree reach: no full solve, however many
        // — a curve across the plate brings hundreds); loads are solved.
        let lazy: Vec<usize> = if self.eager_columns {
            Vec::new()
        } else {
            missing.iter().copied().filter(|&c| !is_load[c]).collect()
        };
        let row_of = |c: usize| {
            (
                free_rows[c].indices.as_slice(),
                free_rows[c].weights.as_slice(),
            )
        };
        let kept: Vec<Option<&Forward>> = lazy.iter().map(|&c| carried_of(c)).collect();
        let fresh = kept.iter().filter(|k| k.is_none()).count();
        let batch: Option<(Vec<Forward>, Vec<f64>)> = if lazy.is_empty() {
            None
        } else if fresh > LAZY_COLUMNS {
            // Many rows (a curve): all of them in one blocked pass, their
            // Gram matrix with it.
            let columns: Vec<(&[usize], &[f64])> = lazy.iter().map(|&c| row_of(c)).collect();
            self.factor.forward_batch(&columns)
        } else {
            let columns: Vec<(&[usize], &[f64])> = lazy
                .iter()
                .zip(&kept)
                .filter(|(_, k)| k.is_none())
                .map(|(&c, _)| row_of(c))
                .collect();
            // Entries between carried rows come from the current G (see
            // below) when it is whole: only pairs with a fresh row are
            // needed then.
            let old_g = self.g.len() == self.rows.len() * self.rows.len();
            self.factor.forward_sparse(&columns).map(|fresh| {
                let mut fresh = fresh.into_iter();
                let forward: Vec<Forward> = kept
                    .iter()
                    .filter_map(|k| k.map_or_else(|| fresh.next(), |f| Some(f.clone())))
                    .collect();
                let gram = if old_g {
                    let l = forward.len();
                    let mut gram = vec![0.0; l * l];
                    for i in 0..l {
                        for j in i..l {
                            if kept[i].is_none() || kept[j].is_none() {
                                let v = forward[i].dot(&forward[j]);
                                gram[i * l + j] = v;
                                gram[j * l + i] = v;
                            }
                        }
                    }
                    gram
                } else {
                    self.factor.gram_of(&forward)
                };
                (forward, gram)
            })
        };
        let (forward, gram) = match batch {
            Some((f, g)) => (Some(f), Some(g)),
            None => (None, None),
        };
        let pending = if gram.is_some() {
            for &c in &lazy {
                z[c] = Some(Column::pending());
            }
            lazy
        } else {
            Vec::new()
        };
        let solve_now: Vec<usize> = missing
            .iter()
            .copied()
            .filter(|&c| z[c].is_none())
            .collect();
        if !solve_now.is_empty() {
            let mut rhs = Mat::<f64>::zeros(n, solve_now.len());
            for (m, &c) in solve_now.iter().enumerate() {
                for (&i, &w) in free_rows[c].indices.iter().zip(&free_rows[c].weights) {
                    rhs[(i, m)] += w;
                }
            }
            self.factor.solve_in_place(rhs.as_mut());
            for (m, &c) in solve_now.iter().enumerate() {
                z[c] = Some(Column::new(rhs.col_as_slice(m)));
            }
        }
        let z: Vec<Column> = z.into_iter().flatten().collect();
        debug_assert_eq!(z.len(), rows.len());
        // G = Aᵀ Z (Z is zero at the pinned points: the free rows suffice).
        let nc = rows.len();
        let mut is_pending = vec![false; nc];
        for &c in &pending {
            is_pending[c] = true;
        }
        let dot = |row: &ScalarRow, col: &Column| -> f64 {
            row.indices
                .iter()
                .zip(&row.weights)
                .map(|(&i, &w)| w * col.values[i])
                .sum()
        };
        // Entries between rows the current problem has too are kept (the
        // same rows and columns: the same numbers, so S over kept
        // equations is the current one entry for entry).
        let nc_old = self.rows.len();
        let old_of: Vec<Option<usize>> = if self.g.len() == nc_old * nc_old {
            rows.iter().map(|r| old.get(&row_key(r)).copied()).collect()
        } else {
            vec![None; nc]
        };
        let mut g = vec![0.0; nc * nc];
        for a in 0..nc {
            for b in 0..nc {
                g[a * nc + b] = match (old_of[a], old_of[b], is_pending[a], is_pending[b]) {
                    (Some(oa), Some(ob), _, _) => self.g[oa * nc_old + ob],
                    (_, _, _, false) => dot(&free_rows[a], &z[b]),
                    (_, _, false, true) => dot(&free_rows[b], &z[a]),
                    (_, _, true, true) => 0.0,
                };
            }
        }
        if let Some(gram) = gram {
            let k = pending.len();
            for (i, &a) in pending.iter().enumerate() {
                for (j, &b) in pending.iter().enumerate() {
                    if old_of[a].is_none() || old_of[b].is_none() {
                        g[a * nc + b] = gram[i * k + j];
                    }
                }
            }
        }
        let s = assemble_s(eqs, &g, nc);
        (z, pending, forward.unwrap_or_default(), g, s)
    }

    /// [`Self::schur`] while a pinned-set change is answered through the
    /// factor of the old set ([`PinUpdate`]): Z = A₁⁻¹[free rows] with
    /// A₁ = K̃ with the current pins eliminated. Columns already solved for
    /// this update are kept; the others are left pending, their entries of
    /// G from Gᵢⱼ = a₀ᵢᵀ Ã⁻¹ a₀ⱼ + αᵢᵀ R⁻¹ αⱼ (see `pin_update`): the first
    /// term from the row's column over the factor when one is at hand (kept
    /// from before the change: a dot product) or from forward halves, α
    /// from the same. No full sparse solve.
    fn schur_updated(
        &mut self,
        rows: &[ScalarRow],
        free_rows: &[ScalarRow],
        eqs: &[ScalarEq],
    ) -> Schur {
        let Some(update) = self.update.as_ref() else {
            unreachable!("schur_updated without an update");
        };
        let (old, was_pending) = self.cached_rows();
        let mut z: Vec<Column> = rows
            .iter()
            .map(|r| match old.get(&row_key(r)) {
                Some(&oc) if !was_pending[oc] => self.z[oc].clone(),
                _ => Column::pending(),
            })
            .collect();
        let missing: Vec<usize> = (0..rows.len()).filter(|&c| z[c].is_pending()).collect();
        // Per missing row: a₀ (its free part over the factor's free
        // points), b_F, and its base column Ã⁻¹a₀ when kept (a row that
        // touches no newly pinned point: its part over the factor's free
        // points is a₀).
        let parts: Vec<(SparseRhs, Vec<f64>, Option<Column>)> = missing
            .iter()
            .map(|&c| {
                let (rest, b_f) = update.split_sparse(&free_rows[c].indices, &free_rows[c].weights);
                let base = if update.touches_newly(&rows[c].indices) {
                    None
                } else {
                    let key = row_key(&rows[c]);
                    self.retired
                        .iter()
                        .find(|(k, _)| *k == key)
                        .map(|(_, col)| col.clone())
                };
                (rest, b_f, base)
            })
            .collect();
        let need: Vec<(&[usize], &[f64])> = parts
            .iter()
            .filter(|p| p.2.is_none())
            .map(|p| (p.0.0.as_slice(), p.0.1.as_slice()))
            .collect();
        let mut fresh = self
            .factor
            .forward_sparse(&need)
            .unwrap_or_default()
            .into_iter();
        let forward: Vec<Option<Forward>> = parts
            .iter()
            .map(|p| if p.2.is_none() { fresh.next() } else { None })
            .collect();
        let xis: Vec<(Vec<f64>, Vec<f64>)> = parts
            .iter()
            .zip(&forward)
            .map(|((_, b_f, base), f)| {
                let alpha = match (base, f) {
                    (Some(col), _) => update.alpha_of_column(&col.values, b_f),
                    (None, Some(f)) => update.alpha_of_forward(f, b_f),
                    (None, None) => vec![0.0; b_f.len()],
                };
                let xi = update.xi(&alpha);
                (alpha, xi)
            })
            .collect();
        let nc = rows.len();
        let mut at = vec![usize::MAX; nc];
        for (m, &c) in missing.iter().enumerate() {
            at[c] = m;
        }
        let sparse_dot = |(i, w): &SparseRhs, x: &[f64]| -> f64 {
            i.iter().zip(w).map(|(&i, &w)| w * x[i]).sum()
        };
        let dot = |row: &ScalarRow, col: &Column| -> f64 {
            row.indices
                .iter()
                .zip(&row.weights)
                .map(|(&i, &w)| w * col.values[i])
                .sum()
        };
        let mut g = vec![0.0; nc * nc];
        for a in 0..nc {
            for b in a..nc {
                let v = match (at[a], at[b]) {
                    (usize::MAX, _) => dot(&free_rows[b], &z[a]),
                    (_, usize::MAX) => dot(&free_rows[a], &z[b]),
                    (i, j) => {
                        let first = match (&parts[i].2, &parts[j].2, &forward[i], &forward[j]) {
                            (_, Some(zb), _, _) => sparse_dot(&parts[i].0, &zb.values),
                            (Some(za), _, _, _) => sparse_dot(&parts[j].0, &za.values),
                            (_, _, Some(fa), Some(fb)) => fa.dot(fb),
                            _ => 0.0,
                        };
                        let cross: f64 = xis[i].0.iter().zip(&xis[j].1).map(|(x, y)| x * y).sum();
                        first + cross
                    }
                };
                g[a * nc + b] = v;
                g[b * nc + a] = v;
            }
        }
        for &c in &missing {
            z[c] = Column::pending();
        }
        let s = assemble_s(eqs, &g, nc);
        (z, missing, Vec::new(), g, s)
    }

    /// Solves the pending columns of Z (see [`Self::pending`]) in one batch
    /// when there are not too many (at most [`SOLVED_WHEN_READ`]); more
    /// stay pending for good (see [`Self::z_is_whole`]).
    fn solve_pending(&mut self) {
        if self.pending.is_empty() || !self.z_is_whole() {
            return;
        }
        self.solve_batch(&[]);
    }

    /// Whether every column of Z is solved, or will be at its first read
    /// ([`Self::solve_pending`]). When not (more than [`SOLVED_WHEN_READ`]
    /// rows pending: a free-form curve's hundreds), what reads Z takes
    /// another way: δ = K̃⁻¹(Σ w_c a_c) by one solve of the combined rows
    /// ([`Self::add_rows_solved`]) instead of Σ w_c z_c.
    fn z_is_whole(&self) -> bool {
        self.pending.len() <= SOLVED_WHEN_READ
    }

    /// K̃⁻¹ of every sparse right-hand side in `extra` (`(indices,
    /// weights)` over the free points), with the pending columns of Z
    /// solved in the same batch when they are few ([`Self::z_is_whole`]). The extra ones' forward halves visit only
    /// the elimination-tree reach of their non-zeros
    /// ([`Factor::forward_sparse`]: a combination of constraint and load
    /// rows touches a fraction of the factor), the pending ones need no
    /// forward half (kept from the Gram), and one backward pass over the
    /// factor serves them all. Dense columns of K̃⁻¹ per right-hand side,
    /// in `extra`'s order.
    fn solve_batch(&mut self, extra: &[SparseRhs]) -> Mat<f64> {
        debug_assert!(self.update.is_none(), "solves settle a pin change first");
        let n = self.dim();
        let (pending, forward) = if self.z_is_whole() {
            (
                std::mem::take(&mut self.pending),
                std::mem::take(&mut self.pending_forward),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let e = extra.len();
        let k = e + pending.len();
        let mut x = Mat::<f64>::zeros(n, k);
        let sparse: Vec<(&[usize], &[f64])> = extra
            .iter()
            .map(|(i, w)| (i.as_slice(), w.as_slice()))
            .collect();
        let halves = if forward.len() == pending.len() {
            self.factor.forward_sparse(&sparse)
        } else {
            None
        };
        if let Some(halves) = halves {
            for (m, f) in halves.iter().chain(&forward).enumerate() {
                f.scatter(x.col_as_slice_mut(m));
            }
            self.factor.backward_in_place(x.as_mut());
        } else {
            for (m, (indices, weights)) in extra.iter().enumerate() {
                for (&i, &w) in indices.iter().zip(weights) {
                    x[(i, m)] += w;
                }
            }
            for (m, &c) in pending.iter().enumerate() {
                let row = &self.free_rows[c];
                for (&i, &w) in row.indices.iter().zip(&row.weights) {
                    x[(i, e + m)] += w;
                }
            }
            self.factor.solve_in_place(x.as_mut());
        }
        for (m, &c) in pending.iter().enumerate() {
            self.z[c] = Column::new(x.col_as_slice(e + m));
        }
        x
    }

    /// S⁻¹ for the new equations `eqs` (over `rows`, S = `s`) from the
    /// current one by block updates instead of a new factorisation: the
    /// equations the change removed are eliminated from the old inverse
    /// (a Schur downdate, (S_kk)⁻¹ = P − Q R⁻¹ Qᵀ), the added ones bordered
    /// on (X = S_kk⁻¹B, T = D − BᵀX). O(m²·(added + removed)) instead of
    /// O(m³). `None` (the caller inverts S from scratch) unless the current
    /// inverse is exact (Cholesky path, same factor), the change is small,
    /// and the result is provably well conditioned and checked: the same
    /// condition bound as [`well_conditioned_blocks`], and S S⁻¹ v = v to
    /// 1e-9 on two probe vectors. With nothing added or removed (a load's
    /// group came or went) S is the current one entry for entry (see
    /// `schur`: G's entries between kept rows are kept), so the current
    /// inverse, permuted, is returned unchecked — a pseudo-inverse too (a
    /// grab after a curve was added: no second eigendecomposition). Returns
    /// what [`pseudo_inverse`] does: S⁻¹, the dropped directions, and
    /// whether it is an exact inverse.
    fn updated_inverse(
        &self,
        rows: &[ScalarRow],
        eqs: &[ScalarEq],
        s: &Mat<f64>,
    ) -> Option<(Vec<f64>, usize, bool)> {
        use faer::linalg::solvers::{DenseSolveCore, Solve};
        let (m_old, m) = (self.eqs.len(), eqs.len());
        if m_old == 0 || m == 0 || self.rows.len() != self.z.len() {
            return None;
        }
        let EquationMatch {
            kept,
            added,
            removed,
        } = match_equations(&self.rows, &self.eqs, rows, eqs);
        let (k, a, r) = (kept.len(), added.len(), removed.len());
        if k == 0 || 4 * (a + r) > m_old.max(m) {
            return None;
        }
        let old = |i: usize, j: usize| self.s_pinv[i * m_old + j];
        if a == 0 && r == 0 {
            // The same equations on the same columns (a load came or went,
            // or equations were only reordered): S is the old one, entry
            // for entry, and so is its inverse — or pseudo-inverse, with
            // the same dropped directions — permuted. Nothing to check.
            let mut out = vec![0.0; m * m];
            for &(e, o) in &kept {
                for &(f, q) in &kept {
                    out[e * m + f] = old(o, q);
                }
            }
            let dropped = self.rank_deficiency.saturating_sub(self.pin_redundant);
            return Some((out, dropped, self.s_exact));
        }
        if !self.s_exact {
            return None;
        }
        // (S_kk)⁻¹ over the kept equations, in the new order.
        let mut inv_k = Mat::<f64>::from_fn(k, k, |i, j| old(kept[i].1, kept[j].1));
        if r > 0 {
            let q = Mat::<f64>::from_fn(k, r, |i, j| old(kept[i].1, removed[j]));
            let rr = Mat::<f64>::from_fn(r, r, |i, j| old(removed[i], removed[j]));
            let llt = rr.llt(faer::Side::Lower).ok()?;
            let rq = llt.solve(q.transpose());
            inv_k = &inv_k - &q * &rq;
        }
        // The new order: kept equations at their new places, then the
        // added ones.
        let place: Vec<usize> = kept
            .iter()
            .map(|&(e, _)| e)
            .chain(added.iter().copied())
            .collect();
        let whole = if a > 0 {
            let b = Mat::<f64>::from_fn(k, a, |i, j| s[(kept[i].0, added[j])]);
            let d = Mat::<f64>::from_fn(a, a, |i, j| s[(added[i], added[j])]);
            let x = &inv_k * &b;
            let t = &d - b.transpose() * &x;
            let t_inv = t.llt(faer::Side::Lower).ok()?.inverse();
            let xt = &x * &t_inv;
            let top = &inv_k + &xt * x.transpose();
            Mat::<f64>::from_fn(k + a, k + a, |i, j| match (i < k, j < k) {
                (true, true) => top[(i, j)],
                (true, false) => -xt[(i, j - k)],
                (false, true) => -xt[(j, i - k)],
                (false, false) => t_inv[(i - k, j - k)],
            })
        } else {
            inv_k
        };
        let mut out = Mat::<f64>::zeros(m, m);
        for (i, &pi) in place.iter().enumerate() {
            for (j, &pj) in place.iter().enumerate() {
                out[(pi, pj)] = whole[(i, j)];
            }
        }
        checked_inverse(s, &out).map(|p| (p, 0, true))
    }

    /// Refactors for `pinned` control points eliminated and `folded`
    /// equations folded in: K̃ = K + Σ ρ a aᵀ with the pinned rows and
    /// columns eliminated. Every cached column belongs to the old factor and
    /// is forgotten. On error the old factor stays (and nothing else changes).
    fn rebuild_factor(&mut self, pinned: Vec<bool>, folded: Vec<Folded>) -> Result<(), SolveError> {
        let augmented = fold(&self.stiffness, &folded);
        self.factor.refactor(augmented.with_pinned(&pinned))?;
        self.factored = pinned.clone();
        self.update = None;
        self.pinned = pinned;
        self.folded = folded;
        self.augmented = augmented;
        self.forget_columns();
        self.last = None;
        Ok(())
    }

    /// Takes a problem that differs from the current one only in its
    /// equations' targets and its loads' forces (the same groups, keys,
    /// rows, directions and gains, in the same order): the factor (its
    /// pinned points and folded rows), Z, S⁻¹ and the drag response are
    /// kept, only the targets and forces change (a bound curve moved,
    /// [`crate::product`]; an icon's target set). Any other problem goes to
    /// [`Self::set_problem`]. On error nothing changes.
    pub fn retarget(&mut self, problem: Problem) -> Result<(), SolveError> {
        if !self.same_structure(&problem) {
            return self.set_problem(problem);
        }
        validate(&problem, self.dim())?;
        self.take_targets(problem);
        Ok(())
    }

    /// Whether `problem` has the current problem's structure (see
    /// [`Self::retarget`]) and the caches built for it are whole.
    fn same_structure(&self, problem: &Problem) -> bool {
        // After a refactor the columns are forgotten until `set_problem`
        // rebuilds them.
        let whole = self.z.len() == self.rows.len()
            && self
                .eqs
                .iter()
                .flat_map(|e| &e.terms)
                .all(|t| t.col < self.z.len())
            && self.loads.iter().all(|l| l.col < self.z.len());
        whole
            && problem.groups.len() == self.problem.groups.len()
            && problem
                .groups
                .iter()
                .zip(&self.problem.groups)
                .all(|(a, b)| same_group(a, b))
    }

    /// The targets and forces of `problem` (of the current structure, valid)
    /// copied into the scalar equations, the pins and the load columns.
    fn take_targets(&mut self, problem: Problem) {
        // The order `set_problem` made them in: group by group, a pin by
        // its control point (stably), a vector equation as its three
        // coordinates.
        let (mut e, mut l) = (0, 0);
        let mut pins: Vec<(usize, DVec3)> = Vec::with_capacity(self.pins.len());
        for group in &problem.groups {
            for eq in &group.equations {
                match eq {
                    Equation::Vector { row, target } if is_pin_row(row) => {
                        pins.push((row.indices[0], *target));
                    }
                    Equation::Vector { target, .. } => {
                        for k in 0..3 {
                            self.eqs[e].target = target[k];
                            e += 1;
                        }
                    }
                    Equation::Projected { target, .. } => {
                        self.eqs[e].target = *target;
                        e += 1;
                    }
                }
            }
            for load in &group.loads {
                self.loads[l].force = load.force;
                l += 1;
            }
        }
        pins.sort_by_key(|p| p.0);
        for (pin, (index, target)) in self.pins.iter_mut().zip(pins) {
            debug_assert_eq!(pin.index, index);
            pin.target = target;
        }
        self.problem = problem;
        self.base = None;
    }

    /// Back to an earlier factor after a failed problem change, and to the
    /// problem it served.
    fn restore_factor(&mut self, (pinned, folded): (Vec<bool>, Vec<Folded>)) {
        if self.rebuild_factor(pinned, folded).is_ok() {
            let old = std::mem::take(&mut self.problem);
            self.pin_points.clear();
            let _ = self.set_problem(old);
        }
    }

    /// Keeps the columns of the current rows that `rows` drops for later,
    /// forgets retired columns `rows` uses again, and evicts the oldest past
    /// [`RETIRED_BYTES`].
    fn retire(&mut self, z: &[Column]) {
        let kept: std::collections::HashSet<*const f64> =
            z.iter().map(|c| c.values.as_ptr()).collect();
        self.retired
            .retain(|(_, col)| !kept.contains(&col.values.as_ptr()));
        for (c, (r, col)) in self.rows.iter().zip(&self.z).enumerate() {
            if !kept.contains(&col.values.as_ptr()) && !self.pending.contains(&c) {
                self.retired.push_back((row_key(r), col.clone()));
            }
        }
        let per_column = (self.dim() * std::mem::size_of::<f64>()).max(1);
        let keep = RETIRED_BYTES / per_column;
        while self.retired.len() > keep {
            self.retired.pop_front();
        }
    }

    /// Solves with the problem's targets and forces (every drag input zero):
    /// `out = reference + δ`.
    pub fn solve(
        &mut self,
        reference: &[DVec3],
        out: &mut [DVec3],
    ) -> Result<SolveReport, SolveError> {
        self.check_io(reference, out)?;
        if let Some(start) = self.still_optimal(reference) {
            out.copy_from_slice(&start);
            self.base = Some(Base {
                reference: reference.to_vec(),
                start,
            });
            return self.checked(self.report(out, None, DVec3::ZERO), out);
        }
        // The shape must move: a deferred pin change is settled first.
        self.settle_pins()?;
        self.solve_pending();
        let inputs = self.inputs(None, DVec3::ZERO);
        let (delta, lambda) = if self.at_rest(&inputs, reference) {
            (vec![DVec3::ZERO; self.dim()], vec![0.0; self.eqs.len()])
        } else {
            self.refined_delta(&inputs, reference)
        };
        for ((o, r), d) in out.iter_mut().zip(reference).zip(&delta) {
            *o = *r + *d;
        }
        self.base = Some(Base {
            reference: reference.to_vec(),
            start: out.to_vec(),
        });
        let report = self.checked(self.report(out, None, DVec3::ZERO), out)?;
        self.last = Some(self.last_solve(reference, out, &lambda));
        Ok(report)
    }

    /// What [`Self::still_optimal`] needs of a full solve: its problem, its
    /// answer, and per group the size of the pull its multipliers exert.
    fn last_solve(&self, reference: &[DVec3], out: &[DVec3], lambda: &[f64]) -> LastSolve {
        let mut pull: HashMap<GroupKey, f64> = HashMap::new();
        // The solve's multipliers are μ; a folded equation's own is
        // λ = μ + ρ a·δ (see [`Folded`]).
        let lambda: Vec<f64> = if self.folded.is_empty() {
            lambda.to_vec()
        } else {
            let rho: HashMap<RowKey, f64> = self
                .folded
                .iter()
                .map(|f| (row_key(&f.row), f.rho))
                .collect();
            let delta: Vec<DVec3> = out.iter().zip(reference).map(|(o, r)| *o - *r).collect();
            self.eqs
                .iter()
                .zip(lambda)
                .map(|(eq, mu)| match (eq.shift, eq.terms.first()) {
                    (Some(k), Some(t)) => {
                        let row = &self.free_rows[t.col];
                        rho.get(&row_key(row))
                            .map_or(*mu, |r| mu + r * row.apply(&delta)[k])
                    }
                    _ => *mu,
                })
                .collect()
        };
        let lambda = lambda.as_slice();
        for (eq, lam) in self.eqs.iter().zip(lambda) {
            let key = self.problem.groups[eq.group].key;
            let size: f64 = eq
                .terms
                .iter()
                .map(|t| column_reach(DVec3::splat(t.coef), &self.z[t.col]).x)
                .sum();
            // A pending column's size is unknown (infinite) unless unused.
            *pull.entry(key).or_default() += if *lam == 0.0 { 0.0 } else { lam.abs() * size };
        }
        if !self.pin_points.is_empty() {
            // A pin's multiplier is its reaction (b − Kδ − Cᵀλ at the pinned
            // point). K⁻¹ is not at hand for a pinned point, so a group
            // whose pins react beyond round-off counts as pulling.
            let n = self.dim();
            let forces = self.inputs(None, DVec3::ZERO).forces;
            let mut rho = vec![DVec3::ZERO; n];
            for (l, f) in self.loads.iter().zip(&forces) {
                let row = &self.rows[l.col];
                for (&i, &w) in row.indices.iter().zip(&row.weights) {
                    rho[i] += *f * w;
                }
            }
            for (eq, lam) in self.eqs.iter().zip(lambda) {
                for t in &eq.terms {
                    let row = &self.rows[t.col];
                    for (&i, &w) in row.indices.iter().zip(&row.weights) {
                        rho[i][t.k] -= t.coef * lam * w;
                    }
                }
            }
            let delta: Vec<DVec3> = out.iter().zip(reference).map(|(o, r)| *o - *r).collect();
            let mut kd = vec![DVec3::ZERO; n];
            self.augmented.mul_points(&delta, &mut kd);
            let scale = rho
                .iter()
                .chain(&kd)
                .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
            for p in &self.pin_points {
                let reaction = (rho[p.index] - kd[p.index]).abs().max_element();
                if reaction > 1e-13 * scale {
                    for e in &self.pins[p.eqs.clone()] {
                        let key = self.problem.groups[e.group].key;
                        pull.insert(key, f64::INFINITY);
                    }
                }
            }
        }
        LastSolve {
            reference: reference.to_vec(),
            out: out.to_vec(),
            problem: self.problem.clone(),
            pull,
        }
    }

    /// The last full solution, when it is still the exact answer to the
    /// current problem — the optimality (KKT) conditions hold unchanged:
    /// same reference, same loads; every group that changed or left pulled
    /// with multipliers whose effect on the shape is below 1e-13 of its size
    /// (so λ = 0 for it is as exact as the solve); every new or changed
    /// equation already satisfied (to 1e-12). Adding an icon where the
    /// surface is, or waking or putting to sleep one that holds it where it
    /// is, then costs no solve at all.
    fn still_optimal(&self, reference: &[DVec3]) -> Option<Vec<DVec3>> {
        let last = self.last.as_ref()?;
        if last.reference != reference {
            return None;
        }
        let extent = max_extent(&last.out);
        fn find(p: &Problem, key: GroupKey) -> Option<&Group> {
            p.groups.iter().find(|g| g.key == key)
        }
        let no_force = |g: &Group| g.loads.iter().all(|l| l.force == DVec3::ZERO);
        for old in &last.problem.groups {
            if find(&self.problem, old.key) == Some(old) {
                continue;
            }
            let pull = last.pull.get(&old.key).copied().unwrap_or(0.0);
            if !no_force(old) || pull > 1e-13 * extent {
                return None;
            }
        }
        for new in &self.problem.groups {
            if find(&last.problem, new.key) == Some(new) {
                continue;
            }
            if !no_force(new) {
                return None;
            }
            for eq in &new.equations {
                let (error, scale) = match eq {
                    Equation::Vector { row, target } => (
                        (row.apply(&last.out) - *target).abs().max_element(),
                        target.abs().max_element(),
                    ),
                    Equation::Projected {
                        row,
                        direction,
                        target,
                    } => (
                        (row.apply(&last.out).dot(*direction) - *target).abs(),
                        target.abs(),
                    ),
                };
                if error > 1e-12 * scale.max(1.0) {
                    return None;
                }
            }
        }
        Some(last.out.clone())
    }

    /// A drag frame: group `key`'s drag input set to `t`, everything else as
    /// in the problem. The first call for a group (or after the reference
    /// changed) costs one dense pass over Z; later calls cost 3N
    /// multiply-adds.
    pub fn drag(
        &mut self,
        key: GroupKey,
        t: DVec3,
        reference: &[DVec3],
        out: &mut [DVec3],
    ) -> Result<SolveReport, SolveError> {
        // A deferred pin change is settled before a grab's first frame
        // (a pin change drops the base and the response).
        self.settle_pins()?;
        let cached = self.base.as_ref().is_some_and(|b| b.reference == reference);
        if cached {
            // Same reference as the cached base: already checked.
            if out.len() != reference.len() {
                return Err(SolveError::Size {
                    expected: reference.len(),
                    got: out.len(),
                });
            }
        } else {
            self.check_io(reference, out)?;
        }
        if !t.is_finite() {
            return Err(SolveError::NotFinite("drag input".into()));
        }
        let group = self
            .problem
            .groups
            .iter()
            .position(|g| g.key == key)
            .ok_or(SolveError::UnknownGroup(key))?;
        // Pending columns are solved where a frame first reads Z (the
        // base's solve, the response's batch): only the first frame pays.
        if !cached {
            let inputs = self.inputs(None, DVec3::ZERO);
            let start = if self.at_rest(&inputs, reference) {
                reference.to_vec()
            } else {
                let (delta, _) = self.refined_delta(&inputs, reference);
                reference.iter().zip(&delta).map(|(r, d)| *r + *d).collect()
            };
            self.base = Some(Base {
                reference: reference.to_vec(),
                start,
            });
        }
        let key = self.problem.groups[group].key;
        if self.response.as_ref().is_none_or(|r| r.key != key) {
            self.counts.computed += 1;
            let response = self.fresh_response(group);
            self.response = Some(response);
        }
        let (Some(base), Some(resp)) = (&self.base, &self.response) else {
            return Err(SolveError::Factor("drag caches missing".into()));
        };
        match &resp.kind {
            ResponseKind::Uniform(rho) => {
                for ((o, s), r) in out.iter_mut().zip(&base.start).zip(rho) {
                    *o = *s + t * *r;
                }
            }
            ResponseKind::Coupled([r0, r1, r2]) => {
                for i in 0..out.len() {
                    out[i] = base.start[i] + r0[i] * t.x + r1[i] * t.y + r2[i] * t.z;
                }
            }
        }
        let report = self.report(out, Some(group), t);
        self.checked(report, out)
    }

    /// The drag response of group `group` (index) computed from scratch:
    /// δ per unit of drag input along x, y and z, refined to convergence
    /// (along x only when the problem is [`Self::symmetric`]). Its first
    /// answer is solved from the combined rows, not summed from Z: a unit
    /// load's column leans on K's soft modes and the sum cancels them, which
    /// cost refinement solves (see [`Self::add_rows_solved`]).
    fn fresh_response(&mut self, group: usize) -> Response {
        let symmetric = self.symmetric();
        let axes: &[DVec3] = if symmetric {
            &[DVec3::X]
        } else {
            &[DVec3::X, DVec3::Y, DVec3::Z]
        };
        let inputs: Vec<Inputs> = axes.iter().map(|&e| self.unit_inputs(group, e)).collect();
        let extents = vec![1.0; inputs.len()];
        let mut solved = self
            // A response is δ per unit of drag input, from a zero
            // reference: its scale is 1.
            .refined_deltas(&inputs, &vec![None; inputs.len()], &extents, true)
            .into_iter();
        let mut next = || solved.next().map(|(delta, _, _)| delta).unwrap_or_default();
        let [r0, r1, r2] = [next(), next(), next()];
        let kind = if symmetric {
            ResponseKind::Uniform(r0.iter().map(|v| v.x).collect())
        } else {
            ResponseKind::new([r0, r1, r2])
        };
        Response {
            key: self.problem.groups[group].key,
            kind,
        }
    }

    /// Whether every coordinate answers alone and alike: each scalar
    /// equation has one term, and the equations on x, y and z are the same
    /// (row, coefficient, drag shift, group) for each. Loads and pins act
    /// alike on every coordinate, so a drag input along x moves only x and
    /// the response is ρ ⊗ I with ρ the x-field of the x input: one input
    /// computed instead of three.
    fn symmetric(&self) -> bool {
        let mut count: HashMap<(usize, u64, bool, usize), [usize; 3]> = HashMap::new();
        for eq in &self.eqs {
            let [t] = eq.terms.as_slice() else {
                return false;
            };
            if eq.shift.is_some_and(|k| k != t.k) {
                return false;
            }
            count
                .entry((t.col, t.coef.to_bits(), eq.shift.is_some(), eq.group))
                .or_default()[t.k] += 1;
        }
        count.values().all(|c| c[0] == c[1] && c[1] == c[2])
    }

    /// The cached basis of the drag fast path, read-only: the shape with
    /// every drag input at zero and, for a uniform response, the scalar
    /// field ρ (one value per control point) with which a drag frame is
    /// `start + ρ·t`. `None` before the first drag or for a coupled
    /// response. A caller comparing two answers can tell whether frames
    /// came from the same basis; whether the current shape came from it at
    /// all is the caller's to check (a full solve does not clear it).
    pub fn drag_basis(&self) -> Option<(&[DVec3], &[f64])> {
        match (&self.base, &self.response) {
            (
                Some(base),
                Some(Response {
                    kind: ResponseKind::Uniform(rho),
                    ..
                }),
            ) => Some((&base.start, rho)),
            _ => None,
        }
    }

    fn check_io(&self, reference: &[DVec3], out: &[DVec3]) -> Result<(), SolveError> {
        let n = self.dim();
        for len in [reference.len(), out.len()] {
            if len != n {
                return Err(SolveError::Size {
                    expected: n,
                    got: len,
                });
            }
        }
        if reference.iter().any(|p| !p.is_finite()) {
            return Err(SolveError::NotFinite("reference shape".into()));
        }
        Ok(())
    }

    /// (C P)_e for every scalar equation.
    fn c_times(&self, p: &[DVec3]) -> Vec<f64> {
        let applied: Vec<DVec3> = self.rows.iter().map(|r| r.apply(p)).collect();
        self.eqs
            .iter()
            .map(|e| e.terms.iter().map(|t| t.coef * applied[t.col][t.k]).sum())
            .collect()
    }

    /// Targets and forces with group `shifted`'s drag input at `t`.
    fn inputs(&self, shifted: Option<usize>, t: DVec3) -> Inputs {
        Inputs {
            targets: self
                .eqs
                .iter()
                .map(|e| match (e.shift, shifted) {
                    (Some(k), Some(g)) if e.group == g => e.target + t[k],
                    _ => e.target,
                })
                .collect(),
            forces: self
                .loads
                .iter()
                .map(|l| {
                    if Some(l.group) == shifted {
                        l.force + t * l.gain
                    } else {
                        l.force
                    }
                })
                .collect(),
            pins: self
                .pin_points
                .iter()
                .map(|p| self.pin_value(p, shifted, t))
                .collect(),
        }
    }

    /// The least-squares value of a pinned point, Σ w (d + shift) / Σ w²,
    /// with group `shifted`'s drag input at `t`.
    fn pin_value(&self, p: &PinPoint, shifted: Option<usize>, t: DVec3) -> DVec3 {
        let eqs = &self.pins[p.eqs.clone()];
        let (mut num, mut den) = (DVec3::ZERO, 0.0);
        for e in eqs {
            let d = if Some(e.group) == shifted {
                e.target + t
            } else {
                e.target
            };
            num += d * e.weight;
            den += e.weight * e.weight;
        }
        num / den
    }

    /// The derivative of the inputs with respect to group `group`'s drag input along `e`.
    fn unit_inputs(&self, group: usize, e: DVec3) -> Inputs {
        Inputs {
            targets: self
                .eqs
                .iter()
                .map(|q| match q.shift {
                    Some(k) if q.group == group => e[k],
                    _ => 0.0,
                })
                .collect(),
            forces: self
                .loads
                .iter()
                .map(|l| {
                    if l.group == group {
                        e * l.gain
                    } else {
                        DVec3::ZERO
                    }
                })
                .collect(),
            pins: self
                .pin_points
                .iter()
                .map(|p| {
                    let eqs = &self.pins[p.eqs.clone()];
                    let den: f64 = eqs.iter().map(|q| q.weight * q.weight).sum();
                    let num: f64 = eqs
                        .iter()
                        .filter(|q| q.group == group)
                        .map(|q| q.weight)
                        .sum();
                    e * (num / den)
                })
                .collect(),
        }
    }

    /// The Lagrange multipliers λ for the given targets/forces and C·P_ref,
    /// and the weights w = f − Cᵀλ with δ = Z w.
    fn lambda_weights(&self, inputs: &Inputs, cx: &[f64]) -> (Vec<f64>, Vec<DVec3>) {
        let nc = self.rows.len();
        let mut w = vec![DVec3::ZERO; nc];
        for (l, f) in self.loads.iter().zip(&inputs.forces) {
            w[l.col] += *f;
        }
        // r = C δ0 + C P_ref − d, with C δ0 from G.
        let r: Vec<f64> = self
            .eqs
            .iter()
            .enumerate()
            .map(|(e, eq)| {
                let cd0: f64 = eq
                    .terms
                    .iter()
                    .map(|t| {
                        t.coef
                            * self
                                .loads
                                .iter()
                                .zip(&inputs.forces)
                                .map(|(l, f)| self.g[t.col * nc + l.col] * f[t.k])
                                .sum::<f64>()
                    })
                    .sum();
                cd0 + cx[e] - inputs.targets[e]
            })
            .collect();
        let m = self.eqs.len();
        let mut lambdas = vec![0.0; m];
        for (e, eq) in self.eqs.iter().enumerate() {
            let lambda: f64 = (0..m).map(|f| self.s_pinv[e * m + f] * r[f]).sum();
            lambdas[e] = lambda;
            for t in &eq.terms {
                w[t.col][t.k] -= t.coef * lambda;
            }
        }
        (lambdas, w)
    }

    /// δ += Σ_c w_c z_c over the solved columns; returns whether a
    /// pending column has a non-zero weight (its part is the caller's:
    /// [`Self::add_rows_solved`]).
    fn add_columns(&self, delta: &mut [DVec3], w: &[DVec3]) -> bool {
        let mut missed = false;
        for (c, wc) in w.iter().enumerate() {
            if *wc == DVec3::ZERO {
                continue;
            }
            if self.z[c].is_pending() {
                missed = true;
                continue;
            }
            if wc.y == 0.0 && wc.z == 0.0 {
                // One coordinate (a symmetric response's x input).
                for (d, &zi) in delta.iter_mut().zip(self.z[c].values.iter()) {
                    d.x += wc.x * zi;
                }
            } else {
                for (d, &zi) in delta.iter_mut().zip(self.z[c].values.iter()) {
                    *d += *wc * zi;
                }
            }
        }
        missed
    }

    /// δ += K̃⁻¹ Σ_c w_c a_c per input and coordinate, as one batched sparse
    /// solve of the combined rows (with the pending columns of Z in the same
    /// batch): the same answer as [`Self::add_columns`], but without its
    /// cancellation. Each column z_c = K̃⁻¹a_c carries the soft modes of K
    /// (a small `rest`: the affine ones) at full size, and Σ w_c z_c cancels
    /// them, leaving a stationarity residual far above round-off that costs
    /// refinement solves; the combined right-hand side cancels them before
    /// the solve, whose residual is the solve's own round-off.
    fn add_rows_solved(&mut self, deltas: &mut [Vec<DVec3>], weights: &[Vec<DVec3>]) {
        let n = self.dim();
        let columns: Vec<(usize, usize)> = weights
            .iter()
            .enumerate()
            .flat_map(|(p, w)| {
                (0..3)
                    .filter(move |&k| w.iter().any(|wc| wc[k] != 0.0))
                    .map(move |k| (p, k))
            })
            .collect();
        if columns.is_empty() && (self.pending.is_empty() || !self.z_is_whole()) {
            return;
        }
        // The combined rows, summed in a dense scratch (in the order the
        // rows come), kept sparse: their non-zeros lie on the rows' points.
        let mut sum = vec![0.0; n];
        let rhs: Vec<SparseRhs> = columns
            .iter()
            .map(|&(p, k)| {
                for (c, wc) in weights[p].iter().enumerate() {
                    let f = wc[k];
                    if f == 0.0 {
                        continue;
                    }
                    let row = &self.free_rows[c];
                    for (&i, &a) in row.indices.iter().zip(&row.weights) {
                        sum[i] += f * a;
                    }
                }
                let mut column: SparseRhs = (Vec::new(), Vec::new());
                for (i, v) in sum.iter_mut().enumerate() {
                    if *v != 0.0 {
                        column.0.push(i);
                        column.1.push(std::mem::take(v));
                    }
                }
                column
            })
            .collect();
        let rhs = self.solve_batch(&rhs);
        for (j, &(p, k)) in columns.iter().enumerate() {
            for (d, &v) in deltas[p].iter_mut().zip(rhs.col_as_slice(j)) {
                d[k] += v;
            }
        }
    }

    /// Whether δ = 0, λ = 0 solves the problem exactly: no load pulls and
    /// the reference already meets every equation (to 1e-12 of its scale).
    /// That is the state after every bake (a released load), so a grab
    /// starts without a solve.
    fn at_rest(&self, inputs: &Inputs, reference: &[DVec3]) -> bool {
        let close = |d: f64, c: f64| (d - c).abs() <= 1e-12 * d.abs().max(c.abs()).max(1.0);
        inputs.forces.iter().all(|f| *f == DVec3::ZERO)
            && self.pin_points.iter().zip(&inputs.pins).all(|(p, v)| {
                let r = reference[p.index];
                (0..3).all(|k| close(v[k], r[k]))
            })
            && inputs
                .targets
                .iter()
                .zip(self.c_times(reference))
                .all(|(d, c)| close(*d, c))
    }

    /// δ with one step of iterative refinement on the optimality conditions
    /// K δ + Cᵀλ = b, C δ = d − C P_ref.
    /// Also returns the Lagrange multipliers λ (one per scalar equation).
    /// `extent` is the size of the shape δ displaces (max |P_ref|).
    fn refined_delta(&mut self, inputs: &Inputs, reference: &[DVec3]) -> (Vec<DVec3>, Vec<f64>) {
        self.refined_deltas(
            std::slice::from_ref(inputs),
            &[Some(reference)],
            &[max_extent(reference)],
            false,
        )
        .pop()
        .map(|(delta, lambda, _)| (delta, lambda))
        .unwrap_or_default()
    }

    /// Per input: δ_pin, the pinned points' displacement from the reference
    /// (`None`: from zero, for a drag response), and u = K_ff⁻¹(−K δ_pin)_f,
    /// the free points' answer to it — one batched sparse solve for every
    /// input whose pins move.
    fn pin_displacements(
        &mut self,
        inputs: &[Inputs],
        references: &[Option<&[DVec3]>],
    ) -> Vec<Option<(Vec<DVec3>, Vec<DVec3>)>> {
        let n = self.dim();
        let mut out: Vec<Option<(Vec<DVec3>, Vec<DVec3>)>> = inputs
            .iter()
            .zip(references)
            .map(|(inp, r)| {
                let mut d = vec![DVec3::ZERO; n];
                let mut moved = false;
                for (p, v) in self.pin_points.iter().zip(&inp.pins) {
                    d[p.index] = *v - r.map_or(DVec3::ZERO, |r| r[p.index]);
                    moved |= d[p.index] != DVec3::ZERO;
                }
                moved.then_some((d, Vec::new()))
            })
            .collect();
        let columns: Vec<(usize, usize)> = out
            .iter()
            .enumerate()
            .filter_map(|(p, o)| o.as_ref().map(|_| p))
            .flat_map(|p| (0..3).map(move |k| (p, k)))
            .collect();
        if columns.is_empty() {
            return out;
        }
        let mut rhs = Mat::<f64>::zeros(n, columns.len());
        let mut kd = vec![DVec3::ZERO; n];
        for (p, o) in out.iter().enumerate() {
            let Some((d, _)) = o else { continue };
            self.augmented.mul_points(d, &mut kd);
            for (c, &(q, k)) in columns.iter().enumerate() {
                if q == p {
                    for (i, v) in kd.iter().enumerate() {
                        if !self.pinned[i] {
                            rhs[(i, c)] = -v[k];
                        }
                    }
                }
            }
        }
        self.factor.solve_in_place(rhs.as_mut());
        for (c, &(p, k)) in columns.iter().enumerate() {
            if let Some((_, u)) = &mut out[p] {
                u.resize(n, DVec3::ZERO);
                for (ui, &v) in u.iter_mut().zip(rhs.col_as_slice(c)) {
                    ui[k] = v;
                }
            }
        }
        out
    }

    /// [`Self::refined_delta`] for several inputs at once, their refinement
    /// steps batched into one sparse solve per step (it streams the factor
    /// once, so 9 right-hand sides cost far less than three solves of 3).
    ///
    /// The first answer is δ = Z w (a pass over the cached columns) or, when
    /// `direct`, one batched solve of the combined rows K̃⁻¹(Σ_c w_c a_c)
    /// (see [`Self::add_rows_solved`]; the pending columns ride along).
    ///
    /// Iterative refinement on the KKT conditions, repeated while it still
    /// gains (at most [`MAX_REFINEMENT_STEPS`]). Per step, input and
    /// coordinate k:
    /// * the stationarity residual ρ_k = b_k − Kδ_k − (Cᵀλ)_k is refined by
    ///   y_k = K⁻¹ρ_k when it exceeds the rounding of the terms it was
    ///   computed from (1e-13 of them); this recovers the digits lost to
    ///   cancellation in δ0 − Yλ when the mass term is small (K is then
    ///   ill-conditioned in its affine modes). Only coordinates that need it
    ///   enter the solve: a coordinate whose weights barely reach the
    ///   columns (Σ_c |w_c,k| ‖z_c‖∞ ≤ 1e-9 of `extent`) cannot carry an
    ///   error above 1e-12 of the shape's size even at u·cond(K) = 1e-3,
    ///   and is left as it is;
    /// * a constraint error above 1e-12 of the targets is projected out
    ///   through S⁺ (no sparse solve). Errors along the directions S⁺
    ///   dropped (contradictory equations) stay: they are the least-squares
    ///   answer's own residual, which no refinement changes.
    ///
    /// One step was measured not to be enough: a drag response at 91 × 54
    /// held the paper's pins only to 2.5e-7 per unit of drag after one step.
    fn refined_deltas(
        &mut self,
        inputs: &[Inputs],
        references: &[Option<&[DVec3]>],
        extents: &[f64],
        direct: bool,
    ) -> Vec<Refined> {
        let n = self.dim();
        let m = self.eqs.len();
        // Σ w_c z_c needs every column of Z.
        let direct = direct || !self.z_is_whole();
        let mut deltas = Vec::with_capacity(inputs.len());
        let mut lambdas: Vec<Vec<f64>> = Vec::with_capacity(inputs.len());
        let mut reaches = Vec::with_capacity(inputs.len());
        let cx_owned: Vec<Vec<f64>> = references
            .iter()
            .map(|r| r.map_or_else(|| vec![0.0; m], |r| self.c_times(r)))
            .collect();
        let cxs: Vec<&[f64]> = cx_owned.iter().map(Vec::as_slice).collect();
        let pinned = self.pin_displacements(inputs, references);
        let mut weights: Vec<Vec<DVec3>> = Vec::with_capacity(inputs.len());
        let mut pin_reaches: Vec<DVec3> = Vec::with_capacity(inputs.len());
        for ((inputs, cx), pin) in inputs.iter().zip(&cxs).zip(pinned) {
            // The pinned points and the free points' answer to them act as
            // a moved reference: C (P_ref + δ_pin + u).
            let (delta, cx_moved, pin_reach) = match pin {
                Some((d, u)) => {
                    let mut moved = d;
                    for (a, b) in moved.iter_mut().zip(&u) {
                        *a += *b;
                    }
                    let cm: Vec<f64> = self
                        .c_times(&moved)
                        .iter()
                        .zip(cx.iter())
                        .map(|(a, b)| a + b)
                        .collect();
                    let reach = u.iter().fold(DVec3::ZERO, |m, v| m.max(v.abs()));
                    (moved, Some(cm), reach)
                }
                None => (vec![DVec3::ZERO; n], None, DVec3::ZERO),
            };
            let (lambda, w) = self.lambda_weights(inputs, cx_moved.as_deref().unwrap_or(cx));
            deltas.push(delta);
            lambdas.push(lambda);
            weights.push(w);
            pin_reaches.push(pin_reach);
        }
        if direct {
            self.add_rows_solved(&mut deltas, &weights);
        } else {
            self.solve_pending();
            for (delta, w) in deltas.iter_mut().zip(&weights) {
                let missed = self.add_columns(delta, w);
                debug_assert!(!missed, "Z is whole on this path");
            }
        }
        for (w, pin_reach) in weights.iter().zip(pin_reaches) {
            // How strongly each coordinate's δ = Σ w_c z_c leans on Z.
            let reach = w
                .iter()
                .zip(&self.z)
                .fold(pin_reach, |m, (wc, col)| m + column_reach(*wc, col));
            reaches.push(reach);
        }
        self.refine(inputs, &cxs, &mut deltas, &mut lambdas, &reaches, extents);
        deltas
            .into_iter()
            .zip(lambdas)
            .zip(reaches)
            .map(|((d, l), r)| (d, l, r))
            .collect()
    }

    /// The refinement loop of [`Self::refined_deltas`] from given starting
    /// answers (δ, λ) and their reaches: steps while a step still gains.
    fn refine(
        &mut self,
        inputs: &[Inputs],
        cxs: &[&[f64]],
        deltas: &mut [Vec<DVec3>],
        lambdas: &mut [Vec<f64>],
        reaches: &[DVec3],
        extents: &[f64],
    ) {
        if self.eqs.is_empty() && self.loads.is_empty() && self.pin_points.is_empty() {
            return;
        }
        // The size of the last residual per input, to stop when a step no
        // longer gains.
        let mut last: Vec<f64> = vec![f64::INFINITY; inputs.len()];
        let mut active: Vec<bool> = vec![true; inputs.len()];
        for _ in 0..MAX_REFINEMENT_STEPS {
            let mut pending: Vec<Pending> = Vec::with_capacity(inputs.len());
            for p in 0..inputs.len() {
                if !active[p] {
                    pending.push((Vec::new(), [None, None, None]));
                    continue;
                }
                let (sigma, refine, size) = self.residuals(
                    &inputs[p],
                    cxs[p],
                    &deltas[p],
                    &lambdas[p],
                    reaches[p],
                    extents[p],
                );
                let target_scale = inputs[p]
                    .targets
                    .iter()
                    .chain(cxs[p].iter())
                    .fold(1.0f64, |m, x| m.max(x.abs()));
                let constraint_error = sigma.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let needs =
                    refine.iter().any(Option::is_some) || constraint_error > 1e-12 * target_scale;
                // Stop when nothing needs refining or a step gained less
                // than half.
                if !needs || size >= 0.5 * last[p] {
                    active[p] = false;
                    pending.push((Vec::new(), [None, None, None]));
                    continue;
                }
                last[p] = size;
                pending.push((sigma, refine));
            }
            if !active.iter().any(|&a| a) {
                break;
            }
            self.counts.refinement_steps += 1;
            self.refinement_step(&pending, &active, deltas, lambdas);
        }
    }

    /// The residuals of one input's (δ, λ): σ = d − C P_ref − C δ, per
    /// coordinate ρ_k when it needs refining (see [`Self::refined_deltas`]),
    /// and a size of the whole residual (max |ρ| relative to its terms plus
    /// max |σ| relative to the targets), to measure progress.
    fn residuals(
        &self,
        inputs: &Inputs,
        cx: &[f64],
        delta: &[DVec3],
        lambda: &[f64],
        reach: DVec3,
        extent: f64,
    ) -> (Vec<f64>, [Option<Vec<f64>>; 3], f64) {
        let n = self.dim();
        // ρ = b − Cᵀλ − K δ, and the size of the terms it sums, per point
        // and coordinate: |b| + |Cᵀ||λ| + |K||δ| (its rounding is a few
        // units of round-off of that).
        let mut rho = vec![DVec3::ZERO; n];
        let mut terms = vec![DVec3::ZERO; n];
        for (l, f) in self.loads.iter().zip(&inputs.forces) {
            let row = &self.rows[l.col];
            for (&i, &w) in row.indices.iter().zip(&row.weights) {
                rho[i] += *f * w;
                terms[i] += (*f * w).abs();
            }
        }
        for (eq, lam) in self.eqs.iter().zip(lambda) {
            for t in &eq.terms {
                let row = &self.rows[t.col];
                for (&i, &w) in row.indices.iter().zip(&row.weights) {
                    rho[i][t.k] -= t.coef * lam * w;
                    terms[i][t.k] += (t.coef * lam * w).abs();
                }
            }
        }
        // The size of the terms whose rounding makes up ρ, per coordinate,
        // over the free points (a pinned point's ρ is its reaction, not an
        // error: it is zeroed).
        let mut computed = DVec3::ZERO;
        let mut k_delta = vec![DVec3::ZERO; n];
        let mut k_abs = vec![DVec3::ZERO; n];
        let x_only = |v: &DVec3| v.y == 0.0 && v.z == 0.0;
        if delta.iter().all(x_only) {
            // One coordinate (a symmetric response's x input): K δ and
            // |K||δ| are zero on y and z, so one scalar pass over K gives
            // the same numbers as the three-coordinate one.
            let x: Vec<f64> = delta.iter().map(|d| d.x).collect();
            mul_with_bound_x(&self.augmented, &x, &mut k_delta, &mut k_abs);
        } else {
            self.augmented
                .mul_points_with_bound(delta, &mut k_delta, &mut k_abs);
        }
        // The componentwise backward error max_i |ρ_i| / (|b| + |Cᵀ||λ| +
        // |K||δ|)_i (Oettli–Prager), per coordinate.
        let mut backward = DVec3::ZERO;
        for (((r, kd), (t, ka)), &pinned) in rho
            .iter_mut()
            .zip(&k_delta)
            .zip(terms.iter().zip(&k_abs))
            .zip(&self.pinned)
        {
            if pinned {
                *r = DVec3::ZERO;
                continue;
            }
            computed = computed.max(r.abs()).max(kd.abs());
            *r -= *kd;
            let size = *t + *ka;
            for k in 0..3 {
                if r[k] != 0.0 {
                    let ratio = if size[k] > 0.0 {
                        r[k].abs() / size[k]
                    } else {
                        f64::INFINITY
                    };
                    backward[k] = backward[k].max(ratio);
                }
            }
        }
        let worst = rho.iter().fold(DVec3::ZERO, |m, r| m.max(r.abs()));
        // A coordinate is refined when its residual is large against the
        // answer (1e-13 of the terms' largest), is more than the rounding
        // of its own computation (componentwise backward error above
        // [`NOISE_BACKWARD_ERROR`]: below it, y = K⁻¹ρ is noise and a step
        // gains nothing), and can reach the shape at all.
        let refine: [Option<Vec<f64>>; 3] = std::array::from_fn(|k| {
            (worst[k] > 1e-13 * computed[k].max(1e-300)
                && backward[k] > NOISE_BACKWARD_ERROR
                && reach[k] > 1e-9 * extent)
                .then(|| rho.iter().map(|r| r[k]).collect())
        });
        // σ = d − C P_ref − C δ: what the constraints still ask.
        let sigma: Vec<f64> = self
            .c_times(delta)
            .iter()
            .zip(&inputs.targets)
            .zip(cx.iter())
            .map(|((cd, d), c)| d - c - cd)
            .collect();
        let target_scale = inputs
            .targets
            .iter()
            .chain(cx.iter())
            .fold(1.0f64, |m, x| m.max(x.abs()));
        let rho_size = (0..3)
            .filter(|&k| refine[k].is_some())
            .map(|k| worst[k] / computed[k].max(1e-300))
            .fold(0.0f64, f64::max);
        let sigma_size = sigma.iter().fold(0.0f64, |m, x| m.max(x.abs())) / target_scale;
        (sigma, refine, rho_size + sigma_size)
    }

    /// One refinement step for every active input: one batched sparse solve
    /// y = K⁻¹ρ for the coordinates that ask, then the constraint error
    /// projected out through S⁺.
    fn refinement_step(
        &mut self,
        pending: &[Pending],
        active: &[bool],
        deltas: &mut [Vec<DVec3>],
        lambdas: &mut [Vec<f64>],
    ) {
        let n = self.dim();
        let columns: Vec<(usize, usize)> = pending
            .iter()
            .enumerate()
            .flat_map(|(p, (_, refine))| {
                (0..3)
                    .filter(move |&k| refine[k].is_some())
                    .map(move |k| (p, k))
            })
            .collect();
        let mut y = Mat::<f64>::zeros(n, columns.len());
        for (c, &(p, k)) in columns.iter().enumerate() {
            if let Some(rho) = &pending[p].1[k] {
                y.col_mut(c).copy_from(faer::ColRef::from_slice(rho));
            }
        }
        if !columns.is_empty() {
            self.factor.solve_in_place(y.as_mut());
        }
        // The weights on pending columns, per input: one batched solve of
        // their combined rows for every input at the end.
        let mut unsolved: Vec<Vec<DVec3>> = vec![Vec::new(); pending.len()];
        for (p, (sigma, _)) in pending.iter().enumerate() {
            if !active[p] {
                continue;
            }
            let mut correction = vec![DVec3::ZERO; n];
            for (c, &(q, k)) in columns.iter().enumerate() {
                if q == p {
                    for (d, &v) in correction.iter_mut().zip(y.col_as_slice(c)) {
                        d[k] = v;
                    }
                }
            }
            let w = self.project(sigma, &correction, &mut deltas[p], &mut lambdas[p]);
            if self.add_columns(&mut deltas[p], &w) {
                unsolved[p] = w
                    .iter()
                    .zip(&self.z)
                    .map(|(wc, col)| if col.is_pending() { *wc } else { DVec3::ZERO })
                    .collect();
            }
        }
        if unsolved.iter().any(|w| !w.is_empty()) {
            self.add_rows_solved(deltas, &unsolved);
        }
    }

    /// δ += y and λ += S⁺ (C y − σ); returns w = −Cᵀ S⁺ (C y − σ), whose
    /// Z w the caller adds to δ ([`Self::add_columns`], and for pending
    /// columns [`Self::add_rows_solved`]): the correction y (K̃⁻¹ of a
    /// stationarity residual) projected onto the constraints, as in
    /// [`Self::lambda_weights`].
    fn project(
        &self,
        sigma: &[f64],
        correction: &[DVec3],
        delta: &mut [DVec3],
        lambda: &mut [f64],
    ) -> Vec<DVec3> {
        // r' = C y − σ.
        let r: Vec<f64> = self
            .c_times(correction)
            .iter()
            .zip(sigma)
            .map(|(cy, s)| cy - s)
            .collect();
        let m = self.eqs.len();
        let mut w = vec![DVec3::ZERO; self.rows.len()];
        for (e, eq) in self.eqs.iter().enumerate() {
            let lam: f64 = (0..m).map(|f| self.s_pinv[e * m + f] * r[f]).sum();
            lambda[e] += lam;
            for t in &eq.terms {
                w[t.col][t.k] -= t.coef * lam;
            }
        }
        for (d, c) in delta.iter_mut().zip(correction) {
            *d += *c;
        }
        w
    }

    /// `report` as a result: a residual above [`RESIDUAL_TOLERANCE`] of the
    /// shape's size (the larger of the answer's extent and the equations'
    /// targets) is [`SolveError::Inexact`] when no equation was dropped,
    /// and a [`SolveWarning::Dependent`] when some were. The tolerance does
    /// not grow with how far the loads alone would move the shape: the
    /// refinement meets the equations to the shape's own size however large
    /// that pull is (`tests/rest_bounds.rs`). Allocation-free.
    fn checked(&self, mut report: SolveReport, out: &[DVec3]) -> Result<SolveReport, SolveError> {
        // The scale is at least 1: most frames stop here, with no pass over
        // the shape.
        if report.constraint_residual <= RESIDUAL_TOLERANCE {
            return Ok(report);
        }
        let targets = self.eqs.iter().fold(0.0f64, |m, e| m.max(e.target.abs()));
        let targets = self
            .pins
            .iter()
            .fold(targets, |m, p| m.max(p.target.abs().max_element()));
        let tolerance = RESIDUAL_TOLERANCE * max_extent(out).max(targets);
        if report.constraint_residual <= tolerance {
            return Ok(report);
        }
        if report.rank_deficiency == 0 {
            return Err(SolveError::Inexact {
                residual: report.constraint_residual,
                tolerance,
            });
        }
        report.warning = Some(SolveWarning::Dependent {
            dropped: report.rank_deficiency,
            residual: report.constraint_residual,
        });
        Ok(report)
    }

    /// The report of `out` with group `shifted`'s drag input at `t`.
    /// Allocation-free: it runs on every drag frame.
    fn report(&self, out: &[DVec3], shifted: Option<usize>, t: DVec3) -> SolveReport {
        let residual = self
            .eqs
            .iter()
            .map(|e| {
                let value: f64 = e
                    .terms
                    .iter()
                    .map(|term| term.coef * self.rows[term.col].apply(out)[term.k])
                    .sum();
                let target = match (e.shift, shifted) {
                    (Some(k), Some(g)) if e.group == g => e.target + t[k],
                    _ => e.target,
                };
                (value - target).abs()
            })
            .fold(0.0, f64::max);
        let residual = self.pins.iter().fold(residual, |m, p| {
            let target = match shifted {
                Some(g) if p.group == g => p.target + t,
                _ => p.target,
            };
            m.max((out[p.index] * p.weight - target).abs().max_element())
        });
        SolveReport {
            constraint_residual: residual,
            rank_deficiency: self.rank_deficiency,
            equations: self.eqs.len(),
            warning: None,
        }
    }
}

/// How the scalar equations of a new problem relate to the current ones.
struct EquationMatch {
    /// (new, old) pairs: the same terms on the same rows.
    kept: Vec<(usize, usize)>,
    /// New equations with no old counterpart.
    added: Vec<usize>,
    /// Old equations with no new counterpart.
    removed: Vec<usize>,
}

/// Matches the scalar equations `new` (over `new_rows`) with `old` (over
/// `old_rows`): an equation is kept when an old one has the same terms
/// (coordinate, coefficient, row, bit for bit); duplicates pair in order.
fn match_equations(
    old_rows: &[ScalarRow],
    old: &[ScalarEq],
    new_rows: &[ScalarRow],
    new: &[ScalarEq],
) -> EquationMatch {
    // New column → old column (the same row, the same cached Z column).
    let old_col: HashMap<RowKey, usize> = old_rows
        .iter()
        .enumerate()
        .map(|(c, r)| (row_key(r), c))
        .collect();
    let map: Vec<Option<usize>> = new_rows
        .iter()
        .map(|r| old_col.get(&row_key(r)).copied())
        .collect();
    type EqKey = Vec<(usize, u64, usize)>;
    let mut old_eqs: HashMap<EqKey, Vec<usize>> = HashMap::new();
    for (e, eq) in old.iter().enumerate().rev() {
        let key = eq
            .terms
            .iter()
            .map(|t| (t.k, t.coef.to_bits(), t.col))
            .collect();
        old_eqs.entry(key).or_default().push(e);
    }
    let mut kept: Vec<(usize, usize)> = Vec::new();
    let mut added: Vec<usize> = Vec::new();
    for (e, eq) in new.iter().enumerate() {
        let key: Option<EqKey> = eq
            .terms
            .iter()
            .map(|t| map[t.col].map(|c| (t.k, t.coef.to_bits(), c)))
            .collect();
        match key.and_then(|k| old_eqs.get_mut(&k)).and_then(Vec::pop) {
            Some(o) => kept.push((e, o)),
            None => added.push(e),
        }
    }
    let mut is_kept = vec![false; old.len()];
    for &(_, o) in &kept {
        is_kept[o] = true;
    }
    let removed: Vec<usize> = (0..old.len()).filter(|&o| !is_kept[o]).collect();
    EquationMatch {
        kept,
        added,
        removed,
    }
}

/// Whether two groups have the same structure: key, rows, directions and
/// gains (targets and forces aside).
fn same_group(a: &Group, b: &Group) -> bool {
    let same_eq = |a: &Equation, b: &Equation| match (a, b) {
        (Equation::Vector { row: r, .. }, Equation::Vector { row: q, .. }) => r == q,
        (
            Equation::Projected {
                row: r,
                direction: d,
                ..
            },
            Equation::Projected {
                row: q,
                direction: e,
                ..
            },
        ) => r == q && d == e,
        _ => false,
    };
    a.key == b.key
        && a.equations.len() == b.equations.len()
        && a.loads.len() == b.loads.len()
        && a.equations
            .iter()
            .zip(&b.equations)
            .all(|(x, y)| same_eq(x, y))
        && a.loads
            .iter()
            .zip(&b.loads)
            .all(|(x, y)| x.row == y.row && x.drag_gain == y.drag_gain)
}

/// A sparse right-hand side over the free points: indices (unique) and
/// values.
type SparseRhs = (Vec<usize>, Vec<f64>);

/// What `Solver::schur` builds: Z (pending placeholders included), the
/// pending columns and their forward halves, G (row-major) and S.
type Schur = (Vec<Column>, Vec<usize>, Vec<Forward>, Vec<f64>, Mat<f64>);

/// S = C K⁻¹ Cᵀ over the scalar equations from G (row-major, nc × nc).
/// Equations of one term (every vector equation's coordinate) take the
/// short way: S_ef = c_e c_f G[col_e, col_f] when they act on the same
/// coordinate, else 0 — the same products as the general sum.
fn assemble_s(eqs: &[ScalarEq], g: &[f64], nc: usize) -> Mat<f64> {
    let m = eqs.len();
    let mut s = Mat::<f64>::zeros(m, m);
    let single: Vec<Option<Term>> = eqs
        .iter()
        .map(|e| match e.terms.as_slice() {
            [t] => Some(*t),
            _ => None,
        })
        .collect();
    // Column by column (S is column-major), each entry from its upper
    // triangle's terms (e ≤ f) so that S is symmetric to the last bit.
    let entry = |e: usize, f: usize| -> f64 {
        match (single[e], single[f]) {
            (Some(t), Some(u)) if t.k == u.k => t.coef * u.coef * g[t.col * nc + u.col],
            (Some(_), Some(_)) => 0.0,
            _ => {
                let mut v = 0.0;
                for t in &eqs[e].terms {
                    for u in eqs[f].terms.iter().filter(|u| u.k == t.k) {
                        v += t.coef * u.coef * g[t.col * nc + u.col];
                    }
                }
                v
            }
        }
    };
    for f in 0..m {
        let column = s
            .col_mut(f)
            .try_as_col_major_mut()
            .map(|c| c.as_slice_mut());
        if let Some(column) = column {
            for (e, x) in column.iter_mut().enumerate() {
                *x = if e <= f { entry(e, f) } else { entry(f, e) };
            }
        }
    }
    s
}

/// One input of a batched refinement: σ = d − C P_ref − C δ, and per
/// coordinate the stationarity residual ρ_k when it needs a refinement step.
type Pending = (Vec<f64>, [Option<Vec<f64>>; 3]);

/// One refined answer: δ, the multipliers λ (one per scalar equation) and
/// the reach of δ on Z per coordinate (Σ_c |w_c| ‖z_c‖∞, see
/// `Solver::residuals`).
type Refined = (Vec<DVec3>, Vec<f64>, DVec3);

struct Inputs {
    targets: Vec<f64>,
    forces: Vec<DVec3>,
    /// The value of every pinned point (`pin_points` order).
    pins: Vec<DVec3>,
}

/// A row on one control point with a non-zero weight: as a vector
/// equation it pins that point (eliminated from the unknowns).
fn is_pin_row(row: &ScalarRow) -> bool {
    row.indices.len() == 1 && row.weights[0] != 0.0
}

fn validate(problem: &Problem, n: usize) -> Result<(), SolveError> {
    let row_ok = |r: &ScalarRow| -> Result<(), SolveError> {
        if r.indices.len() != r.weights.len() {
            return Err(SolveError::Size {
                expected: r.indices.len(),
                got: r.weights.len(),
            });
        }
        if let Some(&index) = r.indices.iter().find(|&&i| i >= n) {
            return Err(SolveError::IndexOutOfRange { index, dim: n });
        }
        if r.weights.iter().any(|w| !w.is_finite()) {
            return Err(SolveError::NotFinite("row weight".into()));
        }
        Ok(())
    };
    let mut keys = std::collections::HashSet::new();
    for g in &problem.groups {
        if !keys.insert(g.key) {
            return Err(SolveError::DuplicateGroup(g.key));
        }
        for eq in &g.equations {
            match eq {
                Equation::Vector { row, target } => {
                    row_ok(row)?;
                    if !target.is_finite() {
                        return Err(SolveError::NotFinite("equation target".into()));
                    }
                }
                Equation::Projected {
                    row,
                    direction,
                    target,
                } => {
                    row_ok(row)?;
                    if !direction.is_finite() || !target.is_finite() {
                        return Err(SolveError::NotFinite("projected equation".into()));
                    }
                    if *direction == DVec3::ZERO {
                        return Err(SolveError::ZeroDirection);
                    }
                }
            }
        }
        for l in &g.loads {
            row_ok(&l.row)?;
            if !l.force.is_finite() || !l.drag_gain.is_finite() {
                return Err(SolveError::NotFinite("load".into()));
            }
        }
    }
    Ok(())
}

/// The pseudo-inverse of the symmetric positive semi-definite `s` (row-major
/// result), the number of dropped eigen-directions, and whether S was
/// provably well conditioned (the Cholesky path).
///
/// S is first equilibrated, Ŝ = D^-½ S D^-½ with D = diag(S), so that the
/// cut-off (1e-12 of the largest eigenvalue of Ŝ) measures linear dependence
/// between equations rather than their scale: exactly redundant equations
/// give eigenvalues at round-off level and are dropped; independent ones,
/// however differently scaled, are kept. S⁺ = D^-½ Ŝ⁺ D^-½.
///
/// Ŝ is taken apart into the blocks its zeros leave independent
/// ([`independent_blocks`]): equations on x, y and z never meet in S
/// unless a normal constraint couples them, so a curve's thousand vector
/// equations are three blocks of a third the size, and when the three are
/// the same matrix (as they are: one K per coordinate) one factorisation
/// serves all. Block by block the answer is the same as whole — the
/// pseudo-inverse of a block-diagonal matrix is block-diagonal — with the
/// same cut-off (the largest eigenvalue of all blocks) and the same
/// Cholesky criterion (the ∞-norms of the whole are the blocks' largest).
/// A curve held on 81 × 159 took 7.5 s to set up with one dense
/// eigendecomposition of all 1245 equations.
fn pseudo_inverse(s: &Mat<f64>) -> Result<(Vec<f64>, usize, bool), SolveError> {
    let m = s.nrows();
    if m == 0 {
        return Ok((Vec::new(), 0, true));
    }
    let Equilibrated {
        scale,
        blocks,
        mats,
        same_as,
    } = equilibrated(s);
    if let Some(out) = blockwise_inverse(m, &scale, &blocks, &mats, &same_as) {
        return Ok((out, 0, true));
    }
    let mut out = vec![0.0; m * m];
    let mut evds = Vec::with_capacity(blocks.len());
    for (k, mat) in mats.iter().enumerate() {
        if same_as[k].is_some() {
            evds.push(None);
            continue;
        }
        let evd = mat
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| SolveError::Factor(format!("eigendecomposition of S: {e:?}")))?;
        evds.push(Some(evd));
    }
    let max = evds
        .iter()
        .flatten()
        .flat_map(|e| (0..e.S().dim()).map(move |i| e.S()[i]))
        .fold(0.0f64, |a, b| a.max(b.abs()));
    let cut = max * 1e-12;
    let mut dropped = 0;
    for (k, b) in blocks.iter().enumerate() {
        let Some(evd) = evds[same_as[k].unwrap_or(k)].as_ref() else {
            continue;
        };
        let (u, lam) = (evd.U(), evd.S());
        let kept: Vec<usize> = (0..b.len())
            .filter(|&c| lam[c] > cut && lam[c].is_finite())
            .collect();
        dropped += b.len() - kept.len();
        // S⁺ = W Wᵀ with W = D^-½ U_kept Λ_kept^-½: one dense product (gemm).
        let w = Mat::<f64>::from_fn(b.len(), kept.len(), |i, c| {
            let e = kept[c];
            u[(i, e)] * scale[b[i]] / lam[e].sqrt()
        });
        let product = &w * w.transpose();
        for (i, &bi) in b.iter().enumerate() {
            for (j, &bj) in b.iter().enumerate() {
                out[bi * m + bj] = product[(i, j)];
            }
        }
    }
    Ok((out, dropped, false))
}

/// S equilibrated (Ŝ = D^-½ S D^-½, `scale` = D^-½, 0 where S's diagonal is
/// not positive) and taken apart into its independent blocks, each block's
/// Ŝ and which earlier block it repeats (see [`pseudo_inverse`]).
struct Equilibrated {
    scale: Vec<f64>,
    blocks: Vec<Vec<usize>>,
    mats: Vec<Mat<f64>>,
    same_as: Vec<Option<usize>>,
}

fn equilibrated(s: &Mat<f64>) -> Equilibrated {
    let m = s.nrows();
    let scale: Vec<f64> = (0..m)
        .map(|i| {
            if s[(i, i)] > 0.0 && s[(i, i)].is_finite() {
                1.0 / s[(i, i)].sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let scaled = Mat::<f64>::from_fn(m, m, |i, j| s[(i, j)] * scale[i] * scale[j]);
    let blocks = independent_blocks(&scaled);
    let mats: Vec<Mat<f64>> = blocks
        .iter()
        .map(|b| Mat::<f64>::from_fn(b.len(), b.len(), |i, j| scaled[(b[i], b[j])]))
        .collect();
    let same_as: Vec<Option<usize>> = (0..blocks.len())
        .map(|k| (0..k).find(|&e| same_as_earlier(&mats[e], &mats[k])))
        .collect();
    Equilibrated {
        scale,
        blocks,
        mats,
        same_as,
    }
}

/// S⁻¹ (row-major) by Cholesky, block by block, when S is provably well
/// conditioned ([`well_conditioned_blocks`]); `None` otherwise.
fn blockwise_inverse(
    m: usize,
    scale: &[f64],
    blocks: &[Vec<usize>],
    mats: &[Mat<f64>],
    same_as: &[Option<usize>],
) -> Option<Vec<f64>> {
    if scale.contains(&0.0) {
        return None;
    }
    let inverses = well_conditioned_blocks(mats, same_as)?;
    let mut out = vec![0.0; m * m];
    for (b, inv) in blocks.iter().zip(&inverses) {
        for (i, &bi) in b.iter().enumerate() {
            for (j, &bj) in b.iter().enumerate() {
                out[bi * m + bj] = inv[(i, j)] * scale[bi] * scale[bj];
            }
        }
    }
    Some(out)
}

/// The Cholesky path of [`pseudo_inverse`] alone: S⁻¹ (row-major) when S
/// is provably well conditioned, `None` (no eigendecomposition) otherwise.
fn cholesky_inverse(s: &Mat<f64>) -> Option<Vec<f64>> {
    let m = s.nrows();
    if m == 0 {
        return Some(Vec::new());
    }
    let e = equilibrated(s);
    blockwise_inverse(m, &e.scale, &e.blocks, &e.mats, &e.same_as)
}

/// The independent blocks of the symmetric `a`: the connected components of
/// its non-zero pattern, each as ascending indices, in the order of their
/// smallest index.
fn independent_blocks(a: &Mat<f64>) -> Vec<Vec<usize>> {
    let m = a.nrows();
    let mut block = vec![usize::MAX; m];
    let mut blocks: Vec<Vec<usize>> = Vec::new();
    for start in 0..m {
        if block[start] != usize::MAX {
            continue;
        }
        let id = blocks.len();
        block[start] = id;
        let mut members = vec![start];
        let mut next = 0;
        while next < members.len() {
            let i = members[next];
            next += 1;
            for j in 0..m {
                if block[j] == usize::MAX && a[(i, j)] != 0.0 {
                    block[j] = id;
                    members.push(j);
                }
            }
        }
        members.sort_unstable();
        blocks.push(members);
    }
    blocks
}

/// Whether `b` is entry for entry the matrix `a`.
fn same_as_earlier(a: &Mat<f64>, b: &Mat<f64>) -> bool {
    a.nrows() == b.nrows() && (0..a.nrows()).all(|i| (0..a.ncols()).all(|j| a[(i, j)] == b[(i, j)]))
}

/// Bound on the 2-norm condition number of Ŝ below which S is inverted by
/// Cholesky instead of an eigendecomposition (a fraction of the cost). A
/// decade below the eigenvalue cut-off (1e12): no eigen-direction the
/// pseudo-inverse would drop can take this path, so both give the same S⁺.
const CHOLESKY_CONDITION_LIMIT: f64 = 1e11;

/// Ŝ⁻¹ block by block when Ŝ is provably well conditioned: for a
/// symmetric matrix ‖·‖₂ ≤ ‖·‖∞, so ‖Ŝ‖∞ · ‖Ŝ⁻¹‖∞ bounds cond₂(Ŝ) from
/// above, and for a block-diagonal Ŝ both norms are the largest of its
/// blocks'. `None` (use the eigendecomposition) when a Cholesky
/// factorisation fails or the bound exceeds [`CHOLESKY_CONDITION_LIMIT`].
/// A block that repeats an earlier one (`same_as`) shares its inverse.
fn well_conditioned_blocks(mats: &[Mat<f64>], same_as: &[Option<usize>]) -> Option<Vec<Mat<f64>>> {
    use faer::linalg::solvers::DenseSolveCore;
    let inf_norm = |a: &Mat<f64>| {
        (0..a.nrows())
            .map(|i| (0..a.ncols()).map(|j| a[(i, j)].abs()).sum::<f64>())
            .fold(0.0f64, f64::max)
    };
    let mut inverses: Vec<Mat<f64>> = Vec::with_capacity(mats.len());
    let (mut norm, mut inv_norm) = (0.0f64, 0.0f64);
    for (k, a) in mats.iter().enumerate() {
        let inverse = match same_as[k] {
            Some(e) => inverses[e].clone(),
            None => {
                let inverse = a.llt(faer::Side::Lower).ok()?.inverse();
                let n = a.nrows();
                Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (inverse[(i, j)] + inverse[(j, i)]))
            }
        };
        norm = norm.max(inf_norm(a));
        inv_norm = inv_norm.max(inf_norm(&inverse));
        inverses.push(inverse);
    }
    let bound = norm * inv_norm;
    (bound.is_finite() && bound < CHOLESKY_CONDITION_LIMIT).then_some(inverses)
}

/// `y[i].x = Σ_j K_ij x_j` and `y_abs[i].x = Σ_j |K_ij| |x_j|` (the
/// other coordinates left as they are), in one pass over the lower
/// triangle of the symmetric `k`: the x field of
/// [`Stiffness::mul_points_with_bound`] for a field that is zero on y and
/// z, with the same terms summed in the same order.
fn mul_with_bound_x(k: &Stiffness, x: &[f64], y: &mut [DVec3], y_abs: &mut [DVec3]) {
    let lower = k.lower();
    let s = lower.symbolic();
    let (cp, ri, v) = (s.col_ptr(), s.row_idx(), lower.val());
    for c in 0..x.len() {
        let xc = x[c];
        let xc_abs = xc.abs();
        let mut acc = 0.0;
        let mut acc_abs = 0.0;
        for (&r, &a) in ri[cp[c]..cp[c + 1]].iter().zip(&v[cp[c]..cp[c + 1]]) {
            y[r].x += xc * a;
            y_abs[r].x += xc_abs * a.abs();
            if r != c {
                acc += x[r] * a;
                acc_abs += x[r].abs() * a.abs();
            }
        }
        y[c].x += acc;
        y_abs[c].x += acc_abs;
    }
}

/// Most steps of iterative refinement per solve (see
/// `Solver::refined_deltas`); it stops earlier when a step gains less than
/// half.
const MAX_REFINEMENT_STEPS: usize = 12;

/// Componentwise backward error (see `Solver::residuals`) below which a
/// residual is the rounding of its own computation: a sum of ~50 stiffness
/// terms and a few constraint and load terms is exact to ~60 units of
/// round-off (6.7e-15) at worst, so iterative refinement stops there (the
/// usual Oettli–Prager stopping rule): a step would add noise, not digits.
const NOISE_BACKWARD_ERROR: f64 = 1e-14;

/// Most new rows whose forward halves are solved column by column
/// (`Factor::forward_sparse`, the Gram by sparse products); more go
/// through `Factor::forward_batch` (dense blocks per supernode).
const LAZY_COLUMNS: usize = 8;

/// Most pending columns of Z (see `Solver::pending`) solved in one batch
/// when Z is first read (the first solve that moves the shape, the first
/// grab): then Σ w_c z_c is a pass over Z, and every later solve costs no
/// sparse solve for it — the paper's straight curve (81 rows on 81 × 159)
/// is paid once, not at every solve (measured: through combined rows
/// `constraint_change_moving` took 2.2× as long). With more, Z is never
/// read (see `Solver::z_is_whole`): a free-form cubic's 415 columns on
/// 81 × 159 took ~1 s of full solves (loaded, load 5).
const SOLVED_WHEN_READ: usize = 128;

/// Memory for retired columns (see [`Solver`]): 160 columns at 81 × 159.
const RETIRED_BYTES: usize = 16 << 20;

/// `inverse` (an S⁻¹ from block updates) as the row-major S⁻¹ when it is
/// provably well conditioned and accurate: the bound of
/// [`well_conditioned_blocks`] on the equilibrated Ŝ, and
/// ‖Ŝ Ŝ⁻¹ v − v‖∞ ≤ 1e-6 ‖v‖∞ for two probe vectors (an inverse that
/// good makes each constraint-projection step of the refinement gain six
/// digits; the refinement then meets the equations as with a fresh one).
fn checked_inverse(s: &Mat<f64>, inverse: &Mat<f64>) -> Option<Vec<f64>> {
    let m = s.nrows();
    let mut scale = Vec::with_capacity(m);
    for i in 0..m {
        let d = s[(i, i)];
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        scale.push(1.0 / d.sqrt());
    }
    let scaled = |i: usize, j: usize| s[(i, j)] * scale[i] * scale[j];
    let scaled_inv = |i: usize, j: usize| inverse[(i, j)] / (scale[i] * scale[j]);
    let norm = |f: &dyn Fn(usize, usize) -> f64| {
        (0..m)
            .map(|i| (0..m).map(|j| f(i, j).abs()).sum::<f64>())
            .fold(0.0f64, f64::max)
    };
    let bound = norm(&scaled) * norm(&scaled_inv);
    if !(bound.is_finite() && bound < CHOLESKY_CONDITION_LIMIT) {
        return None;
    }
    for probe in 0..2 {
        let v: Vec<f64> = (0..m)
            .map(|i| {
                if probe == 0 {
                    1.0
                } else {
                    ((i * 7 + 3) % 11) as f64 / 5.0 - 1.0
                }
            })
            .collect();
        let x: Vec<f64> = (0..m)
            .map(|i| (0..m).map(|j| scaled_inv(i, j) * v[j]).sum())
            .collect();
        let worst = (0..m)
            .map(|i| ((0..m).map(|j| scaled(i, j) * x[j]).sum::<f64>() - v[i]).abs())
            .fold(0.0f64, f64::max);
        let size = v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        if worst.is_nan() || worst > 1e-6 * size {
            return None;
        }
    }
    Some(
        (0..m)
            .flat_map(|i| (0..m).map(move |j| (i, j)))
            .map(|(i, j)| 0.5 * (inverse[(i, j)] + inverse[(j, i)]))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The x-only product used for a symmetric response's residual is the
    /// x field of the three-coordinate one, bit for bit (same terms, same
    /// order), and leaves y and z alone.
    #[test]
    fn the_x_only_product_is_the_three_coordinate_one() {
        let s = crate::bspline::BSplineSurface::plane(1.0, 2.0, 9, 7, 3).unwrap();
        let k = Stiffness::surface(
            s.u_knots(),
            s.v_knots(),
            &crate::energy::SurfaceMaterial::default(),
        )
        .unwrap();
        let n = k.dim();
        let x: Vec<f64> = (0..n).map(|i| ((i * 13) % 7) as f64 - 3.1).collect();
        let points: Vec<DVec3> = x.iter().map(|&v| DVec3::new(v, 0.0, 0.0)).collect();
        let (mut y, mut y_abs) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        k.mul_points_with_bound(&points, &mut y, &mut y_abs);
        let (mut yx, mut yx_abs) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        mul_with_bound_x(&k, &x, &mut yx, &mut yx_abs);
        for i in 0..n {
            assert_eq!(yx[i].x.to_bits(), y[i].x.to_bits());
            assert_eq!(yx_abs[i].x.to_bits(), y_abs[i].x.to_bits());
            assert_eq!(
                (yx[i].y, yx[i].z, yx_abs[i].y, yx_abs[i].z),
                (0.0, 0.0, 0.0, 0.0)
            );
        }
        assert!(y.iter().any(|v| v.x != 0.0));
    }

    /// A well-conditioned SPD matrix (Cholesky path) and a singular one
    /// (eigendecomposition path): S S⁺ S = S and S⁺ symmetric in both, the
    /// inverse exact in the first, the dependent direction dropped in the
    /// second.
    #[test]
    fn pseudo_inverse_takes_the_fast_path_only_when_it_is_exact() {
        let m = 12;
        let b = Mat::<f64>::from_fn(m, m, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 - 2.0 + (i == j) as u8 as f64 * 6.0
        });
        let spd = &b * b.transpose();
        // Two equal rows/columns: rank m − 1.
        let mut singular = spd.clone();
        for j in 0..m {
            singular[(m - 1, j)] = singular[(0, j)];
        }
        for i in 0..m {
            singular[(i, m - 1)] = singular[(i, 0)];
        }
        singular[(m - 1, m - 1)] = singular[(0, 0)];
        for (s, rank_drop) in [(&spd, 0), (&singular, 1)] {
            let scale: Vec<f64> = (0..m).map(|i| 1.0 / s[(i, i)].sqrt()).collect();
            let scaled = Mat::<f64>::from_fn(m, m, |i, j| s[(i, j)] * scale[i] * scale[j]);
            assert_eq!(
                well_conditioned_blocks(&[scaled], &[None]).is_some(),
                rank_drop == 0
            );
            let (p, dropped, fast) = pseudo_inverse(s).unwrap();
            assert_eq!(fast, rank_drop == 0);
            assert_eq!(dropped, rank_drop);
            let p = Mat::<f64>::from_fn(m, m, |i, j| p[i * m + j]);
            let sps = s * &p * s;
            let norm = (0..m).map(|i| s[(i, i)]).fold(0.0f64, f64::max);
            for i in 0..m {
                for j in 0..m {
                    assert!((sps[(i, j)] - s[(i, j)]).abs() < 1e-9 * norm, "S S⁺ S ≠ S");
                    assert!((p[(i, j)] - p[(j, i)]).abs() < 1e-9 * p[(i, i)].abs().max(1e-9));
                }
            }
        }
    }

    /// The pseudo-inverse of a matrix whose zeros split it into blocks
    /// (x, y and z equations interleaved, as a vector equation's three
    /// rows are, plus a block coupling two coordinates) equals the
    /// pseudo-inverse of the whole by one eigendecomposition with the same
    /// cut-off, computed here without blocks; with a redundant equation in
    /// one coordinate it drops exactly that one direction per block it
    /// appears in.
    #[test]
    fn blockwise_pseudo_inverse_equals_the_whole() {
        let n = 7;
        let b = Mat::<f64>::from_fn(n, n, |i, j| {
            ((i * 5 + j * 3) % 7) as f64 - 3.0 + (i == j) as u8 as f64 * 5.0
        });
        let mut g = &b * b.transpose();
        for redundant in [false, true] {
            if redundant {
                // Equation n − 1 repeats equation 0.
                for j in 0..n {
                    g[(n - 1, j)] = g[(0, j)];
                    g[(j, n - 1)] = g[(j, 0)];
                }
                g[(n - 1, n - 1)] = g[(0, 0)];
            }
            // 3n interleaved rows (x, y, z of n vector equations), then a
            // 2 × 2 block of its own.
            let m = 3 * n + 2;
            let s = Mat::<f64>::from_fn(m, m, |i, j| {
                if i < 3 * n && j < 3 * n {
                    if i % 3 == j % 3 {
                        g[(i / 3, j / 3)]
                    } else {
                        0.0
                    }
                } else if i >= 3 * n && j >= 3 * n {
                    [[4.0, 1.0], [1.0, 3.0]][i - 3 * n][j - 3 * n]
                } else {
                    0.0
                }
            });
            assert_eq!(independent_blocks(&s).len(), 4);
            let (p, dropped, fast) = pseudo_inverse(&s).unwrap();
            assert_eq!(dropped, if redundant { 3 } else { 0 });
            assert_eq!(fast, !redundant);
            // The whole, by one eigendecomposition.
            let d: Vec<f64> = (0..m).map(|i| 1.0 / s[(i, i)].sqrt()).collect();
            let scaled = Mat::<f64>::from_fn(m, m, |i, j| s[(i, j)] * d[i] * d[j]);
            let evd = scaled.self_adjoint_eigen(faer::Side::Lower).unwrap();
            let lam = evd.S();
            let max = (0..m).map(|k| lam[k].abs()).fold(0.0f64, f64::max);
            let whole = Mat::<f64>::from_fn(m, m, |i, j| {
                (0..m)
                    .filter(|&k| lam[k] > 1e-12 * max)
                    .map(|k| evd.U()[(i, k)] * evd.U()[(j, k)] / lam[k])
                    .sum::<f64>()
                    * d[i]
                    * d[j]
            });
            let size = (0..m * m).map(|k| p[k].abs()).fold(0.0f64, f64::max);
            for i in 0..m {
                for j in 0..m {
                    assert!(
                        (p[i * m + j] - whole[(i, j)]).abs() <= 1e-9 * size,
                        "({i}, {j}): {} against {}",
                        p[i * m + j],
                        whole[(i, j)]
                    );
                }
            }
        }
    }
}
