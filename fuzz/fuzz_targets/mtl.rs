#![no_main]
//! MTL libraries: a fixed OBJ that names the fuzzed MTL, loaded per object with its materials
//! and as a scene.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

const OBJ: &str =
    "mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n";

fuzz_target!(|data: &[u8]| {
    let dir = common::scratch();
    std::fs::write(dir.join("in.mtl"), data).unwrap();
    let p = dir.join("in.obj");
    if !p.exists() {
        std::fs::write(&p, OBJ).unwrap();
    }
    let _ = cgnodes::nodes::mesh::obj::load_obj_objects(&p);
});
