//! `.npy` grids and row arrays: any bytes give samples or an error, and validation never panics.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rfta_io::{SdfFormat, decode_sdf};

fuzz_target!(|data: &[u8]| {
    // A directory that does not exist, so no sidecar is ever read.
    let path = Path::new("/nonexistent/rfta-fuzz/input.npy");
    if let Ok(raw) = decode_sdf(data, SdfFormat::Npy, path, None) {
        let _ = raw.validate(path);
    }
});
