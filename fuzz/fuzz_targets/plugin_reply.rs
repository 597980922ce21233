#![no_main]
//! Plugin replies: the JSON before the first NUL byte is decoded as each socket type; the
//! bytes after it are the `.npy` file `a.npy` that the reply may name.
use cgnodes::types::SocketType;
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let (json, npy) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let Ok(j) = serde_json::from_slice::<serde_json::Value>(json) else {
        return;
    };
    let dir = common::scratch().join("call");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a.npy"), npy).unwrap();
    let inputs = Default::default();
    for ty in [
        SocketType::Mesh,
        SocketType::Points,
        SocketType::Image,
        SocketType::Table,
        SocketType::Curve,
        SocketType::Float,
        SocketType::Int,
        SocketType::Vec3,
        SocketType::String,
        SocketType::List(Box::new(SocketType::Float)),
        SocketType::List(Box::new(SocketType::Mesh)),
    ] {
        let _ = cgnodes::plugin::codec::decode(&ty, &j, &dir, &inputs);
    }
});
