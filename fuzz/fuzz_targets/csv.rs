#![no_main]
//! Fuzz target `csv`: see `cgnodes::fuzz::csv`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("csv", data, common::scratch());
});
