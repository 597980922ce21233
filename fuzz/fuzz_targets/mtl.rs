#![no_main]
//! Fuzz target `mtl`: see `cgnodes::fuzz::mtl`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("mtl", data, common::scratch());
});
