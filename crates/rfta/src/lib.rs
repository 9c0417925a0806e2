//! Reach for the Arcs (Sellán, Ren, Batty and Stein, "Reach For the Arcs: Reconstructing Surfaces
//! from SDFs via Tangent Points", SIGGRAPH 2024): a triangle mesh from signed distance samples.
//!
//! Every sample `(p_i, s_i)` is a sphere of radius `|s_i|` that the surface touches without
//! entering. [`reconstruct`] runs six steps, each a module of this crate:
//!
//! 1. `normalize`: the samples as spheres in the reference's unit box;
//! 2. and 3. `initial`: empty space next to the spheres of each sign by rasterization
//!    ([`raster`]), and one feasible tangency point per sphere from it
//!    ([`feasible::initial_points`]);
//! 4. and 5. `rounds`: [`Params::rounds`] times, screened Poisson reconstruction ([`spsr`]) of the
//!    points and fine-tuning of the points against its surface ([`feasible::fine_tune`]);
//! 6. `finish`: a final solve, whose mesh is mapped back to the input's coordinates, repaired,
//!    simplified ([`Params::simplify`]: `rfta-simplify`, every sample's side and sphere kept) and
//!    checked.
//!
//! [`check`] guards both ends: the values before anything is built, the mesh before it is
//! returned. [`Params`] owns every setting and derives each stage's from them.
//!
//! The defaults ([`Params::default`]) are the paper's rounds, points per sphere, batch, step and
//! tolerance, with two departures chosen by measurement (docs/speed.md): the Poisson depth follows
//! the sample spacing ([`spsr_depth_for`]) and only spheres within `OWNER_BAND` (3.0) spacings of
//! the surface own points (scattered samples: each sphere's own spacing). [`Params::paper_table`]
//! is the setting of its Table 2.
//! Results are deterministic for a given seed, whatever the thread count.
//!
//! Before any of that, the values are checked ([`check`]): fields that are not a distance
//! (occupancy, random, rescaled, sentinel values) are refused with [`Error::NotADistance`], a
//! clamped SDF is detected and treated as such, and [`Params::memory_limit`] refuses inputs too
//! large for the machine by [`estimate_peak_memory`]. The mesh is checked before it is returned
//! ([`MeshCheck`]), and the [`Report`] lists what the caller should know in `warnings`.
//!
//! # Example
//! ```
//! use rfta::{Params, reconstruct};
//! use rfta::geom::{Grid, SdfSamples};
//!
//! // A sphere of radius 0.5 sampled on a 13^3 grid over [-1, 1]^3.
//! let grid = Grid::cube(12, -1.0, 1.0)?;
//! let values = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let samples = SdfSamples::grid(grid, values)?;
//! let params = Params { rounds: Some(2), ..Params::default() };
//! let out = reconstruct(&samples, &params)?;
//! let v = out.mesh.signed_volume();
//! assert!((v - 0.5236).abs() < 0.05, "volume {v}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod adaptive;
pub mod check;
pub mod consistency;
pub mod field;
mod finish;
mod initial;
mod memory;
mod normalize;
mod params;
mod plan;
pub mod plane;
mod pool;
mod report;
mod rounds;
mod warning;

pub use rfta_feasible as feasible;
pub use rfta_geom as geom;
pub use rfta_plane as plane_stages;
pub use rfta_raster as raster;
pub use rfta_sphere_tree as sphere_tree;
pub use rfta_spsr as spsr;

pub use consistency::{Consistency, Margins};
pub use field::{Field, FieldReport, Reading};
pub use memory::{available_memory, check_memory, estimate_peak_memory, format_bytes};
pub(crate) use params::{CELLS_PER_SPACING, RASTER_REACH, SUB_CELL_LOOP};
pub use params::{InitialPoints, PRESETS, Params, Seeds, screening_at, spsr_depth_for};
pub use pool::{GlobalPool, cores, start_global_pool};
pub use report::{
    FinalSolveReport, InitialReport, InputReport, MeshCheck, Reconstruction, RepairReport, Report,
    RoundsReport, SimplifyReport, Stage, Step,
};
pub use warning::Warning;

use std::sync::atomic::{AtomicBool, Ordering};

use rfta_geom::SdfSamples;

/// Errors of a reconstruction.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Too few spheres admit a feasible tangency point to define a surface.
    #[error(
        "only {feasible} of {spheres} spheres admit a tangency point, too few for a surface (are the values a signed distance?)"
    )]
    TooFewPoints {
        /// Feasible points found.
        feasible: usize,
        /// Spheres (samples).
        spheres: usize,
    },
    /// Every sample has one sign and their spheres leave no empty space of that sign's side
    /// where a surface could be: the samples describe no surface.
    #[error(
        "all {samples} samples are {sign} and their spheres leave no empty space where a surface could be: the samples describe no surface"
    )]
    NoSurface {
        /// Samples given.
        samples: usize,
        /// "positive (outside)" or "negative (inside)" (zeros count with the positive ones).
        sign: &'static str,
    },
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The values do not behave like a signed distance (see [`check`]): reconstructing from them
    /// would give a wrong mesh. [`Params::check`] set to `false` reconstructs anyway.
    #[error("the samples are not a signed distance function: {0}")]
    NotADistance(String),
    /// The input needs more memory than [`Params::memory_limit`] allows.
    #[error(
        "{samples} samples need about {} of memory by rfta's estimate, more than the limit of {}; use fewer samples (a coarser grid) or raise the limit",
        format_bytes(*needed),
        format_bytes(*limit)
    )]
    TooLarge {
        /// Samples given.
        samples: usize,
        /// The estimate, bytes ([`estimate_peak_memory`]).
        needed: u64,
        /// The limit, bytes.
        limit: u64,
    },
    /// The reconstructed mesh has a non-finite vertex (a bug; reported instead of written).
    #[error("the reconstructed mesh has a non-finite vertex ({0}); please report this input")]
    NonFiniteOutput(usize),
    /// Empty-space rasterization failed.
    #[error("rasterization: {0}")]
    Raster(#[from] rfta_raster::Error),
    /// The final screened Poisson solve failed.
    #[error("screened Poisson: {0}")]
    Spsr(#[from] rfta_spsr::Error),
    /// A mesh could not be indexed for [`consistency::measure`] (no faces, a non-finite vertex).
    #[error("consistency check: {0}")]
    Consistency(#[from] rfta_mesh::Error),
    /// The thread pool could not be created.
    #[error("could not start {threads} threads: {reason}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// Why.
        reason: String,
    },
    /// The caller's cancel flag was set ([`reconstruct_cancellable`]).
    #[error("cancelled")]
    Cancelled,
    /// The SDF oracle of an adaptive run failed ([`adaptive::reconstruct_adaptive`]); `source`
    /// is its own error.
    #[error("the SDF failed on batch {batch}: {source}")]
    Oracle {
        /// The batch, counted from 1.
        batch: usize,
        /// The oracle's error.
        source: adaptive::OracleError,
    },
    /// The SDF oracle of an adaptive run answered a batch with the wrong number of values or a
    /// value that is not finite.
    #[error("the SDF's answer to batch {batch} is unusable: {reason}")]
    OracleAnswer {
        /// The batch, counted from 1.
        batch: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// Samples could not be assembled (an adaptive run's, before its reconstruction).
    #[error("samples: {0}")]
    Samples(#[from] rfta_geom::Error),
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Reconstruct a mesh from signed distance samples (negative inside).
///
/// # Errors
/// [`Error::InvalidParams`], [`Error::TooLarge`] above [`Params::memory_limit`],
/// [`Error::NotADistance`] when [`Params::check`] finds the values are not a distance,
/// [`Error::TooFewPoints`] when fewer than 3 spheres admit a tangency point, [`Error::NoSurface`]
/// when the samples all have one sign and their spheres cover the space, [`Error::Raster`],
/// [`Error::Spsr`] when the final solve fails, [`Error::ThreadPool`], [`Error::NonFiniteOutput`].
pub fn reconstruct(samples: &SdfSamples, params: &Params) -> Result<Reconstruction> {
    reconstruct_with_progress(samples, params, &mut |_| {})
}

/// [`reconstruct`], calling `progress` as each stage starts.
///
/// # Errors
/// As [`reconstruct`].
pub fn reconstruct_with_progress(
    samples: &SdfSamples,
    params: &Params,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<Reconstruction> {
    reconstruct_cancellable(samples, params, progress, &AtomicBool::new(false))
}

/// [`reconstruct_with_progress`] that gives up with [`Error::Cancelled`] once `cancel` is set:
/// the flag is read before each stage and each fine-tuning round (an interactive caller's Ctrl-C,
/// a deadline), so a stage under way finishes first.
///
/// # Errors
/// As [`reconstruct`], and [`Error::Cancelled`].
pub fn reconstruct_cancellable(
    samples: &SdfSamples,
    params: &Params,
    progress: &mut (dyn FnMut(Stage) + Send),
    cancel: &AtomicBool,
) -> Result<Reconstruction> {
    run(samples, params, None, progress, cancel)
}

/// [`reconstruct_cancellable`] with its initial points started from `seeds` (an adaptive run's,
/// in the caller's coordinates).
pub(crate) fn run(
    samples: &SdfSamples,
    params: &Params,
    seeds: Option<&feasible::TangentPoints>,
    progress: &mut (dyn FnMut(Stage) + Send),
    cancel: &AtomicBool,
) -> Result<Reconstruction> {
    let go_on = || go_on(cancel);
    // Each stage takes the values the one before returned and gives back its own report; the
    // warnings and the timings go to the journal, in order; the verdict reads them all.
    plan::with_plan(samples, params, |plan, mut journal| {
        go_on()?;
        let (cloud, initial) = initial::initial_points(&plan, seeds, &mut journal, progress)?;
        let (cloud, rounds) = rounds::fine_tune(&plan, cloud, &mut journal, progress, &go_on)?;
        go_on()?;
        let (mesh, mut final_solve) = finish::final_solve(&plan, &cloud, &mut journal, progress)?;
        let (mesh, repair) = finish::repair(&plan, &cloud, mesh, &mut final_solve, &mut journal)?;
        let spacing = plan.samples.spacing();
        let (mesh, simplify) = finish::simplify(&plan, mesh, spacing, &mut journal)?;
        let report = Report {
            input: plan.input.clone(),
            field: plan.field.clone(),
            initial,
            rounds,
            final_solve,
            repair,
            simplify,
            ..Report::default()
        };
        finish::verdict(&plan, mesh, cloud, report, journal)
    })
}

/// [`Error::Cancelled`] once `cancel` is set.
pub(crate) fn go_on(cancel: &AtomicBool) -> Result<()> {
    if cancel.load(Ordering::Relaxed) {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}
