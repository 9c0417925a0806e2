//! The bad-input corpus (`tests/bad_inputs/`) through the library: `rfta_io::read_sdf`, then
//! validation, then `rfta::reconstruct`. Each case stops at a stated step with a stated error, or
//! gives a finite, watertight mesh; the CLI's side is `crates/rfta-cli/tests/bad_inputs.rs`.

use std::path::{Path, PathBuf};

use rfta::Params;
use rfta_geom::Error as GeomError;

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("bad_inputs")
        .join(name)
}

/// Where a case ends.
#[derive(Debug)]
enum Outcome {
    /// `read_sdf` fails with this message.
    Read(String),
    /// Validation fails with this geometry error.
    Invalid(GeomError),
    /// `reconstruct` fails with this error.
    Refused(rfta::Error),
    /// A finite watertight mesh.
    Mesh,
}

fn run(name: &str) -> Outcome {
    let path = corpus(name);
    let raw = match rfta_io::read_sdf(&path, None) {
        Ok(r) => r,
        Err(e) => return Outcome::Read(e.to_string()),
    };
    let samples = match raw.validate(&path) {
        Ok(s) => s,
        Err(rfta_io::Error::Geom { source, .. }) => return Outcome::Invalid(source),
        Err(e) => panic!("{name}: {e}"),
    };
    let params = Params {
        rounds: Some(1),
        ..Params::fast()
    };
    match rfta::reconstruct(&samples, &params) {
        Ok(out) => {
            assert!(out.mesh.vertices.iter().all(|v| v.is_finite()), "{name}");
            assert!(out.report.mesh.watertight, "{name}: {:?}", out.report.mesh);
            Outcome::Mesh
        }
        Err(e) => Outcome::Refused(e),
    }
}

#[test]
fn corpus_cases_end_where_documented() {
    for (name, expected) in [
        ("int32.npy", "unsupported dtype"),
        ("shape_2d.npy", "expected a 3-D grid"),
        ("shape_4d.npy", "expected a 3-D grid"),
        ("truncated.npy", "truncated file"),
        ("header_only.npy", "truncated file"),
        ("garbage.npy", "not a .npy file"),
        ("empty.npy", "not a .npy file"),
        ("garbage.exr", "OpenEXR"),
        ("truncated.exr", "OpenEXR"),
        ("garbage.ply", "not a PLY file"),
        ("truncated.ply", "missing value"),
        ("truncated_binary.ply", "announces 100 records"),
        ("garbage.csv", "not a text file"),
        ("short_row.csv", "expected 4 values"),
        ("not_a_number.csv", "is not a number"),
        ("inverted_bounds.npy", "inverted or of zero size"),
        ("zero_bounds.npy", "inverted or of zero size"),
        ("bad_sidecar.npy", "invalid sidecar"),
        ("oversized_513.npy", "truncated file"),
    ] {
        match run(name) {
            Outcome::Read(msg) => {
                assert!(msg.contains(expected), "{name}: {msg}");
                let file = if msg.contains(".json") {
                    name.replace(".npy", ".json")
                } else {
                    name.to_string()
                };
                assert!(
                    msg.contains(&file),
                    "{name}: the message names the file: {msg}"
                );
            }
            other => panic!("{name}: expected a read error, got {other:?}"),
        }
    }
    let invalid = |name: &str| match run(name) {
        Outcome::Invalid(e) => e,
        other => panic!("{name}: expected invalid samples, got {other:?}"),
    };
    let e = invalid("nan.npy");
    assert!(
        matches!(e, GeomError::NonFiniteValue { index: 100, value } if value.is_nan()),
        "{e}"
    );
    let e = invalid("inf.npy");
    assert!(
        matches!(e, GeomError::NonFiniteValue { index: 7, value } if value == f64::NEG_INFINITY),
        "{e}"
    );
    let e = invalid("grid_1.npy");
    assert!(
        matches!(
            e,
            GeomError::TooFewSamples {
                found: 1,
                needed: 2
            }
        ),
        "{e}"
    );
    let e = invalid("empty.csv");
    assert!(
        matches!(e, GeomError::TooFewSamples { found: 0, .. }),
        "{e}"
    );
    let e = invalid("coincident.csv");
    assert!(
        matches!(
            e,
            GeomError::ConflictingSamples {
                first: 171,
                second: 343,
                ..
            }
        ),
        "{e}"
    );
    let e = invalid("all_zero.npy");
    assert!(
        matches!(e, GeomError::NoSignChange { .. }),
        "all_zero.npy: {e}"
    );
    // One sign is valid input; these spheres (|s| + 0.1 on a spacing of 1/6) cover the box.
    for (name, side) in [
        ("all_positive.npy", "positive (outside)"),
        ("all_negative.npy", "negative (inside)"),
    ] {
        match run(name) {
            Outcome::Refused(rfta::Error::NoSurface { sign, .. }) => assert_eq!(sign, side),
            other => panic!("{name}: {other:?}"),
        }
    }
    for name in ["random.npy", "occupancy.npy", "scaled.npy", "huge.npy"] {
        match run(name) {
            Outcome::Refused(rfta::Error::NotADistance(_)) => {}
            other => panic!("{name}: {other:?}"),
        }
    }
    match run("single_negative.npy") {
        Outcome::Refused(rfta::Error::TooFewPoints { .. }) => {}
        other => panic!("single_negative.npy: {other:?}"),
    }
    // Shape (2, 1, 1): no volume, refused as it is read.
    match run("grid_2.npy") {
        Outcome::Read(e) if e.contains("at least 2 points along every axis") => {}
        other => panic!("grid_2.npy: {other:?}"),
    }
    for name in [
        "sphere.npy",
        "sphere_fortran.npy",
        "sphere_bigendian.npy",
        "zeros.npy",
        "noisy.npy",
        "clamped.npy",
        "grid_2x2x2.npy",
    ] {
        assert!(matches!(run(name), Outcome::Mesh), "{name}");
    }
    // The three layouts hold the same values.
    let read = |n: &str| rfta_io::read_sdf(&corpus(n), None).expect(n).values;
    assert_eq!(read("sphere.npy"), read("sphere_fortran.npy"));
    assert_eq!(read("sphere.npy"), read("sphere_bigendian.npy"));
}

/// The estimate used to refuse oversized inputs lies above the peaks measured with
/// `/usr/bin/time -v rfta reconstruct` and `/proc/PID/status` (docs/hardening.md: 90, 233, 604,
/// 2,638 and 10,927 MiB at 33^3, 65^3, 129^3, 257^3 and 513^3 samples), by less than 2x: a 513^3
/// grid fits a 24 GiB machine, not an 8 GiB one.
#[test]
fn memory_estimate_brackets_the_measured_peaks() {
    let p = Params::default();
    let mib = |n: usize| rfta::estimate_peak_memory(n, &p) as f64 / (1u64 << 20) as f64;
    for (side, measured) in [
        (33usize, 90.0),
        (65, 233.0),
        (129, 604.0),
        (257, 2638.0),
        (513, 10927.0),
    ] {
        let e = mib(side.pow(3));
        assert!(
            e >= measured && e < 2.0 * measured,
            "{side}^3: estimate {e} MiB, measured {measured} MiB"
        );
    }
    assert!(mib(513usize.pow(3)) < 22.0 * 1024.0);
    assert!(mib(513usize.pow(3)) > 8.0 * 1024.0);
}

/// The check must not cry wolf: the exact SDFs of the shared inputs (meshes from Thingi10K and
/// the graphics canon, sampled by libigl at N = 10 to 50) have no overlapping samples and no
/// plateau.
#[test]
fn real_signed_distances_pass_the_check() {
    let Some(data) = rfta_testkit::data_dir_or_skip("real_signed_distances_pass_the_check") else {
        return;
    };
    let mut checked = 0;
    for (_, _, path) in rfta_testkit::input_grids(&data) {
        let samples = rfta_io::read_sdf(&path, None)
            .expect("readable")
            .validate(&path)
            .expect("valid");
        let c = rfta::check::inspect(&samples);
        assert_eq!(c.inconsistent, 0, "{}: {c:?}", path.display());
        assert_eq!(c.clamp, None, "{}", path.display());
        assert!(c.beyond_extent.is_empty(), "{}", path.display());
        checked += 1;
    }
    assert!(checked >= 24, "only {checked} grids");
}
