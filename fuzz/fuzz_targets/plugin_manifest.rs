#![no_main]
//! Fuzz target `plugin_manifest`: see `cgnodes::fuzz::plugin_manifest`.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    cgnodes::fuzz::run("plugin_manifest", data, common::scratch());
});
