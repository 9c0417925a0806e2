//! Marching cubes on a regular grid (Lorensen and Cline, SIGGRAPH 1987): the baseline that
//! Reach for the Arcs is compared against.
//!
//! [`marching_cubes`] extracts the iso-surface `S = iso` of values on a [`Grid`] as a triangle
//! mesh with one vertex per crossed grid edge (shared by all cells around that edge, so the mesh
//! is welded), triangles oriented so their normals point towards larger values (outwards for a
//! signed distance that is negative inside).
//!
//! # Consistent ambiguous faces
//! The case table is not copied from a publication but generated (see [`table`]): on each cube
//! face the edge crossings are paired by a rule that depends only on that face's four corner
//! signs (an ambiguous face joins its two inside corners, as libigl does), and the face segments are chained
//! into loops around the cell. Two cells sharing a face therefore cut it the same way, so a closed
//! iso-surface gives a watertight, consistently oriented mesh.
//!
//! # Example
//! ```
//! use rfta_geom::Grid;
//! let grid = Grid::cube(20, -1.0, 1.0)?;
//! let values: Vec<f64> = (0..grid.len()).map(|i| grid.position(i).length() - 0.7).collect();
//! let mesh = rfta_mc::marching_cubes(&grid, &values, 0.0);
//! // A closed, outward-oriented sphere: positive volume close to 4/3 pi 0.7^3 = 1.437.
//! let v = mesh.signed_volume();
//! assert!((v - 1.437).abs() < 0.03, "{v}");
//! # Ok::<(), rfta_geom::Error>(())
//! ```

use std::collections::HashMap;

use rayon::prelude::*;
use rfta_geom::{Grid, TriMesh, glam::DVec3};

mod squares;
pub mod table;

pub use squares::marching_squares;

/// Cube corner `c` (0..8) as an offset: bit 0 is x, bit 1 is y, bit 2 is z.
fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

/// The iso-surface `values = iso` of a grid (`values[grid.index(i, j, k)]`), as a welded,
/// outward-oriented triangle mesh. Values below `iso` are inside. A grid with fewer than two
/// points along an axis, or whose values never cross `iso`, gives an empty mesh.
///
/// # Panics
/// If `values.len() != grid.len()` (a caller bug; validated inputs come from `SdfSamples`).
pub fn marching_cubes(grid: &Grid, values: &[f64], iso: f64) -> TriMesh {
    assert_eq!(values.len(), grid.len(), "one value per grid point");
    let [nx, ny, nz] = grid.dims();
    if nx < 2 || ny < 2 || nz < 2 {
        return TriMesh::default();
    }
    let cases = table::cases();
    let edges = table::EDGES;
    // Per x slab of cells: triangles as global edge ids (grid point index * 3 + axis).
    let slabs: Vec<Vec<[u64; 3]>> = (0..nx - 1)
        .into_par_iter()
        .map(|i| {
            let mut tris = Vec::new();
            for j in 0..ny - 1 {
                for k in 0..nz - 1 {
                    let mut mask = 0usize;
                    for c in 0..8 {
                        let [dx, dy, dz] = corner_offset(c);
                        if values[grid.index(i + dx, j + dy, k + dz)] < iso {
                            mask |= 1 << c;
                        }
                    }
                    for tri in &cases[mask] {
                        tris.push(tri.map(|e| {
                            let (a, _) = edges[e as usize];
                            let [dx, dy, dz] = corner_offset(a as usize);
                            (grid.index(i + dx, j + dy, k + dz) * 3 + table::edge_axis(e as usize))
                                as u64
                        }));
                    }
                }
            }
            tris
        })
        .collect();
    // Weld: one vertex per crossed edge, numbered in order of first use (deterministic).
    let mut ids: HashMap<u64, u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut faces = Vec::with_capacity(slabs.iter().map(Vec::len).sum());
    for tri in slabs.iter().flatten() {
        faces.push(tri.map(|edge| {
            *ids.entry(edge).or_insert_with(|| {
                vertices.push(edge_vertex(grid, values, iso, edge));
                (vertices.len() - 1) as u32
            })
        }));
    }
    TriMesh { vertices, faces }
}

/// The crossing of `iso` on a global edge, by linear interpolation.
fn edge_vertex(grid: &Grid, values: &[f64], iso: f64, edge: u64) -> DVec3 {
    let point = (edge / 3) as usize;
    let axis = (edge % 3) as usize;
    let [i, j, k] = grid.ijk(point);
    let mut next = [i, j, k];
    next[axis] += 1;
    let b = grid.index(next[0], next[1], next[2]);
    let (va, vb) = (values[point], values[b]);
    let t = if vb != va {
        ((iso - va) / (vb - va)).clamp(0.0, 1.0)
    } else {
        0.5
    };
    grid.position(point).lerp(grid.position(b), t)
}
