#![no_main]
//! OFF text meshes.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = cgnodes::nodes::mesh::off::read_off(text);
    }
});
