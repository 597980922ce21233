#![no_main]
//! Fuzz target `npy`: see `cgnodes::fuzz::npy`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("npy", data, common::scratch());
});
