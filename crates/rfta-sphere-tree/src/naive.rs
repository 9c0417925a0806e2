//! The brute-force oracle: the same questions answered by scanning every sphere.
//!
//! `O(n)` per query; the tree's tests compare against it, and the benchmarks measure against it.

use rfta_geom::{Sphere, glam::DVec3};

/// Whether some sphere `j != ignore` has `|x - p_j| - r_j < threshold`.
pub fn inside_any(spheres: &[Sphere], x: DVec3, threshold: f64, ignore: Option<u32>) -> bool {
    spheres
        .iter()
        .enumerate()
        .any(|(j, s)| Some(j as u32) != ignore && s.signed_distance(x) < threshold)
}

/// Up to `k` spheres `j != ignore` with `|x - p_j| - r_j < threshold`, the deepest first (smallest
/// signed distance; ties by index).
pub fn spheres_containing(
    spheres: &[Sphere],
    x: DVec3,
    k: usize,
    threshold: f64,
    ignore: Option<u32>,
) -> Vec<u32> {
    let mut hits: Vec<(f64, u32)> = spheres
        .iter()
        .enumerate()
        .filter(|(j, _)| Some(*j as u32) != ignore)
        .map(|(j, s)| (s.signed_distance(x), j as u32))
        .filter(|(d, _)| *d < threshold)
        .collect();
    hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    hits.truncate(k);
    hits.into_iter().map(|(_, j)| j).collect()
}

/// Every sphere `j != ignore` with `|x - p_j| - r_j < threshold`, in ascending index order.
pub fn spheres_within(
    spheres: &[Sphere],
    x: DVec3,
    threshold: f64,
    ignore: Option<u32>,
) -> Vec<u32> {
    (0..spheres.len() as u32)
        .filter(|&j| Some(j) != ignore && spheres[j as usize].signed_distance(x) < threshold)
        .collect()
}
