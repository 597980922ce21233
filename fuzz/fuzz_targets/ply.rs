#![no_main]
//! PLY meshes, ASCII and binary (both endians).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cgnodes::nodes::mesh::ply::read_ply(data);
});
