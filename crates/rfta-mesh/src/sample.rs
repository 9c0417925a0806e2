//! Seeded, area-weighted random samples on a triangle mesh.

use rfta_geom::{TriMesh, glam::DVec3, rng::Rng};

/// A point on a mesh with the triangle it lies on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceSample {
    /// The point.
    pub point: DVec3,
    /// Index of its triangle.
    pub face: u32,
}

/// `n` points distributed uniformly by area on `mesh`, from `seed` (same seed, same points).
///
/// A triangle is chosen with probability proportional to its area, then a point uniformly inside
/// it by the square-root map (Osada et al., "Shape distributions", ACM TOG 2002, eq. 1).
/// Returns no points for a mesh of zero area.
pub fn sample_surface(mesh: &TriMesh, n: usize, seed: u64) -> Vec<SurfaceSample> {
    let mut cdf = Vec::with_capacity(mesh.n_faces());
    let mut total = 0.0;
    for f in 0..mesh.n_faces() {
        let a = 0.5 * mesh.face_normal_scaled(f).length();
        total += if a.is_finite() { a } else { 0.0 };
        cdf.push(total);
    }
    if total.is_nan() || total <= 0.0 {
        return Vec::new();
    }
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let u = rng.next_f64() * total;
            // First triangle whose cumulative area exceeds u (skips zero-area ones).
            let face = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
            let [a, b, c] = mesh.triangle(face);
            let (r1, r2) = (rng.next_f64().sqrt(), rng.next_f64());
            let point = (1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c;
            SurfaceSample {
                point,
                face: face as u32,
            }
        })
        .collect()
}
