//! Metamorphosis and the spool demo: grid correspondence of bodies of
//! different degrees and knots keeps both shapes, t = 0 and t = 1 give the
//! bodies exactly, every frame of cube → spool is injective, the spool is a
//! spool, and the display meshes are what the volume says.

use glam::DVec3;
use vsculpt_kernel::body::demo::{SPOOL_RADII, cube, cube_to_spool, spool, spool_body};
use vsculpt_kernel::body::display::BodyDisplay;
use vsculpt_kernel::body::interior::volume;
use vsculpt_kernel::body::morph::correspond;
use vsculpt_kernel::body::{BSplineVolume, Dir, Face, Morph, Path, check_injective};
use vsculpt_kernel::bspline::KnotVector;
mod body_support;
use body_support::Rng;

#[test]
fn the_spool_is_a_spool_and_injective() {
    let s = spool().unwrap();
    let r = check_injective(&s).unwrap();
    assert!(r.lower_bound > 0.0);
    // Flanges wider than the waist: the bottom face's rim reaches out, the
    // middle is narrow, top and bottom are flat at z = ±1.
    let rim = s.point(1.0, 0.5, 0.0);
    let waist = s.point(1.0, 0.5, 0.5);
    assert!((rim.z + 1.0).abs() < 1e-12 && (s.point(0.3, 0.7, 1.0).z - 1.0).abs() < 1e-12);
    assert!(rim.x > 1.3 && waist.x < 0.8, "{rim} {waist}");
    // Round: a face's rim at its middle is at radius r_0, at a corner close to it.
    let corner = s.point(1.0, 1.0, 0.0);
    assert!((corner.truncate().length() - SPOOL_RADII[0]).abs() < 0.15 * SPOOL_RADII[0]);
    // Body 2 and its volume agree, and the volume is positive and below the
    // bounding cylinder's.
    let b = spool_body().unwrap();
    let mut rng = Rng(1);
    for _ in 0..300 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        assert!((b.point(u, v, w) - s.point(u, v, w)).length() < 1e-12);
    }
    let vol = volume(&s);
    assert!(
        vol > 0.0 && vol < std::f64::consts::PI * 1.5 * 1.5 * 2.0,
        "{vol}"
    );
}

#[test]
fn cube_to_spool_starts_and_ends_exactly_and_every_frame_is_injective() {
    let m = cube_to_spool().unwrap();
    let (c, s) = (cube(), spool().unwrap());
    let (a, b) = (m.at(0.0), m.at(1.0));
    let mut rng = Rng(2);
    for _ in 0..1000 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        assert!((a.point(u, v, w) - c.point(u, v, w)).length() < 1e-12);
        assert!((b.point(u, v, w) - s.point(u, v, w)).length() < 1e-12);
        // The cube is the affine map onto [−1, 1]³.
        assert!((a.point(u, v, w) - (DVec3::new(u, v, w) * 2.0 - DVec3::ONE)).length() < 1e-12);
    }
    // Grid points at the ends are the common lattice's exactly.
    assert_eq!(m.at(0.0).points(), m.source().points());
    assert_eq!(m.at(1.0).points(), m.target().points());
    let frames = m.check_injective(100).unwrap();
    assert_eq!(frames.len(), 101);
    assert!(frames.iter().all(|(_, r)| r.lower_bound > 0.0));
    // The middle frame is between: its waist is narrower than the cube's side.
    let mid = m.at(0.5).point(1.0, 0.5, 0.5);
    assert!(mid.x < 1.0 && mid.x > 0.7, "{mid}");
}

#[test]
fn correspondence_of_different_lattices_keeps_both_shapes() {
    let a = cube();
    // Another body: quadratic in u, other knots in w, domain [0, 2] in v.
    let ku = KnotVector::new(2, vec![0., 0., 0., 0.3, 1., 1., 1.]).unwrap();
    let kv = KnotVector::new(3, vec![0., 0., 0., 0., 2., 2., 2., 2.]).unwrap();
    let kw = KnotVector::new(1, vec![0., 0., 0.6, 1., 1.]).unwrap();
    let mut pts = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..3 {
                pts.push(DVec3::new(
                    i as f64,
                    j as f64 + 0.1 * (i * k) as f64,
                    k as f64 * 1.5,
                ));
            }
        }
    }
    let b = BSplineVolume::new(ku, kv, kw, pts).unwrap();
    let (ca, cb) = correspond(&a, &b).unwrap();
    for d in Dir::ALL {
        assert_eq!(ca.knots(d), cb.knots(d));
    }
    assert_eq!(cb.degrees(), [3, 3, 3]);
    let mut rng = Rng(3);
    for _ in 0..500 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        assert!((ca.point(u, v, w) - a.point(u, v, w)).length() < 1e-12);
        assert!((cb.point(u, v, w) - b.point(u, 2.0 * v, w)).length() < 1e-12);
    }
    // Paths: linear is the average at t = ½; eased is slower early; Hermite
    // with zero velocities is the eased path.
    let lin = Morph::new(&a, &b, Path::Linear).unwrap();
    let eased = Morph::new(&a, &b, Path::Eased).unwrap();
    let n = lin.source().points().len();
    let herm = Morph::new(
        &a,
        &b,
        Path::Hermite {
            start: vec![DVec3::ZERO; n],
            end: vec![DVec3::ZERO; n],
        },
    )
    .unwrap();
    for _ in 0..100 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        let want = (ca.point(u, v, w) + cb.point(u, v, w)) * 0.5;
        assert!((lin.at(0.5).point(u, v, w) - want).length() < 1e-12);
        let t = rng.next();
        assert!((herm.at(t).point(u, v, w) - eased.at(t).point(u, v, w)).length() < 1e-12);
    }
    let early = (eased.at(0.1).point(0.5, 0.5, 0.5) - ca.point(0.5, 0.5, 0.5)).length();
    let early_lin = (lin.at(0.1).point(0.5, 0.5, 0.5) - ca.point(0.5, 0.5, 0.5)).length();
    assert!(early < 0.5 * early_lin);
    assert!(
        Morph::new(
            &a,
            &b,
            Path::Hermite {
                start: vec![],
                end: vec![]
            }
        )
        .is_err()
    );
}

#[test]
fn display_meshes_lie_on_the_volume_with_outward_faces() {
    let s = spool().unwrap();
    let mut d = BodyDisplay::new(3, 9);
    d.update(&s);
    assert_eq!(d.faces.len(), 6);
    assert_eq!(d.iso.len(), 9);
    let centre = s.point(0.5, 0.5, 0.5);
    for (f, face) in Face::ALL.iter().enumerate() {
        let t = &d.faces[f];
        assert_eq!(t.positions.len(), 81);
        // The centre vertex of the face, and its normal pointing away from
        // the body's centre.
        let p = t.positions[40];
        let n = t.normals[40];
        let (p, n) = (
            DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64),
            DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64),
        );
        let mut uvw = [0.5; 3];
        uvw[face.dir.index()] = if face.end { 1.0 } else { 0.0 };
        assert!((p - s.point(uvw[0], uvw[1], uvw[2])).length() < 1e-6);
        assert!(n.dot(p - centre) > 0.0, "face {face:?}");
    }
    for (dir, t, mesh) in &d.iso {
        let p = mesh.positions[40];
        let mut uvw = [0.5; 3];
        uvw[dir.index()] = *t;
        let want = s.point(uvw[0], uvw[1], uvw[2]);
        assert!((DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) - want).length() < 1e-6);
    }
}
