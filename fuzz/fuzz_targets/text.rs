//! Text rows: scattered SDF samples (`x y z s`, CSV or whitespace) and oriented points
//! (`x y z nx ny nz`), then validation.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rfta_io::{SdfFormat, decode_oriented_points, decode_sdf};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("/nonexistent/rfta-fuzz/input.csv");
    if let Ok(raw) = decode_sdf(data, SdfFormat::Text, path, None) {
        let _ = raw.validate(path);
    }
    let _ = decode_oriented_points(data, Path::new("input.xyz"));
});
