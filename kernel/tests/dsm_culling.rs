//! Culling by influence range: the error it puts into the field and the surface is
//! within the documented bound (n·τ·D_e in the field, n·τ·D_e/|∇f| in the surface),
//! and the interval classification used to skip space is sound.

use glam::DVec3;
use vsculpt_kernel::dsm::*;

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn vec(&mut self, s: f64) -> DVec3 {
        DVec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * 2.0 * s
    }
}

fn blobs(tau: f64) -> Model {
    let mut rng = Lcg(3);
    let mut m = Model::new(1.0, tau).unwrap();
    let mut density = Vec::new();
    for i in 0..12 {
        let c = rng.vec(3.0);
        density.push(match i % 3 {
            0 => DensityPrimitive::sphere(c, 2.0 + rng.next(), 1.0 + rng.next()).unwrap(),
            1 => DensityPrimitive::blobby(c, 1.5 + rng.next(), 0.8 + rng.next()).unwrap(),
            _ => DensityPrimitive::pipe(c, c + rng.vec(1.0), 1.5, 1.2).unwrap(),
        });
    }
    m.add(Group {
        density,
        ..Default::default()
    })
    .unwrap();
    m
}

fn exact(m: &Model, p: DVec3) -> f64 {
    m.groups()[0]
        .density
        .iter()
        .map(|d| d.value(p, f64::INFINITY))
        .sum()
}

#[test]
fn culled_field_error_is_below_n_tau_de() {
    let tau = 1e-3;
    let m = blobs(tau);
    let n = m.groups()[0].density.len() as f64;
    let mut rng = Lcg(11);
    let mut seen: f64 = 0.0;
    for _ in 0..20000 {
        let p = rng.vec(6.0);
        let err = (m.density_sum(0, p) - exact(&m, p)).abs();
        assert!(err <= n * tau * m.de(), "culling error {err}");
        seen = seen.max(err);
    }
    assert!(
        seen > 0.0,
        "culling never changed the field: the test is vacuous"
    );
}

#[test]
fn culled_surface_moves_by_at_most_n_tau_de_over_gradient() {
    let tau = 1e-3;
    let m = blobs(tau);
    let n = m.groups()[0].density.len() as f64;
    let mut rng = Lcg(5);
    let root = |f: &dyn Fn(DVec3) -> f64, o: DVec3, d: DVec3| {
        // Outermost crossing of f = D_e along o + t d, t ∈ [0, 12].
        let mut t1 = 12.0;
        while t1 > 0.0 && f(o + d * t1) < 1.0 {
            t1 -= 0.01;
        }
        let (mut a, mut b) = (t1, t1 + 0.01);
        for _ in 0..100 {
            let t = 0.5 * (a + b);
            if f(o + d * t) >= 1.0 { a = t } else { b = t }
        }
        a
    };
    let centre = m.groups()[0].density[0].placement.translation();
    for _ in 0..40 {
        let d = rng.vec(1.0).normalize();
        let tc = root(&|p| m.density_sum(0, p), centre, d);
        let te = root(&|p| exact(&m, p), centre, d);
        let g = m.density_jet(0, centre + d * te).grad.length();
        assert!(
            (tc - te).abs() <= n * tau * m.de() / g * 1.01 + 1e-12,
            "moved {} > bound {}",
            (tc - te).abs(),
            n * tau / g
        );
    }
}

#[test]
fn interval_classification_is_sound() {
    let mut m = blobs(1e-9);
    let b = GeometricPrimitive::new(
        GeometricShape::Box {
            half: DVec3::new(1.0, 2.0, 0.5),
        },
        Placement::at(DVec3::new(0.5, 0.0, 0.0)),
    )
    .unwrap();
    let hole = GeometricPrimitive::new(
        GeometricShape::Sphere { radius: 0.7 },
        Placement::at(DVec3::new(0.5, 1.0, 0.0)),
    )
    .unwrap()
    .negated();
    let neg = DensityPrimitive::sphere(DVec3::new(-1.0, 0.0, 0.3), -3.0, 2.0).unwrap();
    let g1 = m
        .add(Group {
            geometric: vec![b, hole],
            density: vec![neg],
            ..Default::default()
        })
        .unwrap();
    m.add(Group {
        geometric: vec![
            GeometricPrimitive::new(
                GeometricShape::Ellipsoid {
                    semi: DVec3::new(1.0, 0.5, 2.0),
                },
                Placement::IDENTITY,
            )
            .unwrap(),
        ],
        incorporated: vec![g1],
        ..Default::default()
    })
    .unwrap();
    let all = m.all_active();
    let mut rng = Lcg(17);
    let (mut decided, mut scratch) = (0, Vec::new());
    for _ in 0..3000 {
        let c = rng.vec(5.0);
        let r = 0.05 + rng.next() * 0.8;
        let act = m.cull(&all, c, r);
        let t = m.classify(c, r, &act);
        if t == vsculpt_kernel::dsm::interval::Tri::Maybe {
            continue;
        }
        decided += 1;
        for _ in 0..40 {
            let p = c + rng.vec(1.0).clamp_length_max(1.0) * r;
            let inside = m.contains(p);
            assert_eq!(
                inside,
                t == vsculpt_kernel::dsm::interval::Tri::Yes,
                "classification {t:?} wrong at {p}"
            );
            // The culled active set gives the same answer as the whole model.
            assert_eq!(
                m.sample(p, &act, f64::INFINITY, &mut scratch).inside,
                inside
            );
        }
    }
    assert!(decided > 500, "only {decided} balls decided");
}
