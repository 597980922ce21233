#![no_main]
//! Fuzz target `image`: see `cgnodes::fuzz::image`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("image", data, common::scratch());
});
