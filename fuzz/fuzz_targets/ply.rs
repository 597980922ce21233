#![no_main]
//! Fuzz target `ply`: see `cgnodes::fuzz::ply`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("ply", data, common::scratch());
});
