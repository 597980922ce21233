#![no_main]
//! Fuzz target `plugin_reply`: see `cgnodes::fuzz::plugin_reply`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("plugin_reply", data, common::scratch());
});
