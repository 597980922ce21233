//! The record a Rust benchmark writes: `bench/results/NAME.json` with the command, commit,
//! date and machine beside its own fields (as `bench/_record.py` does for the scripts).
//! Included by path (`#[path = "record.rs"] mod record;`) in the benches that keep a record.

use serde_json::{json, Value as Json};
use std::path::PathBuf;
use std::process::Command;

/// Writes `bench/results/NAME.json` from `fields` (an object) and returns its path.
pub fn write(name: &str, command: &str, fields: Json) -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out = |cmd: &str, args: &[&str]| {
        Command::new(cmd)
            .args(args)
            .current_dir(&root)
            .output()
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
            .unwrap_or_default()
    };
    let mut rec = json!({
        "benchmark": name,
        "command": command,
        "commit": out("git", &["rev-parse", "--short", "HEAD"]),
        "date": out("date", &["-u", "+%Y-%m-%dT%H:%M:%SZ"]),
        "machine": {
            "cores": std::thread::available_parallelism().map_or(0, |n| n.get()),
            "load_average": std::fs::read_to_string("/proc/loadavg").ok()
                .and_then(|l| l.split_whitespace().next().map(String::from)),
        },
    });
    if let (Some(r), Json::Object(f)) = (rec.as_object_mut(), fields) {
        r.extend(f);
    }
    let path = root.join("bench/results").join(format!("{name}.json"));
    let _ = std::fs::create_dir_all(path.parent().expect("a folder"));
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&rec).unwrap_or_default(),
    )
    .expect("bench/results is writable");
    path
}
