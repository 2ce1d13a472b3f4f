//! Curvature from local quadric fits against analytic surfaces (sphere,
//! cylinder, saddle) on irregular point meshes: a jittered grid whose
//! squares are split by randomly chosen diagonals (valences 4 to 8), points
//! lying exactly on the surface. The 2-ring fit (the default) is compared
//! with the 1-ring fit; both figures are printed.

use glam::{DVec2, DVec3};
use vsculpt_kernel::fairing::{Neighbourhood, PointMesh, estimate};

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
}

/// An irregular mesh of `f` over [a, b] with `k × k` squares; returns the
/// mesh and each point's parameters.
fn irregular(
    f: &dyn Fn(DVec2) -> DVec3,
    a: DVec2,
    b: DVec2,
    k: usize,
    seed: u64,
) -> (PointMesh, Vec<DVec2>) {
    let mut rng = Lcg(seed);
    let h = (b - a) / k as f64;
    let mut params = Vec::new();
    let mut boundary = Vec::new();
    for i in 0..=k {
        for j in 0..=k {
            let on_edge = i == 0 || j == 0 || i == k || j == k;
            let mut p = a + DVec2::new(i as f64 * h.x, j as f64 * h.y);
            if !on_edge {
                p += DVec2::new(
                    (rng.next() - 0.5) * 0.7 * h.x,
                    (rng.next() - 0.5) * 0.7 * h.y,
                );
            }
            params.push(p);
            boundary.push(on_edge);
        }
    }
    let id = |i: usize, j: usize| (i * (k + 1) + j) as u32;
    let mut tris = Vec::new();
    for i in 0..k {
        for j in 0..k {
            let (p00, p10, p01, p11) = (id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1));
            if rng.next() < 0.5 {
                tris.push([p00, p10, p11]);
                tris.push([p00, p11, p01]);
            } else {
                tris.push([p00, p10, p01]);
                tris.push([p10, p11, p01]);
            }
        }
    }
    let points = params.iter().map(|p| f(*p)).collect();
    (PointMesh::new(points, tris, boundary).unwrap(), params)
}

/// Max and RMS errors of H and K at points at least 3 squares from the edge.
fn errors(
    mesh: &PointMesh,
    params: &[DVec2],
    k: usize,
    exact: &dyn Fn(DVec2) -> (f64, f64),
    hood: Neighbourhood,
) -> (f64, f64, f64, f64) {
    let c = estimate(mesh, hood).unwrap();
    let (mut mh, mut mk, mut sh, mut sk, mut n) = (0.0f64, 0.0f64, 0.0, 0.0, 0);
    for idx in 0..mesh.len() {
        let (i, j) = (idx / (k + 1), idx % (k + 1));
        if i < 3 || j < 3 || i + 3 > k || j + 3 > k {
            continue;
        }
        let (h, g) = exact(params[idx]);
        let (eh, ek) = ((c[idx].mean - h).abs(), (c[idx].gaussian - g).abs());
        mh = mh.max(eh);
        mk = mk.max(ek);
        sh += eh * eh;
        sk += ek * ek;
        n += 1;
    }
    (mh, (sh / n as f64).sqrt(), mk, (sk / n as f64).sqrt())
}

fn check(
    name: &str,
    f: &dyn Fn(DVec2) -> DVec3,
    exact: &dyn Fn(DVec2) -> (f64, f64),
    a: DVec2,
    b: DVec2,
    bound_h: f64,
    bound_k: f64,
) {
    let k = 40;
    let (mesh, params) = irregular(f, a, b, k, 7);
    let e2 = errors(&mesh, &params, k, exact, Neighbourhood::Ring2);
    let e1 = errors(&mesh, &params, k, exact, Neighbourhood::Ring1);
    println!(
        "{name}: 2-ring H max {:.2e} rms {:.2e}, K max {:.2e} rms {:.2e}; 1-ring H max {:.2e} rms {:.2e}, K max {:.2e} rms {:.2e}",
        e2.0, e2.1, e2.2, e2.3, e1.0, e1.1, e1.2, e1.3
    );
    assert!(e2.0 < bound_h && e2.2 < bound_k, "{name}: {e2:?}");
    // The 2-ring cubic fit is the better estimator on irregular meshes (why
    // it is the default): smaller worst errors than the 1-ring quadric.
    assert!(
        e2.0 < e1.0 && e2.2 < e1.2,
        "{name}: 2-ring {e2:?} vs 1-ring {e1:?}"
    );
}

#[test]
fn sphere_curvature_on_an_irregular_mesh() {
    let r = 2.0;
    // Outward normals need (θ, φ) counter-clockwise seen from outside.
    let f = move |p: DVec2| {
        DVec3::new(
            r * p.y.cos() * p.x.cos(),
            r * p.y.cos() * p.x.sin(),
            r * p.y.sin(),
        )
    };
    let exact = move |_: DVec2| (1.0 / r, 1.0 / (r * r));
    check(
        "sphere R=2",
        &f,
        &exact,
        DVec2::new(-0.6, -0.6),
        DVec2::new(0.6, 0.6),
        2e-3,
        2e-3,
    );
}

#[test]
fn cylinder_curvature_on_an_irregular_mesh() {
    let r = 1.5;
    let f = move |p: DVec2| DVec3::new(r * p.x.cos(), r * p.x.sin(), p.y);
    let exact = move |_: DVec2| (0.5 / r, 0.0);
    check(
        "cylinder R=1.5",
        &f,
        &exact,
        DVec2::new(-0.8, -1.0),
        DVec2::new(0.8, 1.0),
        2e-3,
        2e-3,
    );
}

#[test]
fn saddle_curvature_on_an_irregular_mesh() {
    // z = (x² − y²)/2 with the upward normal.
    let f = |p: DVec2| DVec3::new(p.x, p.y, 0.5 * (p.x * p.x - p.y * p.y));
    let exact = |p: DVec2| {
        let (fx, fy) = (p.x, -p.y);
        let (fxx, fyy, fxy) = (1.0, -1.0, 0.0);
        let w2: f64 = 1.0 + fx * fx + fy * fy;
        let hm = (fxx * (1.0 + fy * fy) - 2.0 * fx * fy * fxy + fyy * (1.0 + fx * fx))
            / (2.0 * w2 * w2.sqrt());
        let k = (fxx * fyy - fxy * fxy) / (w2 * w2);
        (-hm, k)
    };
    check(
        "saddle",
        &f,
        &exact,
        DVec2::new(-1.0, -1.0),
        DVec2::new(1.0, 1.0),
        5e-3,
        5e-3,
    );
}
