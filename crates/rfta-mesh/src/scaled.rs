//! A mesh's signed distance at any scale: a mesh far smaller or larger than the unit (1e-300,
//! 1e155) is measured at a power-of-two scale near 1, where squared distances neither underflow
//! to zero nor overflow to infinity (hostile test E7: an all-zero grid at 1e-300, NaN at 1e155).
//! Multiplying by a power of two is exact in floating point, so a mesh whose coordinates are
//! within 2^-64 to 2^64 of the unit is measured exactly as [`MeshIndex`] measures it.

use rayon::prelude::*;
use rfta_geom::{Aabb, Grid, TriMesh, glam::DVec3};

use crate::{MeshIndex, Result};

/// Meshes whose largest coordinate lies within `[2^-SCALE_FREE, 2^SCALE_FREE]` are measured as
/// they are: their squared distances are far from the limits of `f64`.
const SCALE_FREE: i32 = 64;

/// The signed distance of a mesh (negative inside, by the winding number), measured at a
/// power-of-two scale near the unit and given back in the mesh's own units.
#[derive(Debug)]
pub struct MeshSdf {
    index: MeshIndex,
    /// What positions are multiplied by before they are measured: `2^k`.
    scale: f64,
}

/// `2^k` for `k` in the range of normal numbers.
fn pow2(k: i32) -> f64 {
    let k = k.clamp(-1022, 1023);
    f64::from_bits(((1023 + k) as u64) << 52)
}

/// The binary exponent of a positive normal `x` (`x` in `[2^e, 2^(e+1))`).
fn exponent(x: f64) -> i32 {
    ((x.to_bits() >> 52) & 0x7ff) as i32 - 1023
}

/// The power of two that brings the largest coordinate of `mesh` near 1 (1 for a mesh whose
/// largest coordinate is within 64 binary orders of it): what [`MeshSdf`] measures
/// at, and what a volume or an orientation of a mesh far from the unit is computed at.
pub fn unit_scale(mesh: &TriMesh) -> f64 {
    let largest = mesh
        .vertices
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0f64, f64::max);
    let e = if largest.is_normal() {
        exponent(largest)
    } else {
        0
    };
    if e.abs() <= SCALE_FREE { 1.0 } else { pow2(-e) }
}

/// `mesh` with every vertex multiplied by `scale`.
pub fn scaled(mesh: &TriMesh, scale: f64) -> TriMesh {
    TriMesh {
        vertices: mesh.vertices.iter().map(|&v| v * scale).collect(),
        faces: mesh.faces.clone(),
    }
}

impl MeshSdf {
    /// Indexes `mesh` at the scale that brings its largest coordinate near 1 ([`unit_scale`]).
    ///
    /// # Errors
    /// As [`MeshIndex::new`].
    pub fn new(mesh: &TriMesh) -> Result<Self> {
        let scale = unit_scale(mesh);
        let index = if scale == 1.0 {
            MeshIndex::new(mesh)?
        } else {
            MeshIndex::new(&scaled(mesh, scale))?
        };
        Ok(Self { index, scale })
    }

    /// The mesh's bounding box, in its own units.
    pub fn bounds(&self) -> Aabb {
        let b = self.index.bounds();
        Aabb::new(b.min / self.scale, b.max / self.scale)
    }

    /// The signed distance at `p`, in the mesh's units.
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        if self.scale == 1.0 {
            return self.index.signed_distance(p);
        }
        self.index.signed_distance(p * self.scale) / self.scale
    }

    /// [`MeshSdf::signed_distance`] at every point, in parallel; the result does not depend on
    /// the thread count.
    pub fn signed_distances(&self, points: &[DVec3]) -> Vec<f64> {
        points
            .par_iter()
            .map(|&p| self.signed_distance(p))
            .collect()
    }

    /// [`MeshSdf::signed_distance`] at every point of `grid`, in the grid's flat order, in
    /// parallel over x slabs; `on_slab` is called after each slab (for progress reporting).
    pub fn signed_distance_grid(&self, grid: &Grid, on_slab: &(dyn Fn() + Sync)) -> Vec<f64> {
        let [nx, ny, nz] = grid.dims();
        let slabs: Vec<Vec<f64>> = (0..nx)
            .into_par_iter()
            .map(|i| {
                let slab = (0..ny * nz)
                    .map(|jk| self.signed_distance(grid.position(i * ny * nz + jk)))
                    .collect();
                on_slab();
                slab
            })
            .collect();
        slabs.concat()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// The unit cube's signed distance at the centre is -0.5 and 0.5 beyond a face; the same
    /// cube scaled by 1e-300 and 1e155 gives the same values scaled, to rounding.
    #[test]
    fn distances_scale_with_the_mesh() {
        let cube = shapes::cuboid(DVec3::splat(0.5));
        for s in [1.0, 1e-300, 1e155, 3.0e-200, 7.0e250] {
            let mut mesh = cube.clone();
            for v in &mut mesh.vertices {
                *v *= s;
            }
            let sdf = MeshSdf::new(&mesh).expect("sdf");
            for (p, want) in [
                (DVec3::ZERO, -0.5),
                (DVec3::new(1.0, 0.0, 0.0), 0.5),
                (DVec3::new(0.25, 0.1, -0.2), -0.25),
                (DVec3::new(1.5, 1.5, 0.0), 2f64.sqrt()),
            ] {
                let d = sdf.signed_distance(p * s);
                assert!(
                    (d / s - want).abs() < 1e-12,
                    "scale {s:e} at {p}: {d:e}, want {:e}",
                    want * s
                );
            }
            let b = sdf.bounds();
            assert!((b.max.x / s - 0.5).abs() < 1e-12);
        }
    }

    /// A mesh near the unit is measured exactly as the index measures it.
    #[test]
    fn unit_meshes_are_measured_as_they_are() {
        let mesh = shapes::icosphere(0.5, 2);
        let sdf = MeshSdf::new(&mesh).expect("sdf");
        let index = MeshIndex::new(&mesh).expect("index");
        for k in 0..50 {
            let t = f64::from(k) * 0.37;
            let p = DVec3::new(t.sin(), t.cos(), (2.0 * t).sin()) * 0.8;
            assert_eq!(
                sdf.signed_distance(p).to_bits(),
                index.signed_distance(p).to_bits()
            );
        }
    }
}
