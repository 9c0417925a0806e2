//! The plane's value types: 2D SDF samples on a grid or scattered, and closed polylines.
//!
//! A 2D sample `(p_i, s_i)` is a circle of radius `|s_i|` that the curve touches without entering
//! (the paper's Figure 5). The 2D types mirror the 3D ones ([`Grid2`] ~ [`crate::Grid`],
//! [`SdfSamples2`] ~ [`crate::SdfSamples`]); the output is [`Polylines`], closed loops with the
//! inside on their left (outer loops counter-clockwise).
//!
//! ```
//! use rfta_geom::plane::{Grid2, Polylines, SdfSamples2};
//! use rfta_geom::glam::DVec2;
//!
//! // The unit circle's SDF on a 33 x 33 grid over [-2, 2]^2.
//! let grid = Grid2::from_bounds([33, 33], DVec2::splat(-2.0), DVec2::splat(2.0)).expect("valid test input");
//! let values: Vec<f64> = (0..grid.len()).map(|i| grid.position(i).length() - 1.0).collect();
//! let samples = SdfSamples2::grid(grid, values).expect("valid test input");
//! assert_eq!(samples.len(), 33 * 33);
//! // A square, counter-clockwise: one closed loop.
//! let square = Polylines::new(
//!     vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
//!     vec![[0, 1], [1, 2], [2, 3], [3, 0]],
//! ).expect("valid test input");
//! assert_eq!(square.loops(), 1);
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
pub struct SdfSamples2 {
    positions: Vec<DVec2>,
    values: Vec<f64>,
    grid: Option<Grid2>,
}

impl SdfSamples2 {
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

/// Polylines: vertices and directed edges `a -> b`. Closed loops from marching squares
/// (`rfta_mc::marching_squares`) and the 2D pipeline have the inside on the left of every edge.
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!(SdfSamples2::grid(grid, vec![0.0; 4]).is_err());
        assert!(SdfSamples2::grid(grid, vec![1.0, f64::NAN, 1.0, -1.0]).is_err());
        assert!(SdfSamples2::grid(grid, vec![1.0; 3]).is_err());
        let p = vec![DVec2::ZERO, DVec2::ZERO, DVec2::ONE];
        assert!(SdfSamples2::scattered(p, vec![1.0, 2.0, -1.0]).is_err());
        assert!(Polylines::new(vec![DVec2::ZERO], vec![[0, 1]]).is_err());
    }
}
