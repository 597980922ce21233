#![no_main]
//! Fuzz target `off`: see `cgnodes::fuzz::off`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("off", data, common::scratch());
});
