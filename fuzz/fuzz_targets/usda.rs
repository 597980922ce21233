#![no_main]
//! USDA layers: the parser, then mesh reading of every mesh prim with and without transforms.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    use cgnodes::nodes::mesh::usda;
    let Ok(layer) = usda::parse_usda(text) else {
        return;
    };
    let _ = usda::read_usda(text, "", true);
    for p in usda::mesh_paths(&layer).iter().take(4) {
        let _ = usda::read_usda(text, p, true);
        let _ = usda::read_usda(text, p, false);
    }
});
