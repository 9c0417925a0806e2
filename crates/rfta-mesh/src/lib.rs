//! Triangle-mesh queries for rfta: closest point, unsigned and signed distance, the fast
//! generalized winding number, seeded area-weighted surface samples, and topology checks.
//!
//! [`MeshIndex`] builds a bounding volume hierarchy over a [`TriMesh`] once (split by the
//! surface area heuristic in `f64` boxes, so every query is exact in double precision; the
//! halves of large ranges are built side by side, into the same tree on any number of threads)
//! and answers queries from any number of threads.
//!
//! - [`MeshIndex::closest_point`] and [`MeshIndex::unsigned_distance`]: exact point-to-triangle
//!   distance with best-first pruning.
//! - [`MeshIndex::winding_number`]: the generalized winding number (Jacobson et al. 2013),
//!   evaluated hierarchically with far-field expansions (Barill et al. 2018); exact for nearby
//!   triangles.
//! - [`MeshIndex::segment_hits`]: whether a segment crosses the mesh (collision queries);
//!   [`MeshIndex::segment_crossings`]: where, and which faces.
//! - [`MeshIndex::signed_distance`]: the unsigned distance, negative where the winding number
//!   exceeds 1/2 (libigl's convention), so it works on meshes with small holes too.
//! - [`sample_surface`]: area-weighted random points with a seed.
//! - [`Topology`]: watertight, manifold, oriented, Euler characteristic, genus, components;
//!   [`face_components`], their [`signed_volume`], the inward ones ([`cavities`]);
//!   [`Incidence`], the faces around each vertex.
//! - [`short_loops`]: the handles a short loop goes around (thinner than a sampling resolves);
//!   [`cut_along`] such a loop, [`join`] two components by a tube.
//!
//! # Example
//! ```
//! use rfta_geom::{glam::DVec3, shapes};
//! use rfta_mesh::{MeshIndex, Topology};
//!
//! let mesh = shapes::icosphere(1.0, 3);
//! let index = MeshIndex::new(&mesh)?;
//! // The centre is inside: about one unit below the surface.
//! let d = index.signed_distance(DVec3::ZERO);
//! assert!((d + 1.0).abs() < 0.01);
//! // A point outside is positive.
//! assert!(index.signed_distance(DVec3::new(2.0, 0.0, 0.0)) > 0.99);
//! let topo = Topology::of(&mesh);
//! assert!(topo.is_watertight() && topo.genus() == Some(0));
//! # Ok::<(), rfta_mesh::Error>(())
//! ```

mod build;
mod bvh;
mod components;
mod incidence;
mod loops;
mod moments;
mod node;
mod polylines;
mod sample;
mod scaled;
mod surgery;
mod topology;
mod union_find;
mod winding;

pub use bvh::{ClosestPoint, MeshIndex, Shell};
pub use components::{cavities, face_components, signed_volume};
pub use incidence::Incidence;
pub use loops::{ShortLoops, short_loops};
pub use polylines::{Closest, PolylineIndex};
pub use rfta_geom::TriMesh;
pub use sample::{SurfaceSample, sample_surface};
pub use scaled::{MeshSdf, scaled, unit_scale};
pub use surgery::{cut_along, join};
pub use topology::Topology;
pub use union_find::UnionFind;

/// What can go wrong building a mesh index.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The mesh has no triangles, so there is no surface to measure against.
    #[error("the mesh has no triangles")]
    EmptyMesh,
    /// The mesh itself is invalid.
    #[error(transparent)]
    Geom(#[from] rfta_geom::Error),
}

/// Shorthand for results whose error is this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
