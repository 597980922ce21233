#![no_main]
//! Fuzz target `usda`: see `cgnodes::fuzz::usda`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("usda", data, common::scratch());
});
