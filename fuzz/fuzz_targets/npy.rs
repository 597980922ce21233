#![no_main]
//! `.npy` arrays as plugins return them, and their conversions.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(a) = cgnodes::plugin::npy::NpyArray::from_bytes(data) {
        let _ = a.shape_str();
        let _ = a.to_f64();
        let _ = a.to_i64();
        let _ = a.to_bytes();
    }
});
