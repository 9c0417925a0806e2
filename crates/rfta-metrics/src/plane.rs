//! The metrics for 2D outputs, defined as the 3D ones and as the shared 2D reference scores them:
//! Chamfer is the sum of the two root-mean-square one-sided distances over length-uniform samples
//! of each polyline set, Hausdorff the larger one-sided maximum over vertices.

use rayon::prelude::*;
use rfta_geom::glam::DVec2;
use rfta_geom::plane::Polylines;
use rfta_mesh::PolylineIndex;

/// `n` points spread uniformly by length over the edges: the midpoints of `n` equal pieces of the
/// total length (deterministic; no seed needed).
pub fn sample_polylines(lines: &Polylines, n: usize) -> Vec<DVec2> {
    let total = lines.length();
    if lines.is_empty() || n == 0 || total <= 0.0 {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(n);
    let mut done = 0.0;
    let mut k = 0;
    for &e in &lines.edges {
        let s = lines.segment(e);
        let len = s.length();
        while k < n {
            let at = (k as f64 + 0.5) / n as f64 * total;
            if at > done + len {
                break;
            }
            let t = if len > 0.0 { (at - done) / len } else { 0.0 };
            out.push(s.a + (s.b - s.a) * t.clamp(0.0, 1.0));
            k += 1;
        }
        done += len;
    }
    // Rounding can leave the last few pieces past the final edge's end.
    if let Some(&last) = lines.edges.last() {
        out.resize(n, lines.segment(last).b);
    }
    out
}

/// Root-mean-square distance from `n` length-uniform samples of `from` to `to`.
pub fn rms_distance_2d(from: &Polylines, to: &PolylineIndex<'_>, n: usize) -> f64 {
    let samples = sample_polylines(from, n);
    if samples.is_empty() {
        return f64::INFINITY;
    }
    let sum: f64 = samples
        .par_iter()
        .map(|&p| to.closest(p).distance.powi(2))
        .sum();
    (sum / samples.len() as f64).sqrt()
}

/// Chamfer distance between two polyline sets, `n` samples each way.
pub fn chamfer_2d(a: &Polylines, b: &Polylines, n: usize) -> f64 {
    let (ia, ib) = (PolylineIndex::new(a), PolylineIndex::new(b));
    rms_distance_2d(a, &ib, n) + rms_distance_2d(b, &ia, n)
}

/// Hausdorff distance over vertices: the larger of the farthest vertex of each set from the other.
pub fn hausdorff_2d(a: &Polylines, b: &Polylines) -> f64 {
    let one = |from: &Polylines, to: &Polylines| {
        let index = PolylineIndex::new(to);
        from.vertices
            .par_iter()
            .map(|&v| index.closest(v).distance)
            .reduce(|| 0.0, f64::max)
    };
    one(a, b).max(one(b, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(side: f64, offset: DVec2) -> Polylines {
        let h = side / 2.0;
        let v = [(-h, -h), (h, -h), (h, h), (-h, h)]
            .map(|(x, y)| DVec2::new(x, y) + offset)
            .to_vec();
        Polylines::new(v, vec![[0, 1], [1, 2], [2, 3], [3, 0]]).expect("valid test input")
    }

    #[test]
    fn samples_are_uniform_by_length() {
        let s = sample_polylines(&square(2.0, DVec2::ZERO), 8);
        // Perimeter 8: midpoints of eight pieces of length 1.
        let expected = [(-0.5, -1.0), (0.5, -1.0), (1.0, -0.5), (1.0, 0.5)];
        for (p, (x, y)) in s.iter().zip(expected) {
            assert!((*p - DVec2::new(x, y)).length() < 1e-12, "{p}");
        }
        assert_eq!(s.len(), 8);
    }

    #[test]
    fn concentric_squares_have_the_analytic_distances() {
        // Squares of side 2 and 2.2 with the same centre: every point of one is 0.1 from the
        // other, except near the outer square's corners, whose nearest inner point is a corner
        // (distance 0.1 * sqrt 2 over the last 0.1 before each corner, on both sides).
        let (a, b) = (square(2.0, DVec2::ZERO), square(2.2, DVec2::ZERO));
        assert!((rms_distance_2d(&a, &PolylineIndex::new(&b), 100_000) - 0.1).abs() < 1e-9);
        let outer = rms_distance_2d(&b, &PolylineIndex::new(&a), 100_000);
        // Over the outer perimeter 8.8: 8 units at 0.1; 0.8 units at sqrt(0.01 + t^2), t in 0..0.1.
        let corner_mean_sq = 0.01 + 0.01 / 3.0;
        let expected = ((8.0 * 0.01 + 0.8 * corner_mean_sq) / 8.8f64).sqrt();
        assert!((outer - expected).abs() < 1e-4, "{outer} vs {expected}");
        assert!((hausdorff_2d(&a, &b) - 0.1 * 2f64.sqrt()).abs() < 1e-12);
    }
}
