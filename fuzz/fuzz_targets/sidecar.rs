//! The JSON sidecar beside a grid: any bytes as `NAME.json` next to a valid `.npy` (or `.exr`
//! volume) give a grid or an error naming the sidecar, never a panic; then validation.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use rfta_io::{SdfFormat, decode_sdf, write_npy_f64};

/// A folder of this process's own, holding the sidecar each input is written to.
fn dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("rfta-fuzz-sidecar-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("a scratch folder");
        d
    })
}

/// A 3 x 3 x 3 grid of a sphere's distances, as `.npy` bytes.
fn grid() -> &'static [u8] {
    static NPY: OnceLock<Vec<u8>> = OnceLock::new();
    NPY.get_or_init(|| {
        let values: Vec<f64> = (0..27)
            .map(|i| {
                let c = [(i / 9) as f64 - 1.0, ((i / 3) % 3) as f64 - 1.0, (i % 3) as f64 - 1.0];
                (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() - 0.9
            })
            .collect();
        let mut bytes = Vec::new();
        write_npy_f64(&mut bytes, &[3, 3, 3], &values).expect("npy bytes");
        bytes
    })
}

fuzz_target!(|data: &[u8]| {
    let path = dir().join("grid.npy");
    if std::fs::write(dir().join("grid.json"), data).is_err() {
        return;
    }
    if let Ok(raw) = decode_sdf(grid(), SdfFormat::Npy, &path, None) {
        let _ = raw.validate(&path);
    }
});
