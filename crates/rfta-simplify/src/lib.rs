//! Simplification of closed triangle meshes by edge collapse, cheapest first by quadric error
//! (Garland and Heckbert, "Surface simplification using quadric error metrics", SIGGRAPH 1997),
//! that keeps what a mesh from signed distance samples has to keep:
//!
//! - **the topology**: a collapse is made only where the link condition holds (Dey et al. 1999),
//!   so a closed manifold stays closed and manifold with the same genus and components; vertices
//!   on a boundary or a non-manifold edge never move;
//! - **the surface**: within [`Options::tolerance`] of the input both ways, measured at points
//!   (every input vertex within it of the output; every vertex a collapse places, and its new
//!   faces' centroids, within it of the input);
//! - **the faces' shape**: no face turns over (nor by more than 60 degrees), none is left without
//!   area or much thinner than the thinnest it replaces;
//! - **the caller's judge**: every collapse that passes the rest is offered to a [`Judge`] as a
//!   [`Patch`] (the faces before and after), which can refuse it; rfta's refuses any collapse
//!   that moves the surface across a sample or deeper into a sample's sphere.
//!
//! [`simplify_polylines`] does the same for closed 2D polylines, removing vertices on nearly
//! straight runs.
//!
//! It stops at [`Options::max_faces`] or when no collapse passes. The cheapest collapses are
//! tried in batches on rayon's threads; the output does not depend on their number: the same
//! mesh, options and judge give the same output.
//!
//! # Example
//! ```
//! use rfta_geom::shapes;
//! use rfta_simplify::{Options, simplify};
//!
//! // A finely tessellated ball of radius 1, kept within 0.01 of itself.
//! let ball = shapes::icosphere(1.0, 5);
//! let options = Options { tolerance: 0.01, max_faces: None };
//! let out = simplify(&ball, &options, &|_: &rfta_simplify::Patch<'_>| true)?;
//! assert!(out.mesh.n_faces() * 4 < ball.n_faces(), "{} faces", out.mesh.n_faces());
//! assert!(out.largest_deviation <= 0.01);
//! assert!(out.mesh.vertices.iter().all(|v| (v.length() - 1.0).abs() <= 0.01 + 1e-12));
//! # Ok::<(), rfta_simplify::Error>(())
//! ```

mod buckets;
mod collapse;
mod deviation;
mod editable;
mod nearest;
mod patch;
mod polylines;
mod quadric;
mod watch;

use rfta_geom::TriMesh;
use rfta_mesh::MeshIndex;

pub use patch::Patch;
pub use polylines::{Patch2, PolylineJudge, SimplifiedPolylines, simplify_polylines};
pub use watch::Watch;

/// The tolerance, in sample spacings, that costs a reconstruction from samples `per_axis`
/// spacings across (the samples' longest extent over their spacing) about 2% of its mean
/// Chamfer distance: `0.8 / per_axis`, i.e. `0.8 h^2 / L`, within 0.008 to 0.06.
///
/// A reconstruction's own error falls about as the square of the spacing (rfta's mean Chamfer on
/// its dev set: 0.047, 0.020, 0.0077, 0.0029 at 10, 20, 30 and 50 spacings across), so a
/// tolerance that costs it a fixed share does too; the factor was measured on that set between
/// 0.01 and 0.2 spacings (docs/eval/README.md). The cap is for coarse samples: at 10 spacings
/// across, 0.08 took a quarter of rfta's run (a surface that may stray that far can enter every
/// sphere it touches by rfta's slack, so its judge watches them all), while 0.06 still gives
/// under 3 times marching cubes' faces there. The floor is for fine ones, where the same
/// tolerance costs less: on the dev set at 128 spacings across, 0.00625 (the factor's) cost 0.2%
/// of the mean Chamfer for 3.75 times marching cubes' faces (median), 0.008 0.1% (each shape at
/// most 1.9%) for 2.99 times, 0.01 0.6% (one shape 3.4%) for 2.39 times.
pub fn default_tolerance(per_axis: f64) -> f64 {
    (DEFAULT_TOLERANCE / per_axis.max(1.0)).clamp(DEFAULT_AT_LEAST, DEFAULT_AT_MOST)
}

/// The factor of [`default_tolerance`].
const DEFAULT_TOLERANCE: f64 = 0.8;

/// [`default_tolerance`]'s floor, in spacings (reached beyond 100 spacings across).
const DEFAULT_AT_LEAST: f64 = 0.008;

/// [`default_tolerance`]'s cap, in spacings.
const DEFAULT_AT_MOST: f64 = 0.06;

/// What the simplification may do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The largest distance between the input and the output surface, both ways (the mesh's
    /// units; `f64::INFINITY`: no limit).
    pub tolerance: f64,
    /// Stop at this many faces (`None`: when no collapse passes).
    pub max_faces: Option<usize>,
}

/// The caller's say over each collapse. It is asked from several threads at once, about
/// collapses that share no vertex, and must answer from the patch alone.
pub trait Judge: Sync {
    /// Whether the collapse that turns `patch.before` into `patch.after` may be made.
    fn allows(&self, patch: &Patch<'_>) -> bool;
}

impl<F: Fn(&Patch<'_>) -> bool + Sync> Judge for F {
    fn allows(&self, patch: &Patch<'_>) -> bool {
        self(patch)
    }
}

/// A simplified mesh and what it took.
#[derive(Debug, Clone)]
pub struct Simplified {
    /// The output: the input's surviving vertices and faces in their order, unused vertices
    /// dropped.
    pub mesh: TriMesh,
    /// Edge collapses made (each removes two faces and a vertex).
    pub collapses: usize,
    /// The largest distance measured between the input and the output, both ways (at most
    /// [`Options::tolerance`]; see the crate documentation for where it is measured). From the
    /// output to the input it is measured to the input face a walk from a nearby face reached,
    /// the nearest face near there: no less than the distance to the input.
    pub largest_deviation: f64,
}

/// Why a mesh cannot be simplified.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The tolerance is negative or NaN.
    #[error("the tolerance must be zero or more (got {0})")]
    Tolerance(f64),
    /// The mesh is not valid (an index out of range, a vertex that is not finite).
    #[error("{0}")]
    Invalid(#[from] rfta_geom::Error),
    /// The mesh cannot be indexed (no faces).
    #[error("{0}")]
    Mesh(#[from] rfta_mesh::Error),
    /// The index given to [`simplify_indexed`] is of a mesh with another number of faces.
    #[error("the index has {index} faces, the mesh {mesh}: it is another mesh's")]
    IndexOfAnotherMesh {
        /// The index's faces.
        index: usize,
        /// The mesh's.
        mesh: usize,
    },
}

/// `mesh` simplified as `options` allow and `judge` agrees (see the crate documentation).
///
/// # Errors
/// [`Error::Tolerance`] for a negative or NaN tolerance, [`Error::Invalid`] for an invalid mesh,
/// [`Error::Mesh`] for one that cannot be indexed.
pub fn simplify(mesh: &TriMesh, options: &Options, judge: &dyn Judge) -> Result<Simplified, Error> {
    mesh.validate()?;
    simplify_indexed(mesh, &MeshIndex::new(mesh)?, options, judge)
}

/// [`simplify`] with the input's index (`MeshIndex::new(mesh)`) given, for a caller whose judge
/// indexes the mesh too.
///
/// # Errors
/// As [`simplify`], and [`Error::IndexOfAnotherMesh`] when `index` has another face count.
pub fn simplify_indexed(
    mesh: &TriMesh,
    index: &MeshIndex,
    options: &Options,
    judge: &dyn Judge,
) -> Result<Simplified, Error> {
    if options.tolerance.is_nan() || options.tolerance < 0.0 {
        return Err(Error::Tolerance(options.tolerance));
    }
    mesh.validate()?;
    if index.n_faces() != mesh.n_faces() {
        return Err(Error::IndexOfAnotherMesh {
            index: index.n_faces(),
            mesh: mesh.n_faces(),
        });
    }
    let mut deviation = deviation::Deviation::new(mesh, index, options.tolerance);
    let mut editable = editable::Editable::new(mesh);
    let collapses = collapse::run(
        &mut editable,
        &mut deviation,
        options.tolerance,
        options.max_faces.unwrap_or(0),
        judge,
    );
    Ok(Simplified {
        mesh: editable.into_mesh(),
        collapses,
        largest_deviation: deviation.largest,
    })
}
