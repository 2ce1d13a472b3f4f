//! n-sided patches on curve networks (paper 004 §2–3): every patch
//! interpolates its boundary curves to 1e-12 and the normals of the two
//! patches on every shared curve agree to 1e-9 rad at 50 points per curve,
//! for faces of 3 to 8 sides and the bottle; tuning, twist and scale handles
//! change the interior but not those figures. Normals come from the
//! patches' exact derivatives (forward-mode jets), checked here against
//! finite differences.

use glam::{DVec2, DVec3};
use vsculpt_kernel::network::demo::{bottle, wheel};
use vsculpt_kernel::network::{CurveNetwork, Patch};

/// Largest distance between each patch's boundary and its sides' curves,
/// over 52 points per side (ends included).
fn boundary_error(net: &CurveNetwork) -> f64 {
    let mut worst = 0.0f64;
    for patch in net.patches() {
        for (i, side) in patch.ribbons().iter().enumerate() {
            for k in 0..=51 {
                let s = k as f64 / 51.0;
                let p = patch.point(patch.domain().side_point(i, s));
                let c = side
                    .curve
                    .point(side.t_start + s * (side.t_end - side.t_start));
                worst = worst.max((p - c).length());
            }
        }
    }
    worst
}

/// Largest angle between the two patches' normals along every curve piece
/// shared by two faces, at 50 interior points per shared piece (edge).
fn g1_error(net: &CurveNetwork) -> (f64, usize) {
    let patches = net.patches();
    let topo = net.topology();
    let mut worst = 0.0f64;
    let mut shared = 0;
    for (e, edge) in topo.edges.iter().enumerate() {
        // (patch, side) holding the edge.
        let holders: Vec<(usize, usize)> = topo
            .faces
            .iter()
            .enumerate()
            .flat_map(|(f, face)| {
                face.sides
                    .iter()
                    .enumerate()
                    .filter(move |(_, s)| s.edges.contains(&e))
                    .map(move |(i, _)| (f, i))
            })
            .collect();
        if holders.len() != 2 {
            continue;
        }
        shared += 1;
        for k in 1..=50 {
            let t = edge.t0 + (edge.t1 - edge.t0) * k as f64 / 51.0;
            let normals: Vec<DVec3> = holders
                .iter()
                .map(|&(f, i)| {
                    let p: &Patch = &patches[f];
                    let r = &p.ribbons()[i];
                    let s = (t - r.t_start) / (r.t_end - r.t_start);
                    p.normal(p.domain().side_point(i, s))
                })
                .collect();
            // atan2, not acos: acos(1 − ε) cannot resolve angles below 2e-8.
            let angle = normals[0]
                .cross(normals[1])
                .length()
                .atan2(normals[0].dot(normals[1]));
            worst = worst.max(angle);
        }
    }
    (worst, shared)
}

fn centre_face(net: &CurveNetwork, n: usize) -> usize {
    net.faces()
        .iter()
        .position(|f| f.sides.len() == n && f.sides.iter().all(|s| s.curve < n))
        .expect("the wheel's centre face")
}

#[test]
fn wheels_of_3_to_8_sides_interpolate_and_join_g1() {
    for n in 3..=8 {
        let net = wheel(n).unwrap();
        assert_eq!(net.faces().len(), n + 1, "n = {n}");
        let centre = centre_face(&net, n);
        assert_eq!(net.faces()[centre].sides.len(), n);
        let b = boundary_error(&net);
        let (g, shared) = g1_error(&net);
        println!("n = {n}: boundary {b:.2e}, normal angle {g:.2e} rad over {shared} shared edges");
        assert!(b <= 1e-12, "n = {n}: boundary off by {b}");
        assert_eq!(shared, 2 * n, "n = {n}: inner sides and spokes are shared");
        assert!(g <= 1e-9, "n = {n}: normals differ by {g} rad");
    }
}

#[test]
fn handles_change_the_interior_not_the_boundary_or_the_joins() {
    for n in 3..=8 {
        let mut net = wheel(n).unwrap();
        let centre = centre_face(&net, n);
        let probe = [DVec2::new(0.1, -0.05), DVec2::new(-0.3, 0.2), DVec2::ZERO];
        let before: Vec<DVec3> = probe
            .iter()
            .map(|p| net.patch(centre).unwrap().point(*p))
            .collect();
        let mut h = vec![DVec3::ZERO; n + 1];
        h[0] = DVec3::new(0.0, 0.0, 0.3);
        h[1] = DVec3::new(0.1, -0.2, 0.1);
        net.set_tuning(centre, h).unwrap();
        // Twist every spoke and scale a side of every face.
        for e in 0..net.topology().edges.len() {
            let c = net.topology().edges[e].curve;
            if (n..2 * n).contains(&c) {
                net.set_twist(e, 0.2).unwrap();
            }
        }
        for f in 0..net.faces().len() {
            net.set_scale(f, 0, 1.6).unwrap();
        }
        let after: Vec<DVec3> = probe
            .iter()
            .map(|p| net.patch(centre).unwrap().point(*p))
            .collect();
        for (a, b) in before.iter().zip(&after) {
            assert!(
                (*a - *b).length() > 1e-3,
                "n = {n}: the interior moved ({a} → {b})"
            );
        }
        let b = boundary_error(&net);
        let (g, _) = g1_error(&net);
        println!("n = {n} tuned: boundary {b:.2e}, normal angle {g:.2e} rad");
        assert!(b <= 1e-12 && g <= 1e-9, "n = {n}: {b} {g}");
    }
}

#[test]
fn jet_derivatives_match_finite_differences() {
    let mut net = wheel(5).unwrap();
    let centre = centre_face(&net, 5);
    net.set_twist(7, 0.3).unwrap();
    net.set_tuning(centre, vec![DVec3::new(0.1, 0.2, 0.3); 6])
        .unwrap();
    for f in 0..net.faces().len() {
        let p = net.patch(f).unwrap();
        for q in [
            DVec2::new(0.1, 0.2),
            DVec2::new(-0.4, -0.1),
            DVec2::new(0.3, -0.5),
        ] {
            if !p.domain().contains(q, -0.05) {
                continue;
            }
            let (_, sx, sy) = p.derivs(q);
            let h = 1e-5;
            let fx = (p.point(q + DVec2::X * h) - p.point(q - DVec2::X * h)) / (2.0 * h);
            let fy = (p.point(q + DVec2::Y * h) - p.point(q - DVec2::Y * h)) / (2.0 * h);
            assert!(
                (fx - sx).length() < 1e-7 * (1.0 + sx.length()),
                "{fx} vs {sx}"
            );
            assert!(
                (fy - sy).length() < 1e-7 * (1.0 + sy.length()),
                "{fy} vs {sy}"
            );
        }
    }
}

#[test]
fn patch_normals_face_the_network_normals() {
    // The domain is counter-clockwise and the faces are walked
    // counter-clockwise about the vertex normals: S_x × S_y agrees with them.
    let net = wheel(6).unwrap();
    for (f, p) in net.patches().iter().enumerate() {
        let n = p.normal(DVec2::new(0.05, 0.02));
        let v = net.faces()[f].sides[0].start;
        assert!(n.dot(net.topology().vertices[v].normal) > 0.5, "face {f}");
    }
}

#[test]
fn bottle_has_six_faces_one_five_sided_joined_g1() {
    let net = bottle().unwrap();
    let sides: Vec<usize> = net.faces().iter().map(|f| f.sides.len()).collect();
    println!("bottle faces: {sides:?}");
    assert_eq!(sides.len(), 6);
    assert_eq!(sides.iter().filter(|&&s| s == 5).count(), 1);
    assert_eq!(sides.iter().filter(|&&s| s == 3).count(), 2);
    assert_eq!(sides.iter().filter(|&&s| s == 4).count(), 3);
    let b = boundary_error(&net);
    let (g, shared) = g1_error(&net);
    let planarity = net
        .topology()
        .vertices
        .iter()
        .map(|v| v.planarity)
        .fold(0.0, f64::max);
    println!(
        "bottle: boundary {b:.2e}, normal angle {g:.2e} rad over {shared} shared edges, vertex planarity defect {planarity:.2e}"
    );
    assert!(b <= 1e-12);
    assert!(g <= 1e-9);
    // Outward normals: the label face's middle faces +x.
    let five = sides.iter().position(|&s| s == 5).unwrap();
    let p = net.patch(five).unwrap();
    assert!(p.normal(DVec2::ZERO).x > 0.9);
    // Its middle is near the bottle's surface (the patch only knows the curves).
    let c = p.point(DVec2::ZERO);
    let r = (c.x * c.x + c.y * c.y).sqrt();
    assert!((r - 1.0).abs() < 0.05, "label face middle at radius {r}");
}

#[test]
fn sampler_matches_direct_evaluation_before_and_after_a_drag() {
    use vsculpt_kernel::network::PatchSampler;
    let mut net = bottle().unwrap();
    let mut samplers: Vec<PatchSampler> = net
        .patches()
        .iter()
        .map(|p| PatchSampler::new(p, 9))
        .collect();
    for round in 0..3 {
        let mut out = Vec::new();
        for (f, s) in samplers.iter_mut().enumerate() {
            let p = net.patch(f).unwrap();
            assert!(s.evaluate(&p, &mut out));
            for (q, x) in s.mesh().points.iter().zip(&out) {
                assert!(
                    (p.point(*q) - *x).length() < 1e-13,
                    "round {round} face {f}"
                );
            }
        }
        // Drag the bottom ring's middle outwards (its meetings stay put),
        // then a diagonal's middle (moving no meeting either).
        let curve = if round == 0 { 0 } else { 7 };
        let mut c = net.curves()[curve].clone();
        let k = c.points().len() / 2;
        c.points_mut()[k] += DVec3::new(0.03, 0.0, 0.01);
        net.set_curve(curve, c).unwrap();
    }
}
