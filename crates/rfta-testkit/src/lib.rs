//! Test support for rfta (not published): the shared data directory and analytic signed
//! distance functions with known answers.
//!
//! Real meshes and reference results live outside the repository, in `../shared/data` beside the
//! checkout (or wherever `RFTA_DATA_DIR` points). [`data_dir`] finds it; when it is missing, a test
//! fails under CI (`CI` set) and is skipped with a loud message otherwise.
//!
//! ```
//! use rfta_geom::glam::DVec3;
//! let torus = rfta_testkit::Analytic::Torus { major: 0.6, minor: 0.25 };
//! assert!((torus.sdf(DVec3::new(0.6, 0.0, 0.0)) + 0.25).abs() < 1e-15);
//! ```

use std::path::PathBuf;

pub mod browser;

/// The shared data directory (`RFTA_DATA_DIR`, else `shared/data` found beside or above the
/// workspace), or `None` if absent.
pub fn data_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("RFTA_DATA_DIR") {
        return Some(PathBuf::from(dir)).filter(|p| p.is_dir());
    }
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.ancestors()
        .flat_map(|a| [a.join("shared/data"), a.join("../shared/data")])
        .find(|p| p.join("inputs").is_dir())
}

/// The data directory, or: under CI a panic (data must be there), locally `None` after printing why
/// the calling test is skipped.
pub fn data_dir_or_skip(test: &str) -> Option<PathBuf> {
    match data_dir() {
        Some(d) => Some(d),
        None if std::env::var_os("CI").is_some() => {
            panic!(
                "{test}: shared data not found (set RFTA_DATA_DIR or place it at ../shared/data); required under CI"
            )
        }
        None => {
            #[expect(clippy::print_stderr, reason = "a skipped test must say so")]
            {
                eprintln!("SKIPPED {test}: shared data not found (set RFTA_DATA_DIR)");
            }
            None
        }
    }
}

/// Names of the prepared inputs (`inputs/NAME/`), sorted.
pub fn input_names(data: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(data.join("inputs"))
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter(|e| e.path().join("gt.obj").is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// The prepared grids (`inputs/NAME/sdf_nN.npy` for N = 10, 20, 30, 50) that exist: name, N
/// and path, by name then N.
pub fn input_grids(data: &std::path::Path) -> Vec<(String, usize, PathBuf)> {
    input_names(data)
        .into_iter()
        .flat_map(|name| {
            [10, 20, 30, 50].into_iter().filter_map(move |n| {
                let path = data.join(format!("inputs/{name}/sdf_n{n}.npy"));
                path.is_file().then(|| (name.clone(), n, path))
            })
        })
        .collect()
}

/// Shapes with exact signed distance functions (moved to `rfta_geom`, where the demos use them).
pub use rfta_geom::Analytic;

/// The SDF of the circle of radius `r` about the origin on the `n` x `n` grid over `[-1, 1]^2`.
pub fn circle_grid(n: usize, r: f64) -> (rfta_geom::plane::Grid2, Vec<f64>) {
    use rfta_geom::glam::DVec2;
    let grid = rfta_geom::plane::Grid2::from_bounds([n, n], DVec2::splat(-1.0), DVec2::splat(1.0))
        .expect("a valid grid");
    let values = (0..grid.len())
        .map(|i| grid.position(i).length() - r)
        .collect();
    (grid, values)
}
