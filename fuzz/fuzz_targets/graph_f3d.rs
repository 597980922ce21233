#![no_main]
//! Framework3D saved node trees: import (strict and lenient), with aliases read from the
//! part after the first NUL byte, then parse and validate as a graph.
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let (tree, aliases) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &b"{}"[..]),
    };
    let Ok(raw) = serde_json::from_slice::<serde_json::Value>(tree) else {
        return;
    };
    let aliases: cgnodes::f3d::Aliases = serde_json::from_slice(aliases).unwrap_or_default();
    let reg = cgnodes::nodes::builtin_registry();
    let _ = cgnodes::f3d::import(&raw, &aliases, &reg);
    let _ = cgnodes::f3d::import_lenient(&raw, &aliases, &reg);
    let text = String::from_utf8_lossy(tree);
    if let Ok(g) = cgnodes::graph::parse_with(
        &text,
        Path::new("fuzz.json"),
        Path::new("/nonexistent"),
        &aliases,
        &reg,
    ) {
        let _ = cgnodes::validate::validate(&g, &reg);
    }
});
