//! Geometry kernel of rfta: value types and small robust kernels, in `f64` throughout.
//!
//! This crate is the vocabulary every other rfta crate speaks.
//! It does no I/O, spawns no threads and depends only on [`glam`] (re-exported) and `thiserror`.
//!
//! # Principal types
//! - [`Sphere`] and [`Aabb`]: a sample of a signed distance function (SDF) is a sphere of
//!   radius `|s|` that the surface touches without entering (Sellán et al. 2024).
//! - [`TriMesh`]: an indexed triangle mesh, validated on construction.
//! - [`OrientedPoints`]: positions with unit normals and optional weights, the input of
//!   screened Poisson reconstruction.
//! - [`SdfSamples`]: SDF values on a regular [`Grid`] or at scattered positions, validated on
//!   construction (non-finite values, length mismatches, too few samples, no sign change).
//!
//! # Kernels
//! The [`kernels`] module holds the primitives the reconstruction needs: the circle where two
//! spheres meet, the points common to three spheres (trilateration), the closest point on a circle,
//! radial projection onto a sphere, transport of a point along a great circle, and the closest
//! point on a triangle. Each handles its degenerate cases without producing NaN.
//!
//! # Example
//! ```
//! use rfta_geom::{glam::DVec3, kernels, Sphere};
//!
//! let a = Sphere::new(DVec3::ZERO, 1.0);
//! let b = Sphere::new(DVec3::new(1.0, 0.0, 0.0), 1.0);
//! let circle = kernels::sphere_sphere_circle(&a, &b).circle().expect("the spheres overlap");
//! assert!((circle.center.x - 0.5).abs() < 1e-15);
//! assert!((circle.radius - 0.75f64.sqrt()).abs() < 1e-15);
//! // Every point on that circle lies on both spheres.
//! let p = kernels::closest_point_on_circle(&circle, DVec3::new(0.0, 3.0, 0.0));
//! assert!(a.signed_distance(p).abs() < 1e-12 && b.signed_distance(p).abs() < 1e-12);
//! ```

pub use glam;

mod aabb;
mod analytic;
mod cubic;
mod error;
pub mod feature_transform;
pub mod kernels;
pub mod math;
mod mesh;
pub mod plane;
mod points;
pub mod rng;
mod sdf;
pub mod shapes;
mod sphere;

pub use aabb::Aabb;
pub use analytic::Analytic;
pub use cubic::CubicField;
pub use error::Error;
pub use mesh::TriMesh;
pub use points::OrientedPoints;
pub use sdf::{Grid, Layout, SdfSamples, SignBalance};
pub use sphere::{Sphere, SphereSet};

/// Shorthand for results whose error is this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
