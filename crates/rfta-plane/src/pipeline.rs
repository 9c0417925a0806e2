//! The 2D pipeline (the paper's Figure 5): closed polylines from 2D SDF samples, composed of this
//! crate's stages with the same steps as the 3D pipeline (normalize, rasterize, initial points,
//! rounds, final solve, repair).
//!
//! ```
//! use rfta_geom::glam::DVec2;
//! use rfta_geom::plane::{Grid2, SdfSamples2};
//! use rfta_plane::{PlaneParams, reconstruct};
//!
//! // A disc of radius 0.5 sampled on a 17 x 17 grid over [-1, 1]^2.
//! let grid = Grid2::from_bounds([17, 17], DVec2::splat(-1.0), DVec2::splat(1.0)).expect("valid test input");
//! let values = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let samples = SdfSamples2::grid(grid, values).expect("valid test input");
//! let out = reconstruct(&samples, &PlaneParams::default()).expect("valid test input");
//! assert_eq!(out.curve.loops(), 1);
//! assert!(out.curve.vertices.iter().all(|v| (v.length() - 0.5).abs() < 0.01));
//! ```

use std::time::Instant;

use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Polylines, SdfSamples2};
use rfta_mesh::PolylineIndex;

use crate::arcs::{Circle, TuneParams};
use crate::islands::{drop_islands, mean_nearest};
use crate::params::ENTER_MARGIN;
use crate::spsr::{self, Domain, SpsrParams};
use crate::{Error, PlaneParams, Result};

/// Cells of the finest solve per sample spacing.
const CELLS_PER_SPACING: f64 = 4.0;

/// The square of the 2D Poisson solves, in unit boxes around the samples' unit box.
const PLANE_BOX: f64 = 1.5;

/// Screening weight of the 2D solves, `alpha h` in `rfta-plane`'s units (chosen on the shared 2D
/// inputs, docs/2d.md).
const PLANE_SCREENING: f64 = 4.0;

/// V-cycles after the full-multigrid pass in the rounds' solves (the final solve runs
/// `SpsrParams::default().cycles`). A round's curve only guides the next moves; measured on the
/// shared 2D inputs (docs/2d.md): 0 instead of 2 costs 4% of the mean Chamfer at 17^2 and 33^2,
/// nothing at 65^2, and a third of the time.
const ROUND_CYCLES: usize = 0;

/// What a 2D reconstruction did (its serde form: these field names, as the command line's
/// `--report` JSON writes them).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Report2 {
    /// Samples given.
    pub samples: usize,
    /// Circles that own tangency points.
    pub circles_with_points: usize,
    /// Tangency points in the final solve.
    pub points: usize,
    /// Depth of the Poisson solves.
    pub depth: u32,
    /// Fine-tuning rounds run.
    pub rounds: usize,
    /// Loops in the output.
    pub loops: usize,
    /// Small loops removed because no sample supports them (see [`PlaneParams::min_island`]).
    pub islands_removed: usize,
    /// Holes around outside samples opened through a wall that no inside sample shows (unless
    /// [`PlaneParams::keep_cavities`]; grids only: [`crate::holes`]).
    pub holes_opened: usize,
    /// Holes around outside samples in the output: walled in by inside samples (a void the samples
    /// show), or kept by [`PlaneParams::keep_cavities`] or for want of a channel that enters no
    /// circle.
    pub holes: usize,
    /// Edges of the curve before simplification ([`PlaneParams::simplify`]).
    pub edges_unsimplified: usize,
    /// The largest distance measured between the simplified and the unsimplified curve, in
    /// sample spacings (0 without simplification).
    pub simplify_deviation: f64,
    /// Seconds, whole reconstruction.
    pub seconds: f64,
}

/// A 2D reconstruction.
#[derive(Debug, Clone)]
pub struct Reconstruction2 {
    /// Closed polylines, inside on the left, in the samples' coordinates.
    pub curve: Polylines,
    /// The tangency points and their outward normals, in the samples' coordinates.
    pub points: Vec<(DVec2, DVec2)>,
    /// What was done.
    pub report: Report2,
}

/// Reconstruct closed polylines from 2D samples, on the caller's rayon pool: the samples as
/// circles in the unit square, initial points on their free arcs, `params.rounds` fine-tuning
/// rounds against the curve of a screened Poisson solve, the final solve, the small loops no
/// sample supports removed, and (unless [`PlaneParams::keep_cavities`]) the holes the samples
/// leave open opened.
///
/// # Errors
/// [`Error::NoSurface`] when no circle has a free arc of the side a curve needs,
/// [`Error::TooFewPoints`], [`Error::Solve`].
pub fn reconstruct(samples: &SdfSamples2, params: &PlaneParams) -> Result<Reconstruction2> {
    let start = Instant::now();
    let UnitSquare {
        lo,
        scale,
        values,
        clamp,
        circles,
        spacing,
        extent,
    } = UnitSquare::new(samples, params);
    let owners = owners(samples, params, &circles, &values, clamp, spacing);
    let n = samples.len() as f64;
    let res = params
        .raster_resolution
        .unwrap_or(64 * (n.sqrt() / 16.0).ceil() as usize);
    let mut cloud = crate::initial_points(
        &circles,
        &values,
        &owners,
        params.tolerance,
        res,
        DVec2::ZERO,
        extent.max_element(),
    );
    if cloud.points() < 2 {
        return Err(no_points(samples.len(), &values, cloud.points()));
    }
    let domain = solve_domain(&cloud, &circles, extent);
    let (spsr_params, final_params) = solver_settings(params, &domain, spacing);
    let depth = spsr_params.depth;
    let tune = tune_params(params);
    let solve = |cloud: &crate::arcs::Owners, last: bool| -> Result<spsr::Solution> {
        let (points, normals) = cloud.oriented(&circles, &values);
        spsr::solve(
            &points,
            &normals,
            domain,
            if last { &final_params } else { &spsr_params },
        )
        .map_err(|e| Error::Solve(format!("2D screened Poisson: {e}")))
    };
    let mut rounds = 0;
    for _ in 0..params.rounds {
        if cloud.points() < 2 {
            break;
        }
        let curve = solve(&cloud, false)?.curve();
        if curve.is_empty() {
            break;
        }
        cloud.fine_tune(&circles, &values, &PolylineIndex::new(&curve), &tune);
        rounds += 1;
    }
    if cloud.points() < 2 {
        return Err(Error::TooFewPoints {
            feasible: cloud.points(),
            spheres: samples.len(),
        });
    }
    let curve = solve(&cloud, true)?.curve();
    let (mut curve, islands) = drop_islands(curve, &circles, &values, spacing, params.min_island);
    let holes = samples.as_grid().map(|g| {
        // The grid in the unit square, its positions the circles' centres.
        let unit =
            rfta_geom::plane::Grid2::new(g.dims(), (g.origin() - lo) / scale, g.spacing() / scale);
        match unit {
            Ok(grid) => holes(params, &mut curve, &grid, &values, &circles, spacing),
            Err(_) => crate::holes::Opened::default(),
        }
    });
    let simplify = crate::simplify::simplify;
    let (mut curve, simplified) = simplify(curve, &circles, &values, spacing, extent, params);
    curve.vertices.iter_mut().for_each(|v| *v = *v * scale + lo);
    let (points, normals) = cloud.oriented(&circles, &values);
    let points = (points.into_iter().zip(normals))
        .map(|(p, n)| (p * scale + lo, n))
        .collect();
    let report = Report2 {
        samples: samples.len(),
        circles_with_points: owners.len(),
        points: cloud.points(),
        depth,
        rounds,
        loops: curve.loops(),
        islands_removed: islands,
        holes_opened: holes.as_ref().map_or(0, |h| h.opened),
        holes: holes.as_ref().map_or(0, |h| h.kept),
        edges_unsimplified: simplified.edges_before,
        simplify_deviation: simplified.deviation,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(Reconstruction2 {
        curve,
        points,
        report,
    })
}

/// The fine-tuning moves' settings.
fn tune_params(params: &PlaneParams) -> TuneParams {
    TuneParams {
        max_points: params.max_points_per_sphere,
        step: params.transport_step,
        tolerance: params.tolerance,
        severe: 0.8,
    }
}

/// The circles that own points: larger than the tolerance, within [`PlaneParams::owner_band`]
/// spacings on a grid, not clamped.
fn owners(
    samples: &SdfSamples2,
    params: &PlaneParams,
    circles: &[Circle],
    values: &[f64],
    clamp: Option<f64>,
    spacing: f64,
) -> Vec<usize> {
    let band = match (samples.as_grid(), params.owner_band) {
        (Some(_), Some(b)) => b * spacing,
        _ => f64::INFINITY,
    };
    (0..circles.len())
        .filter(|&i| {
            let r = circles[i].radius;
            r > params.tolerance && r < band && clamp.is_none_or(|c| values[i].abs() < c)
        })
        .collect()
}

/// The rounds' and the final solve's settings on `domain`, for samples `spacing` apart (unit
/// square): [`PlaneParams::spsr_depth`] or the depth with `CELLS_PER_SPACING` cells per spacing.
fn solver_settings(
    params: &PlaneParams,
    domain: &Domain,
    spacing: f64,
) -> (SpsrParams, SpsrParams) {
    let depth = params.spsr_depth.unwrap_or_else(|| {
        (rfta_geom::math::log2(domain.side * CELLS_PER_SPACING / spacing).ceil() as u32)
            .clamp(4, 11)
    });
    let rounds = SpsrParams {
        depth,
        screening: PLANE_SCREENING,
        cycles: ROUND_CYCLES,
        ..SpsrParams::default()
    };
    let last = SpsrParams {
        cycles: SpsrParams::default().cycles,
        ..rounds.clone()
    };
    (rounds, last)
}

/// The holes of `curve` around outside samples of `grid` (unit square): opened through a wall no
/// inside sample shows, or, with [`PlaneParams::keep_cavities`], counted.
fn holes(
    params: &PlaneParams,
    curve: &mut Polylines,
    grid: &rfta_geom::plane::Grid2,
    values: &[f64],
    circles: &[Circle],
    spacing: f64,
) -> crate::holes::Opened {
    let margin = ENTER_MARGIN * spacing;
    if params.keep_cavities {
        crate::holes::Opened {
            opened: 0,
            kept: crate::holes::enclosing(curve, grid, values),
        }
    } else {
        crate::holes::open_holes(curve, grid, values, circles, margin)
    }
}

/// The samples as circles in the unit square, normalized as the reference does: the longer side
/// of the samples' box becomes 1.
struct UnitSquare {
    /// The box's lower corner and its longer side: `p = unit * scale + lo`.
    lo: DVec2,
    scale: f64,
    /// The values, clamp and circles in the unit square.
    values: Vec<f64>,
    clamp: Option<f64>,
    circles: Vec<Circle>,
    /// The sample spacing there: the grid's smaller axis, or for scattered samples the mean
    /// distance to the nearest other sample.
    spacing: f64,
    /// The box's size there.
    extent: DVec2,
}

impl UnitSquare {
    fn new(samples: &SdfSamples2, params: &PlaneParams) -> Self {
        let (lo, hi) = samples.bounds();
        let scale = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let unit = |p: DVec2| (p - lo) / scale;
        let values: Vec<f64> = samples.values().iter().map(|s| s / scale).collect();
        let clamp = params.clamp.map(|c| c / scale);
        let circles: Vec<Circle> = samples
            .positions()
            .iter()
            .zip(&values)
            .map(|(&p, &s)| Circle {
                center: unit(p),
                radius: clamp.map_or(s.abs(), |c| s.abs().min(c)),
            })
            .collect();
        let spacing = match samples.as_grid() {
            Some(g) => g.spacing().min_element() / scale,
            None => mean_nearest(&circles),
        };
        let extent = (hi - lo) / scale;
        Self {
            lo,
            scale,
            values,
            clamp,
            circles,
            spacing,
            extent,
        }
    }
}

/// The error for samples that give fewer than 2 tangency points: no surface when they are all of
/// one sign, too few points otherwise.
fn no_points(samples: usize, values: &[f64], feasible: usize) -> Error {
    let sign = if values.iter().all(|&v| v >= 0.0) {
        Some("positive (outside)")
    } else if values.iter().all(|&v| v < 0.0) {
        Some("negative (inside)")
    } else {
        None
    };
    match sign {
        Some(sign) => Error::NoSurface { samples, sign },
        None => Error::TooFewPoints {
            feasible,
            spheres: samples,
        },
    }
}

/// The solves' square: the unit box's centre, [`PLANE_BOX`] unit boxes wide, grown to hold every
/// owner's circle (so no point can leave it).
fn solve_domain(cloud: &crate::arcs::Owners, circles: &[Circle], extent: DVec2) -> Domain {
    let centre = extent / 2.0;
    let reach = cloud
        .circle
        .iter()
        .map(|&i| {
            ((circles[i].center - centre).abs() + DVec2::splat(circles[i].radius)).max_element()
        })
        .fold(PLANE_BOX / 2.0, f64::max);
    Domain {
        min: centre - DVec2::splat(reach * 1.02),
        side: 2.04 * reach,
    }
}
