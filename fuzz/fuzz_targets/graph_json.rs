#![no_main]
//! Native graph JSON: parse, validate against the built-in nodes, render as DOT.
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let reg = cgnodes::nodes::builtin_registry();
    if let Ok(g) = cgnodes::graph::parse(text, Path::new("fuzz.json"), Path::new("/nonexistent")) {
        if let Ok(v) = cgnodes::validate::validate(&g, &reg) {
            let _ = v.to_dot();
        }
    }
});
