//! Binary glTF meshes: any bytes give a validated mesh or an error, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rfta_io::{MeshFormat, decode_mesh};

fuzz_target!(|data: &[u8]| {
    let _ = decode_mesh(data, MeshFormat::Glb, Path::new("input.glb"));
});
