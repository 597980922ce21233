#![no_main]
//! OBJ through tobj and cgnodes' checks: whole-file mesh, one group, and per-object load.
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let dir = common::scratch();
    let p = dir.join("in.obj");
    std::fs::write(&p, data).unwrap();
    let _ = cgnodes::nodes::mesh::obj::load_obj(&p, "");
    let _ = cgnodes::nodes::mesh::obj::load_obj(&p, "g0");
    let _ = cgnodes::nodes::mesh::obj::load_obj_objects(&p);
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = cgnodes::nodes::mesh::obj::find_bad_obj_line(text);
    }
});
