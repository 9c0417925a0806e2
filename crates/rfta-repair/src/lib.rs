//! Mesh repair against signed distance samples: what the last step of rfta (Reach for the Arcs,
//! Sellán et al. 2024) does to the screened Poisson surface so that it agrees with the samples,
//! usable without the pipeline.
//!
//! - [`remove_islands`]: connected components removed by the caller's verdicts ([`Island`]),
//!   the largest always kept; [`face_components`], [`signed_volume`] of a part.
//! - [`dent_wrong_side`]: the surface moved past samples near it that lie on its wrong side.
//! - [`push_out_of_spheres`], [`clear_spheres`]: vertices out of the sample spheres the surface
//!   enters (the surface may not enter a sample's sphere, §3 of the paper), faces split where they
//!   cut a sphere no vertex is in.
//! - [`cut_sub_cell_handles`]: the handles narrower than the solve's finest cell cut (the
//!   extraction's choice at a saddle of the function near its iso-value, not a feature of it).
//! - [`to_genus`]: a known genus reached, components joined by tubes and the shortest handle
//!   loops cut ([`rfta_mesh::join`], [`rfta_mesh::cut_along`]; [`cut_disjoint`], the pass both
//!   make).
//! - [`cavity_openings`]: where a cavity's wall is one the samples leave undecided (outside
//!   samples on both sides, next to each other on the grid): points for the caller to keep
//!   outside, so that a gap or a hole the surface closed opens again.
//! - [`edit`]: the edits all of these are made of, none of which turns a face over.
//!
//! Spheres come as [`Spheres`]: their centres and radii in a frame of their own (the pipeline's
//! unit box), the samples' values (for their signs) and the [`Frame`] that maps the mesh's
//! coordinates there.
//!
//! # Example
//! ```
//! use rfta_geom::{glam::DVec3, shapes, Sphere};
//! use rfta_repair::{Among, Frame, Spheres, clear_spheres};
//!
//! // A ball of radius 1 and an outside sample whose sphere (radius 0.3) it enters by 0.2.
//! let mut mesh = shapes::icosphere(1.0, 3);
//! let spheres = [Sphere::new(DVec3::new(1.1, 0.0, 0.0), 0.3)];
//! let set = Spheres { spheres: &spheres, values: &[0.3], frame: Frame::IDENTITY, spacing: 1.0 };
//! clear_spheres(&mut mesh, &set, Among::SmallerThan(f64::INFINITY), 0.001);
//! assert!(mesh.vertices.iter().all(|v| v.distance(spheres[0].center) > 0.3 - 0.001 - 1e-9));
//! ```

mod cavities;
mod clear;
mod components;
mod dent;
pub mod edit;
mod genus;
mod tunnel;

use rfta_geom::SphereSet;
use rfta_geom::glam::DVec3;

pub use cavities::{Openings, cavity_openings};
pub use clear::{Among, clear_spheres, push_out_of_spheres};
pub use components::{Island, remove_islands};
pub use dent::dent_wrong_side;
pub use edit::apply_moves;
pub use genus::{CUT_GAP, CutTest, cut_disjoint, cut_sub_cell_handles, to_genus};
pub use rfta_mesh::{face_components, signed_volume};
pub use tunnel::tunnel_cavities;

/// The map from a mesh's coordinates into the spheres' frame: `(p - origin) / scale`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// The mesh point at the frame's origin.
    pub origin: DVec3,
    /// One unit of the frame, in the mesh's units.
    pub scale: f64,
}

impl Frame {
    /// The mesh's own coordinates.
    pub const IDENTITY: Frame = Frame {
        origin: DVec3::ZERO,
        scale: 1.0,
    };

    /// A point of the mesh's coordinates in the frame.
    pub fn to_frame(&self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.scale
    }

    /// A point of the frame in the mesh's coordinates.
    pub fn to_mesh(&self, p: DVec3) -> DVec3 {
        p * self.scale + self.origin
    }
}

/// Sample spheres to repair a mesh against.
#[derive(Clone, Copy)]
pub struct Spheres<'a> {
    /// Centres and radii `|s_i|`, in the frame.
    pub spheres: &'a dyn SphereSet,
    /// The samples' values (negative inside), one per sphere: their signs say which side of the
    /// surface each sphere lies on.
    pub values: &'a [f64],
    /// From the mesh's coordinates to the spheres'.
    pub frame: Frame,
    /// The sample spacing, in the frame: how far a vertex may move ([`clear_spheres`]).
    pub spacing: f64,
}

impl std::fmt::Debug for Spheres<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Spheres")
            .field("spheres", &self.spheres.len())
            .field("values", &self.values.len())
            .field("frame", &self.frame)
            .field("spacing", &self.spacing)
            .finish()
    }
}
