//! The embedded store on its own: designs with distinct unguessable tokens,
//! versions numbered in order with their metadata and snapshots, working
//! state, deletion, and everything back after reopening the same directory.

use vsculpt_server::store::{Role, Store};

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("vsculpt-store-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn designs_versions_and_working_state_survive_reopen() {
    let dir = tmp("reopen");
    let (a, b);
    {
        let store = Store::open(&dir).unwrap();
        a = store.create_design("shell", b"s0").unwrap();
        b = store.create_design("lid", b"l0").unwrap();
        assert_ne!(a.id, b.id);
        let v1 = store.commit(a.id, "ann", "first", b"s1").unwrap();
        let v2 = store.commit(a.id, "bob", "second", b"s2").unwrap();
        assert_eq!((v1.number, v2.number), (1, 2));
        assert!(v2.time_ms >= v1.time_ms);
        store.save_working(a.id, b"s2+drag").unwrap();
    }
    let store = Store::open(&dir).unwrap();
    let designs = store.designs().unwrap();
    assert_eq!(designs, vec![a.clone(), b.clone()]);
    let versions = store.versions(a.id).unwrap();
    assert_eq!(versions.len(), 2);
    assert_eq!(
        (versions[0].author.as_str(), versions[0].message.as_str()),
        ("ann", "first")
    );
    assert_eq!(store.version(a.id, 1).unwrap().unwrap().1, b"s1");
    assert_eq!(store.latest_version(a.id).unwrap().unwrap().1, b"s2");
    assert_eq!(store.working(a.id).unwrap().unwrap(), b"s2+drag");
    assert_eq!(store.working(b.id).unwrap().unwrap(), b"l0");
    assert!(store.version(a.id, 3).unwrap().is_none());
    assert!(store.versions(b.id).unwrap().is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tokens_are_distinct_random_and_map_to_roles() {
    let dir = tmp("tokens");
    let store = Store::open(&dir).unwrap();
    let a = store.create_design("a", b"").unwrap();
    let b = store.create_design("b", b"").unwrap();
    let all = [
        &a.tokens.editor,
        &a.tokens.viewer,
        &a.tokens.device,
        &b.tokens.editor,
        &b.tokens.viewer,
        &b.tokens.device,
    ];
    for (k, t) in all.iter().enumerate() {
        assert_eq!(t.len(), 64);
        assert!(t.chars().all(|c| c.is_ascii_hexdigit()));
        for u in &all[k + 1..] {
            assert_ne!(t, u);
        }
    }
    assert_eq!(a.tokens.role_of(&a.tokens.editor), Some(Role::Editor));
    assert_eq!(a.tokens.role_of(&a.tokens.viewer), Some(Role::Viewer));
    assert_eq!(a.tokens.role_of(&a.tokens.device), Some(Role::Device));
    assert_eq!(a.tokens.role_of(&b.tokens.editor), None);
    assert_eq!(a.tokens.role_of(""), None);
    assert!(!Role::Viewer.can_edit());
    assert!(Role::Device.can_edit() && !Role::Device.can_manage());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn deleted_designs_disappear_and_refuse_commits() {
    let dir = tmp("delete");
    let store = Store::open(&dir).unwrap();
    let a = store.create_design("a", b"x").unwrap();
    store.delete_design(a.id).unwrap();
    assert!(store.design(a.id).unwrap().is_none());
    assert!(store.designs().unwrap().is_empty());
    assert!(store.commit(a.id, "x", "y", b"z").is_err());
    assert!(store.delete_design(a.id).is_err());
    assert!(store.delete_design(999).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}
