//! Figure 22's collision queries: random segments tested against the ground truth and against
//! each method's mesh.

use anyhow::Result;
use rayon::prelude::*;
use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_mesh::MeshIndex;

/// Segments against a ground truth and a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Collisions {
    pub(super) segments: usize,
    /// Segments that hit the ground truth.
    pub(super) gt_hits: usize,
    /// Segments that hit the ground truth and miss the mesh.
    pub(super) false_negatives: usize,
    /// Segments that miss the ground truth and hit the mesh.
    pub(super) false_positives: usize,
}

impl Collisions {
    /// `segments` (with whether each hits the ground truth) against `mesh`.
    pub(super) fn count(segments: &[Segment], gt_hit: &[bool], mesh: &TriMesh) -> Result<Self> {
        let hits: Vec<bool> = if mesh.is_empty() {
            vec![false; segments.len()]
        } else {
            let index = MeshIndex::new(mesh)?;
            segments
                .par_iter()
                .map(|&(a, b)| index.segment_hits(a, b))
                .collect()
        };
        let both = |g: bool, m: bool| {
            gt_hit
                .iter()
                .zip(&hits)
                .filter(|&(&x, &y)| x == g && y == m)
                .count()
        };
        Ok(Collisions {
            segments: segments.len(),
            gt_hits: gt_hit.iter().filter(|&&h| h).count(),
            false_negatives: both(true, false),
            false_positives: both(false, true),
        })
    }

    pub(super) fn false_negative_rate(&self) -> f64 {
        self.false_negatives as f64 / self.gt_hits.max(1) as f64
    }

    pub(super) fn false_positive_rate(&self) -> f64 {
        self.false_positives as f64 / (self.segments - self.gt_hits).max(1) as f64
    }

    /// Share of all segments the mesh answers wrongly.
    pub(super) fn misclassified(&self) -> f64 {
        (self.false_negatives + self.false_positives) as f64 / self.segments.max(1) as f64
    }
}

/// A segment, from one end to the other.
pub(super) type Segment = (DVec3, DVec3);

/// Segments per shape and length in the collision scenario.
pub(super) const COLLISION_SEGMENTS: usize = 20_000;

/// `COLLISION_SEGMENTS` segments of length `length` with midpoints uniform in `bounds` grown by
/// 0.1 and directions uniform on the sphere.
pub(super) fn projectiles(bounds: rfta_geom::Aabb, length: f64, seed: u64) -> Vec<Segment> {
    let b = bounds.padded(0.1);
    let mut rng = rfta_geom::rng::Rng::new(seed);
    (0..COLLISION_SEGMENTS)
        .map(|_| {
            let mid = b.min
                + (b.max - b.min) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            // Uniform direction: z uniform in [-1, 1], azimuth uniform.
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = std::f64::consts::TAU * rng.next_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let half = 0.5 * length * DVec3::new(r * phi.cos(), r * phi.sin(), z);
            (mid - half, mid + half)
        })
        .collect()
}
