//! Property-based fuzzing on stable Rust (proptest) of the IGES reader,
//! which takes whole files from the network (`POST …/import`). Inputs are
//! arbitrary text and structured mutations — byte flips, deleted,
//! duplicated and swapped 80-column lines, numbers in the parameter data
//! replaced by extreme ones — of the committed corpus
//! `server/tests/fuzz/iges/` (a valid panel and nasty variants: huge
//! counts and degrees, 1e300 coordinates and transforms, dangling and
//! self-referencing pointers, overlong Hollerith strings, truncation) and
//! of the real-world fixtures in `server/tests/fixtures/iges/`. Every input
//! gives surfaces or a typed [`IgesError`], never a panic, and no single
//! allocation is much larger than the file.
//!
//! `cargo test` runs 256 cases per property; run longer locally with
//! `PROPTEST_CASES=20000 cargo test --release -p vsculpt-server --test fuzz_iges`.

use proptest::prelude::*;
use std::path::PathBuf;
use vsculpt_server::cad::iges::MAX_IGES_MAGNITUDE;
use vsculpt_server::cad::{IgesError, read_iges, read_iges_parts};

#[path = "../../protocol/tests/largest_allocation/mod.rs"]
mod largest_allocation;
use largest_allocation::measured;

/// No single allocation may exceed a multiple of the file size plus a
/// constant: a header's counts cannot make the reader reserve more than
/// the data it actually carries.
fn allowed(len: usize) -> usize {
    64 * len + 256 * 1024
}

fn files(dir: &str) -> Vec<(String, String)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut out: Vec<(String, String)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "igs"))
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (
                p.file_name().unwrap().to_string_lossy().to_string(),
                String::from_utf8_lossy(&bytes).into_owned(),
            )
        })
        .collect();
    out.sort();
    out
}

/// Small seeds for mutation (the big fixtures are read whole once).
fn seeds() -> Vec<String> {
    let mut out: Vec<String> = files("tests/fuzz/iges").into_iter().map(|f| f.1).collect();
    out.extend(
        files("tests/fixtures/iges")
            .into_iter()
            .filter(|(_, t)| t.len() < 32 * 1024)
            .map(|f| f.1),
    );
    out
}

fn check(text: &str) -> Result<(), TestCaseError> {
    let (parts, largest) = measured(|| read_iges_parts(text));
    prop_assert!(
        largest <= allowed(text.len()),
        "{largest} bytes allocated reading a {}-byte file",
        text.len()
    );
    let (surfaces, largest) = measured(|| read_iges(text));
    prop_assert!(largest <= allowed(text.len()));
    // Typed errors with a message; accepted geometry within the limits.
    for e in [parts.as_ref().err(), surfaces.as_ref().err()]
        .into_iter()
        .flatten()
    {
        prop_assert!(!e.to_string().is_empty());
    }
    // Whatever is accepted is a consistent surface within the limits.
    if let Ok(surfaces) = &surfaces {
        for s in surfaces {
            prop_assert_eq!(s.points.len(), s.nu * s.nv);
            prop_assert_eq!(s.u_knots.len(), s.nu + s.u_degree + 1);
            prop_assert_eq!(s.v_knots.len(), s.nv + s.v_degree + 1);
            let ok = |x: f64| x.is_finite() && x.abs() <= MAX_IGES_MAGNITUDE;
            prop_assert!(s.points.iter().all(|p| ok(p.x) && ok(p.y) && ok(p.z)));
            prop_assert!(s.u_knots.iter().chain(&s.v_knots).all(|k| ok(*k)));
        }
    }
    Ok(())
}

#[test]
fn every_seed_and_fixture_reads_or_fails_typed() {
    for (name, text) in files("tests/fuzz/iges")
        .into_iter()
        .chain(files("tests/fixtures/iges"))
    {
        check(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn the_nasty_seeds_are_refused_with_the_expected_error() {
    let all = files("tests/fuzz/iges");
    let get = |n: &str| read_iges_parts(&all.iter().find(|f| f.0 == n).unwrap().1);
    assert!(get("panel.igs").is_ok());
    for name in [
        "nasty_huge_counts.igs",
        "nasty_huge_degree.igs",
        "nasty_dangling_pointer.igs",
        "nasty_truncated.igs",
        "nasty_negative_counts.igs",
        "nasty_empty.igs",
        "nasty_nan.igs",
    ] {
        assert!(get(name).is_err(), "{name} was accepted");
    }
    for name in ["nasty_huge_coordinate.igs", "nasty_huge_transform.igs"] {
        assert!(
            matches!(get(name), Err(IgesError::TooLarge { .. })),
            "{name}: {:?}",
            get(name)
        );
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    FlipByte(usize, u8),
    DeleteLine(usize),
    DuplicateLine(usize),
    SwapLines(usize, usize),
    Truncate(usize),
    /// Replaces the k-th number of the text with an extreme one.
    Number(usize, &'static str),
}

const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "999999999",
    "2147483648",
    "-2147483649",
    "1.D300",
    "-1.D308",
    "1.D-320",
    "1.E9",
    "1.000001E9",
    "NaN",
    "1.D",
    "",
    "99999999999999999999",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::FlipByte(i, b)),
        any::<usize>().prop_map(Mutation::DeleteLine),
        any::<usize>().prop_map(Mutation::DuplicateLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), prop::sample::select(NUMBERS)).prop_map(|(k, n)| Mutation::Number(k, n)),
    ]
}

fn apply(seed: &str, mutations: &[Mutation]) -> String {
    let mut bytes = seed.as_bytes().to_vec();
    for m in mutations {
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let mut lines: Vec<&str> = text.split('\n').collect();
        let n = lines.len().max(1);
        bytes = match m {
            Mutation::FlipByte(i, b) if !bytes.is_empty() => {
                let k = i % bytes.len();
                // Printable ASCII keeps the 80-column layout reachable.
                bytes[k] = 0x20 + b % 0x5f;
                bytes
            }
            Mutation::DeleteLine(i) if !lines.is_empty() => {
                lines.remove(i % n);
                lines.join("\n").into_bytes()
            }
            Mutation::DuplicateLine(i) if !lines.is_empty() => {
                let l = lines[i % n];
                lines.insert(i % n, l);
                lines.join("\n").into_bytes()
            }
            Mutation::SwapLines(a, b) if !lines.is_empty() => {
                lines.swap(a % n, b % n);
                lines.join("\n").into_bytes()
            }
            Mutation::Truncate(i) => {
                bytes.truncate(i % (bytes.len() + 1));
                bytes
            }
            Mutation::Number(k, new) => {
                // The k-th run of digits (with sign, point and exponent).
                let spans: Vec<(usize, usize)> = number_spans(&text);
                if spans.is_empty() {
                    bytes
                } else {
                    let (s, e) = spans[k % spans.len()];
                    format!("{}{}{}", &text[..s], new, &text[e..]).into_bytes()
                }
            }
            _ => bytes,
        };
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            let s = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || b".DE+-".contains(&b[i])) {
                i += 1;
            }
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

proptest! {
    #[test]
    fn reader_survives_arbitrary_text(text in "\\PC{0,400}") {
        check(&text)?;
    }

    #[test]
    fn reader_survives_arbitrary_80_column_records(
        lines in prop::collection::vec("[ -~]{72}[SGDPT][ 0-9]{7}", 0..24)
    ) {
        check(&lines.join("\n"))?;
    }

    #[test]
    fn reader_survives_mutated_files(
        seed in prop::sample::select(seeds()),
        ms in prop::collection::vec(mutation(), 1..6),
    ) {
        check(&apply(&seed, &ms))?;
    }
}
