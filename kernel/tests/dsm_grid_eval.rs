//! The separable grid evaluation of D(u, v) and h(u, v) (used by the height-field
//! mesh and the inverse transformation's report) against the point-by-point jets,
//! at every node of grids that do and do not line up with the charges, with and
//! without a connecting function.

use glam::DVec2;
use vsculpt_kernel::dsm::*;

fn surface(connect: bool) -> EqualDensitySurface {
    let n = 9;
    let heights: Vec<f64> = (0..n * n)
        .map(|k| 1.0 + 0.5 * (0.9 * (k % n) as f64).sin() * (0.7 * (k / n) as f64).cos())
        .collect();
    let net =
        PassingPointsNet::regular(DVec2::new(-1.0, 0.5), DVec2::new(0.3, 0.4), n, n, &heights)
            .unwrap();
    let (mut s, _) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.3)).unwrap();
    if connect {
        let (lo, hi) = net.uv_box();
        s.connect = Some(Connecting::to_plane(lo, hi, 0.5).unwrap());
    }
    s
}

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-11 * scale.max(1.0)
}

#[test]
fn grid_jets_equal_point_jets_at_every_node() {
    for connect in [false, true] {
        let s = surface(connect);
        // A grid wider than the net (charges' disks cut by its edges) at a spacing
        // unrelated to the net's.
        let (lo, hi) = (DVec2::new(-1.7, 0.1), DVec2::new(2.3, 4.1));
        let (nu, nv) = (37, 23);
        let grid = s.jets_on_grid(lo, hi, nu, nv);
        assert_eq!(grid.len(), (nu + 1) * (nv + 1));
        let mut compared = 0;
        for j in 0..=nv {
            for i in 0..=nu {
                let p = lo + (hi - lo) * DVec2::new(i as f64 / nu as f64, j as f64 / nv as f64);
                let g = grid[j * (nu + 1) + i];
                match (s.jet(p), g) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        let sc = a.value.abs()
                            + a.grad.length()
                            + a.hess.abs().to_cols_array().iter().sum::<f64>();
                        assert!(
                            close(a.value, b.value, sc),
                            "h at {p}: {} vs {}",
                            a.value,
                            b.value
                        );
                        assert!(
                            close(a.grad.x, b.grad.x, sc) && close(a.grad.y, b.grad.y, sc),
                            "grad at {p}"
                        );
                        for (x, y) in a.hess.to_cols_array().iter().zip(b.hess.to_cols_array()) {
                            assert!(close(*x, y, sc), "hessian at {p}: {x} vs {y}");
                        }
                        compared += 1;
                    }
                    (a, b) => panic!("defined differently at {p}: {a:?} vs {b:?}"),
                }
            }
        }
        assert!(
            compared > (nu + 1) * (nv + 1) / 2,
            "only {compared} nodes compared"
        );
    }
}

#[test]
fn height_mesh_vertices_are_the_surface() {
    let s = surface(false);
    let (lo, hi) = (DVec2::new(-0.7, 0.9), DVec2::new(1.1, 3.3));
    let m = s.mesh(lo, hi, 19, 13).unwrap();
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let c = s.curvature(p.truncate()).unwrap();
        assert!((s.height(p.truncate()).unwrap() - p.z).abs() <= 1e-11 * p.z.abs().max(1.0));
        assert!((c.normal - *n).length() <= 1e-11);
    }
}
