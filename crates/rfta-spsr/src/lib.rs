//! Screened Poisson surface reconstruction (Kazhdan and Hoppe, "Screened Poisson Surface
//! Reconstruction", ACM TOG 2013): oriented points in, a watertight triangle mesh out.
//!
//! The input is mapped into a cube ([`SpsrParams::box_scale`] times its bounding box), points
//! that share a finest cell are merged, and a density estimate gives every sample a depth and the
//! surface area it stands for, so sparse regions get coarser, smoother support
//! ([`SpsrParams::samples_per_node`]). The inward normal field is splatted into an adaptive
//! octree that is refined only near samples and graded so that every depth's hats overlap active
//! hats one depth coarser. The indicator function, a sum of trilinear hats over all depths
//! (degree-1 B-splines, the basis PoissonRecon uses by default and Reach for the Arcs runs),
//! minimises `∫|∇χ - V|² + α Σ w (χ(p) - 1/2)²` with natural (Neumann) or zero (Dirichlet)
//! boundary conditions. It is solved by a cascadic multigrid pass: conjugate gradients on the
//! coarsest complete grids, then a few multi-colour Gauss-Seidel sweeps per depth with the
//! coarser solution moved to the right-hand side. The iso-value is the weighted mean of `χ` at
//! the samples, and the surface is extracted crack-free over the adaptive leaves.
//!
//! Everything is deterministic: the same input and parameters give the same mesh, bit for bit,
//! whatever the number of threads. The work runs on the caller's rayon pool (the global one, or
//! one the caller installs: `pool.install(|| reconstruct(..))`).
//!
//! # Example
//! ```
//! use rfta_spsr::{OrientedPoints, SpsrParams, glam::DVec3, reconstruct};
//!
//! // 4,000 points on the unit sphere (a Fibonacci spiral), normals pointing out.
//! let n = 4000;
//! let pts: Vec<DVec3> = (0..n)
//!     .map(|i| {
//!         let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
//!         let r = (1.0 - z * z).sqrt();
//!         let phi = i as f64 * 2.399963229728653;
//!         DVec3::new(r * phi.cos(), r * phi.sin(), z)
//!     })
//!     .collect();
//! let cloud = OrientedPoints::new(pts.clone(), pts, None)?;
//! let params = SpsrParams { depth: 6, ..SpsrParams::default() };
//! let out = reconstruct(&cloud, &params)?;
//! // Closed and outward: the volume is close to 4/3 pi.
//! let v = out.mesh.signed_volume();
//! assert!((v - 4.18879).abs() < 0.1, "{v}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// Stencil code indexes several fixed-size arrays with one loop variable; iterators would hide that.
#![allow(clippy::needless_range_loop)]

mod basis;
mod extract;
mod flat;
mod keys;
mod run;
mod sides;
mod solve;
mod tree;
mod triangulate;

use std::time::Duration;

use run::run;

/// The types of this crate's API, so that depending on `rfta-spsr` alone is enough.
pub use rfta_geom::{OrientedPoints, TriMesh, glam};
pub use sides::{SidePoint, SideSet};

/// Errors of the reconstruction. Each says what is wrong with the input or the parameters.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Fewer points than a surface needs.
    #[error("screened Poisson needs at least 3 oriented points, got {found}")]
    TooFewPoints {
        /// Number of points given.
        found: usize,
    },
    /// The input describes no surface (for example, all points are identical).
    #[error("{0}")]
    DegenerateInput(String),
    /// A parameter is out of its range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The solved function has no iso-surface inside the cube.
    #[error(
        "the reconstructed function has no iso-surface (iso-value {iso}); the normals may be inconsistent"
    )]
    NoSurface {
        /// The iso-value that was looked for.
        iso: f64,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Boundary condition on the faces of the reconstruction cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Natural boundary (zero normal derivative): PoissonRecon's default.
    #[default]
    Neumann,
    /// The function is zero on the cube's faces.
    Dirichlet,
}

/// Parameters. The finite elements are degree-1 B-splines (trilinear hats on cell corners,
/// PoissonRecon's default since version 11). The defaults are PoissonRecon 18's (`--depth 8 --pointWeight 2 --degree 1
/// --bType 3 --scale 1.1 --samplesPerNode 1.5 --fullDepth 5 --iters 8`);
/// [`SpsrParams::rfta_reference`] is the setting Reach for the Arcs uses.
#[derive(Debug, Clone, PartialEq)]
pub struct SpsrParams {
    /// Maximum octree depth: the finest cell is `box_scale * extent / 2^depth`. An upper bound:
    /// where samples are sparse the tree stops coarser. 1 to 16.
    pub depth: u32,
    /// Screening weight α (`--pointWeight`): how strongly the function is pulled to the iso-value
    /// at the samples, scaled internally by the average sample area so it does not depend on the
    /// number of points. 0 gives the unscreened Poisson reconstruction of 2006.
    pub screening: f64,
    /// Boundary condition.
    pub boundary: Boundary,
    /// Side of the reconstruction cube over the largest side of the points' bounding box (≥ 1).
    pub box_scale: f64,
    /// Target number of samples per node in the density-adaptive depth; raise it (15-20) for
    /// noisy input.
    pub samples_per_node: f64,
    /// Depth up to which the tree is complete (a regular grid); the depths below it are solved by
    /// conjugate gradients.
    pub full_depth: u32,
    /// Gauss-Seidel sweeps per depth from `full_depth` up.
    pub iterations: usize,
    /// Conjugate-gradient iterations cap per depth below `full_depth`.
    pub base_iterations: usize,
    /// Where the surface lies within this distance (in the points' coordinates) of a plane
    /// across a refined cell up to 3 depths above the finest, the extraction takes the cell
    /// whole: fewer, larger triangles, within twice the distance of the full extraction's
    /// surface, with its vertices on the same edges. `None` (the default): every leaf.
    pub flat_tolerance: Option<f64>,
}

impl Default for SpsrParams {
    fn default() -> Self {
        Self {
            depth: 8,
            screening: 2.0,
            boundary: Boundary::Neumann,
            box_scale: 1.1,
            samples_per_node: 1.5,
            full_depth: 5,
            iterations: 8,
            base_iterations: 200,
            flat_tolerance: None,
        }
    }
}

impl SpsrParams {
    /// The setting of the Reach for the Arcs reference implementation (its `point_cloud_to_mesh`):
    /// depth 10, screening 10, degree 1, Neumann, and a cube 3.2 times the cloud's extent.
    pub fn rfta_reference() -> Self {
        Self {
            depth: 10,
            screening: 10.0,
            box_scale: 3.2,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        if !(1..=16).contains(&self.depth) {
            return Err(Error::InvalidParams(format!(
                "depth must be 1 to 16, got {}",
                self.depth
            )));
        }
        if !(self.screening >= 0.0 && self.screening.is_finite()) {
            return Err(Error::InvalidParams(format!(
                "screening weight must be finite and >= 0, got {}",
                self.screening
            )));
        }
        if !(self.box_scale >= 1.0 && self.box_scale.is_finite()) {
            return Err(Error::InvalidParams(format!(
                "box scale must be finite and >= 1, got {}",
                self.box_scale
            )));
        }
        if !(self.samples_per_node > 0.0 && self.samples_per_node.is_finite()) {
            return Err(Error::InvalidParams(format!(
                "samples per node must be finite and > 0, got {}",
                self.samples_per_node
            )));
        }
        Ok(())
    }
}

/// What a reconstruction did, for logs and benchmarks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SpsrReport {
    /// Input points.
    pub points: usize,
    /// Samples after merging points per finest cell.
    pub samples: usize,
    /// Active hat functions (unknowns) per depth, coarsest first.
    pub nodes_per_depth: Vec<usize>,
    /// Octree cells per depth.
    pub cells_per_depth: Vec<usize>,
    /// The iso-value (weighted mean of the function at the samples).
    pub iso_value: f64,
    /// The side of the finest cells the surface was extracted from, in the input's coordinates:
    /// no loop of the mesh around a handle shorter than about this is a feature of the function
    /// (the extraction's choice at a saddle of it near the iso-value, which a cell cannot resolve).
    pub finest_cell: f64,
    /// With side points ([`reconstruct_with_sides`]): how many were on the wrong side after each
    /// solve, the last entry for the surface returned. Empty without them.
    pub side_errors: Vec<usize>,
    /// Leaves whose face segments did not close into loops (always 0 unless there is a bug; the
    /// mesh is then not watertight there).
    pub broken_leaves: usize,
    /// Time to merge samples, estimate density and build the octree.
    pub tree_time: Duration,
    /// Time to splat normals and assemble the per-depth systems.
    pub system_time: Duration,
    /// Time of the multigrid solve and the iso-value.
    pub solve_time: Duration,
    /// Time of the iso-surface extraction (with the first solve made again for its surface,
    /// when a re-solve's reached the cube's faces after side points refined the octree).
    pub extract_time: Duration,
}

/// A reconstructed surface.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// The mesh, in the input's coordinates, triangles oriented outward (along the normals).
    pub mesh: TriMesh,
    /// Statistics and timings.
    pub report: SpsrReport,
}

/// Reconstruct a surface from oriented points.
///
/// # Errors
/// [`Error::TooFewPoints`] below 3 points, [`Error::DegenerateInput`] when all points coincide,
/// [`Error::InvalidParams`], [`Error::NoSurface`] when the normals are so inconsistent that the
/// solution has no level set.
pub fn reconstruct(points: &OrientedPoints, params: &SpsrParams) -> Result<Reconstruction> {
    params.validate()?;
    run(points, params, crate::sides::NO_SIDES)
}

/// [`reconstruct`], with points known to lie inside or outside the surface.
///
/// The screened Poisson energy pulls the indicator function toward 1/2 at the samples. Here, after
/// the first solve, every side point where the function is not at least `SIDE_MARGIN` (0.02) on its
/// side of the iso-value becomes a screening term of its own, with the target iso ± `SIDE_TARGET`
/// (0.1) and weight `SIDE_WEIGHT` (1.0), and the system is solved again on the same octree,
/// starting from the solution before (`SIDE_RESOLVE_SWEEPS` (2) sweeps); up to `SIDE_PASSES` (4)
/// times, each adding the points still wrong and multiplying the weight of those that stay wrong by
/// `SIDE_WEIGHT_GROWTH` (4.0). This is the screening term with a target per point, in the spirit of
/// the envelope constraints of Kazhdan, Chuang, Rusinkiewicz and Hoppe ("Poisson Surface
/// Reconstruction with Envelope Constraints", SGP 2020), applied only where the plain solution
/// disagrees. A wrong side point whose cell the octree does not refine to its finest depth gets its
/// cell refined (the octree rebuilt as if a sample were there): a constraint on coarse depths alone
/// is undone by the finer hats beside it. Side points outside the reconstruction cube are ignored,
/// and re-solves whose surface reaches the cube's faces (where it would come out open) are dropped
/// for the first solve's surface when that one stays inside. [`SpsrReport::side_errors`] says how
/// many were wrong after each solve whose surface it returns.
///
/// ```
/// use rfta_spsr::{OrientedPoints, SidePoint, SpsrParams, glam::DVec3, reconstruct_with_sides};
///
/// // Points on two spheres of radius 0.5 whose centres are 1.05 apart: a 0.05 gap that the
/// // smooth solution bridges at depth 5; the gap's centre is outside.
/// let mut pts = Vec::new();
/// let mut nrm = Vec::new();
/// for c in [-0.525, 0.525] {
///     for i in 0..1500 {
///         let z = 1.0 - 2.0 * (i as f64 + 0.5) / 1500.0;
///         let phi = i as f64 * 2.399963229728653;
///         let s = (1.0 - z * z).sqrt();
///         let n = DVec3::new(z, s * phi.cos(), s * phi.sin());
///         pts.push(DVec3::new(c, 0.0, 0.0) + 0.5 * n);
///         nrm.push(n);
///     }
/// }
/// let cloud = OrientedPoints::new(pts, nrm, None)?;
/// let sides = [SidePoint { position: DVec3::ZERO, inside: false }];
/// let params = SpsrParams { depth: 5, ..SpsrParams::default() };
/// let out = reconstruct_with_sides(&cloud, &sides, &params)?;
/// // Wrong after the first solve, right after the last.
/// assert_eq!(out.report.side_errors.first(), Some(&1));
/// assert_eq!(out.report.side_errors.last(), Some(&0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`reconstruct`].
pub fn reconstruct_with_sides(
    points: &OrientedPoints,
    sides: &dyn SideSet,
    params: &SpsrParams,
) -> Result<Reconstruction> {
    params.validate()?;
    run(points, params, sides)
}
