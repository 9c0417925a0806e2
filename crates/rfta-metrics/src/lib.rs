//! Reconstruction metrics as Reach for the Arcs (Sellán et al. 2024, §5) defines them.
//!
//! - [`chamfer`]: `sqrt(mean d1^2) + sqrt(mean d2^2)`, with `d1` the distances from `n` seeded,
//!   area-weighted samples of the first mesh to the second mesh's surface and `d2` the other way
//!   round. The paper measured to the nearest of `10^6` samples of the other mesh; the distance
//!   to the surface is that definition's limit without its small positive bias.
//! - [`hausdorff`]: the larger of the two maximum vertex-to-mesh distances (libigl's
//!   `hausdorff`, which the paper used).
//! - [`sdf_energy`]: `1000 * mean_i (|s_i| - dist(p_i, mesh))^2` over the input samples.
//! - [`MeshSummary`]: counts, watertightness, genus and components.
//!
//! All distances are exact point-to-triangle distances ([`rfta_mesh::MeshIndex`]); evaluation is
//! parallel and deterministic. The `_indexed` forms take indices the caller already built, so
//! scoring many reconstructions against one ground truth builds its tree once.
//!
//! # Example
//! ```
//! use rfta_geom::shapes;
//! // Concentric spheres of radius 1 and 1.1: every point is about 0.1 from the other surface.
//! let a = shapes::icosphere(1.0, 4);
//! let b = shapes::icosphere(1.1, 4);
//! let c = rfta_metrics::chamfer(&a, &b, 10_000, 1)?;
//! assert!((c - 0.2).abs() < 0.005, "{c}");
//! # Ok::<(), rfta_mesh::Error>(())
//! ```

pub mod plane;

use rayon::prelude::*;
use rfta_geom::{TriMesh, glam::DVec3};
use rfta_mesh::{MeshIndex, Result, Topology, sample_surface};

/// Root-mean-square distance from `n` area-weighted samples of `from` (seeded) to `to`'s surface
/// (zero when `from` has no area).
pub fn rms_distance(from: &TriMesh, to: &MeshIndex, n: usize, seed: u64) -> f64 {
    let samples = sample_surface(from, n, seed);
    if samples.is_empty() {
        return 0.0;
    }
    let sum: f64 = samples
        .par_iter()
        .map(|s| to.closest_point(s.point).distance_squared)
        .sum();
    (sum / samples.len() as f64).sqrt()
}

/// The paper's Chamfer distance between two meshes with `n` samples on each.
///
/// # Errors
/// [`rfta_mesh::Error::EmptyMesh`] if either mesh has no triangles.
pub fn chamfer(a: &TriMesh, b: &TriMesh, n: usize, seed: u64) -> Result<f64> {
    let (ia, ib) = (MeshIndex::new(a)?, MeshIndex::new(b)?);
    Ok(chamfer_indexed((a, &ia), (b, &ib), n, seed))
}

/// [`chamfer`] with both meshes' indices already built (each mesh paired with its index).
pub fn chamfer_indexed(
    a: (&TriMesh, &MeshIndex),
    b: (&TriMesh, &MeshIndex),
    n: usize,
    seed: u64,
) -> f64 {
    rms_distance(a.0, b.1, n, seed) + rms_distance(b.0, a.1, n, seed.wrapping_add(1))
}

/// The larger of the maximum distance from `a`'s vertices to `b` and from `b`'s vertices to `a`.
///
/// # Errors
/// [`rfta_mesh::Error::EmptyMesh`] if either mesh has no triangles.
pub fn hausdorff(a: &TriMesh, b: &TriMesh) -> Result<f64> {
    let (ia, ib) = (MeshIndex::new(a)?, MeshIndex::new(b)?);
    Ok(hausdorff_indexed((a, &ia), (b, &ib)))
}

/// [`hausdorff`] with both meshes' indices already built.
pub fn hausdorff_indexed(a: (&TriMesh, &MeshIndex), b: (&TriMesh, &MeshIndex)) -> f64 {
    let max_to = |from: &TriMesh, to: &MeshIndex| -> f64 {
        from.vertices
            .par_iter()
            .map(|v| to.unsigned_distance(*v))
            .reduce(|| 0.0, f64::max)
    };
    max_to(a.0, b.1).max(max_to(b.0, a.1))
}

/// `1000 * mean((|s_i| - dist(p_i, mesh))^2)` over samples `(p_i, s_i)`.
///
/// # Errors
/// [`rfta_mesh::Error::EmptyMesh`] if the mesh has no triangles.
pub fn sdf_energy(positions: &[DVec3], values: &[f64], mesh: &TriMesh) -> Result<f64> {
    Ok(sdf_energy_indexed(
        positions,
        values,
        &MeshIndex::new(mesh)?,
    ))
}

/// [`sdf_energy`] with the mesh's index already built.
pub fn sdf_energy_indexed(positions: &[DVec3], values: &[f64], index: &MeshIndex) -> f64 {
    let n = positions.len().min(values.len());
    if n == 0 {
        return 0.0;
    }
    let sum: f64 = (0..n)
        .into_par_iter()
        .map(|i| {
            let e = values[i].abs() - index.unsigned_distance(positions[i]);
            e * e
        })
        .sum();
    1000.0 * sum / n as f64
}

/// Counts and topology of a mesh, as the evaluation reports them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeshSummary {
    /// Vertices.
    pub n_vertices: usize,
    /// Faces.
    pub n_faces: usize,
    /// Every edge has exactly two faces.
    pub watertight: bool,
    /// Genus of a closed manifold (`None` otherwise).
    pub genus: Option<i64>,
    /// Connected components.
    pub components: usize,
    /// Components that face inward: cavities ([`rfta_mesh::cavities`]).
    pub cavities: usize,
    /// Edges with one face.
    pub boundary_edges: usize,
}

impl MeshSummary {
    /// Summarises `mesh`.
    pub fn of(mesh: &TriMesh) -> Self {
        let t = Topology::of(mesh);
        Self {
            n_vertices: mesh.n_vertices(),
            n_faces: mesh.n_faces(),
            watertight: t.is_watertight(),
            genus: t.genus(),
            components: t.components,
            cavities: rfta_mesh::cavities(mesh).len(),
            boundary_edges: t.boundary_edges,
        }
    }
}
