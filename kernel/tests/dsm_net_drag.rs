//! A net node drag solved by updating the drag's first factorisation
//! (Sherman–Morrison–Woodbury) against a from-scratch inverse transformation of
//! the same net, frame by frame; refused heights change nothing.

use glam::DVec2;
use vsculpt_kernel::dsm::*;

fn net(n: usize) -> PassingPointsNet {
    let heights: Vec<f64> = (0..n * n)
        .map(|k| 1.0 + 0.4 * (0.5 * (k % n) as f64).sin() * (0.3 * (k / n) as f64).cos())
        .collect();
    PassingPointsNet::regular(DVec2::ZERO, DVec2::splat(0.25), n, n, &heights).unwrap()
}

#[test]
fn drag_frames_match_a_fresh_inverse_transformation() {
    let n = 12;
    let base = net(n);
    let opts = InverseOptions::for_net(&base, 1.0);
    for node in [5 * n + 6, n + 1, 2 * n + n - 2] {
        let (mut drag, _) = NetDrag::start(base.clone(), opts, node).unwrap();
        let mut updated = 0;
        for step in 0..12 {
            let h = 1.0 + 0.05 * step as f64;
            let (s, info) = drag.set_height(h).unwrap();
            if !info.refactorised {
                updated += 1;
            }
            let mut reference = base.clone();
            reference.set_height(node, h).unwrap();
            assert_eq!(drag.net(), &reference);
            let (r, _) = inverse_transform(&reference, &opts).unwrap();
            // The node passes where it was dragged, like the rest.
            assert!(
                (s.height(reference.nodes()[node].truncate()).unwrap() - h).abs()
                    <= 1e-9 * reference.size()
            );
            // Same surface between the nodes.
            for j in 0..=40 {
                for i in 0..=40 {
                    let p = DVec2::new(i as f64, j as f64) * (0.25 * (n - 1) as f64 / 40.0);
                    let (a, b) = (s.height(p).unwrap(), r.height(p).unwrap());
                    assert!((a - b).abs() <= 1e-8 * reference.size(), "{p}: {a} vs {b}");
                }
            }
        }
        assert!(updated >= 10, "only {updated} frames used the update");
    }
}

#[test]
fn a_refused_height_changes_nothing() {
    let base = net(6);
    let opts = InverseOptions::for_net(&base, 1.0);
    let (mut drag, _) = NetDrag::start(base.clone(), opts, 14).unwrap();
    drag.set_height(1.3).unwrap();
    let before = drag.net().clone();
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(drag.set_height(h).is_err());
        assert_eq!(drag.net(), &before);
    }
    assert!(NetDrag::start(base, opts, 99).is_err());
}
