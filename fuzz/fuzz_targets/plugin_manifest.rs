#![no_main]
//! Plugin manifests (`cgnodes-plugin.json`), loaded and registered.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let dir = common::scratch().join("plugin");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(cgnodes::plugin::MANIFEST), data).unwrap();
    if let Ok(p) = cgnodes::plugin::load(&dir) {
        let mut reg = cgnodes::nodes::builtin_registry();
        let _ = cgnodes::plugin::register(&mut reg, p);
    }
});
