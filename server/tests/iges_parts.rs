//! IGES parts: several named surfaces (entity 128) and curves (entity 126)
//! in one file. Round trips of our own export (checked record by record
//! against the IGES 5.3 layout by a reader written here, not ours), files
//! written by other CAD tools (tests/fixtures/iges/README.md gives their
//! sources), the rules for which entities are parts and what they are
//! called (on files composed here record by record), and hostile input.

use glam::DVec3;
use vsculpt_server::cad::{
    IgesCurve, IgesEntity, IgesError, IgesMeta, IgesPart, IgesSurface, read_iges, read_iges_parts,
    write_iges_parts,
};

fn fixture(name: &str) -> String {
    let path = format!("{}/tests/fixtures/iges/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// A nu×nv bicubic-ish patch with clamped uniform knots and a bump.
fn patch(nu: usize, nv: usize, du: usize, dv: usize, lift: f64) -> IgesSurface {
    let knots = |n: usize, d: usize| -> Vec<f64> {
        let inner = n - d;
        (0..n + d + 1)
            .map(|k| (k.saturating_sub(d)).min(inner) as f64 / inner as f64 * 3.7)
            .collect()
    };
    let mut points = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let z = lift * (i as f64 * 0.9).sin() * (j as f64 * 0.4).cos() + 1.0 / 3.0;
            points.push(DVec3::new(i as f64 * 10.1, j as f64 * -7.3, z));
        }
    }
    IgesSurface {
        u_degree: du,
        v_degree: dv,
        u_knots: knots(nu, du),
        v_knots: knots(nv, dv),
        nu,
        nv,
        points,
    }
}

fn curve(n: usize, degree: usize, seed: f64) -> IgesCurve {
    let mut knots = vec![0.0; degree + 1];
    for k in 1..n - degree {
        knots.push(k as f64 * 0.1 + seed * 1e-3);
    }
    knots.extend(vec![(n - degree) as f64 * 0.1 + 1.0; degree + 1]);
    IgesCurve {
        degree,
        knots,
        points: (0..n)
            .map(|k| {
                let t = k as f64 + seed;
                [t.sin() * 40.0, t.cos() * 1e-7, t * t / 7.0 - 123.456]
            })
            .collect(),
    }
}

fn product() -> Vec<IgesPart> {
    let part = |name: Option<&str>, entity| IgesPart {
        name: name.map(str::to_string),
        entity,
    };
    vec![
        part(
            Some("top shell"),
            IgesEntity::Surface(patch(16, 12, 3, 3, 5.0)),
        ),
        part(Some("C"), IgesEntity::Curve(curve(9, 3, 0.25))),
        part(
            Some("left side panel (G1 to top), rev 2; 5Hfake"),
            IgesEntity::Surface(patch(5, 4, 2, 1, -2.5)),
        ),
        part(None, IgesEntity::Curve(curve(2, 1, 3.0))),
        part(
            Some("scroll-wheel well"),
            IgesEntity::Surface(patch(20, 15, 5, 4, 0.125)),
        ),
        part(Some("feature line"), IgesEntity::Curve(curve(12, 5, 1.5))),
    ]
}

fn meta() -> IgesMeta {
    IgesMeta::now("mouse", "tester")
}

#[test]
fn parts_round_trip_exactly_with_their_names() {
    let parts = product();
    let text = write_iges_parts(&parts, &meta()).unwrap();
    let back = read_iges_parts(&text).unwrap();
    // PartialEq on f64: every knot and coordinate bit for bit.
    assert_eq!(back, parts);
    // The old single-surface reader still finds the surfaces.
    let surfaces: Vec<IgesSurface> = parts
        .iter()
        .filter_map(|p| match &p.entity {
            IgesEntity::Surface(s) => Some(s.clone()),
            IgesEntity::Curve(_) | IgesEntity::Trimmed(_) => None,
        })
        .collect();
    assert_eq!(read_iges(&text).unwrap(), surfaces);
}

#[test]
fn names_are_written_as_printable_ascii() {
    let mut parts = product();
    parts[0].name = Some("Crème brûlée — été".into());
    parts[1].name = Some("two\nlines\ttab".into());
    parts[2].name = Some("日本語".into());
    parts[3].name = Some("x".repeat(300));
    parts[4].name = Some("   ".into());
    let text = write_iges_parts(&parts, &meta()).unwrap();
    assert!(text.is_ascii());
    for line in text.lines() {
        assert_eq!(line.len(), 80, "{line:?}");
    }
    let back = read_iges_parts(&text).unwrap();
    let names: Vec<Option<String>> = back.into_iter().map(|p| p.name).collect();
    assert_eq!(
        names,
        vec![
            Some("Cr_me br_l_e _ _t_".into()),
            Some("two_lines_tab".into()),
            Some("___".into()),
            Some("x".repeat(300)),
            None,
            Some("feature line".into()),
        ]
    );
}

/// One record of a fixed-format file, split by columns.
struct Record<'a> {
    body: &'a str,
    section: char,
    seq: usize,
}

fn records(text: &str) -> Vec<Record<'_>> {
    text.lines()
        .map(|l| {
            assert_eq!(l.len(), 80, "{l:?}");
            Record {
                body: &l[..72],
                section: l.as_bytes()[72] as char,
                seq: l[73..].trim().parse().unwrap(),
            }
        })
        .collect()
}

fn field(body: &str, k: usize) -> &str {
    body[8 * k..8 * k + 8].trim()
}

#[test]
fn export_follows_the_iges_record_layout() {
    let parts = product();
    let text = write_iges_parts(&parts, &meta()).unwrap();
    let recs = records(&text);
    // Sections in order, each numbered 1..n, counted by the Terminate record.
    let mut order: Vec<char> = recs.iter().map(|r| r.section).collect();
    order.dedup();
    assert_eq!(order, vec!['S', 'G', 'D', 'P', 'T']);
    let count = |c: char| recs.iter().filter(|r| r.section == c).count();
    for c in ['S', 'G', 'D', 'P'] {
        let seqs: Vec<usize> = recs
            .iter()
            .filter(|r| r.section == c)
            .map(|r| r.seq)
            .collect();
        assert_eq!(seqs, (1..=seqs.len()).collect::<Vec<_>>(), "{c}");
    }
    let t = recs.last().unwrap().body;
    assert_eq!(
        t.trim_end(),
        format!(
            "S{:>7}G{:>7}D{:>7}P{:>7}",
            count('S'),
            count('G'),
            count('D'),
            count('P')
        )
    );
    // Directory: pairs naming the same type; each entity's parameter lines
    // are exactly those pointing back to it, contiguous from field 2, as
    // many as field 14 says.
    let d: Vec<&str> = recs
        .iter()
        .filter(|r| r.section == 'D')
        .map(|r| r.body)
        .collect();
    let p: Vec<&Record> = recs.iter().filter(|r| r.section == 'P').collect();
    let mut pd_of = std::collections::HashMap::new();
    for (k, pair) in d.chunks(2).enumerate() {
        let de = 2 * k + 1;
        assert_eq!(field(pair[0], 0), field(pair[1], 0));
        let first: usize = field(pair[0], 1).parse().unwrap();
        let n: usize = field(pair[1], 3).parse().unwrap();
        let mine: Vec<usize> = p
            .iter()
            .filter(|r| r.body[64..].trim() == de.to_string())
            .map(|r| r.seq)
            .collect();
        assert_eq!(mine, (first..first + n).collect::<Vec<_>>(), "D{de}");
        let pd: String = mine.iter().map(|&s| &p[s - 1].body[..64]).collect();
        pd_of.insert(de, (pair[0], pair[1], pd));
    }
    // Every part is an independent 128 or 126 with a name property that
    // points back to a 406 form 15 carrying the name as a Hollerith string.
    let mut de = 1;
    for part in &parts {
        let (d1, d2, pd) = &pd_of[&de];
        let ty = match part.entity {
            IgesEntity::Surface(_) => "128",
            IgesEntity::Curve(_) => "126",
            IgesEntity::Trimmed(_) => "144",
        };
        assert_eq!(field(d1, 0), ty);
        assert_eq!(&d1[64..72], "00000000", "D{de} status");
        assert_eq!(field(d1, 2), "0", "D{de} structure");
        assert_eq!(field(d2, 4), "0", "D{de} form");
        assert!(pd.starts_with(&format!("{ty},")), "{pd}");
        let Some(name) = &part.name else {
            assert!(field(d2, 7).is_empty());
            de += 2;
            continue;
        };
        let name_de = de + 2;
        assert!(
            pd.trim_end().ends_with(&format!(",0,1,{name_de};")),
            "D{de}: {pd}"
        );
        // The label is the name's first 8 characters.
        assert_eq!(&d2[56..64], format!("{:>8}", &name[..name.len().min(8)]));
        let (n1, n2, npd) = &pd_of[&name_de];
        assert_eq!(field(n1, 0), "406");
        assert_eq!(field(n2, 4), "15");
        assert_eq!(
            npd.trim_end(),
            format!("406,1,{}H{name};", name.len()),
            "D{name_de}"
        );
        de += 4;
    }
    assert_eq!(de, d.len() + 1);
    // The first part's parameters in IGES order: K1, K2, M1, M2, flags
    // (polynomial), u knots, v knots, weights 1, points u fastest.
    let IgesEntity::Surface(s) = &parts[0].entity else {
        unreachable!()
    };
    let fields: Vec<f64> = pd_of[&1]
        .2
        .trim_end()
        .trim_end_matches(';')
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect();
    assert_eq!(
        fields[..10],
        [128.0, 15.0, 11.0, 3.0, 3.0, 0.0, 0.0, 1.0, 0.0, 0.0]
    );
    let mut k = 10;
    assert_eq!(fields[k..k + 20], s.u_knots[..]);
    k += 20;
    assert_eq!(fields[k..k + 16], s.v_knots[..]);
    k += 16;
    assert!(fields[k..k + 192].iter().all(|&w| w == 1.0));
    k += 192;
    let (i, j) = (1, 0); // the second point written is u index 1, v index 0
    assert_eq!(fields[k + 3..k + 6], s.points[i * s.nv + j].to_array());
}

#[test]
fn curves_written_as_entity_126() {
    let c = curve(9, 3, 0.25);
    let parts = [IgesPart {
        name: None,
        entity: IgesEntity::Curve(c.clone()),
    }];
    let text = write_iges_parts(&parts, &meta()).unwrap();
    let pd: String = records(&text)
        .iter()
        .filter(|r| r.section == 'P')
        .map(|r| &r.body[..64])
        .collect();
    let fields: Vec<f64> = pd
        .trim_end()
        .trim_end_matches(';')
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect();
    // 126, K, M, planar 0, open 0, polynomial 1, non-periodic 0, knots,
    // weights, points, V0, V1, normal.
    assert_eq!(fields[..7], [126.0, 8.0, 3.0, 0.0, 0.0, 1.0, 0.0]);
    assert_eq!(fields[7..20], c.knots[..]);
    assert!(fields[20..29].iter().all(|&w| w == 1.0));
    let pts: Vec<f64> = c.points.iter().flatten().copied().collect();
    assert_eq!(fields[29..56], pts[..]);
    assert_eq!(fields[56..], [c.knots[3], c.knots[9], 0.0, 0.0, 0.0]);
}

#[test]
fn reads_rhino_curves_with_their_labels() {
    // Rhinoceros 2010 (pythonocc-core examples): six independent cubic
    // curves, D0 exponents, planar ones with a normal, labels "3d BsCrv"
    // with subscript 0.
    let parts = read_iges_parts(&fixture("rhino_curve_geom_plate.igs")).unwrap();
    assert_eq!(parts.len(), 6);
    let counts: Vec<usize> = parts
        .iter()
        .map(|p| match &p.entity {
            IgesEntity::Curve(c) => {
                assert_eq!(c.degree, 3);
                assert_eq!(p.name.as_deref(), Some("3d BsCrv(0)"));
                c.points.len()
            }
            IgesEntity::Surface(_) | IgesEntity::Trimmed(_) => panic!("a surface"),
        })
        .collect();
    assert_eq!(counts, vec![6, 5, 5, 5, 7, 7]);
    let IgesEntity::Curve(c) = &parts[0].entity else {
        unreachable!()
    };
    let end = 16.48566235018374;
    assert_eq!(
        c.knots,
        vec![
            0.0,
            0.0,
            0.0,
            0.0,
            6.696836136295956,
            12.53004301528411,
            end,
            end,
            end,
            end
        ]
    );
    assert_eq!(c.points[0], [12.05104335564882, 6.511168855975367, 0.0]);
    assert_eq!(
        c.points[3],
        [9.728591342963917, -3.664998927002043, -3.840386244052771]
    );
    assert_eq!(c.points[5], [5.270516142678511, -6.641806192114689, 0.0]);
    let IgesEntity::Curve(last) = &parts[5].entity else {
        unreachable!()
    };
    assert_eq!(last.points[6], [21.27157613451663, -1.867352103411764, 0.0]);
}

#[test]
fn reads_a_rhino_surface_named_by_a_406_property() {
    // Rhinoceros 2022 (pythonocc-core tests), CRLF lines: one bilinear
    // surface whose parameter data ends "0,1,5" — a Name property (D5,
    // 406 form 15, "test"), exactly what our writer emits.
    let parts = read_iges_parts(&fixture("rhino_named_surface.igs")).unwrap();
    assert_eq!(parts.len(), 1);
    assert_eq!(parts[0].name.as_deref(), Some("test"));
    let IgesEntity::Surface(s) = &parts[0].entity else {
        panic!("not a surface")
    };
    assert_eq!((s.u_degree, s.v_degree, s.nu, s.nv), (1, 1, 2, 2));
    let (u, v) = (35.53017372307497, 27.81101597164092);
    assert_eq!(s.u_knots, vec![0.0, 0.0, u, u]);
    assert_eq!(s.v_knots, vec![0.0, 0.0, v, v]);
    // IGES lists u fastest; ours is i * nv + j.
    assert_eq!(
        s.points,
        vec![
            DVec3::new(0.6478892123989652, -1.511404777835494, 0.0),
            DVec3::new(22.26938756285151, 9.955893545296618, 0.0),
            DVec3::new(-17.4713751196072, 18.99888250379516, 0.0),
            DVec3::new(1.831971402399674, 39.01970722272699, 0.0),
        ]
    );
}

#[test]
fn reads_the_45_trimmed_faces_of_an_opencascade_export() {
    // 45 trimmed surfaces (144), each on a physically dependent 128; 376
    // physically dependent 126 (boundaries in composite curves and curves
    // on surfaces) are pieces, not parts.
    let parts = read_iges_parts(&fixture("occt_45_faces.igs")).unwrap();
    assert_eq!(parts.len(), 45);
    let mut shapes: Vec<(usize, usize, usize, usize)> = parts
        .iter()
        .map(|p| {
            assert_eq!(p.name, None);
            match &p.entity {
                IgesEntity::Surface(s) => (s.u_degree, s.v_degree, s.nu, s.nv),
                IgesEntity::Curve(_) => panic!("a boundary curve became a part"),
                IgesEntity::Trimmed(_) => panic!("the reader gives no trimmed surfaces"),
            }
        })
        .collect();
    shapes.sort_unstable();
    let mut want = Vec::new();
    want.extend([(1, 1, 2, 2); 21]);
    want.extend([(4, 1, 5, 2); 4]);
    want.extend([(5, 1, 6, 2); 10]);
    want.extend([(5, 4, 6, 5); 8]);
    want.push((5, 5, 9, 9));
    want.push((5, 5, 33, 9));
    assert_eq!(shapes, want);
}

#[test]
fn reads_geomagic_surfaces_in_inches_as_millimetres() {
    // Raindrop Geomagic Studio 5 (pythonocc-core tests): nine independent
    // bicubic 16×16 surfaces, blank status fields, units flag 1 "IN".
    let parts = read_iges_parts(&fixture("geomagic_sunglasses_lens.igs")).unwrap();
    assert_eq!(parts.len(), 9);
    for p in &parts {
        let IgesEntity::Surface(s) = &p.entity else {
            panic!("not a surface")
        };
        assert_eq!((s.u_degree, s.v_degree, s.nu, s.nv), (3, 3, 16, 16));
    }
    let IgesEntity::Surface(s) = &parts[0].entity else {
        unreachable!()
    };
    assert_eq!(s.u_knots[4], 0.0769230769231);
    assert_eq!(
        s.points[0],
        DVec3::new(-12.2390305788, -1.98267038541, 2.07486185645) * 25.4
    );
    assert_eq!(
        s.points[16],
        DVec3::new(-12.2464213461, -1.98271311354, 2.07540809703) * 25.4
    );
}

#[test]
fn a_truly_rational_surface_in_an_ansa_file_is_refused_by_name() {
    // ANSA 9.x (OpenCASCADE test data OCC131-3): the trimmed face at D33 is
    // rational with weights from 0.999067 to 1.
    let text = fixture("ansa_trimmed_faces.igs");
    let want = IgesError::RationalWeights {
        de: 33,
        min: 0.999067,
        max: 1.0,
    };
    assert_eq!(read_iges_parts(&text).unwrap_err(), want);
    assert!(want.to_string().contains("D33"));
}

/// One entity of a file composed record by record in this test.
struct Ent {
    ty: u32,
    form: u32,
    status: &'static str,
    xform: usize,
    label: &'static str,
    sub: &'static str,
    params: String,
}

fn ent(ty: u32, status: &'static str, params: &str) -> Ent {
    Ent {
        ty,
        form: 0,
        status,
        xform: 0,
        label: "",
        sub: "",
        params: params.to_string(),
    }
}

/// A fixed-format file of `ents` (entity k at D2k+1), built here by hand.
fn compose(ents: &[Ent]) -> String {
    compose_in("2,2HMM", ents)
}

/// [`compose`] with Global fields 14–15 (units flag and name) `units`.
fn compose_in(units: &str, ents: &[Ent]) -> String {
    let mut out = format!("{:<72}S{:>7}\n", "composed by the iges_parts test", 1);
    out += &format!(
        "{:<72}G{:>7}\n",
        format!("1H,,1H;,4Htest,8Htest.igs,,,32,38,6,308,15,,1.,{units};"),
        1
    );
    let mut p = String::new();
    let mut pseq = 0;
    for (k, e) in ents.iter().enumerate() {
        let de = 2 * k + 1;
        let mut lines: Vec<String> = vec![String::new()];
        let text = format!("{};", e.params);
        for tok in text.split_inclusive(',') {
            if lines.last().unwrap().len() + tok.len() > 64 {
                lines.push(String::new());
            }
            lines.last_mut().unwrap().push_str(tok);
        }
        let first = pseq + 1;
        for l in &lines {
            pseq += 1;
            p += &format!("{l:<64}{de:>8}P{pseq:>7}\n");
        }
        out += &format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}\n",
            e.ty, first, 0, 0, 0, 0, e.xform, 0, e.status, de
        );
        out += &format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}\n",
            e.ty,
            0,
            0,
            lines.len(),
            e.form,
            "",
            "",
            e.label,
            e.sub,
            de + 1
        );
    }
    out += &p;
    out += &format!(
        "{:<72}T{:>7}\n",
        format!("S{:>7}G{:>7}D{:>7}P{:>7}", 1, 1, 2 * ents.len(), pseq),
        1
    );
    out
}

/// A bilinear unit patch as entity 128 parameters, offset by `z`.
const BILINEAR: &str =
    "128,1,1,1,1,0,0,1,0,0,0,0,1,1,0,0,1,1,1,1,1,1,0,0,0,1,0,0,0,1,0,1,1,0,0,1,0,1";

/// A straight degree-1 curve from (0,0,0) to (1,2,3) as entity 126.
const LINE: &str = "126,1,1,0,0,1,0,0,0,1,1,1,1,0,0,0,1,2,3,0,1,0,0,0";

fn file_with_dependents() -> String {
    let named = |ty, status, params: &str, label, sub| Ent {
        label,
        sub,
        ..ent(ty, status, params)
    };
    compose(&[
        // D1: translation by (5, 0, 0).
        ent(124, "00000000", "124,1,0,0,5,0,1,0,0,0,0,1,0"),
        // D3: the base surface of the trimmed surface at D7, turned by D39.
        Ent {
            xform: 39,
            ..ent(128, "00010000", BILINEAR)
        },
        // D5: a boundary curve of it (physically dependent, parametric).
        ent(126, "00010500", LINE),
        // D7: trimmed surface on D3, moved by D1, named by D9.
        Ent {
            xform: 1,
            ..ent(144, "00000000", "144,3,0,0,0,0,1,9")
        },
        // D9: its name.
        Ent {
            form: 15,
            ..ent(406, "00000000", "406,1,9HTop shell")
        },
        // D11: an independent curve in some parameter space (use 05).
        ent(126, "00000500", LINE),
        // D13: a curve named by its label and subscript.
        named(126, "00000000", LINE, "CRV", "12"),
        // D15, D17: members of the group at D19, unnamed themselves.
        ent(128, "00000000", BILINEAR),
        ent(128, "00020000", BILINEAR),
        // D19: an unordered group without back pointers, named by D21.
        Ent {
            form: 7,
            ..ent(402, "00000000", "402,2,15,17,0,1,21")
        },
        Ent {
            form: 15,
            ..ent(406, "00000000", "406,1,11HSide panels")
        },
        // D23, D25: physically dependent on nothing we read: pieces.
        ent(128, "00010000", BILINEAR),
        ent(126, "00010000", LINE),
        // D27: a curve with both a label and a Name property (D29).
        named(126, "00000000", &format!("{LINE},0,1,29"), "SHORT", ""),
        Ent {
            form: 15,
            ..ent(406, "00000000", "406,1,15HLong curve name")
        },
        // D31: the surface of the B-rep face D33, named by the face's label.
        ent(128, "00010000", BILINEAR),
        named(510, "00010000", "510,31,0,1", "FACE", "3"),
        // D35: the surface of the bounded surface D37.
        ent(128, "00010000", BILINEAR),
        named(143, "00000000", "143,0,35,0", "BND", ""),
        // D39: a quarter turn about z.
        ent(124, "00000000", "124,0,-1,0,0,1,0,0,0,0,0,1,0"),
    ])
}

#[test]
fn parts_are_the_independent_entities_and_the_bases_of_trimmed_surfaces() {
    let text = file_with_dependents();
    let parts = read_iges_parts(&text).unwrap();
    let names: Vec<Option<&str>> = parts.iter().map(|p| p.name.as_deref()).collect();
    assert_eq!(
        names,
        vec![
            Some("Top shell"),
            Some("CRV(12)"),
            Some("Side panels 1"),
            Some("Side panels 2"),
            Some("Long curve name"),
            Some("FACE(3)"),
            Some("BND"),
        ]
    );
    let kinds: Vec<&str> = parts
        .iter()
        .map(|p| match p.entity {
            IgesEntity::Surface(_) => "surface",
            IgesEntity::Curve(_) => "curve",
            IgesEntity::Trimmed(_) => "trimmed",
        })
        .collect();
    assert_eq!(
        kinds,
        [
            "surface", "curve", "surface", "surface", "curve", "surface", "surface"
        ]
    );
    // The base surface is turned by its own transformation, then moved by
    // its trimmed surface's: (0, 1, 0) → (−1, 0, 0) → (4, 0, 0).
    let IgesEntity::Surface(top) = &parts[0].entity else {
        unreachable!()
    };
    assert_eq!(top.points[1], DVec3::new(4.0, 0.0, 0.0));
    assert_eq!(top.points[3], DVec3::new(4.0, 1.0, 0.0));
    let IgesEntity::Surface(side) = &parts[2].entity else {
        unreachable!()
    };
    assert_eq!(side.points[3], DVec3::new(1.0, 1.0, 0.0));
    let IgesEntity::Curve(c) = &parts[1].entity else {
        unreachable!()
    };
    assert_eq!(c.points, vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]);
    assert_eq!(c.knots, vec![0.0, 0.0, 1.0, 1.0]);
}

#[test]
fn curves_used_by_other_entities_are_pieces_whatever_their_status() {
    // Blank status fields everywhere, as some writers leave them.
    let text = compose(&[
        ent(128, "", BILINEAR),
        // D3: in the composite curve D11; D5, D7: the parameter-space and
        // model-space curves of the curve on surface D13; D9: an edge of
        // the edge list D15.
        ent(126, "", LINE),
        ent(126, "", LINE),
        ent(126, "", LINE),
        ent(126, "", LINE),
        ent(102, "", "102,1,3"),
        ent(142, "", "142,1,1,5,7,1"),
        Ent {
            form: 1,
            ..ent(504, "", "504,1,9,0,1,0,2")
        },
        // D17: a curve nothing uses.
        Ent {
            label: "FREE",
            ..ent(126, "", LINE)
        },
    ]);
    let parts = read_iges_parts(&text).unwrap();
    let got: Vec<(bool, Option<&str>)> = parts
        .iter()
        .map(|p| (matches!(p.entity, IgesEntity::Curve(_)), p.name.as_deref()))
        .collect();
    assert_eq!(got, vec![(false, None), (true, Some("FREE"))]);
}

#[test]
fn coordinates_are_converted_to_millimetres_when_units_agree() {
    let end = |units: &str| -> [f64; 3] {
        let parts = read_iges_parts(&compose_in(units, &[ent(126, "00000000", LINE)])).unwrap();
        let IgesEntity::Curve(c) = &parts[0].entity else {
            panic!()
        };
        assert_eq!(c.knots, vec![0.0, 0.0, 1.0, 1.0], "knots are not lengths");
        c.points[1]
    };
    assert_eq!(end("2,2HMM"), [1.0, 2.0, 3.0]);
    assert_eq!(end("6,1HM"), [1000.0, 2000.0, 3000.0]);
    assert_eq!(end("1,4HINCH"), [25.4, 2.0 * 25.4, 3.0 * 25.4]);
    assert_eq!(end("10,2Hcm"), [10.0, 20.0, 30.0]);
    assert_eq!(end("3,2HFT"), [304.8, 2.0 * 304.8, 3.0 * 304.8]);
    // Flag and name contradicting each other, or missing: as written.
    assert_eq!(end("1,2HMM"), [1.0, 2.0, 3.0]);
    assert_eq!(end("6,"), [1.0, 2.0, 3.0]);
    assert_eq!(end(","), [1.0, 2.0, 3.0]);
}

#[test]
fn rational_curves_with_equal_weights_are_accepted_others_refused() {
    let equal = "126,1,1,0,0,0,0,0,0,1,1,2.5,2.5,0,0,0,1,2,3,0,1,0,0,0";
    let parts = read_iges_parts(&compose(&[ent(126, "00000000", equal)])).unwrap();
    let IgesEntity::Curve(c) = &parts[0].entity else {
        panic!()
    };
    assert_eq!(c.points, vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]);
    let unequal = "126,1,1,0,0,0,0,0,0,1,1,1,0.5,0,0,0,1,2,3,0,1,0,0,0";
    let text = compose(&[
        ent(128, "00000000", BILINEAR),
        ent(126, "00000000", unequal),
    ]);
    assert_eq!(
        read_iges_parts(&text).unwrap_err(),
        IgesError::RationalCurve {
            de: 3,
            min: 0.5,
            max: 1.0
        }
    );
}

#[test]
fn writer_refuses_what_it_cannot_write() {
    assert_eq!(write_iges_parts(&[], &meta()), Err(IgesError::NoParts));
    let bad = |c: IgesCurve| {
        let parts = [IgesPart {
            name: Some("bad".into()),
            entity: IgesEntity::Curve(c),
        }];
        match write_iges_parts(&parts, &meta()) {
            Err(IgesError::InvalidCurve(_)) => {}
            other => panic!("{other:?}"),
        }
    };
    let mut c = curve(5, 3, 0.0);
    c.points[2][1] = f64::NAN;
    bad(c);
    let mut c = curve(5, 3, 0.0);
    c.knots.pop();
    bad(c);
    let mut c = curve(5, 3, 0.0);
    c.knots.swap(4, 5);
    c.knots[4] = 99.0;
    bad(c);
    let mut c = curve(5, 3, 0.0);
    c.degree = 0;
    bad(c);
    let mut c = curve(5, 3, 0.0);
    c.points.truncate(3);
    c.knots.truncate(7);
    bad(c);
    // Degree 31 is beyond what the reader accepts, so it is not written.
    bad(curve(40, 31, 0.0));
    let c = curve(40, 30, 0.0);
    let parts = [IgesPart {
        name: None,
        entity: IgesEntity::Curve(c.clone()),
    }];
    let text = write_iges_parts(&parts, &meta()).unwrap();
    assert_eq!(
        read_iges_parts(&text).unwrap()[0].entity,
        IgesEntity::Curve(c)
    );
    let mut s = patch(4, 4, 3, 3, 1.0);
    s.v_knots[1] = f64::INFINITY;
    let parts = [IgesPart {
        name: None,
        entity: IgesEntity::Surface(s),
    }];
    assert!(matches!(
        write_iges_parts(&parts, &meta()),
        Err(IgesError::InvalidSurface(_))
    ));
}

#[test]
fn files_without_parts_are_refused() {
    let only_pieces = compose(&[
        ent(128, "00010000", BILINEAR),
        ent(126, "00010000", LINE),
        ent(110, "00000000", "110,0,0,0,1,1,1"),
    ]);
    assert_eq!(read_iges_parts(&only_pieces), Err(IgesError::NoParts));
}

fn small_export() -> String {
    write_iges_parts(&product()[..4], &meta()).unwrap()
}

#[test]
fn truncated_files_are_errors_not_panics() {
    let text = small_export();
    let lines: Vec<&str> = text.lines().collect();
    let last_p = lines.iter().rposition(|l| &l[72..73] == "P").unwrap();
    for k in 0..lines.len() {
        let cut: String = lines[..k].iter().map(|l| format!("{l}\n")).collect();
        let r = read_iges_parts(&cut);
        if k <= last_p {
            assert!(r.is_err(), "cut after {k} lines parsed");
        }
    }
    // Cut mid-record.
    for n in [1, 100, text.len() / 2, text.len() - 90] {
        assert!(read_iges_parts(&text[..n]).is_err(), "{n} bytes");
    }
}

#[test]
fn bad_pointers_are_errors() {
    let with = |tail: &str| {
        compose(&[
            ent(128, "00000000", &format!("{BILINEAR},{tail}")),
            Ent {
                form: 15,
                ..ent(406, "00000000", "406,1,4Hname")
            },
        ])
    };
    let good = read_iges_parts(&with("0,1,3")).unwrap();
    assert_eq!(good[0].name.as_deref(), Some("name"));
    for (tail, what) in [
        ("0,1,99", "D99"),
        ("0,1,4", "directory pointer"),
        ("0,1,-3", "directory pointer"),
        ("0,7,3", "pointer count"),
        ("0,999999999999,3", "pointer count"),
        ("0,2,3", "pointer count"),
        ("0,1,1", ""),
    ] {
        match read_iges_parts(&with(tail)) {
            Err(IgesError::BadParameter { de: 1, reason }) => {
                assert!(reason.contains(what), "{tail}: {reason}")
            }
            // A pointer to itself (a 128, not a 406) is not a name.
            Ok(parts) if tail == "0,1,1" => assert_eq!(parts[0].name, None),
            other => panic!("{tail}: {other:?}"),
        }
    }
    let text = small_export();
    // A parameter-data pointer beyond the file, and a transformation
    // pointer to a missing entry.
    let d1 = text.lines().find(|l| &l[72..73] == "D").unwrap();
    let far = format!("{}{:>8}{}", &d1[..8], 9999, &d1[16..]);
    assert!(matches!(
        read_iges_parts(&text.replacen(d1, &far, 1)),
        Err(IgesError::BadParameter { de: 1, .. })
    ));
    let xf = format!("{}{:>8}{}", &d1[..48], 41, &d1[56..]);
    assert!(matches!(
        read_iges_parts(&text.replacen(d1, &xf, 1)),
        Err(IgesError::BadParameter { de: 1, .. })
    ));
}

#[test]
fn huge_counts_nan_and_huge_numbers_are_errors() {
    let line = |params: &str| compose(&[ent(126, "00000000", params)]);
    for params in [
        "126,999999999999,3,0,0,1,0,0,0,1,1",
        "126,1,99,0,0,1,0,0,0,1,1",
        "126,-1,1,0,0,1,0,0,0,1,1",
        "126,1,1,0,0,1,0,0,0,1,1,1,1,0,0,0,1,2",
        "126,1,1,0,0,1,0,0,0,NaN,1,1,1,0,0,0,1,2,3,0,1,0,0,0",
        "126,1,1,0,0,1,0,0,0,1,1,1,1,0,0,inf,1,2,3,0,1,0,0,0",
        "126,1,1,0,0,1,0,0,0,1,1,1,1,0,0,0,1,2,1E999,0,1,0,0,0",
        "126,1,1,0,0,1,0,1,0,1,1,1,1,0,0,0,1,2,3,0,1,0,0,0",
        "126,1,1,0,0,1,0,0,0,1,1,1,1,0,0,0,1,2,3,0,1,0,0,0,0,1,99H",
    ] {
        assert!(
            matches!(
                read_iges_parts(&line(params)),
                Err(IgesError::BadParameter { de: 1, .. })
            ),
            "{params}"
        );
    }
    let big = line("126,1,1,0,0,1,0,0,0,1,1,1,1,0,0,0,1,2,1E300,0,1,0,0,0");
    assert_eq!(
        read_iges_parts(&big),
        Err(IgesError::TooLarge {
            de: 1,
            what: "control point coordinate",
            value: 1e300
        })
    );
    let knot = line("126,1,1,0,0,1,0,0,0,1,2E9,1,1,0,0,0,1,2,3,0,1,0,0,0");
    assert!(matches!(
        read_iges_parts(&knot),
        Err(IgesError::TooLarge { what: "knot", .. })
    ));
    let group = compose(&[
        ent(128, "00000000", BILINEAR),
        Ent {
            form: 7,
            ..ent(402, "00000000", "402,99999999999,1")
        },
    ]);
    assert!(matches!(
        read_iges_parts(&group),
        Err(IgesError::BadParameter { de: 3, .. })
    ));
    let trimmed = compose(&[
        ent(128, "00010000", BILINEAR),
        ent(144, "00000000", "144,77,0,0,0"),
    ]);
    assert!(matches!(
        read_iges_parts(&trimmed),
        Err(IgesError::BadParameter { de: 3, .. })
    ));
}

#[test]
fn mutated_exports_never_panic() {
    let text = small_export();
    let bytes = text.as_bytes();
    let alphabet = b"0123456789,;H.-E D+ \n";
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut errors = 0;
    for _ in 0..3000 {
        let mut m = bytes.to_vec();
        for _ in 0..1 + next() % 3 {
            let at = (next() % m.len() as u64) as usize;
            m[at] = alphabet[(next() % alphabet.len() as u64) as usize];
        }
        let s = String::from_utf8(m).unwrap();
        if read_iges_parts(&s).is_err() {
            errors += 1;
        }
        let _ = read_iges(&s);
    }
    // Most single-byte changes to numbers still parse; some must not.
    assert!(errors > 0);
}
