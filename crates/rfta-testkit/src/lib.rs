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

use rfta_geom::glam::DVec3;

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

/// Shapes with exact signed distance functions (negative inside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Analytic {
    /// Sphere about the origin.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// Torus about the z axis.
    Torus {
        /// Distance from the axis to the tube's centre.
        major: f64,
        /// Tube radius.
        minor: f64,
    },
    /// Axis-aligned box about the origin.
    Box {
        /// Half side lengths.
        half: DVec3,
    },
}

impl Analytic {
    /// The exact signed distance at `p`.
    pub fn sdf(&self, p: DVec3) -> f64 {
        match *self {
            Analytic::Sphere { radius } => p.length() - radius,
            Analytic::Torus { major, minor } => {
                let ring = (p.x * p.x + p.y * p.y).sqrt() - major;
                (ring * ring + p.z * p.z).sqrt() - minor
            }
            Analytic::Box { half } => {
                let q = p.abs() - half;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
        }
    }

    /// `n` seeded, area-uniform points on the surface with outward unit normals (sphere: uniform
    /// directions; torus: rejection on the tube angle; box: faces chosen by area).
    pub fn oriented_samples(&self, n: usize, seed: u64) -> (Vec<DVec3>, Vec<DVec3>) {
        let mut rng = rfta_geom::rng::Rng::new(seed);
        let (mut p, mut nn) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let unit = |rng: &mut rfta_geom::rng::Rng| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - DVec3::ONE
        };
        while p.len() < n {
            match *self {
                Analytic::Sphere { radius } => {
                    let v = unit(&mut rng);
                    let l = v.length();
                    if l > 0.1 && l <= 1.0 {
                        p.push(v / l * radius);
                        nn.push(v / l);
                    }
                }
                Analytic::Torus { major, minor } => {
                    let th = rng.next_f64() * std::f64::consts::TAU;
                    let ph = rng.next_f64() * std::f64::consts::TAU;
                    if rng.next_f64() * (major + minor) >= major + minor * ph.cos() {
                        continue;
                    }
                    let normal = DVec3::new(ph.cos() * th.cos(), ph.cos() * th.sin(), ph.sin());
                    p.push(DVec3::new(major * th.cos(), major * th.sin(), 0.0) + minor * normal);
                    nn.push(normal);
                }
                Analytic::Box { half } => {
                    let areas = [half.y * half.z, half.x * half.z, half.x * half.y];
                    let mut t = rng.next_f64() * areas.iter().sum::<f64>();
                    let mut axis = 0;
                    while axis < 2 && t >= areas[axis] {
                        t -= areas[axis];
                        axis += 1;
                    }
                    let side = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
                    let mut q = unit(&mut rng) * half;
                    q[axis] = side * half[axis];
                    let mut normal = DVec3::ZERO;
                    normal[axis] = side;
                    p.push(q);
                    nn.push(normal);
                }
            }
        }
        (p, nn)
    }
}
