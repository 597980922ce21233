#![no_main]
//! CSV tables: the shared reader (all option combinations) and compare_series' column reader.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for comments in [false, true] {
        for trim in [false, true] {
            let _ = cgnodes::io::csv::read(text, comments, trim);
        }
    }
    let _ = cgnodes::nodes::metrics::compare_series::read_csv_columns(text, "x", "y");
    let _ = cgnodes::nodes::metrics::compare_series::read_csv_columns(text, "t", "h");
});
