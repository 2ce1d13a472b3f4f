//! `--log-file PATH --log-format json`: the lines land in `PATH.YYYY-MM-DD`
//! (today, UTC) in PATH's directory (created when missing), one JSON object
//! per line carrying the level, the message and the event's fields.

use std::time::Duration;
use vsculpt_logging::{LogArgs, LogFormat};

#[test]
fn json_lines_go_to_the_dated_log_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("logs").join("vsculpt-server.log");
    let args = LogArgs {
        log_file: Some(path.clone()),
        log_format: LogFormat::Json,
    };
    let logging = vsculpt_logging::init(&args, "info").unwrap();
    tracing::info!(design = 7u64, client = "ann", "client joined");
    tracing::debug!("filtered out by the default filter");
    assert!(logging.flush(Duration::from_secs(30)));

    let files: Vec<_> = std::fs::read_dir(dir.path().join("logs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    let name = &files[0];
    let date = name
        .strip_prefix("vsculpt-server.log.")
        .unwrap_or_else(|| panic!("{name}"));
    // YYYY-MM-DD
    let parts: Vec<&str> = date.split('-').collect();
    assert_eq!(
        parts.iter().map(|p| p.len()).collect::<Vec<_>>(),
        vec![4, 2, 2],
        "{name}"
    );
    assert!(parts.iter().all(|p| p.chars().all(|c| c.is_ascii_digit())));

    let text = std::fs::read_to_string(dir.path().join("logs").join(name)).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1, "{text}");
    let v: serde_json::Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(v["level"], "INFO");
    assert_eq!(v["fields"]["message"], "client joined");
    assert_eq!(v["fields"]["design"], 7);
    assert_eq!(v["fields"]["client"], "ann");
    assert_eq!(vsculpt_logging::dropped_lines(), 0);
    // A second install is refused, not silently doubled.
    assert!(vsculpt_logging::init(&LogArgs::default(), "info").is_err());
}
