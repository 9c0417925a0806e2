//! OpenVDB level sets: any bytes give a dense grid of samples or an error, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rfta_io::{SdfFormat, decode_sdf};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("/nonexistent/rfta-fuzz/input.vdb");
    if let Ok(raw) = decode_sdf(data, SdfFormat::Vdb, path, None) {
        let _ = raw.validate(path);
    }
});
