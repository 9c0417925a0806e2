//! The plane: 2D SDF samples, closed polylines, and the queries and contouring the 2D pipeline
//! shares with its baseline.
//!
//! A 2D sample `(p_i, s_i)` is a circle of radius `|s_i|` that the curve touches without entering
//! (the paper's Figure 5). The 2D types mirror the 3D ones ([`Grid2`] ~ [`crate::Grid`],
//! [`Samples2`] ~ [`crate::SdfSamples`]); the output is [`Polylines`], closed loops with the inside
//! on their left (outer loops counter-clockwise).
//!
//! ```
//! use rfta_geom::plane::{contour, Grid2, PolylineIndex};
//! use rfta_geom::glam::DVec2;
//!
//! // The unit circle's SDF on a 33 x 33 grid over [-2, 2]^2, contoured at 0.
//! let grid = Grid2::from_bounds([33, 33], DVec2::splat(-2.0), DVec2::splat(2.0)).expect("valid test input");
//! let values: Vec<f64> = (0..grid.len()).map(|i| grid.position(i).length() - 1.0).collect();
//! let curve = contour(&grid, &values, 0.0);
//! assert_eq!(curve.loops(), 1);
//! let index = PolylineIndex::new(&curve);
//! assert_eq!(index.winding(DVec2::ZERO), 1); // counter-clockwise around the inside
//! assert!((index.closest(DVec2::new(3.0, 0.0)).distance - 2.0).abs() < 0.01);
//! ```

use glam::DVec2;

use crate::{Error, Result};

/// A regular 2D grid: `dims[0] x dims[1]` points, point `(i, j)` at `origin + (i, j) * spacing`,
/// stored in C order with y fastest (flat index `i * dims[1] + j`, NumPy's `S[i, j]` at
/// `(x_i, y_j)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid2 {
    dims: [usize; 2],
    origin: DVec2,
    spacing: DVec2,
}

impl Grid2 {
    /// A grid from its point counts, the position of point `(0, 0)` and the spacing.
    ///
    /// # Errors
    /// [`Error::InvalidGrid`] if a count is below 2 or the total overflows, the origin is not
    /// finite or a spacing is not positive and finite.
    pub fn new(dims: [usize; 2], origin: DVec2, spacing: DVec2) -> Result<Self> {
        if dims.iter().any(|&d| d < 2) {
            return Err(Error::InvalidGrid(format!(
                "a 2D grid needs at least 2 points per axis, got {dims:?}"
            )));
        }
        if dims[0].checked_mul(dims[1]).is_none() {
            return Err(Error::InvalidGrid(format!(
                "dimensions {dims:?} overflow the address space"
            )));
        }
        if !origin.is_finite() {
            return Err(Error::InvalidGrid(format!("origin {origin} is not finite")));
        }
        if !(spacing.cmpgt(DVec2::ZERO).all() && spacing.is_finite()) {
            return Err(Error::InvalidGrid(format!(
                "spacing {spacing} must be positive and finite"
            )));
        }
        Ok(Self {
            dims,
            origin,
            spacing,
        })
    }

    /// A grid whose corner points are `min` and `max` (`numpy.linspace` along each axis).
    ///
    /// # Errors
    /// As [`Grid2::new`], and if `max` is not above `min`.
    pub fn from_bounds(dims: [usize; 2], min: DVec2, max: DVec2) -> Result<Self> {
        if !(max.cmpgt(min).all()) {
            return Err(Error::InvalidGrid(format!("bounds {min}..{max} are empty")));
        }
        let cells = DVec2::new(
            dims[0].saturating_sub(1).max(1) as f64,
            dims[1].saturating_sub(1).max(1) as f64,
        );
        Self::new(dims, min, (max - min) / cells)
    }

    /// The grid whose points `positions` are, in any order, with each position's flat index in
    /// it (as [`crate::Grid::fit`] in 3D): `None` unless every position is a grid point (to
    /// 10^-6 of the spacing), each grid point appears once, and both axes have 2 points or more.
    pub fn fit(positions: &[DVec2]) -> Option<(Self, Vec<usize>)> {
        let lift: Vec<glam::DVec3> = positions.iter().map(|p| p.extend(0.0)).collect();
        // A third axis of one point is not a 3D grid; fit x and y as the first two of three
        // axes by giving z two layers, then map back.
        let doubled: Vec<glam::DVec3> = lift
            .iter()
            .copied()
            .chain(lift.iter().map(|p| glam::DVec3::new(p.x, p.y, 1.0)))
            .collect();
        let (grid, index) = crate::Grid::fit(&doubled)?;
        let [nx, ny, _] = grid.dims();
        let spacing = grid.spacing();
        let g = Self::new(
            [nx, ny],
            grid.origin().truncate(),
            DVec2::new(spacing.x, spacing.y),
        )
        .ok()?;
        // Flat 3D index (i * ny + j) * 2 + k with k = 0 for the first copy.
        let index = index[..positions.len()].iter().map(|&i| i / 2).collect();
        Some((g, index))
    }

    /// Points per axis.
    pub fn dims(&self) -> [usize; 2] {
        self.dims
    }

    /// Position of point `(0, 0)`.
    pub fn origin(&self) -> DVec2 {
        self.origin
    }

    /// Distance between neighbouring points along each axis.
    pub fn spacing(&self) -> DVec2 {
        self.spacing
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    /// Never true: a grid has at least 2 x 2 points.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Flat index of point `(i, j)`.
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.dims[1] + j
    }

    /// Position of the point with flat index `index`.
    pub fn position(&self, index: usize) -> DVec2 {
        let (i, j) = (index / self.dims[1], index % self.dims[1]);
        self.origin + DVec2::new(i as f64, j as f64) * self.spacing
    }
}

/// Validated 2D SDF samples: on a [`Grid2`] or at scattered positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples2 {
    positions: Vec<DVec2>,
    values: Vec<f64>,
    grid: Option<Grid2>,
}

impl Samples2 {
    /// Samples on a grid, `values` in the grid's order.
    ///
    /// # Errors
    /// A length mismatch, a non-finite value, or values that are all zero.
    pub fn grid(grid: Grid2, values: Vec<f64>) -> Result<Self> {
        if values.len() != grid.len() {
            return Err(Error::LengthMismatch {
                expected_what: "the grid",
                expected: grid.len(),
                found_what: "the values",
                found: values.len(),
            });
        }
        let positions = (0..grid.len()).map(|i| grid.position(i)).collect();
        Self::checked(positions, values, Some(grid))
    }

    /// Samples at scattered positions.
    ///
    /// # Errors
    /// A length mismatch, fewer than 3 samples, a non-finite position or value, two samples at one
    /// position with different values, or values that are all zero.
    pub fn scattered(positions: Vec<DVec2>, values: Vec<f64>) -> Result<Self> {
        if positions.len() != values.len() {
            return Err(Error::LengthMismatch {
                expected_what: "the positions",
                expected: positions.len(),
                found_what: "the values",
                found: values.len(),
            });
        }
        if positions.len() < 3 {
            return Err(Error::TooFewSamples {
                found: positions.len(),
                needed: 3,
            });
        }
        if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
            let p = positions[index];
            return Err(Error::NonFinitePosition {
                what: "sample",
                index,
                x: p.x,
                y: p.y,
                z: 0.0,
            });
        }
        let mut order: Vec<usize> = (0..positions.len()).collect();
        order.sort_by(|&a, &b| {
            let (p, q) = (positions[a], positions[b]);
            p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y))
        });
        for pair in order.windows(2) {
            let (a, b) = (pair[0].min(pair[1]), pair[0].max(pair[1]));
            if positions[a] == positions[b] && values[a] != values[b] {
                let p = positions[a];
                return Err(Error::ConflictingSamples {
                    first: a,
                    second: b,
                    x: p.x,
                    y: p.y,
                    z: 0.0,
                    first_value: values[a],
                    second_value: values[b],
                });
            }
        }
        Self::checked(positions, values, None)
    }

    fn checked(positions: Vec<DVec2>, values: Vec<f64>, grid: Option<Grid2>) -> Result<Self> {
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteValue {
                index,
                value: values[index],
            });
        }
        if values.iter().all(|&v| v == 0.0) {
            return Err(Error::NoSignChange {
                n: values.len(),
                sign: "zero",
                min: 0.0,
                max: 0.0,
            });
        }
        Ok(Self {
            positions,
            values,
            grid,
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Never true: validation requires samples.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Sample positions.
    pub fn positions(&self) -> &[DVec2] {
        &self.positions
    }

    /// SDF values, negative inside.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The grid, for grid samples.
    pub fn as_grid(&self) -> Option<&Grid2> {
        self.grid.as_ref()
    }

    /// Smallest and largest corner of the samples' bounding box.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        self.positions.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }
}

/// Polylines: vertices and directed edges `a -> b`. Closed loops from [`contour`] and the 2D
/// pipeline have the inside on the left of every edge.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polylines {
    /// Vertex positions.
    pub vertices: Vec<DVec2>,
    /// Directed edges as vertex index pairs.
    pub edges: Vec<[u32; 2]>,
}

impl Polylines {
    /// Polylines from vertices and edges.
    ///
    /// # Errors
    /// A non-finite vertex, or an edge naming a vertex that does not exist.
    pub fn new(vertices: Vec<DVec2>, edges: Vec<[u32; 2]>) -> Result<Self> {
        if let Some(index) = vertices.iter().position(|p| !p.is_finite()) {
            let p = vertices[index];
            return Err(Error::NonFinitePosition {
                what: "vertex",
                index,
                x: p.x,
                y: p.y,
                z: 0.0,
            });
        }
        for (face, e) in edges.iter().enumerate() {
            if let Some(&vertex) = e.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(Error::FaceIndexOutOfRange {
                    face,
                    vertex,
                    n_vertices: vertices.len(),
                });
            }
        }
        Ok(Self { vertices, edges })
    }

    /// True when there is no edge.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// The number of vertices that no edge uses. Every curve rfta returns or writes has none.
    pub fn unreferenced_vertices(&self) -> usize {
        crate::mesh::unreferenced(self.vertices.len(), &self.edges)
    }

    /// Removes the vertices that no edge uses, keeping the others in their order; edges are
    /// renumbered. Returns how many went.
    pub fn remove_unreferenced_vertices(&mut self) -> usize {
        crate::mesh::remove_unreferenced(&mut self.vertices, &mut self.edges)
    }

    /// Total length of the edges.
    pub fn length(&self) -> f64 {
        self.edges.iter().map(|&e| self.segment(e).length()).sum()
    }

    /// The connected components of the edges (loops, for closed polylines).
    pub fn loops(&self) -> usize {
        let mut parent: Vec<u32> = (0..self.vertices.len() as u32).collect();
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        let mut used = vec![false; self.vertices.len()];
        for &[a, b] in &self.edges {
            used[a as usize] = true;
            used[b as usize] = true;
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
        (0..self.vertices.len() as u32)
            .filter(|&v| used[v as usize] && root(&mut parent, v) == v)
            .count()
    }

    /// True when every vertex that an edge uses starts exactly one edge and ends exactly one.
    pub fn is_closed(&self) -> bool {
        let mut balance = vec![(0u32, 0u32); self.vertices.len()];
        for &[a, b] in &self.edges {
            balance[a as usize].0 += 1;
            balance[b as usize].1 += 1;
        }
        balance.iter().all(|&(out, into)| out == into && out <= 1)
    }

    /// Edge `e` as a segment.
    pub fn segment(&self, e: [u32; 2]) -> Segment {
        Segment {
            a: self.vertices[e[0] as usize],
            b: self.vertices[e[1] as usize],
        }
    }
}

/// A directed segment `a -> b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Start.
    pub a: DVec2,
    /// End.
    pub b: DVec2,
}

impl Segment {
    /// Length.
    pub fn length(&self) -> f64 {
        (self.b - self.a).length()
    }

    /// The point of the segment closest to `p` (a degenerate segment answers `a`).
    pub fn closest_point(&self, p: DVec2) -> DVec2 {
        let d = self.b - self.a;
        let len2 = d.length_squared();
        if len2 <= 0.0 {
            return self.a;
        }
        self.a + d * ((p - self.a).dot(d) / len2).clamp(0.0, 1.0)
    }
}

/// Marching squares: the curve `value = iso` of the bilinear interpolant of `values` on `grid`,
/// as polylines with one vertex per crossed grid edge and the inside (`value < iso`) on the left.
///
/// Along a grid edge the interpolant is linear, so every vertex lies exactly on the level set; in
/// a cell whose corners alternate in sign the bilinear saddle value decides which corners the
/// curve joins (the asymptotic decider), so the loops have the topology of the interpolant.
/// Loops that reach the grid's border end there open.
///
/// # Panics
/// If `values.len() != grid.len()` (a caller bug; validated inputs come from [`Samples2`]).
pub fn contour(grid: &Grid2, values: &[f64], iso: f64) -> Polylines {
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

    fn circle_grid(n: usize, r: f64) -> (Grid2, Vec<f64>) {
        let grid = Grid2::from_bounds([n, n], DVec2::splat(-1.0), DVec2::splat(1.0))
            .expect("valid test input");
        let values = (0..grid.len())
            .map(|i| grid.position(i).length() - r)
            .collect();
        (grid, values)
    }

    #[test]
    fn a_circle_contours_to_one_closed_counter_clockwise_loop_on_it() {
        let (grid, values) = circle_grid(41, 0.6);
        let c = contour(&grid, &values, 0.0);
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
    fn an_annulus_gives_two_loops_with_the_hole_clockwise() {
        let grid = Grid2::from_bounds([61, 61], DVec2::splat(-1.0), DVec2::splat(1.0))
            .expect("valid test input");
        let values: Vec<f64> = (0..grid.len())
            .map(|i| {
                let r = grid.position(i).length();
                (r - 0.8).max(0.3 - r)
            })
            .collect();
        let c = contour(&grid, &values, 0.0);
        assert_eq!(c.loops(), 2);
        assert!(c.is_closed());
        let index = PolylineIndex::new(&c);
        assert_eq!(index.winding(DVec2::ZERO), 0);
        assert_eq!(index.winding(DVec2::new(0.55, 0.01)), 1);
        assert_eq!(index.winding(DVec2::new(0.9, 0.9)), 0);
    }

    #[test]
    fn the_saddle_follows_the_bilinear_interpolant() {
        // Corners (0,0) and (1,1) inside; the interpolant's saddle value decides.
        let grid = Grid2::from_bounds([2, 2], DVec2::ZERO, DVec2::ONE).expect("valid test input");
        // values [S00, S01, S10, S11]: y fastest.
        let joined = contour(&grid, &[-1.0, 1.0, 1.0, -2.0], 0.0); // saddle (2-1)/(-5) < 0
        let split = contour(&grid, &[-1.0, 2.0, 2.0, -1.0], 0.0); // saddle (1-4)/(-6) > 0
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
    fn closest_points_equal_brute_force() {
        let (grid, values) = circle_grid(23, 0.5);
        let c = contour(&grid, &values, 0.0);
        let index = PolylineIndex::new(&c);
        let mut rng = crate::rng::Rng::new(7);
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

    #[test]
    fn a_shuffled_grid_is_recognised() {
        let grid = Grid2::from_bounds([4, 3], DVec2::new(-1.0, 0.0), DVec2::new(2.0, 1.0))
            .expect("valid test input");
        let order = [5, 0, 11, 3, 7, 1, 9, 2, 10, 4, 8, 6];
        let positions: Vec<DVec2> = order.iter().map(|&i| grid.position(i)).collect();
        let (fit, index) = Grid2::fit(&positions).expect("a grid");
        assert_eq!(fit.dims(), [4, 3]);
        assert!((fit.origin() - grid.origin()).length() < 1e-12);
        assert!((fit.spacing() - grid.spacing()).length() < 1e-12);
        assert_eq!(index, order.to_vec());
        let mut off = positions.clone();
        off[3].x += 0.1;
        assert!(Grid2::fit(&off).is_none());
    }

    #[test]
    fn bad_grids_and_samples_are_errors() {
        assert!(Grid2::new([1, 5], DVec2::ZERO, DVec2::ONE).is_err());
        assert!(Grid2::new([5, 5], DVec2::ZERO, DVec2::new(0.0, 1.0)).is_err());
        let grid = Grid2::new([2, 2], DVec2::ZERO, DVec2::ONE).expect("valid test input");
        assert!(Samples2::grid(grid, vec![0.0; 4]).is_err());
        assert!(Samples2::grid(grid, vec![1.0, f64::NAN, 1.0, -1.0]).is_err());
        assert!(Samples2::grid(grid, vec![1.0; 3]).is_err());
        let p = vec![DVec2::ZERO, DVec2::ZERO, DVec2::ONE];
        assert!(Samples2::scattered(p, vec![1.0, 2.0, -1.0]).is_err());
        assert!(Polylines::new(vec![DVec2::ZERO], vec![[0, 1]]).is_err());
    }

    #[test]
    fn contour_vertices_are_exactly_the_crossed_grid_edges() {
        // Brute force: every grid edge whose ends are on different sides of the iso-value holds
        // one vertex, at the linear interpolation; and every vertex is used by two edges.
        let grid = Grid2::from_bounds([19, 23], DVec2::new(-1.0, -1.2), DVec2::new(1.1, 1.0))
            .expect("valid test input");
        let mut rng = crate::rng::Rng::new(5);
        let values: Vec<f64> = (0..grid.len())
            .map(|i| {
                let p = grid.position(i);
                (3.0 * p.x).sin() + (2.0 * p.y).cos() - 0.3 + 0.1 * rng.next_f64()
            })
            .collect();
        let c = contour(&grid, &values, 0.0);
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
