//! [`PolylineIndex`]: exact closest-point and winding-number queries on closed polylines, the 2D
//! counterpart of [`crate::MeshIndex`].
//!
//! ```
//! use rfta_geom::glam::DVec2;
//! use rfta_geom::plane::Polylines;
//! use rfta_mesh::PolylineIndex;
//!
//! // A unit square, counter-clockwise around its inside.
//! let square = Polylines::new(
//!     vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
//!     vec![[0, 1], [1, 2], [2, 3], [3, 0]],
//! ).expect("valid test input");
//! let index = PolylineIndex::new(&square);
//! assert_eq!(index.winding(DVec2::splat(0.5)), 1);
//! assert!((index.closest(DVec2::new(3.0, 0.5)).distance - 2.0).abs() < 1e-12);
//! ```

use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Polylines, Segment};

/// The closest point of a polyline set to a query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Distance from the query.
    pub distance: f64,
    /// The closest point.
    pub point: DVec2,
    /// Index of its edge.
    pub edge: usize,
}

/// Exact closest-point and winding-number queries on [`Polylines`], over a bucket grid.
///
/// Results depend only on the query (ties go to the lowest edge index), so parallel queries are
/// deterministic.
#[derive(Debug, Clone)]
pub struct PolylineIndex<'a> {
    lines: &'a Polylines,
    min: DVec2,
    max: DVec2,
    cell: f64,
    dims: [usize; 2],
    /// Edges overlapping each bucket, CSR.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// Edges crossing each bucket row's y range, CSR (for the winding number's ray).
    row_starts: Vec<u32>,
    row_items: Vec<u32>,
}

impl<'a> PolylineIndex<'a> {
    /// Index `lines` (about two edges per bucket).
    pub fn new(lines: &'a Polylines) -> Self {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &[a, b] in &lines.edges {
            for v in [a, b] {
                min = min.min(lines.vertices[v as usize]);
                max = max.max(lines.vertices[v as usize]);
            }
        }
        if lines.edges.is_empty() {
            min = DVec2::ZERO;
            max = DVec2::ONE;
        }
        let extent = (max - min).max(DVec2::splat(1e-12));
        let buckets = (lines.edges.len() as f64 / 2.0).max(1.0);
        let cell = (extent.x * extent.y / buckets)
            .sqrt()
            .max(extent.max_element() / 4096.0)
            .max(1e-12);
        let dims = [
            (extent.x / cell) as usize + 1,
            (extent.y / cell) as usize + 1,
        ];
        let bucket = |p: DVec2| -> (usize, usize) {
            let q = ((p - min) / cell).max(DVec2::ZERO);
            (
                (q.x as usize).min(dims[0] - 1),
                (q.y as usize).min(dims[1] - 1),
            )
        };
        let mut counts = vec![0u32; dims[0] * dims[1] + 1];
        let mut row_counts = vec![0u32; dims[1] + 1];
        let ranges: Vec<_> = lines
            .edges
            .iter()
            .map(|&e| {
                let s = lines.segment(e);
                (bucket(s.a.min(s.b)), bucket(s.a.max(s.b)))
            })
            .collect();
        for &((x0, y0), (x1, y1)) in &ranges {
            for y in y0..=y1 {
                row_counts[y] += 1;
                for x in x0..=x1 {
                    counts[y * dims[0] + x] += 1;
                }
            }
        }
        let prefix = |counts: &mut Vec<u32>| {
            let mut total = 0;
            for c in counts.iter_mut() {
                let n = *c;
                *c = total;
                total += n;
            }
        };
        prefix(&mut counts);
        prefix(&mut row_counts);
        let mut items = vec![0u32; *counts.last().unwrap_or(&0) as usize];
        let mut row_items = vec![0u32; *row_counts.last().unwrap_or(&0) as usize];
        let mut fill = counts.clone();
        let mut row_fill = row_counts.clone();
        for (e, &((x0, y0), (x1, y1))) in ranges.iter().enumerate() {
            for y in y0..=y1 {
                row_items[row_fill[y] as usize] = e as u32;
                row_fill[y] += 1;
                for x in x0..=x1 {
                    let b = y * dims[0] + x;
                    items[fill[b] as usize] = e as u32;
                    fill[b] += 1;
                }
            }
        }
        Self {
            lines,
            min,
            max,
            cell,
            dims,
            starts: counts,
            items,
            row_starts: row_counts,
            row_items,
        }
    }

    /// The closest point of the polylines to `p` (an empty set answers an infinite distance).
    pub fn closest(&self, p: DVec2) -> Closest {
        let mut best = Closest {
            distance: f64::INFINITY,
            point: p,
            edge: usize::MAX,
        };
        if self.lines.edges.is_empty() {
            return best;
        }
        let max = self.min + DVec2::new(self.dims[0] as f64, self.dims[1] as f64) * self.cell;
        let inside = p.clamp(self.min, max);
        let to_box = (p - inside).length();
        let q = (inside - self.min) / self.cell;
        let (cx, cy) = (
            (q.x as usize).min(self.dims[0] - 1) as isize,
            (q.y as usize).min(self.dims[1] - 1) as isize,
        );
        let mut best2 = f64::INFINITY;
        let rings = self.dims[0].max(self.dims[1]) as isize;
        for r in 0..=rings {
            // Every bucket of ring r is at least (r - 1) cells from the clamped query, and the
            // query is no nearer to anything in the box than its clamped copy.
            let bound = to_box.max((r - 1).max(0) as f64 * self.cell);
            if bound * bound > best2 {
                break;
            }
            for y in cy - r..=cy + r {
                if y < 0 || y >= self.dims[1] as isize {
                    continue;
                }
                let step = if y == cy - r || y == cy + r {
                    1
                } else {
                    (2 * r).max(1)
                };
                let mut x = cx - r;
                while x <= cx + r {
                    if x >= 0 && x < self.dims[0] as isize {
                        let b = y as usize * self.dims[0] + x as usize;
                        for &e in &self.items[self.starts[b] as usize..self.starts[b + 1] as usize]
                        {
                            let s = self.lines.segment(self.lines.edges[e as usize]);
                            let c = s.closest_point(p);
                            let d2 = (c - p).length_squared();
                            if d2 < best2 || (d2 == best2 && (e as usize) < best.edge) {
                                best2 = d2;
                                best.point = c;
                                best.edge = e as usize;
                            }
                        }
                    }
                    x += step;
                }
            }
        }
        best.distance = best2.sqrt();
        best
    }

    /// Winding number of the polylines around `p`: +1 inside a counter-clockwise loop, the sum
    /// over loops (a ray to `+x`, counting each edge that crosses it upward as +1 when `p` is
    /// left of it and downward as -1 when right of it).
    pub fn winding(&self, p: DVec2) -> i32 {
        if self.lines.edges.is_empty() {
            return 0;
        }
        if p.y < self.min.y || p.y > self.max.y {
            return 0;
        }
        let row = (((p.y - self.min.y) / self.cell) as usize).min(self.dims[1] - 1);
        let mut w = 0;
        for &e in &self.row_items[self.row_starts[row] as usize..self.row_starts[row + 1] as usize]
        {
            let Segment { a, b } = self.lines.segment(self.lines.edges[e as usize]);
            let side = (b - a).perp_dot(p - a);
            if a.y <= p.y && b.y > p.y && side > 0.0 {
                w += 1;
            } else if b.y <= p.y && a.y > p.y && side < 0.0 {
                w -= 1;
            }
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::plane::Grid2;
    use rfta_testkit::circle_grid;

    #[test]
    fn an_annulus_gives_two_loops_with_the_hole_clockwise() {
        let grid = Grid2::from_bounds([61, 61], DVec2::splat(-1.0), DVec2::splat(1.0))
            .expect("valid test input");
        let values: Vec<f64> = (0..grid.len())
            .map(|i| {
                let r = grid.position(i).length();
                (r - 0.8).max(0.3 - r)
            })
            .collect();
        let c = rfta_mc::marching_squares(&grid, &values, 0.0);
        assert_eq!(c.loops(), 2);
        assert!(c.is_closed());
        let index = PolylineIndex::new(&c);
        assert_eq!(index.winding(DVec2::ZERO), 0);
        assert_eq!(index.winding(DVec2::new(0.55, 0.01)), 1);
        assert_eq!(index.winding(DVec2::new(0.9, 0.9)), 0);
    }

    #[test]
    fn closest_points_equal_brute_force() {
        let (grid, values) = circle_grid(23, 0.5);
        let c = rfta_mc::marching_squares(&grid, &values, 0.0);
        let index = PolylineIndex::new(&c);
        let mut rng = rfta_geom::rng::Rng::new(7);
        for _ in 0..2000 {
            let p = DVec2::new(rng.next_f64() * 6.0 - 3.0, rng.next_f64() * 6.0 - 3.0);
            let brute = c
                .edges
                .iter()
                .map(|&e| (c.segment(e).closest_point(p) - p).length())
                .fold(f64::INFINITY, f64::min);
            let got = index.closest(p);
            assert_eq!(got.distance, brute, "at {p}");
            assert_eq!((got.point - p).length(), got.distance);
        }
    }
}
