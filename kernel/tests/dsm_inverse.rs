//! The inverse transformation (paper eqs. 8–11), the explicit equal density
//! surface h(u, v) (eq. 12) with its curvature, and the connecting function (eq. 13).

use glam::{DVec2, DVec3};
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
}

fn regular_net(n: usize, rough: bool) -> PassingPointsNet {
    let mut rng = Lcg(7);
    let heights: Vec<f64> = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f64, (k / n) as f64);
            if rough {
                0.5 + 1.5 * rng.next()
            } else {
                1.0 + 0.4 * (0.5 * i).sin() * (0.3 * j).cos()
            }
        })
        .collect();
    PassingPointsNet::regular(DVec2::new(-2.0, -1.0), DVec2::new(0.5, 0.5), n, n, &heights).unwrap()
}

fn assert_passes_through_interior(
    net: &PassingPointsNet,
    surface: &EqualDensitySurface,
    report: &InverseReport,
) {
    let size = net.size();
    let mut worst: f64 = 0.0;
    for (i, n) in net.nodes().iter().enumerate() {
        if net.is_peripheral(i) {
            continue;
        }
        let h = surface.height(n.truncate()).expect("D > 0 at a node");
        worst = worst.max((h - n.z).abs());
    }
    assert!(
        worst <= 1e-9 * size,
        "max node error {worst} of size {size}"
    );
    assert!(report.max_residual <= 1e-9 * size);
    assert!(
        report.condition.is_finite() && report.condition >= 1.0,
        "condition {}",
        report.condition
    );
}

#[test]
fn regular_smooth_net_is_interpolated_at_every_interior_node() {
    let net = regular_net(20, false);
    let (surface, report) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.0)).unwrap();
    assert_eq!(report.charges, 18 * 18);
    assert_passes_through_interior(&net, &surface, &report);
}

#[test]
fn regular_rough_net_is_interpolated_and_its_excursions_reported() {
    let net = regular_net(12, true);
    let (surface, report) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.0)).unwrap();
    assert_passes_through_interior(&net, &surface, &report);
    // The sampled range is reported and contains every interior height.
    let hs: Vec<f64> = net
        .nodes()
        .iter()
        .enumerate()
        .filter(|(i, _)| !net.is_peripheral(*i))
        .map(|(_, n)| n.z)
        .collect();
    assert!(report.min_height <= hs.iter().copied().fold(f64::INFINITY, f64::min) + 1e-12);
    assert!(report.max_height >= hs.iter().copied().fold(f64::NEG_INFINITY, f64::max) - 1e-12);
    assert_eq!(report.below_plane, report.min_height <= 0.0);
}

#[test]
fn scattered_net_is_interpolated_at_every_interior_node() {
    let mut rng = Lcg(99);
    let mut nodes = Vec::new();
    for j in 0..10 {
        for i in 0..10 {
            let u = i as f64 * 0.6 + 0.25 * (rng.next() - 0.5);
            let v = j as f64 * 0.6 + 0.25 * (rng.next() - 0.5);
            nodes.push(DVec3::new(u, v, 0.8 + 0.6 * rng.next()));
        }
    }
    let net = PassingPointsNet::scattered(nodes).unwrap();
    let peripheral = (0..100).filter(|&i| net.is_peripheral(i)).count();
    assert!((4..40).contains(&peripheral), "hull nodes {peripheral}");
    let (surface, report) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.5)).unwrap();
    assert_eq!(report.charges, 100 - peripheral);
    assert_passes_through_interior(&net, &surface, &report);
}

#[test]
fn bad_nets_get_clear_errors() {
    let mut h = vec![1.0; 16];
    h[5] = 0.0;
    assert!(matches!(
        PassingPointsNet::regular(DVec2::ZERO, DVec2::ONE, 4, 4, &h),
        Err(DsmError::NonPositiveHeight { node: 5, .. })
    ));
    h[5] = -1.0;
    assert!(PassingPointsNet::regular(DVec2::ZERO, DVec2::ONE, 4, 4, &h).is_err());
    h[5] = f64::NAN;
    assert!(PassingPointsNet::regular(DVec2::ZERO, DVec2::ONE, 4, 4, &h).is_err());
    let pts = vec![
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(0.5, 0.5, 1.0),
        DVec3::new(0.5, 0.5, 1.2),
        DVec3::new(0.0, 1.0, 1.0),
        DVec3::new(1.0, 1.0, 1.0),
    ];
    assert!(matches!(
        PassingPointsNet::scattered(pts),
        Err(DsmError::CoincidentNodes { a: 2, b: 3, .. })
    ));
    // Only hull nodes: nothing carries a charge.
    let square = vec![
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(0.0, 1.0, 1.0),
        DVec3::new(1.0, 1.0, 1.0),
    ];
    let net = PassingPointsNet::scattered(square).unwrap();
    assert!(matches!(
        inverse_transform(&net, &InverseOptions::for_net(&net, 1.0)),
        Err(DsmError::DegenerateNet(_))
    ));
    // A drag to h ≤ 0 is refused and leaves the net unchanged.
    let mut net = regular_net(5, false);
    let before = net.clone();
    assert!(net.set_height(7, 0.0).is_err());
    assert_eq!(net, before);
    // Nearly coincident charges make C singular.
    let mut pts = Vec::new();
    for j in 0..5 {
        for i in 0..5 {
            pts.push(DVec3::new(i as f64, j as f64, 1.0));
        }
    }
    pts.push(DVec3::new(2.0 + 1e-8, 2.0, 1.3));
    let net = PassingPointsNet::scattered(pts).unwrap();
    let opts = InverseOptions {
        a_min: 1e-3,
        ..InverseOptions::for_net(&net, 1.0)
    };
    match inverse_transform(&net, &opts) {
        Err(DsmError::Singular { condition }) => assert!(condition > 1e14),
        Ok((_, r)) => panic!("accepted with condition {}", r.condition),
        Err(e) => panic!("unexpected {e}"),
    }
}

fn check_jet(s: &EqualDensitySurface, p: DVec2) {
    let j = s.jet(p).unwrap();
    let h = 1e-5;
    let f = |q: DVec2| s.height(q).unwrap();
    let gu = (f(p + DVec2::X * h) - f(p - DVec2::X * h)) / (2.0 * h);
    let gv = (f(p + DVec2::Y * h) - f(p - DVec2::Y * h)) / (2.0 * h);
    assert!(
        (gu - j.grad.x).abs() < 1e-7 * (1.0 + gu.abs())
            && (gv - j.grad.y).abs() < 1e-7 * (1.0 + gv.abs()),
        "gradient at {p}"
    );
    let huu = (s.jet(p + DVec2::X * h).unwrap().grad.x - s.jet(p - DVec2::X * h).unwrap().grad.x)
        / (2.0 * h);
    let huv = (s.jet(p + DVec2::Y * h).unwrap().grad.x - s.jet(p - DVec2::Y * h).unwrap().grad.x)
        / (2.0 * h);
    let hvv = (s.jet(p + DVec2::Y * h).unwrap().grad.y - s.jet(p - DVec2::Y * h).unwrap().grad.y)
        / (2.0 * h);
    let sc = 1.0 + j.hess.x_axis.length() + j.hess.y_axis.length();
    assert!(
        (huu - j.hess.x_axis.x).abs() < 1e-6 * sc,
        "h_uu at {p}: {} vs {huu}",
        j.hess.x_axis.x
    );
    assert!(
        (huv - j.hess.y_axis.x).abs() < 1e-6 * sc && (huv - j.hess.x_axis.y).abs() < 1e-6 * sc,
        "h_uv at {p}"
    );
    assert!((hvv - j.hess.y_axis.y).abs() < 1e-6 * sc, "h_vv at {p}");
    // Curvature from the differenced derivatives.
    let (hu, hv) = (j.grad.x, j.grad.y);
    let w2 = 1.0 + hu * hu + hv * hv;
    let k = (huu * hvv - huv * huv) / (w2 * w2);
    let hm = ((1.0 + hv * hv) * huu - 2.0 * hu * hv * huv + (1.0 + hu * hu) * hvv)
        / (2.0 * w2 * w2.sqrt());
    let c = s.curvature(p).unwrap();
    assert!(
        (c.gaussian - k).abs() < 1e-5 * (1.0 + k.abs())
            && (c.mean - hm).abs() < 1e-5 * (1.0 + hm.abs()),
        "curvature at {p}"
    );
}

#[test]
fn curvature_matches_central_differences() {
    let net = regular_net(10, false);
    let (mut surface, _) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.0)).unwrap();
    for p in [
        DVec2::new(-0.7, 0.3),
        DVec2::new(0.4, 1.1),
        DVec2::new(1.3, 2.2),
        DVec2::new(0.05, 0.95),
    ] {
        check_jet(&surface, p);
    }
    // With a connecting function, on its ramps.
    surface.connect =
        Some(Connecting::to_plane(DVec2::new(-2.0, -1.0), DVec2::new(2.5, 3.5), 1.0).unwrap());
    for p in [
        DVec2::new(-1.6, 0.3),
        DVec2::new(2.1, -0.5),
        DVec2::new(0.4, 1.1),
    ] {
        check_jet(&surface, p);
    }
}

#[test]
fn single_charge_gives_the_analytic_paraboloid_and_its_curvature() {
    // 3 × 3 net: one charge X at the centre, h = (ln X − a_d ρ² − ln D_e)/a, a
    // paraboloid z = h₀ − b ρ² with b = a_d / a. Its principal curvatures (upward
    // normal) are −2b/(1 + 4b²ρ²)^{3/2} (meridian) and −2b/(1 + 4b²ρ²)^{1/2}.
    let mut h = vec![0.7; 9];
    h[4] = 1.6;
    let net = PassingPointsNet::regular(DVec2::new(-1.0, -1.0), DVec2::ONE, 3, 3, &h).unwrap();
    let a = 1.3;
    let opts = InverseOptions::for_net(&net, a);
    let (s, report) = inverse_transform(&net, &opts).unwrap();
    assert_eq!(report.charges, 1);
    let c = s.distribution.charges()[0];
    // eq. (8) with h_m = 0.7, r_m = mean of 4 × 1 and 4 × √2.
    let rm = (4.0 + 4.0 * 2f64.sqrt()) / 8.0;
    let ad = ((1.6f64 / 0.7).ln() * (a * (1.6 - 0.7)).exp() / (rm * rm)).abs() + opts.a_min;
    assert!((c.reducing - ad).abs() < 1e-12 * ad);
    // X e^{−a h} = D_e at the centre.
    assert!((c.strength - (a * 1.6f64).exp()).abs() < 1e-12 * c.strength);
    let b = ad / a;
    for rho in [0.0, 0.1, 0.35, 0.6] {
        let p = DVec2::new(rho * 0.6, rho * 0.8);
        assert!((s.height(p).unwrap() - (1.6 - b * rho * rho)).abs() < 1e-12);
        let q = 1.0 + 4.0 * b * b * rho * rho;
        let (k1, k2) = (-2.0 * b / q.powf(1.5), -2.0 * b / q.sqrt());
        let cv = s.curvature(p).unwrap();
        assert!(
            (cv.mean - 0.5 * (k1 + k2)).abs() < 1e-10 * b,
            "H at ρ = {rho}"
        );
        assert!(
            (cv.gaussian - k1 * k2).abs() < 1e-10 * b * b,
            "K at ρ = {rho}"
        );
    }
}

#[test]
fn connecting_function_meets_the_plane_with_zero_slope_and_curvature() {
    let net = regular_net(8, false);
    let (mut s, _) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.0)).unwrap();
    let plain = s.clone();
    let (lo, hi) = (DVec2::new(-2.0, -1.0), DVec2::new(1.5, 2.5));
    s.connect = Some(Connecting::to_plane(lo, hi, 0.8).unwrap());
    // On the rim: h, ∇h and ∇²h vanish.
    for p in [
        DVec2::new(lo.x, 0.3),
        DVec2::new(hi.x, 1.2),
        DVec2::new(0.1, lo.y),
        DVec2::new(-0.4, hi.y),
    ] {
        let j = s.jet(p).unwrap();
        assert!(
            j.value.abs() < 1e-15
                && j.grad.length() < 1e-12
                && j.hess.x_axis.length() + j.hess.y_axis.length() < 1e-9,
            "at {p}: {j:?}"
        );
    }
    // Inside the plateau it is eq. (12) unchanged.
    let p = DVec2::new(-0.3, 0.7);
    assert!((s.height(p).unwrap() - plain.height(p).unwrap()).abs() < 1e-15);
}

#[test]
fn plane_primitive_solid_is_bounded_by_the_explicit_surface() {
    // The 3-D level set of the plane-based primitive is z = ±h(u, v) (eq. 12 from eq. 4).
    let net = regular_net(8, false);
    let (s, _) = inverse_transform(&net, &InverseOptions::for_net(&net, 1.0)).unwrap();
    let (lo, hi) = net.uv_box();
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    m.add(Group {
        density: vec![s.primitive(lo, hi, Placement::IDENTITY).unwrap()],
        ..Default::default()
    })
    .unwrap();
    for p in [
        DVec2::new(-1.1, 0.2),
        DVec2::new(0.3, 1.7),
        DVec2::new(0.9, 0.4),
    ] {
        let h = s.height(p).unwrap();
        assert!(h > 0.0);
        assert!(
            m.contains(DVec3::new(p.x, p.y, h - 1e-9))
                && !m.contains(DVec3::new(p.x, p.y, h + 1e-9))
        );
        assert!(
            m.contains(DVec3::new(p.x, p.y, -h + 1e-9))
                && !m.contains(DVec3::new(p.x, p.y, -h - 1e-9))
        );
    }
}
