//! PLY, ascii and binary: as a mesh, as scattered SDF samples and as oriented points.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rfta_io::{MeshFormat, SdfFormat, decode_mesh, decode_oriented_points, decode_sdf};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("/nonexistent/rfta-fuzz/input.ply");
    let _ = decode_mesh(data, MeshFormat::Ply, path);
    if let Ok(raw) = decode_sdf(data, SdfFormat::Ply, path, None) {
        let _ = raw.validate(path);
    }
    let _ = decode_oriented_points(data, path);
});
