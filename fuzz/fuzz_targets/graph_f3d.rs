#![no_main]
//! Fuzz target `graph_f3d`: see `cgnodes::fuzz::graph_f3d`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("graph_f3d", data, common::scratch());
});
