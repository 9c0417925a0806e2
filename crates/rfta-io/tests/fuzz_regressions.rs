//! Every input the fuzzers found (`fuzz/regressions/<target>/`) and every file of the bad-input
//! corpus (`tests/bad_inputs/`) goes through every reader: each must return, with a mesh, samples
//! or an error, without a panic and in well under a second.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use rfta_io::{MeshFormat, SdfFormat, decode_mesh, decode_oriented_points, decode_sdf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    out.retain(|p| p.is_file());
    out.sort();
    out
}

/// Runs `bytes` through every decoder and the validation of what they accept, as the fuzz
/// targets do; a panic fails the test.
fn every_reader(bytes: &[u8]) {
    // A directory that does not exist: no sidecar is read.
    let at = |ext: &str| PathBuf::from(format!("/nonexistent/rfta-regression/input.{ext}"));
    for (format, ext) in [
        (MeshFormat::Obj, "obj"),
        (MeshFormat::Off, "off"),
        (MeshFormat::Ply, "ply"),
        (MeshFormat::Stl, "stl"),
        (MeshFormat::Glb, "glb"),
    ] {
        let _ = decode_mesh(bytes, format, &at(ext));
    }
    for (format, ext) in [
        (SdfFormat::Npy, "npy"),
        (SdfFormat::Exr, "exr"),
        (SdfFormat::Vdb, "vdb"),
        (SdfFormat::Ply, "ply"),
        (SdfFormat::Text, "csv"),
    ] {
        if let Ok(raw) = decode_sdf(bytes, format, &at(ext), None) {
            let _ = raw.validate(&at(ext));
        }
    }
    for ext in ["ply", "xyz"] {
        let _ = decode_oriented_points(bytes, &at(ext));
    }
}

#[test]
fn fuzzer_findings_and_the_bad_input_corpus_never_panic_or_hang() {
    let mut dirs = vec![repo().join("tests/bad_inputs")];
    if let Ok(d) = std::fs::read_dir(repo().join("fuzz/regressions")) {
        let mut targets: Vec<PathBuf> = d.filter_map(|e| e.ok().map(|e| e.path())).collect();
        targets.sort();
        dirs.extend(targets.into_iter().filter(|p| p.is_dir()));
    }
    let mut n = 0;
    for dir in dirs {
        for file in files(&dir) {
            let bytes = std::fs::read(&file).expect("readable");
            let t = Instant::now();
            every_reader(&bytes);
            assert!(
                t.elapsed() < Duration::from_secs(2),
                "{} took {:?}",
                file.display(),
                t.elapsed()
            );
            n += 1;
        }
    }
    assert!(n >= 50, "only {n} files found");
}

#[test]
fn a_ply_element_without_properties_and_a_huge_count_is_not_a_loop() {
    // What the PLY fuzzer found first: `element te 5555555555555555555` with no properties in a
    // binary file made the reader count to 5.6e18.
    let bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement te 5555555555555555555\nend_header\n\0\0\0\0\0\0\0\0\0\0\0\0";
    let t = Instant::now();
    let _ = decode_mesh(bytes, MeshFormat::Ply, Path::new("x.ply"));
    assert!(t.elapsed() < Duration::from_secs(1));
}

#[test]
fn writers_refuse_non_finite_data_and_write_nothing() {
    use rfta_geom::{Grid, TriMesh, glam::DVec3};
    let dir = std::env::temp_dir().join(format!("rfta-io-nan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mesh = TriMesh {
        vertices: vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, f64::NAN, 0.0)],
        faces: vec![[0, 1, 2]],
    };
    for ext in ["obj", "ply", "stl", "glb"] {
        let path = dir.join(format!("nan.{ext}"));
        let e = rfta_io::write_mesh(&path, &mesh).expect_err("refused");
        assert!(
            e.to_string()
                .contains("vertex 2 has a non-finite coordinate"),
            "{e}"
        );
        assert!(!path.exists());
    }
    let grid = Grid::cube(1, 0.0, 1.0).expect("grid");
    let mut values = vec![1.0; 8];
    values[3] = f64::INFINITY;
    for ext in ["npy", "exr"] {
        let path = dir.join(format!("inf.{ext}"));
        let e = rfta_io::write_sdf_grid(&path, &grid, &values).expect_err("refused");
        assert!(e.to_string().contains("sample 3 is not finite"), "{e}");
        assert!(!path.exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_exr_header_declaring_a_huge_image_is_refused_before_allocating() {
    // What the EXR fuzzer found: a 706-byte file whose header declares about 40 GB of pixels; the
    // exr crate allocates every layer before reading pixel data.
    let file = repo().join("fuzz/regressions/exr/crash-f40f6df8e7e66a342ea936e6ea874add35166249");
    let bytes = std::fs::read(&file).expect("regression file");
    let e = decode_sdf(&bytes, SdfFormat::Exr, Path::new("x.exr"), None).expect_err("refused");
    assert!(
        e.to_string()
            .contains("bytes of pixels, more than a 706-byte file can hold"),
        "{e}"
    );
}
