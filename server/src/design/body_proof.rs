//! Injectivity proofs of body lattices kept between checks (issue 13).
//!
//! One `body_edit` proves the edited body's det J > 0 where the edit is
//! checked (`BodyPart::move_points`), again where the document is
//! validated, and where the body's engine is rebuilt: three proofs of the
//! same lattice, each of every knot-span cell (tens of milliseconds for a
//! tricubic 8³ lattice). The kernel's [`InjectivityCache`] keeps a proof
//! per cell and proves again only the cells whose control points changed,
//! with the verdict and the fold reported of a fresh proof; here a few
//! caches are kept process-wide (one per body being edited, most recently
//! used first), so that the second and third proofs of a lattice cost a
//! comparison of its points, and an edit moving one point proves only the
//! cells that point reaches.
//!
//! A cache is taken out of the pool while it proves (no lock is held
//! during a proof: designs prove in parallel) and put back in front.

use std::sync::Mutex;
use vsculpt_kernel::body::{BSplineVolume, BodyError, InjectivityCache, InjectivityReport};

/// Caches kept (bodies edited at once across designs before the least
/// recently used is dropped).
pub const KEPT: usize = 8;

static POOL: Mutex<Vec<InjectivityCache>> = Mutex::new(Vec::new());

/// Proves det J > 0 for `vol` (as `vsculpt_kernel::body::check_injective`,
/// same verdict and fold), reusing the kept proof of the most similar
/// lattice.
pub fn prove(vol: &BSplineVolume) -> Result<InjectivityReport, BodyError> {
    let mut cache = take(vol);
    let result = cache.check(vol);
    if cache.last().is_some() {
        let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
        pool.insert(0, cache);
        pool.truncate(KEPT);
    }
    result
}

/// The kept cache with the fewest cells changed for `vol` (removed from the
/// pool), or a new one.
fn take(vol: &BSplineVolume) -> InjectivityCache {
    let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
    let best = pool
        .iter()
        .enumerate()
        .map(|(i, c)| (i, c.changed_cells(vol)))
        .min_by_key(|&(_, n)| n);
    match best {
        Some((i, _)) => pool.remove(i),
        None => InjectivityCache::default(),
    }
}

/// Drops every kept proof: the next proofs are made from scratch (to
/// measure what keeping them buys, or to free their memory).
pub fn forget() {
    POOL.lock().unwrap_or_else(|e| e.into_inner()).clear();
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use vsculpt_kernel::body::check_injective;

    #[test]
    fn kept_proofs_refuse_and_accept_as_fresh_ones() {
        let base = BSplineVolume::affine(
            DVec3::ZERO,
            [DVec3::X, DVec3::Y, DVec3::Z],
            [3, 3, 3],
            [5, 5, 5],
        )
        .unwrap();
        let idx = base.index(2, 2, 2);
        let at = |d: DVec3| {
            let mut v = base.clone();
            v.set_point(idx, base.points()[idx] + d).unwrap();
            v
        };
        // Proved, then a small move (kept proofs), a fold, the small move
        // again (its proof kept whole), and another body in between.
        let other = at(DVec3::new(0.0, 0.05, 0.0));
        for v in [
            base.clone(),
            at(DVec3::new(0.05, 0.0, 0.0)),
            at(DVec3::new(0.0, 0.0, 3.0)),
            other.clone(),
            at(DVec3::new(0.05, 0.0, 0.0)),
            other,
        ] {
            assert_eq!(
                prove(&v).map(|r| r.cells),
                check_injective(&v).map(|r| r.cells)
            );
        }
        assert!(prove(&at(DVec3::new(0.0, 0.0, 3.0))).is_err());
    }
}
