//! Which spheres contain a point: a bounding volume hierarchy over spheres.
//!
//! Reach for the Arcs (Sellán et al. 2024) asks two questions millions of times: is a candidate
//! tangency point `x` strictly inside some sample sphere other than its own
//! ([`SphereTree::inside_any`]), and which spheres (nearly) contain it
//! ([`SphereTree::spheres_containing`]). Sphere `j` counts when its signed distance
//! `|x - p_j| - r_j` is below a threshold `t`: the reference uses `t = -1e-4` for "strictly inside"
//! and `t = +1e-4` for "inside or touching" (in coordinates normalised to the unit box).
//!
//! # Why not a plain box tree
//! SDF samples give heavily overlapping spheres: every sample far from the surface is a large
//! sphere whose box covers much of the domain. A traversal that descends into every node whose box
//! holds `x` (the reference's) then visits a large part of the tree per query, which is what makes
//! the method quadratic without batching. This tree keeps, per node, the box of the sphere
//! *centres* and the largest radius, which bounds the signed distance of every sphere below it:
//! `|x - p_j| - r_j >= dist(x, centre box) - max radius`, and the signed distance from `x` to the
//! union of the spheres' boxes bounds it too (the larger is used). The bound is Euclidean (tighter
//! than a box test at corners), visits children nearest-first, and stops as soon as the answer is
//! known: at the first containing sphere for `inside_any`, and once `k` spheres deeper than any
//! remaining bound are found for `spheres_containing`. [`SphereTree::spheres_within_into`] lists
//! every sphere within a threshold, for callers that test many nearby points.
//! `cargo bench -p rfta-sphere-tree` measures the gain.
//!
//! obvhs builds the hierarchy; it never appears in this crate's API. Every answer is exact in
//! `f64`: the nodes' bounds are kept in `f32` (a node is one cache line), rounded so that they
//! never exceed the exact bounds, and the spheres themselves are tested in `f64`.
//!
//! # Example
//! ```
//! use rfta_geom::{glam::DVec3, Sphere};
//! use rfta_sphere_tree::{SphereTree, naive};
//!
//! let spheres: Vec<Sphere> = (0..100)
//!     .map(|i| Sphere::new(DVec3::new(i as f64 * 0.1, 0.0, 0.0), 0.08))
//!     .collect();
//! let tree = SphereTree::new(&spheres);
//! let x = DVec3::new(0.54, 0.0, 0.0);
//! // x is 0.04 deep in sphere 5 (centre 0.5) and 0.02 deep in sphere 6; ignoring 5 leaves 6.
//! assert!(tree.inside_any(x, -1e-4, Some(5)));
//! assert_eq!(tree.spheres_containing(x, 8, 1e-4, None), vec![5, 6]);
//! assert_eq!(tree.spheres_containing(x, 8, 1e-4, None), naive::spheres_containing(&spheres, x, 8, 1e-4, None));
//! ```

mod build;
pub mod naive;
mod query;

pub use build::SphereTree;
