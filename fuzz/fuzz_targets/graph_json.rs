#![no_main]
//! Fuzz target `graph_json`: see `cgnodes::fuzz::graph_json`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("graph_json", data, common::scratch());
});
