//! The OpenVDB reader against OpenVDB itself: the test files in `tests/data/vdb` were written by
//! OpenVDB 10.0.1 (`make.py`, `codecs.cpp` there), each level set beside the dense grid OpenVDB's
//! own `copyToArray` makes of it over the box of its active voxels, with OpenVDB's world
//! position of that box's first voxel, its voxel size and its background. The reader must give
//! the same grid and values: exactly for float and double grids, to half precision for a grid
//! saved as halves.

use std::path::{Path, PathBuf};

use rfta_geom::{Layout, glam::DVec3};
use rfta_io::{RawSdf, parse_npy, peek_sdf_len, read_sdf, read_vdb};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/vdb")
        .join(name)
}

/// OpenVDB's dense grid of a level set: shape, values, origin, voxel size, background.
struct Twin {
    dims: [usize; 3],
    values: Vec<f64>,
    origin: DVec3,
    spacing: DVec3,
    background: f64,
}

fn twin(name: &str) -> Twin {
    let npy = parse_npy(&std::fs::read(data(&format!("{name}.npy"))).expect("test data"))
        .expect("test data");
    let json: serde_json::Value = serde_json::from_slice(
        &std::fs::read(data(&format!("{name}.twin.json"))).expect("test data"),
    )
    .expect("test data");
    let v3 = |k: &str| {
        let a: Vec<f64> = json[k]
            .as_array()
            .expect("test data")
            .iter()
            .map(|x| x.as_f64().expect("test data"))
            .collect();
        DVec3::new(a[0], a[1], a[2])
    };
    Twin {
        dims: [npy.shape[0], npy.shape[1], npy.shape[2]],
        values: npy.data,
        origin: v3("origin"),
        spacing: v3("spacing"),
        background: json["background"].as_f64().expect("test data"),
    }
}

/// Checks `raw` against OpenVDB's twin; values within `tol(value)`.
fn same_as(raw: &RawSdf, t: &Twin, tol: impl Fn(f64) -> f64) {
    let Layout::Grid(g) = &raw.layout else {
        panic!("a level set reads as a grid")
    };
    assert_eq!(g.dims(), t.dims, "the box of the active voxels");
    assert_eq!(
        g.origin(),
        t.origin,
        "the box's first voxel, where OpenVDB puts it"
    );
    assert_eq!(g.spacing(), t.spacing, "the voxel size");
    let clamp = raw.clamp.expect("a level set's background is its clamp");
    assert!(
        (clamp - t.background).abs() <= tol(t.background),
        "background {clamp}"
    );
    assert_eq!(raw.values.len(), t.values.len());
    let worst = raw
        .values
        .iter()
        .zip(&t.values)
        .map(|(a, b)| (a - b).abs() - tol(*b))
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        worst <= 0.0,
        "a value differs from OpenVDB's by {worst} beyond the tolerance"
    );
    // The band and both sides of it are there: values inside, outside, and at the clamp.
    let inside = raw.values.iter().filter(|&&v| v <= -t.background).count();
    let outside = raw.values.iter().filter(|&&v| v >= t.background).count();
    let band = raw.values.len() - inside - outside;
    assert!(
        inside > 0 && outside > 0 && band > 100,
        "{inside} {outside} {band}"
    );
}

#[test]
fn float_grids_in_every_codec_read_exactly_as_openvdb_makes_them_dense() {
    let box_ = twin("box");
    for file in ["box.vdb", "box-zip.vdb", "box-mask.vdb", "box-double.vdb"] {
        let raw = read_sdf(&data(file), None).unwrap_or_else(|e| panic!("{file}: {e}"));
        same_as(&raw, &box_, |_| 0.0);
        assert!(raw.description.contains("\"box\""), "{}", raw.description);
        assert_eq!(raw.bounds_source, "file");
    }
    let raw = read_sdf(&data("box-double.vdb"), None).expect("test data");
    assert!(raw.description.contains("double"), "{}", raw.description);
}

#[test]
fn a_grid_saved_as_halves_reads_to_half_precision() {
    let raw = read_sdf(&data("box-half.vdb"), None).expect("test data");
    assert!(raw.description.contains("half"), "{}", raw.description);
    // A half keeps 11 significant bits: within 2^-11 of the value, or 2^-24 near zero.
    same_as(&raw, &twin("box"), |v| {
        v.abs() * 2f64.powi(-11) + 2f64.powi(-24)
    });
}

#[test]
fn the_first_level_set_is_taken_and_others_are_named_with_what_they_are() {
    let ball = twin("ball");
    same_as(
        &read_sdf(&data("three.vdb"), None).expect("test data"),
        &ball,
        |_| 0.0,
    );
    same_as(
        &read_vdb(&data("three.vdb"), Some("ball"), None).expect("test data"),
        &ball,
        |_| 0.0,
    );
    let err = |grid| {
        read_vdb(&data("three.vdb"), Some(grid), None)
            .expect_err("an error")
            .to_string()
    };
    assert!(
        err("density").contains("fog volume, not a level set"),
        "{}",
        err("density")
    );
    assert!(err("mask").contains("Tree_bool_5_4_3"), "{}", err("mask"));
    let none = err("nope");
    assert!(
        none.contains("no grid named \"nope\"") && none.contains("\"density\", \"mask\", \"ball\""),
        "{none}"
    );
}

#[test]
fn the_dense_size_is_known_from_the_header() {
    let t = twin("box");
    let n = peek_sdf_len(&data("box.vdb")).expect("test data");
    assert_eq!(n, Some(t.dims.iter().product()));
}

#[test]
fn truncated_and_foreign_files_are_errors_that_say_so() {
    let bytes = std::fs::read(data("box.vdb")).expect("test data");
    let dir = std::env::temp_dir().join(format!("rfta-io-vdb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("test data");
    let path = dir.join("cut.vdb");
    for cut in (0..bytes.len()).step_by(997).chain([bytes.len() - 1]) {
        std::fs::write(&path, &bytes[..cut]).expect("test data");
        let e = read_sdf(&path, None).expect_err("an error").to_string();
        assert!(e.contains("cut.vdb"), "{e}");
    }
    std::fs::write(&path, b"not a level set at all").expect("test data");
    let e = read_sdf(&path, None).expect_err("an error").to_string();
    assert!(e.contains("not an OpenVDB file"), "{e}");
    std::fs::remove_dir_all(&dir).expect("test data");
}
