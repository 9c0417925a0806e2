//! The 2D pipeline with the same [`Params`] as the 3D one: the input check (`check::samples2`),
//! then `rfta_plane::reconstruct` on the run's pool.
//!
//! ```
//! use rfta::{Params, plane};
//! use rfta::geom::glam::DVec2;
//! use rfta::geom::plane::{Grid2, SdfSamples2};
//!
//! // A disc of radius 0.5 sampled on a 17 x 17 grid over [-1, 1]^2.
//! let grid = Grid2::from_bounds([17, 17], DVec2::splat(-1.0), DVec2::splat(1.0)).expect("valid test input");
//! let values = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let samples = SdfSamples2::grid(grid, values).expect("valid test input");
//! let out = plane::reconstruct(&samples, &Params::default()).expect("valid test input");
//! assert_eq!(out.curve.loops(), 1);
//! assert!(out.curve.vertices.iter().all(|v| (v.length() - 0.5).abs() < 0.01));
//! ```

use rfta_geom::plane::SdfSamples2;
use rfta_plane::PlaneParams;
pub use rfta_plane::{Reconstruction2, Report2};

use crate::{Error, Params, Result};

/// Reconstruct closed polylines from 2D samples ([`rfta_plane::reconstruct`]).
///
/// Uses [`Params::rounds`], [`Params::max_points_per_sphere`], [`Params::transport_step`],
/// [`Params::tolerance`], [`Params::raster_resolution`], [`Params::clamp`], [`Params::spsr_depth`]
/// (the quadtree's depth; default from the sample spacing), [`Params::owner_band`],
/// [`Params::min_island`], [`Params::keep_cavities`], [`Params::simplify`],
/// [`Params::simplify_tolerance`], [`Params::faces`] (as the most edges), [`Params::check`] and
/// [`Params::threads`].
///
/// # Errors
/// [`Error::InvalidParams`] (also when [`Params::genus`] is given), [`Error::NotADistance`],
/// [`Error::NoSurface`] when no circle has a free arc of the side a curve needs,
/// [`Error::TooFewPoints`], [`Error::ThreadPool`].
pub fn reconstruct(samples: &SdfSamples2, params: &Params) -> Result<Reconstruction2> {
    params.validate()?;
    if let Some(g) = params.genus {
        return Err(Error::InvalidParams(format!(
            "genus ({g}) is for surfaces: a 2D reconstruction is closed curves, which have none"
        )));
    }
    crate::pool::on_pool(params.threads, || {
        if params.check {
            crate::check::samples2(samples, params.max_inconsistent)?;
        }
        rfta_plane::reconstruct(samples, &plane_params(params)).map_err(|e| match e {
            rfta_plane::Error::NoSurface { samples, sign } => Error::NoSurface { samples, sign },
            rfta_plane::Error::TooFewPoints { feasible, spheres } => {
                Error::TooFewPoints { feasible, spheres }
            }
            other => Error::InvalidParams(other.to_string()),
        })
    })
}

/// The 2D pipeline's settings from `params`.
fn plane_params(params: &Params) -> PlaneParams {
    PlaneParams {
        // Fewer rounds are a rule of 3D grids only.
        rounds: params.rounds_for(false, None),
        max_points_per_sphere: params.max_points_per_sphere,
        transport_step: params.transport_step,
        tolerance: params.tolerance,
        raster_resolution: params.raster_resolution,
        clamp: params.clamp,
        spsr_depth: params.spsr_depth,
        owner_band: params.owner_band,
        min_island: params.min_island,
        keep_cavities: params.keep_cavities,
        simplify: params.simplify,
        simplify_tolerance: params.simplify_tolerance_set(),
        max_edges: params.faces,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A standalone user of `rfta-plane` gets the pipeline's defaults.
    #[test]
    fn the_plane_defaults_are_the_pipelines() {
        assert_eq!(plane_params(&Params::default()), PlaneParams::default());
    }
}
