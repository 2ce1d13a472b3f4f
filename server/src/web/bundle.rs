//! The web client's bundle: the page's modules and the parts of three.js
//! they use, minified into a few files by `web-client/tools/bundle.mjs` at
//! install time, in `web-client/dist/<sources>/` with a `manifest.json`.
//! `<sources>` is [`sources_hash`] of the client's own modules and three's
//! version, so the page is served from the bundle only while it was built
//! from the modules on disk ([`current`]); after an edit of `src/` (a
//! developer at work) the page is served from the modules again, never
//! stale. The bundle's URLs carry `<sources>`, so they are immutable.

use super::content_hash;
use std::path::Path;

/// A bundle built from the current sources.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Bundle {
    /// The sources' hash: the bundle's folder under `dist/` and its URL path.
    pub sources: String,
    /// The page's entry module, a file in that folder.
    pub entry: String,
    /// The chunks the entry imports statically (hinted with `modulepreload`).
    pub preload: Vec<String>,
}

/// The hash that names a bundle (the same as `sourcesHash` in
/// `tools/bundle.mjs`): the [`content_hash`] of one line `PATH HASH` per
/// own JavaScript module (`own`: sorted `/src/NAME` and content hash, as
/// `own_files` gives them; other files are skipped) and a last line
/// `three@VERSION`, each line ending in a newline.
pub fn sources_hash(own: &[(String, String)], three: &str) -> String {
    let mut text = String::new();
    for (path, hash) in own.iter().filter(|(p, _)| p.ends_with(".js")) {
        text.push_str(&format!("{path} {hash}\n"));
    }
    text.push_str(&format!("three@{three}\n"));
    content_hash(text.as_bytes())
}

/// A plain file name: what a manifest may name (no path, nothing to escape in HTML).
fn file_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 128
        && !name.starts_with('.')
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_' || b == b'.')
}

/// The bundle of the current sources, if `web_dir/dist/<sources>/` holds
/// one with a sound manifest and its entry; `None` otherwise (not built,
/// built from other sources, or damaged: the page then loads the modules).
pub fn current(web_dir: &Path, own: &[(String, String)], three: &str) -> Option<Bundle> {
    let sources = sources_hash(own, three);
    let dir = web_dir.join("dist").join(&sources);
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).ok()?).ok()?;
    if manifest.get("sources")?.as_str()? != sources {
        return None;
    }
    let entry = manifest.get("entry")?.as_str()?.to_string();
    let preload = manifest
        .get("preload")?
        .as_array()?
        .iter()
        .map(|v| v.as_str().map(str::to_string))
        .collect::<Option<Vec<_>>>()?;
    let sound = file_name(&entry)
        && preload.iter().all(|p| file_name(p))
        && std::iter::once(&entry)
            .chain(&preload)
            .all(|f| dir.join(f).is_file());
    sound.then_some(Bundle {
        sources,
        entry,
        preload,
    })
}

/// index.html loading `bundle` instead of the modules: the entry script
/// `/src/app.js` becomes the bundle's entry, and the modules'
/// `modulepreload` hints give way to hints for the entry's chunks.
pub fn bundled_index(html: &str, bundle: &Bundle) -> String {
    let base = format!("/dist/{}/", bundle.sources);
    let mut out = String::with_capacity(html.len());
    let mut hinted = false;
    for line in html.split_inclusive('\n') {
        if line.trim_start().starts_with("<link rel=\"modulepreload\"") {
            if !hinted {
                let indent = &line[..line.len() - line.trim_start().len()];
                for chunk in &bundle.preload {
                    out.push_str(&format!(
                        "{indent}<link rel=\"modulepreload\" href=\"{base}{chunk}\">\n"
                    ));
                }
                hinted = true;
            }
            continue;
        }
        out.push_str(line);
    }
    out.replace(
        "<script type=\"module\" src=\"/src/app.js\">",
        &format!("<script type=\"module\" src=\"{base}{}\">", bundle.entry),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sources_hash_is_the_documented_fnv_of_the_lines() {
        let own = vec![
            ("/src/a.js".to_string(), "0000000000000001".to_string()),
            ("/src/b.css".to_string(), "0000000000000002".to_string()),
            ("/src/c.js".to_string(), "0000000000000003".to_string()),
        ];
        let text = "/src/a.js 0000000000000001\n/src/c.js 0000000000000003\nthree@0.187.0\n";
        assert_eq!(sources_hash(&own, "0.187.0"), content_hash(text.as_bytes()));
        assert_ne!(sources_hash(&own, "0.188.0"), sources_hash(&own, "0.187.0"));
    }

    #[test]
    fn the_bundled_page_loads_the_entry_and_hints_its_chunks_only() {
        let html = "<head>\n  <link rel=\"modulepreload\" href=\"/src/a.js\">\n  <link rel=\"modulepreload\" href=\"/vendor/three/x.js\">\n  <link rel=\"stylesheet\" href=\"/src/style.css\">\n</head>\n<script type=\"module\" src=\"/src/app.js\"></script>\n";
        let b = Bundle {
            sources: "00ff".into(),
            entry: "app.js".into(),
            preload: vec!["chunk-A.js".into(), "chunk-B.js".into()],
        };
        assert_eq!(
            bundled_index(html, &b),
            "<head>\n  <link rel=\"modulepreload\" href=\"/dist/00ff/chunk-A.js\">\n  <link rel=\"modulepreload\" href=\"/dist/00ff/chunk-B.js\">\n  <link rel=\"stylesheet\" href=\"/src/style.css\">\n</head>\n<script type=\"module\" src=\"/dist/00ff/app.js\"></script>\n"
        );
    }

    #[test]
    fn a_manifest_naming_paths_is_not_trusted() {
        for bad in ["../x.js", "a/b.js", "", ".hidden", "a\"b.js", "a b.js"] {
            assert!(!file_name(bad), "{bad:?}");
        }
        assert!(file_name("chunk-4QMBQ2TV.js"));
    }

    #[test]
    fn only_a_bundle_of_the_current_sources_is_used() {
        /// A scratch web folder, removed when the test ends (also on failure).
        struct Scratch(std::path::PathBuf);
        impl Drop for Scratch {
            fn drop(&mut self) {
                let _ = std::fs::remove_dir_all(&self.0);
            }
        }
        let web = Scratch(
            std::env::temp_dir().join(format!("vsculpt-web-bundle-{}", std::process::id())),
        );
        let own = vec![("/src/app.js".to_string(), "00000000000000aa".to_string())];
        let sources = sources_hash(&own, "0.187.0");
        let dir = web.0.join("dist").join(&sources);
        std::fs::create_dir_all(&dir).unwrap();
        let manifest = |sources: &str, preload: &str| {
            format!(r#"{{"sources": "{sources}", "entry": "app.js", "preload": [{preload}]}}"#)
        };
        std::fs::write(
            dir.join("manifest.json"),
            manifest(&sources, r#""chunk-A.js""#),
        )
        .unwrap();
        std::fs::write(dir.join("app.js"), "x").unwrap();
        // A hinted chunk that is missing: not sound.
        assert_eq!(current(&web.0, &own, "0.187.0"), None);
        std::fs::write(dir.join("chunk-A.js"), "y").unwrap();
        assert_eq!(
            current(&web.0, &own, "0.187.0"),
            Some(Bundle {
                sources: sources.clone(),
                entry: "app.js".into(),
                preload: vec!["chunk-A.js".into()]
            })
        );
        // A module edited since, or another three: the modules, not the bundle.
        let edited = vec![("/src/app.js".to_string(), "00000000000000ab".to_string())];
        assert_eq!(current(&web.0, &edited, "0.187.0"), None);
        assert_eq!(current(&web.0, &own, "0.188.0"), None);
        // A manifest that names a path outside its folder is refused.
        std::fs::write(
            dir.join("manifest.json"),
            manifest(&sources, r#""../../x.js""#),
        )
        .unwrap();
        assert_eq!(current(&web.0, &own, "0.187.0"), None);
    }
}
