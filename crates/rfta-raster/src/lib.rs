//! Empty-space sampling for Reach for the Arcs: rasterize the sample spheres of one sign on a
//! regular grid and emit one point in every empty cell next to an occupied one.
//!
//! Sellán et al. (2024, §4.1) start each sphere's tangency point from the nearest point of the
//! empty space `W` outside all spheres of the same sign. This crate samples `W` as the reference
//! implementation's CPU rasterizer does: spheres (in coordinates normalised to the unit box) are
//! slightly shrunk (`|x - c|^2 <= 0.95 r^2`), each cell is tested at one jittered sample point,
//! and only empty cells with an occupied neighbour (a one-cell narrow band, 26-neighbourhood)
//! inside the spheres' bounding box are kept, in grid order.
//!
//! # Exact and identical on CPU and GPU
//! Sample points and sphere centres live on a lattice of [`SUBCELLS`] steps per cell, and the
//! occupancy test compares integer squared distances with an integer threshold computed once on
//! the host. The CPU path ([`rasterize`] with [`Backend::Cpu`], rayon) and the GPU path
//! ([`Backend::Gpu`], wgpu compute, feature `gpu`) therefore produce the same cells bit for bit;
//! the narrow band and the emitted points are computed from the occupancy by the same code.
//! The jitter of a cell is a hash of the seed and the cell index, so results do not depend on the
//! thread count or the device.
//!
//! Memory: one bit per cell (`res = 512` takes 16 MiB), plus the emitted points.
//!
//! # Example
//! ```
//! use rfta_geom::glam::DVec3;
//! use rfta_raster::{rasterize, Backend, RasterParams};
//!
//! // One sphere of radius 0.25 in the middle of the unit box.
//! let params = RasterParams { res: 32, seed: 1 };
//! let out = rasterize(&[DVec3::splat(0.5)], &[0.25], &params, Backend::Cpu)?;
//! // Every emitted point is outside the shrunk sphere (up to the lattice step 1/(16 res) by which
//! // centres are rounded) and within two cell diagonals of it.
//! let h = 1.0 / 32.0;
//! for p in &out.points {
//!     let d = (*p - DVec3::splat(0.5)).length();
//!     assert!(d > 0.95f64.sqrt() * 0.25 - h / 16.0 && d < 0.25 + 2.0 * 3f64.sqrt() * h);
//! }
//! assert!(out.points.len() > 500);
//! # Ok::<(), rfta_raster::Error>(())
//! ```

mod band;
mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
mod lattice;
pub mod shaders;

pub use band::BitGrid;
#[cfg(feature = "gpu")]
pub use gpu::GpuRasterizer;
pub use lattice::{SUBCELLS, cell_sample};

use rfta_geom::glam::DVec3;

/// Rasterization settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RasterParams {
    /// Cells per axis over the unit box (at most [`MAX_RES`]).
    pub res: usize,
    /// Seed of the per-cell jitter.
    pub seed: u64,
}

/// The largest supported resolution (the reference's cap; the integer lattice fits `u32` up to it).
pub const MAX_RES: usize = 1024;

/// The reference's default resolution for `n` samples in total: `64 * ceil(n^(1/3) / 16)`, at most 1024.
pub fn default_resolution(n_samples: usize) -> usize {
    let r = 64
        * (rfta_geom::math::cbrt(n_samples as f64) / 16.0)
            .ceil()
            .max(1.0) as usize;
    r.min(MAX_RES)
}

/// Where to rasterize.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// rayon on the CPU.
    Cpu,
    /// wgpu compute (needs feature `gpu`); falls back to the CPU, with a logged message, when no
    /// adapter exists or the grid does not fit the device's buffer limits.
    Gpu,
}

/// The result: points in empty space next to the spheres.
#[derive(Debug, Clone, PartialEq)]
pub struct EmptySpace {
    /// The resolution used.
    pub res: usize,
    /// One jittered point per kept cell, in grid order (x slowest, z fastest).
    pub points: Vec<DVec3>,
    /// Number of occupied cells.
    pub n_occupied: usize,
    /// Which backend actually ran.
    pub backend: Backend,
}

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The resolution is zero or above [`MAX_RES`].
    #[error("raster resolution {0} is out of range 1..={MAX_RES}")]
    Resolution(usize),
    /// Centres and radii differ in length.
    #[error("{centers} sphere centres but {radii} radii")]
    LengthMismatch {
        /// Number of centres.
        centers: usize,
        /// Number of radii.
        radii: usize,
    },
    /// A centre or radius is not finite, or a radius is negative.
    #[error("sphere {0} has a non-finite centre or an invalid radius")]
    InvalidSphere(usize),
    /// The GPU failed after it was found (device lost, mapping failed).
    #[error("GPU rasterization failed: {0}")]
    Gpu(String),
}

/// Rasterizes spheres (`centers[i]`, `radii[i]`, in unit-box coordinates) and samples the empty
/// narrow band around them.
///
/// # Errors
/// [`Error::Resolution`], [`Error::LengthMismatch`], [`Error::InvalidSphere`]; [`Error::Gpu`] if the
/// GPU path fails after a device was found.
pub fn rasterize(
    centers: &[DVec3],
    radii: &[f64],
    params: &RasterParams,
    backend: Backend,
) -> Result<EmptySpace, Error> {
    let spheres = lattice::prepare(centers, radii, params)?;
    let (occ, used) = match backend {
        Backend::Cpu => (cpu::occupancy(&spheres, params), Backend::Cpu),
        Backend::Gpu => gpu_or_cpu(&spheres, params)?,
    };
    let bbox = lattice::cell_bbox(centers, radii, params.res);
    let points = occ.narrow_band_points(bbox, params);
    Ok(EmptySpace {
        res: params.res,
        points,
        n_occupied: occ.count_ones(),
        backend: used,
    })
}

/// Occupancy only (no band): which cells hold a sample point inside some shrunk sphere.
///
/// # Errors
/// As [`rasterize`].
pub fn occupancy(
    centers: &[DVec3],
    radii: &[f64],
    params: &RasterParams,
    backend: Backend,
) -> Result<BitGrid, Error> {
    let spheres = lattice::prepare(centers, radii, params)?;
    Ok(match backend {
        Backend::Cpu => cpu::occupancy(&spheres, params),
        Backend::Gpu => gpu_or_cpu(&spheres, params)?.0,
    })
}

#[cfg(feature = "gpu")]
fn gpu_or_cpu(
    spheres: &[lattice::QSphere],
    params: &RasterParams,
) -> Result<(BitGrid, Backend), Error> {
    match GpuRasterizer::shared() {
        Some(gpu) => match gpu.occupancy(spheres, params)? {
            Some(bits) => Ok((bits, Backend::Gpu)),
            None => {
                log::info!(
                    "grid of {}^3 cells exceeds the GPU's buffer limits; rasterizing on the CPU",
                    params.res
                );
                Ok((cpu::occupancy(spheres, params), Backend::Cpu))
            }
        },
        None => {
            log::info!("no GPU adapter found; rasterizing on the CPU");
            Ok((cpu::occupancy(spheres, params), Backend::Cpu))
        }
    }
}

#[cfg(not(feature = "gpu"))]
fn gpu_or_cpu(
    spheres: &[lattice::QSphere],
    params: &RasterParams,
) -> Result<(BitGrid, Backend), Error> {
    log::info!("rfta-raster was built without the `gpu` feature; rasterizing on the CPU");
    Ok((cpu::occupancy(spheres, params), Backend::Cpu))
}
