//! Marching squares: closed polylines (open where they reach the grid's border) from values on a
//! 2D grid, with the asymptotic decider in saddle cells.
//!
//! ```
//! use rfta_geom::glam::DVec2;
//! use rfta_geom::plane::Grid2;
//!
//! let grid = Grid2::from_bounds([21, 21], DVec2::splat(-1.0), DVec2::splat(1.0)).expect("valid test input");
//! let values: Vec<f64> = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let curve = rfta_mc::marching_squares(&grid, &values, 0.0);
//! assert_eq!(curve.loops(), 1);
//! ```

use rfta_geom::plane::{Grid2, Polylines};

/// Marching squares, the 2D baseline and the 2D screened Poisson extraction: the curve `value =
/// iso` of the bilinear interpolant of `values` on `grid`, as polylines with one vertex per crossed
/// grid edge and the inside (`value < iso`) on the left.
///
/// Along a grid edge the interpolant is linear, so every vertex lies exactly on the level set; in
/// a cell whose corners alternate in sign the bilinear saddle value decides which corners the
/// curve joins (the asymptotic decider), so the loops have the topology of the interpolant.
/// Loops that reach the grid's border end there open.
///
/// # Panics
/// If `values.len() != grid.len()` (a caller bug; validated inputs come from [`rfta_geom::plane::SdfSamples2`]).
pub fn marching_squares(grid: &Grid2, values: &[f64], iso: f64) -> Polylines {
    let [nx, ny] = grid.dims();
    assert_eq!(values.len(), nx * ny, "one value per grid point");
    let inside = |i: usize, j: usize| values[i * ny + j] < iso;
    // Vertex of each crossed grid edge: key 2 * index(i, j) for the edge to (i + 1, j), + 1 for
    // the edge to (i, j + 1).
    let mut vertex_of = vec![u32::MAX; 2 * nx * ny];
    let mut vertices = Vec::new();
    let mut vertex = |key: usize, (i0, j0): (usize, usize), (i1, j1): (usize, usize)| -> u32 {
        if vertex_of[key] == u32::MAX {
            let (a, b) = (values[i0 * ny + j0] - iso, values[i1 * ny + j1] - iso);
            let t = (a / (a - b)).clamp(0.0, 1.0);
            let p0 = grid.position(i0 * ny + j0);
            let p1 = grid.position(i1 * ny + j1);
            vertex_of[key] = vertices.len() as u32;
            vertices.push(p0 + (p1 - p0) * t);
        }
        vertex_of[key]
    };
    let mut edges = Vec::new();
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            // Corners counter-clockwise from (i, j); side k joins corner k to corner k + 1.
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let ins = corners.map(|(a, b)| inside(a, b));
            if ins.iter().all(|&x| x) || ins.iter().all(|&x| !x) {
                continue;
            }
            let key = |k: usize| -> usize {
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
                2 * (lo.0 * ny + lo.1) + usize::from(hi.1 != lo.1)
            };
            // Starts: sides left going inside -> outside counter-clockwise; ends: outside -> inside.
            let mut starts = [0usize; 2];
            let mut ends = [0usize; 2];
            let (mut ns, mut ne) = (0, 0);
            for k in 0..4 {
                match (ins[k], ins[(k + 1) % 4]) {
                    (true, false) => {
                        starts[ns] = k;
                        ns += 1;
                    }
                    (false, true) => {
                        ends[ne] = k;
                        ne += 1;
                    }
                    _ => {}
                }
            }
            let side = |k: usize| (corners[k], corners[(k + 1) % 4]);
            let mut emit = |s: usize, e: usize, edges: &mut Vec<[u32; 2]>| {
                let (a0, a1) = side(s);
                let (b0, b1) = side(e);
                let (va, vb) = (vertex(key(s), a0, a1), vertex(key(e), b0, b1));
                if va != vb {
                    edges.push([va, vb]);
                }
            };
            if ns == 1 {
                emit(starts[0], ends[0], &mut edges);
            } else {
                // Saddle: the bilinear interpolant's value at its critical point.
                let v = corners.map(|(a, b)| values[a * ny + b] - iso);
                let saddle = (v[0] * v[2] - v[1] * v[3]) / (v[0] + v[2] - v[1] - v[3]);
                let joined = saddle < 0.0;
                for &s in &starts[..2] {
                    // Inside corners joined: the curve cuts off the outside corner after `s`.
                    let e = if joined { (s + 1) % 4 } else { (s + 3) % 4 };
                    emit(s, e, &mut edges);
                }
            }
        }
    }
    Polylines { vertices, edges }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::glam::DVec2;
    use rfta_testkit::circle_grid;

    #[test]
    fn a_circle_contours_to_one_closed_counter_clockwise_loop_on_it() {
        let (grid, values) = circle_grid(41, 0.6);
        let c = marching_squares(&grid, &values, 0.0);
        assert_eq!(c.loops(), 1);
        assert!(c.is_closed());
        // Vertices on grid edges of a linear interpolant of a convex function: within the
        // interpolation error h^2 / (8 r) of the circle (h = 0.05), never outside it.
        for v in &c.vertices {
            assert!((v.length() - 0.6).abs() < 0.05 * 0.05 / (8.0 * 0.6) * 1.5 + 1e-12);
        }
        // Counter-clockwise: positive signed area, close to the disc's.
        let area: f64 = c
            .edges
            .iter()
            .map(|&e| {
                let s = c.segment(e);
                s.a.perp_dot(s.b) / 2.0
            })
            .sum();
        assert!((area - std::f64::consts::PI * 0.36).abs() < 0.01, "{area}");
        assert!((c.length() - 2.0 * std::f64::consts::PI * 0.6).abs() < 0.01);
    }

    #[test]
    fn the_saddle_follows_the_bilinear_interpolant() {
        // Corners (0,0) and (1,1) inside; the interpolant's saddle value decides.
        let grid = Grid2::from_bounds([2, 2], DVec2::ZERO, DVec2::ONE).expect("valid test input");
        // values [S00, S01, S10, S11]: y fastest.
        let joined = marching_squares(&grid, &[-1.0, 1.0, 1.0, -2.0], 0.0); // saddle (2-1)/(-5) < 0
        let split = marching_squares(&grid, &[-1.0, 2.0, 2.0, -1.0], 0.0); // saddle (1-4)/(-6) > 0
        let centre = DVec2::splat(0.5);
        assert_eq!(joined.edges.len(), 2);
        assert_eq!(split.edges.len(), 2);
        // Joined insides: the centre is inside, i.e. each segment has it on its left.
        for &e in &joined.edges {
            let s = joined.segment(e);
            assert!((s.b - s.a).perp_dot(centre - s.a) > 0.0);
        }
        for &e in &split.edges {
            let s = split.segment(e);
            assert!((s.b - s.a).perp_dot(centre - s.a) < 0.0);
        }
    }

    #[test]
    fn contour_vertices_are_exactly_the_crossed_grid_edges() {
        // Brute force: every grid edge whose ends are on different sides of the iso-value holds
        // one vertex, at the linear interpolation; and every vertex is used by two edges.
        let grid = Grid2::from_bounds([19, 23], DVec2::new(-1.0, -1.2), DVec2::new(1.1, 1.0))
            .expect("valid test input");
        let mut rng = rfta_geom::rng::Rng::new(5);
        let values: Vec<f64> = (0..grid.len())
            .map(|i| {
                let p = grid.position(i);
                (3.0 * p.x).sin() + (2.0 * p.y).cos() - 0.3 + 0.1 * rng.next_f64()
            })
            .collect();
        let c = marching_squares(&grid, &values, 0.0);
        let [nx, ny] = grid.dims();
        let mut expected = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                for (di, dj) in [(1, 0), (0, 1)] {
                    let (a, b) = (grid.index(i, j), (i + di) * ny + j + dj);
                    if i + di >= nx || j + dj >= ny || (values[a] < 0.0) == (values[b] < 0.0) {
                        continue;
                    }
                    let t = values[a] / (values[a] - values[b]);
                    expected.push(grid.position(a) + (grid.position(b) - grid.position(a)) * t);
                }
            }
        }
        assert_eq!(c.vertices.len(), expected.len());
        for e in &expected {
            assert!(c.vertices.iter().any(|v| (*v - *e).length() < 1e-12), "{e}");
        }
        let mut uses = vec![0; c.vertices.len()];
        for &[a, b] in &c.edges {
            uses[a as usize] += 1;
            uses[b as usize] += 1;
        }
        // Vertices on the grid's border end open loops there; every other one joins two edges.
        for (v, &n) in c.vertices.iter().zip(&uses) {
            let border = (v.x - -1.0).abs() < 1e-12
                || (v.x - 1.1).abs() < 1e-12
                || (v.y - -1.2).abs() < 1e-12
                || (v.y - 1.0).abs() < 1e-12;
            assert!(n == 2 || (border && n == 1), "{v}: {n}");
        }
    }
}
