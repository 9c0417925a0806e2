//! The bad-input corpus (`tests/bad_inputs/`, see its README) through the `rfta` binary: every
//! case ends with its documented exit status and a message that names the file and the problem,
//! never a panic; every mesh written is finite and watertight.

mod common;

use std::path::{Path, PathBuf};

use common::{rfta, s, temp};
use rfta_geom::TriMesh;

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/bad_inputs")
        .join(name)
}

/// Runs `rfta reconstruct` (one fine-tuning round, to keep the suite quick) on a corpus file.
fn reconstruct(name: &str, out: &Path, extra: &[&str]) -> (i32, String) {
    let input = corpus(name);
    let mut args = vec![
        "reconstruct",
        s(&input),
        "-o",
        s(out),
        "--preset",
        "fast",
        "--iters",
        "1",
    ];
    args.extend_from_slice(extra);
    let o = rfta(&args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!err.contains("panicked"), "{name}: {err}");
    (o.status.code().unwrap_or(-1), err)
}

/// Checks a written mesh: finite, no face with a repeated vertex, watertight; returns the largest
/// distance of a vertex from the sphere of radius 0.5 the corpus grids sample.
fn check_sphere_mesh(path: &Path) -> (TriMesh, f64) {
    let mesh = rfta_io::read_mesh(path).expect("readable output");
    assert!(mesh.n_faces() > 0, "{}: empty", path.display());
    assert!(mesh.vertices.iter().all(|v| v.is_finite()));
    let topo = rfta_mesh::Topology::of(&mesh);
    assert_eq!(topo.degenerate_faces, 0);
    assert!(topo.is_watertight(), "{}: {topo:?}", path.display());
    let worst = mesh
        .vertices
        .iter()
        .map(|v| (v.length() - 0.5).abs())
        .fold(0.0, f64::max);
    (mesh, worst)
}

/// The corpus grids have spacing 1/6.
const H: f64 = 1.0 / 6.0;

#[test]
fn unreadable_and_malformed_files_are_errors_naming_file_and_problem() {
    let dir = temp("files");
    let out = dir.join("out.obj");
    let cases: &[(&str, &str)] = &[
        ("nan.npy", "SDF value at sample 100 is not finite (NaN)"),
        ("inf.npy", "SDF value at sample 7 is not finite (-inf)"),
        ("int32.npy", "unsupported dtype '<i4'"),
        // A 3D grid saved as 2D is read as 2D, and its values are no 2D distance.
        (
            "shape_2d.npy",
            "samples overlap their nearest sample of the other sign",
        ),
        ("nan_2d.npy", "SDF value at sample 10 is not finite (NaN)"),
        (
            "pixel_1.png",
            "a 2D grid needs at least 2 points per axis, got [1, 1]",
        ),
        ("gray_8bit.png", "expected a 16-bit grayscale PNG"),
        ("no_range.png", "needs the value range in its sidecar"),
        (
            "ragged_2d.csv",
            "line 4: expected 3 numbers (x y s), found 4",
        ),
        ("shape_4d.npy", "found shape [13, 13, 13, 1]"),
        ("truncated.npy", "(truncated file)"),
        ("header_only.npy", "(truncated file)"),
        ("garbage.npy", "not a .npy file"),
        ("empty.npy", "not a .npy file"),
        ("garbage.exr", "invalid OpenEXR"),
        ("empty.exr", "invalid OpenEXR"),
        ("truncated.exr", "invalid OpenEXR"),
        ("garbage.ply", "not a PLY file"),
        ("empty.ply", "not a PLY file"),
        ("truncated.ply", "line 11: missing value for z"),
        ("truncated_binary.ply", "announces 100 records"),
        ("garbage.csv", "not a text file"),
        ("empty.csv", "too few samples: 0 given"),
        (
            "short_row.csv",
            "line 4: expected 4 values (x y z s), found 3",
        ),
        ("not_a_number.csv", "line 3: 'zero' is not a number"),
        (
            "inverted_bounds.npy",
            "inverted or of zero size: min 1 >= max -1",
        ),
        (
            "zero_bounds.npy",
            "inverted or of zero size: min 0 >= max 0",
        ),
        ("bad_sidecar.npy", "invalid sidecar"),
        ("grid_1.npy", "too few samples: 1 given, at least 2 needed"),
        (
            "coincident.csv",
            "samples 171 and 343 are both at (0, 0, 0) but have different values (-0.5 and 0.25)",
        ),
    ];
    for &(name, expected) in cases {
        let (code, err) = reconstruct(name, &out, &[]);
        assert_eq!(code, 1, "{name}: {err}");
        assert!(err.starts_with("error: "), "{name}: {err}");
        assert!(
            err.contains(expected),
            "{name}: expected '{expected}' in {err}"
        );
        // The sidecar's errors name the sidecar; all others the input.
        let named = if name.ends_with("bounds.npy") || name == "bad_sidecar.npy" {
            name.replace(".npy", ".json")
        } else {
            name.to_string()
        };
        assert!(err.contains(&named), "{name}: {err}");
        assert_eq!(err.lines().count(), 1, "{name}: one line: {err}");
        assert!(!out.exists(), "{name}: nothing may be written");
    }
    // Every mesh reader, through `rfta info`.
    for name in [
        "garbage.obj",
        "truncated.obj",
        "garbage.off",
        "empty.off",
        "truncated.off",
        "garbage.stl",
        "empty.stl",
        "truncated.stl",
        "garbage.glb",
        "empty.glb",
        "truncated.glb",
    ] {
        let o = rfta(&["info", s(&corpus(name))]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(name),
            "{name}: {err}"
        );
    }
}

#[test]
fn an_unwritable_output_is_refused_before_the_work() {
    for (out, expected) in [
        (
            "/nonexistent-dir/mesh.obj",
            "the folder /nonexistent-dir does not exist",
        ),
        ("mesh.off", "OFF is read-only"),
        ("mesh.xyz", "unsupported file type"),
    ] {
        let o = rfta(&["reconstruct", s(&corpus("sphere.npy")), "-o", out]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{out}: {err}");
        assert!(err.contains(expected), "{out}: {err}");
        // Refused at once: no progress, no reconstruction summary.
        assert_eq!(err.lines().count(), 1, "{out}: {err}");
    }
}

#[test]
fn no_surface_writes_an_empty_mesh_and_exits_with_status_3() {
    let dir = temp("nosurface");
    for (name, sign) in [
        ("all_positive.npy", "positive (outside)"),
        ("all_negative.npy", "negative (inside)"),
        ("all_zero.npy", "are zero"),
    ] {
        for ext in ["obj", "ply", "glb"] {
            let out = dir.join(format!("{name}.{ext}"));
            let (code, err) = reconstruct(name, &out, &[]);
            assert_eq!(code, 3, "{name}: {err}");
            assert!(err.contains("no surface") && err.contains(sign), "{err}");
            assert!(err.contains("wrote an empty mesh"), "{err}");
            let mesh = rfta_io::read_mesh(&out).expect("an empty mesh file");
            assert!(mesh.is_empty());
        }
    }
}

#[test]
fn values_that_are_not_distances_are_refused_unless_the_check_is_off() {
    let dir = temp("notsdf");
    let out = dir.join("out.ply");
    for name in ["random.npy", "occupancy.npy", "scaled.npy"] {
        let (code, err) = reconstruct(name, &out, &[]);
        assert_eq!(code, 1, "{name}: {err}");
        assert!(
            err.contains("not a signed distance function") && err.contains("overlap"),
            "{name}: {err}"
        );
        assert!(!out.exists());
    }
    let (code, err) = reconstruct("huge.npy", &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("sample 0 ") && err.contains("exceeds the diagonal"),
        "{err}"
    );
    // Forced through, random values give a mesh or a clear error, and never NaN.
    let (code, err) = reconstruct("random.npy", &out, &["--no-check"]);
    assert!(code == 0 || code == 1, "{err}");
    if code == 0 {
        let mesh = rfta_io::read_mesh(&out).expect("readable");
        assert!(mesh.vertices.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn degenerate_grids_are_clear_errors_or_meshes() {
    let dir = temp("tiny");
    let out = dir.join("out.obj");
    // Shape (2, 1, 1): a flat grid is no volume (D6 of the hostile test: a one-sample axis got
    // an invented spacing and a "watertight" mesh).
    let (code, err) = reconstruct("grid_2.npy", &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("a 3D grid needs at least 2 points along every axis")
            && err.contains("has 1 along axis 1"),
        "{err}"
    );
    assert!(!out.exists());
    let (code, err) = reconstruct("single_negative.npy", &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("only 1 of 2197 spheres"), "{err}");
    // Eight samples, one negative at a corner of [-1, 1]^3 with |s| = 0.2: a closed surface
    // around it that no positive sphere enters.
    let (code, err) = reconstruct("grid_2x2x2.npy", &out, &[]);
    assert_eq!(code, 0, "{err}");
    let mesh = rfta_io::read_mesh(&out).expect("readable");
    assert!(mesh.vertices.iter().all(|v| v.is_finite()));
    assert!(rfta_mesh::Topology::of(&mesh).is_watertight());
}

#[test]
fn layouts_and_imperfect_distances_give_faithful_meshes() {
    let dir = temp("good");
    // The same grid in C order, Fortran order and big-endian: byte-identical meshes.
    let mut bytes = Vec::new();
    for name in ["sphere.npy", "sphere_fortran.npy", "sphere_bigendian.npy"] {
        let out = dir.join(format!("{name}.ply"));
        let (code, err) = reconstruct(name, &out, &[]);
        assert_eq!(code, 0, "{name}: {err}");
        let (_, worst) = check_sphere_mesh(&out);
        assert!(worst < H / 2.0, "{name}: {worst}");
        bytes.push(std::fs::read(&out).expect("written"));
    }
    assert!(bytes.windows(2).all(|w| w[0] == w[1]));

    // Exact zeros: on the surface, no tangency point of their own, reported.
    let out = dir.join("zeros.ply");
    let (code, err) = reconstruct("zeros.npy", &out, &["-v"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains(" spheres without a point"), "{err}");
    assert!(check_sphere_mesh(&out).1 < H / 2.0);

    // 5% noise: reconstructed, with a warning that counts the inconsistent samples.
    let out = dir.join("noisy.ply");
    let (code, err) = reconstruct("noisy.npy", &out, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: ") && err.contains("overlap the nearest sample"),
        "{err}"
    );
    assert!(check_sphere_mesh(&out).1 < H, "noisy");

    // Clamped at two spacings without --clamp: detected, said, and treated as clamped.
    let out = dir.join("clamped.ply");
    let (code, err) = reconstruct("clamped.npy", &out, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("look clamped at 0.333"), "{err}");
    assert!(check_sphere_mesh(&out).1 < H / 2.0, "clamped");

    // A sentinel 1e30 with --clamp: that sample counts as far, the rest as distances.
    let out = dir.join("huge.ply");
    let (code, err) = reconstruct("huge.npy", &out, &["--clamp", "1"]);
    assert_eq!(code, 0, "{err}");
    assert!(check_sphere_mesh(&out).1 < H / 2.0, "huge with clamp");
}

#[test]
fn an_input_larger_than_memory_is_refused_from_its_header() {
    let dir = temp("oversized");
    let out = dir.join("out.obj");
    // The file holds only a header claiming 513^3 float32 values: refused before reading data.
    let (code, err) = reconstruct("oversized_513.npy", &out, &["--max-memory", "8G"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("oversized_513.npy: refused before reading (the limit is --max-memory)")
            && err.contains("135005697 samples need about 17.2 GiB of memory")
            && err.contains("more than the limit of 8.0 GiB"),
        "{err}"
    );
    // With the limit lifted the data is read, and found missing.
    let (code, err) = reconstruct("oversized_513.npy", &out, &["--max-memory", "100T"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("truncated file"), "{err}");
    let (code, err) = reconstruct("sphere.npy", &out, &["--max-memory", "12X"]);
    assert_eq!(code, 2, "{err}");
    // Sampling a grid no machine holds is refused before the first allocation.
    let o = rfta(&[
        "sample",
        "--shape",
        "sphere",
        "--res",
        "100000",
        "-o",
        s(&dir.join("big.npy")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("choose a smaller --res"), "{err}");
}
