//! A token is found through indexes, not by loading every design: the
//! lookup gives the right design and role for every token among many
//! designs (none for an unknown, empty or deleted design's token), and
//! SQLite's own query plan shows index searches, no table scan.

use vsculpt_server::store::token_index::TOKEN_LOOKUP;
use vsculpt_server::store::{Role, Store};

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("vsculpt-tokidx-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn every_token_finds_its_design_and_role() {
    let dir = tmp("lookup");
    let store = Store::open(&dir).unwrap();
    store.ensure_token_indexes().unwrap();
    let recs: Vec<_> = (0..50)
        .map(|k| store.create_design(&format!("d{k}"), b"{}").unwrap())
        .collect();
    for r in &recs {
        for (token, role) in [
            (&r.tokens.editor, Role::Editor),
            (&r.tokens.viewer, Role::Viewer),
            (&r.tokens.device, Role::Device),
        ] {
            let (found, got) = store.design_by_token(token).unwrap().unwrap();
            assert_eq!((found.id, got), (r.id, role));
        }
    }
    assert!(store.design_by_token("").unwrap().is_none());
    assert!(store.design_by_token(&"0".repeat(64)).unwrap().is_none());
    store.delete_design(recs[7].id).unwrap();
    assert!(
        store
            .design_by_token(&recs[7].tokens.editor)
            .unwrap()
            .is_none()
    );
    drop(store);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_lookup_searches_indexes_and_scans_no_table() {
    let dir = tmp("plan");
    let store = Store::open(&dir).unwrap();
    store.ensure_token_indexes().unwrap();
    for k in 0..20 {
        store.create_design(&format!("d{k}"), b"{}").unwrap();
    }
    drop(store);
    let conn = rusqlite::Connection::open(dir.join("vsculpt.db")).unwrap();
    let mut stmt = conn
        .prepare(&format!("EXPLAIN QUERY PLAN {TOKEN_LOOKUP}"))
        .unwrap();
    let details: Vec<String> = stmt
        .query_map(["abc"], |row| row.get::<_, String>(3))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert!(
        details.iter().all(|d| !d.starts_with("SCAN designs")),
        "{details:?}"
    );
    let searches = details
        .iter()
        .filter(|d| d.starts_with("SEARCH designs USING INDEX designs_"))
        .count();
    assert_eq!(searches, 3, "{details:?}");
    drop(stmt);
    drop(conn);
    let _ = std::fs::remove_dir_all(&dir);
}
