//! The drag fast path of `PatchSampler` (ribbon values kept per side and
//! re-evaluated only for the sides whose data changed) against the
//! straightforward evaluation: at random drags of random control points of
//! the bottle's curves, mixed with handle edits, every sample equals
//! `Patch::point` at its domain point to 1e-13 and equals, bit for bit, the
//! same sampler made to re-evaluate every side; and a local drag really
//! skips the sides it does not touch.

use glam::DVec3;
use vsculpt_kernel::network::PatchSampler;
use vsculpt_kernel::network::demo::bottle;

/// A small deterministic generator (the test must not depend on a seed
/// the code under test sees).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

#[test]
fn kept_ribbon_values_equal_a_full_re_evaluation_at_random_drags() {
    let mut net = bottle().unwrap();
    let mut fast: Vec<PatchSampler> = net
        .patches()
        .iter()
        .map(|p| PatchSampler::new(p, 7))
        .collect();
    let mut full = fast.clone();
    let mut rng = Lcg(20261124);
    let (mut accepted, mut skipped_sides, mut refreshed_sides) = (0, 0, 0);
    for round in 0..40 {
        match round % 5 {
            // Mostly drags of one control point.
            0..=2 => {
                let c = rng.below(net.curves().len());
                let mut curve = net.curves()[c].clone();
                let k = rng.below(curve.points().len());
                let d = DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
                curve.points_mut()[k] += d * 0.04;
                if net.set_curve(c, curve).is_ok() {
                    accepted += 1;
                }
            }
            3 => {
                let e = rng.below(net.topology().edges.len());
                net.set_twist(e, (rng.next() - 0.5) * 0.4).unwrap();
            }
            _ => {
                let f = rng.below(net.faces().len());
                let n = net.faces()[f].sides.len();
                net.set_scale(f, rng.below(n), 0.7 + rng.next()).unwrap();
                let h = (0..=n)
                    .map(|_| DVec3::new(rng.next(), rng.next(), rng.next()) * 0.02)
                    .collect();
                net.set_tuning(f, h).unwrap();
            }
        }
        for (f, (s, r)) in fast.iter_mut().zip(full.iter_mut()).enumerate() {
            let p = net.patch(f).unwrap();
            let (mut a, mut b) = (Vec::new(), Vec::new());
            assert!(s.evaluate(&p, &mut a));
            r.invalidate();
            assert!(r.evaluate(&p, &mut b));
            assert!(r.refreshed().iter().all(|x| *x));
            assert_eq!(a, b, "round {round} face {f}: kept values differ");
            for (q, x) in s.mesh().points.iter().zip(&a) {
                let e = (p.point(*q) - *x).length();
                assert!(e < 1e-13, "round {round} face {f}: {e:.2e}");
            }
            for x in s.refreshed() {
                if *x {
                    refreshed_sides += 1;
                } else {
                    skipped_sides += 1;
                }
            }
        }
    }
    println!(
        "{accepted} drags accepted; sides re-evaluated {refreshed_sides}, kept {skipped_sides}"
    );
    assert!(accepted >= 10, "only {accepted} drags accepted");
    assert!(refreshed_sides > 0 && skipped_sides > 0);
}

#[test]
fn a_local_drag_re_evaluates_only_the_sides_it_touches() {
    let mut net = bottle().unwrap();
    let mut samplers: Vec<PatchSampler> = net
        .patches()
        .iter()
        .map(|p| PatchSampler::new(p, 6))
        .collect();
    let mut out = Vec::new();
    for (f, s) in samplers.iter_mut().enumerate() {
        assert!(s.evaluate(&net.patch(f).unwrap(), &mut out));
    }
    // The bottom ring's middle control point: its support is the middle of
    // the label face's bottom side, away from every meeting.
    let mut ring = net.curves()[0].clone();
    let k = ring.points().len() / 2;
    ring.points_mut()[k] += DVec3::new(0.03, 0.0, 0.0);
    net.set_curve(0, ring).unwrap();
    let mut refreshed = Vec::new();
    for (f, s) in samplers.iter_mut().enumerate() {
        let p = net.patch(f).unwrap();
        assert!(s.evaluate(&p, &mut out));
        for (q, x) in s.mesh().points.iter().zip(&out) {
            assert!((p.point(*q) - *x).length() < 1e-13);
        }
        refreshed.extend(
            s.refreshed()
                .iter()
                .enumerate()
                .filter(|x| *x.1)
                .map(|(i, _)| (f, i)),
        );
    }
    assert_eq!(refreshed.len(), 1, "sides re-evaluated: {refreshed:?}");
    let (f, i) = refreshed[0];
    assert_eq!(net.faces()[f].sides.len(), 5, "the label face");
    assert_eq!(net.faces()[f].sides[i].curve, 0, "its bottom side");
}
