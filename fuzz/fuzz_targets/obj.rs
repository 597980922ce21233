#![no_main]
//! Fuzz target `obj`: see `cgnodes::fuzz::obj`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("obj", data, common::scratch());
});
