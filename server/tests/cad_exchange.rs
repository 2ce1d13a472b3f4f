//! CAD exchange without a server: IGES entity 128 write → read round trips
//! bit for bit, a fixture in another tool's style (D exponents, CRLF,
//! rational flag with unit weights, a transformation matrix, other
//! entities) reads to the known control points, genuinely rational surfaces
//! and malformed files are refused, and the mesh writers produce files that
//! parse back to the same counts and indices.

use glam::DVec3;
use vsculpt_server::cad::{
    IgesError, IgesMeta, IgesSurface, Mesh, read_iges, write_gltf, write_iges, write_obj, write_stl,
};

fn dome(nu: usize, nv: usize) -> IgesSurface {
    let knots = |n: usize| {
        let mut k = vec![0.0; 4];
        for s in 1..n - 3 {
            k.push(s as f64 / (n - 3) as f64);
        }
        k.extend([1.0; 4]);
        k
    };
    let mut points = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let x = i as f64 / (nu - 1) as f64;
            let y = j as f64 / (nv - 1) as f64;
            points.push(DVec3::new(
                120.0 * x - 60.0,
                70.0 * y - 35.0,
                30.0 * (std::f64::consts::PI * x).sin() * (std::f64::consts::PI * y).sin()
                    + 0.1 / 3.0,
            ));
        }
    }
    IgesSurface {
        u_degree: 3,
        v_degree: 3,
        u_knots: knots(nu),
        v_knots: knots(nv),
        nu,
        nv,
        points,
    }
}

#[test]
fn iges_round_trip_is_exact() {
    let s = dome(16, 12);
    let text = write_iges(&s, &IgesMeta::now("mouse shell", "tester")).unwrap();
    for (k, line) in text.lines().enumerate() {
        assert_eq!(line.len(), 80, "line {k} is not 80 columns: {line:?}");
    }
    let letters: String = text.lines().map(|l| &l[72..73]).collect();
    let sections: Vec<char> = {
        let mut v: Vec<char> = letters.chars().collect();
        v.dedup();
        v
    };
    assert_eq!(sections, vec!['S', 'G', 'D', 'P', 'T']);
    let back = read_iges(&text).unwrap();
    assert_eq!(back.len(), 1);
    assert_eq!(back[0], s);
}

#[test]
fn iges_parameter_lines_point_back_to_their_entity() {
    let text = write_iges(&dome(5, 4), &IgesMeta::now("x", "y")).unwrap();
    let p: Vec<&str> = text.lines().filter(|l| &l[72..73] == "P").collect();
    assert!(p.len() > 1);
    for l in p {
        assert_eq!(l[64..72].trim(), "1");
    }
    let t = text.lines().last().unwrap();
    assert!(t.starts_with("S      1G"));
}

#[test]
fn reads_a_file_in_another_tools_style() {
    let text = include_str!("data/occt_style_panel.igs");
    let s = read_iges(text).unwrap();
    assert_eq!(s.len(), 1);
    let s = &s[0];
    assert_eq!((s.u_degree, s.v_degree, s.nu, s.nv), (2, 1, 3, 2));
    assert_eq!(s.u_knots, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    assert_eq!(s.v_knots, vec![0.0, 0.0, 1.0, 1.0]);
    // IGES lists u fastest; the kernel layout is i * nv + j. The file's
    // entity-124 transform translates by (100, 0, 0).
    let expect = [
        (0, 0, [0.0, 0.0, 0.0]),
        (1, 0, [5.0, 0.0, 2.0]),
        (2, 0, [10.0, 0.0, 0.0]),
        (0, 1, [0.0, 8.0, 0.0]),
        (1, 1, [5.0, 8.0, 2.0]),
        (2, 1, [10.0, 8.0, 0.0]),
    ];
    for (i, j, p) in expect {
        let want = DVec3::from(p) + DVec3::new(100.0, 0.0, 0.0);
        assert_eq!(s.points[i * s.nv + j], want, "point ({i},{j})");
    }
}

#[test]
fn iges_export_of_any_name_is_80_ascii_columns_and_reads_back() {
    let s = dome(6, 5);
    // Non-ASCII letters (one straddling column 72 of the Start record),
    // line breaks, control characters, the delimiters and a fake Hollerith
    // prefix, and a name longer than a record.
    let straddle = format!("{}é{}", "a".repeat(15), "b".repeat(80));
    let names = [
        "Crème brûlée — été",
        "two\nlines\r\n\u{7}bell\ttab",
        "commas, semi; 5Hfake",
        straddle.as_str(),
        "日本語のデザイン名",
    ];
    for name in names {
        let text = write_iges(&s, &IgesMeta::now(name, "tést\nauthor")).unwrap();
        assert!(text.is_ascii(), "{name:?}");
        for line in text.lines() {
            assert_eq!(line.len(), 80, "{name:?}: {line:?}");
        }
        let back = read_iges(&text).unwrap_or_else(|e| panic!("{name:?}: {e}"));
        assert_eq!(back, vec![s.clone()], "{name:?}");
    }
}

#[test]
fn iges_import_refuses_coordinates_beyond_1e9() {
    for (value, ok) in [
        (1e9, true),
        (-1e9, true),
        (1.5e9, false),
        (1e20, false),
        (1e300, false),
    ] {
        let mut s = dome(4, 4);
        s.points[5].y = value;
        let text = write_iges(&s, &IgesMeta::now("big", "t")).unwrap();
        match read_iges(&text) {
            Ok(back) if ok => assert_eq!(back[0].points[5].y, value),
            Err(IgesError::TooLarge {
                de: 1,
                what,
                value: v,
            }) if !ok => {
                assert_eq!(what, "control point coordinate");
                assert_eq!(v, value);
            }
            other => panic!("{value}: {other:?}"),
        }
    }
    let mut s = dome(4, 4);
    let n = s.u_knots.len();
    s.u_knots[n - 4..].fill(1e12);
    let text = write_iges(&s, &IgesMeta::now("knots", "t")).unwrap();
    let e = read_iges(&text).unwrap_err();
    assert!(
        matches!(e, IgesError::TooLarge { what: "knot", .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("1e9"), "{e}");
}

#[test]
fn rejects_rational_weights_clearly() {
    let text = include_str!("data/rational_arc_panel.igs");
    match read_iges(text) {
        Err(IgesError::RationalWeights { de, min, max }) => {
            assert_eq!(de, 5);
            assert_eq!(min, 0.707);
            assert_eq!(max, 1.0);
        }
        other => panic!("expected RationalWeights, got {other:?}"),
    }
}

#[test]
fn rejects_malformed_files() {
    assert!(matches!(
        read_iges("hello world"),
        Err(IgesError::NotIges(_))
    ));
    assert!(matches!(read_iges(""), Err(IgesError::NotIges(_))));
    let good = write_iges(&dome(4, 4), &IgesMeta::now("x", "y")).unwrap();
    // Truncate the parameter data: the entity's last P line goes missing.
    let cut: Vec<&str> = good.lines().collect();
    let without_last_p: String = cut
        .iter()
        .enumerate()
        .filter(|(k, l)| !(&l[72..73] == "P" && cut[k + 1].as_bytes()[72] == b'T'))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    assert!(read_iges(&without_last_p).is_err());
    // A number replaced by garbage.
    let garbage = good.replacen("128,3,3,3,3", "128,X,3,3,3", 1);
    assert!(matches!(
        read_iges(&garbage),
        Err(IgesError::BadParameter { .. })
    ));
    // A file with no surface entity.
    let none: String = include_str!("data/occt_style_panel.igs").replace("     128", "     126");
    assert!(read_iges(&none).is_err());
    // Inconsistent surface refused by the writer.
    let mut bad = dome(4, 4);
    bad.points.pop();
    assert!(matches!(
        write_iges(&bad, &IgesMeta::now("x", "y")),
        Err(IgesError::InvalidSurface(_))
    ));
    let mut nan = dome(4, 4);
    nan.points[3].x = f64::NAN;
    assert!(write_iges(&nan, &IgesMeta::now("x", "y")).is_err());
}

/// A flat n×n vertex grid: (n−1)² quads, two triangles each.
fn grid(n: usize) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let mut p = Vec::new();
    let mut nrm = Vec::new();
    for i in 0..n {
        for j in 0..n {
            p.push([i as f32, j as f32, 0.0]);
            nrm.push([0.0, 0.0, 1.0]);
        }
    }
    let mut idx = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let a = (i * n + j) as u32;
            let b = a + n as u32;
            idx.extend([a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    (p, nrm, idx)
}

#[test]
fn mesh_validation_refuses_bad_meshes() {
    let (p, n, i) = grid(3);
    assert!(Mesh::new(&p, &n[1..], &i).is_err());
    assert!(Mesh::new(&p, &n, &i[1..]).is_err());
    let mut bad = i.clone();
    bad[0] = 99;
    assert!(Mesh::new(&p, &n, &bad).is_err());
    let mut q = p.clone();
    q[0][0] = f32::INFINITY;
    assert!(Mesh::new(&q, &n, &i).is_err());
}

#[test]
fn obj_parses_back() {
    let (p, n, i) = grid(5);
    let mesh = Mesh::new(&p, &n, &i).unwrap();
    let obj = write_obj(&mesh, "demo shell");
    let (mut v, mut vn, mut faces) = (Vec::new(), 0, Vec::new());
    for line in obj.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => v.push(it.map(|x| x.parse::<f32>().unwrap()).collect::<Vec<_>>()),
            Some("vn") => vn += 1,
            Some("f") => {
                let f: Vec<u32> = it
                    .map(|c| {
                        let (a, b) = c.split_once("//").unwrap();
                        assert_eq!(a, b);
                        a.parse().unwrap()
                    })
                    .collect();
                assert_eq!(f.len(), 3);
                faces.extend(f);
            }
            _ => {}
        }
    }
    assert_eq!(v.len(), 25);
    assert_eq!(vn, 25);
    assert_eq!(faces.len(), i.len());
    for (k, &f) in faces.iter().enumerate() {
        assert_eq!(f, i[k] + 1);
        assert_eq!(v[(f - 1) as usize], p[i[k] as usize].to_vec());
    }
}

#[test]
fn stl_has_the_published_binary_layout() {
    let (p, n, i) = grid(4);
    let mesh = Mesh::new(&p, &n, &i).unwrap();
    let stl = write_stl(&mesh, "x");
    let tris = i.len() / 3;
    assert_eq!(stl.len(), 84 + 50 * tris);
    assert!(!stl.starts_with(b"solid"));
    assert_eq!(
        u32::from_le_bytes(stl[80..84].try_into().unwrap()) as usize,
        tris
    );
    let f = |o: usize| f32::from_le_bytes(stl[o..o + 4].try_into().unwrap());
    for t in 0..tris {
        let o = 84 + 50 * t;
        // Triangles of a flat grid in z = 0, wound (a, b, a+1) counter-clockwise seen from +z.
        assert_eq!([f(o), f(o + 4), f(o + 8)], [0.0, 0.0, 1.0]);
        for c in 0..3 {
            let v = [f(o + 12 + 12 * c), f(o + 16 + 12 * c), f(o + 20 + 12 * c)];
            assert_eq!(v, p[i[3 * t + c] as usize]);
        }
        assert_eq!(&stl[o + 48..o + 50], &[0, 0]);
    }
}

#[test]
fn gltf_json_and_buffer_agree() {
    use base64::Engine;
    let (p, n, i) = grid(6);
    let mesh = Mesh::new(&p, &n, &i).unwrap();
    let doc: serde_json::Value = serde_json::from_str(&write_gltf(&mesh, "demo")).unwrap();
    assert_eq!(doc["asset"]["version"], "2.0");
    let uri = doc["buffers"][0]["uri"].as_str().unwrap();
    let b64 = uri
        .strip_prefix("data:application/octet-stream;base64,")
        .unwrap();
    let buf = base64::engine::general_purpose::STANDARD
        .decode(b64)
        .unwrap();
    assert_eq!(
        doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
        buf.len()
    );
    let prim = &doc["meshes"][0]["primitives"][0];
    let acc = |k: &serde_json::Value| &doc["accessors"][k.as_u64().unwrap() as usize];
    let pos = acc(&prim["attributes"]["POSITION"]);
    let nor = acc(&prim["attributes"]["NORMAL"]);
    let ind = acc(&prim["indices"]);
    assert_eq!(pos["count"], p.len());
    assert_eq!(nor["count"], n.len());
    assert_eq!(ind["count"], i.len());
    assert_eq!(pos["min"], serde_json::json!([0.0, 0.0, 0.0]));
    assert_eq!(pos["max"], serde_json::json!([5.0, 5.0, 0.0]));
    let view =
        |a: &serde_json::Value| &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let mut end = 0;
    for (a, size) in [(pos, 12), (nor, 12), (ind, 4)] {
        let v = view(a);
        let off = v["byteOffset"].as_u64().unwrap() as usize;
        let len = v["byteLength"].as_u64().unwrap() as usize;
        assert_eq!(len, size * a["count"].as_u64().unwrap() as usize);
        assert!(off + len <= buf.len());
        end = end.max(off + len);
    }
    assert_eq!(end, buf.len());
    let ioff = view(ind)["byteOffset"].as_u64().unwrap() as usize;
    for (k, &want) in i.iter().enumerate() {
        let got = u32::from_le_bytes(buf[ioff + 4 * k..ioff + 4 * k + 4].try_into().unwrap());
        assert_eq!(got, want);
        assert!((got as usize) < p.len());
    }
}
