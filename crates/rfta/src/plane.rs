//! The 2D pipeline: closed polylines from 2D SDF samples (the paper's Figure 5), with the same
//! [`Params`] and the same steps as the 3D one (normalize, rasterize, initial points, rounds,
//! final solve), on `rfta-plane`'s stages.
//!
//! ```
//! use rfta::{Params, plane};
//! use rfta::geom::glam::DVec2;
//! use rfta::geom::plane::{Grid2, Samples2};
//!
//! // A disc of radius 0.5 sampled on a 17 x 17 grid over [-1, 1]^2.
//! let grid = Grid2::from_bounds([17, 17], DVec2::splat(-1.0), DVec2::splat(1.0)).expect("valid test input");
//! let values = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let samples = Samples2::grid(grid, values).expect("valid test input");
//! let out = plane::reconstruct(&samples, &Params::default()).expect("valid test input");
//! assert_eq!(out.curve.loops(), 1);
//! assert!(out.curve.vertices.iter().all(|v| (v.length() - 0.5).abs() < 0.01));
//! ```

use std::time::Instant;

use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Polylines, Samples2};
use rfta_mesh::PolylineIndex;
use rfta_plane::arcs::{Circle, TuneParams};
use rfta_plane::spsr::{self, Domain, SpsrParams};

use crate::{CELLS_PER_SPACING, Error, Params, Result};

/// The square of the 2D Poisson solves, in unit boxes around the samples' unit box.
const PLANE_BOX: f64 = 1.5;

/// Screening weight of the 2D solves, `alpha h` in `rfta-plane`'s units (chosen on the shared 2D
/// inputs, docs/2d.md).
pub(crate) const PLANE_SCREENING: f64 = 4.0;

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
    /// Small loops removed because no sample supports them (see [`Params::min_island`]).
    pub islands_removed: usize,
    /// Holes around outside samples opened through a wall that no inside sample shows (unless
    /// [`Params::keep_cavities`]; grids only: [`rfta_plane::holes`]).
    pub holes_opened: usize,
    /// Holes around outside samples in the output: walled in by inside samples (a void the
    /// samples show), or kept by [`Params::keep_cavities`] or for want of a channel that enters no
    /// circle.
    pub holes: usize,
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

/// Reconstruct closed polylines from 2D samples.
///
/// Uses [`Params::rounds`], [`Params::max_points_per_sphere`], [`Params::transport_step`],
/// [`Params::tolerance`], [`Params::raster_resolution`], [`Params::clamp`], [`Params::spsr_depth`]
/// (the quadtree's depth; default from the sample spacing), [`Params::owner_band`] and
/// [`Params::threads`]; the 2D screening is `PLANE_SCREENING` (4.0).
///
/// # Errors
/// [`Error::InvalidParams`] (also when [`Params::genus`] is given), [`Error::NoSurface`] when no circle has a free arc of the side a
/// curve needs, [`Error::TooFewPoints`], [`Error::ThreadPool`].
pub fn reconstruct(samples: &Samples2, params: &Params) -> Result<Reconstruction2> {
    params.validate()?;
    if let Some(g) = params.genus {
        return Err(Error::InvalidParams(format!(
            "genus ({g}) is for surfaces: a 2D reconstruction is closed curves, which have none"
        )));
    }
    crate::pool::on_pool(params.threads, || run(samples, params))
}

fn run(samples: &Samples2, params: &Params) -> Result<Reconstruction2> {
    let start = Instant::now();
    if params.check {
        check_separation(samples, params.max_inconsistent)?;
        check_sign_convention(samples)?;
    }
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
    let mut cloud = rfta_plane::initial_points(
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
    let solve = |cloud: &rfta_plane::arcs::Owners, last: bool| -> Result<spsr::Solution> {
        let (points, normals) = cloud.oriented(&circles, &values);
        spsr::solve(
            &points,
            &normals,
            domain,
            if last { &final_params } else { &spsr_params },
        )
        .map_err(|e| Error::InvalidParams(format!("2D screened Poisson: {e}")))
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
            Err(_) => rfta_plane::holes::Opened::default(),
        }
    });
    for v in &mut curve.vertices {
        *v = *v * scale + lo;
    }
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
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(Reconstruction2 {
        curve,
        points,
        report,
    })
}

/// The fine-tuning moves' settings.
fn tune_params(params: &Params) -> TuneParams {
    TuneParams {
        max_points: params.max_points_per_sphere,
        step: params.transport_step,
        tolerance: params.tolerance,
        severe: 0.8,
    }
}

/// The circles that own points: larger than the tolerance, within [`Params::owner_band`]
/// spacings on a grid, not clamped.
fn owners(
    samples: &Samples2,
    params: &Params,
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
/// square): [`Params::spsr_depth`] or the depth with `CELLS_PER_SPACING` cells per spacing.
fn solver_settings(params: &Params, domain: &Domain, spacing: f64) -> (SpsrParams, SpsrParams) {
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
/// inside sample shows, or, with [`Params::keep_cavities`], counted.
fn holes(
    params: &Params,
    curve: &mut Polylines,
    grid: &rfta_geom::plane::Grid2,
    values: &[f64],
    circles: &[Circle],
    spacing: f64,
) -> rfta_plane::holes::Opened {
    let margin = crate::consistency::ENTER_MARGIN * spacing;
    if params.keep_cavities {
        rfta_plane::holes::Opened {
            opened: 0,
            kept: rfta_plane::holes::enclosing(curve, grid, values),
        }
    } else {
        rfta_plane::holes::open_holes(curve, grid, values, circles, margin)
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
    fn new(samples: &Samples2, params: &Params) -> Self {
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
fn solve_domain(cloud: &rfta_plane::arcs::Owners, circles: &[Circle], extent: DVec2) -> Domain {
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

/// Refuses values that are not a signed distance, by the 3D check's rule
/// ([`crate::check::SEVERE_RATIO`]): the curve crosses the segment between two samples of
/// opposite signs, so their circles can at most touch (`|s_i| + |s_j| <= |p_i - p_j|`); more than
/// `max_fraction` of the samples overlapping their nearest sample of the other sign by a quarter
/// of the distance is an occupancy image or a field in other units than the positions, and
/// reconstructing from it gives a wrong curve or none. (The 3D check also detects clamps and
/// measures noise; in 2D this is the whole check.)
/// Refuses an inside-positive field as the 3D check does ([`crate::check::looks_flipped`]): the
/// samples around the set (a grid's outer rows and columns; otherwise the twentieth farthest from
/// the centre of their box) nearly all negative, around positive ones.
fn check_sign_convention(samples: &Samples2) -> Result<()> {
    let (p, v) = (samples.positions(), samples.values());
    let on_grid = samples.as_grid().map(|g| {
        let [nx, ny] = g.dims();
        // The first and last columns whole, the first and last rows between them.
        let columns = [0, nx - 1]
            .into_iter()
            .flat_map(move |x| (0..ny).map(move |y| (x, y)));
        let rows = (1..nx.saturating_sub(1)).flat_map(move |x| [(x, 0), (x, ny - 1)]);
        let mut rim: Vec<usize> = columns.chain(rows).map(|(x, y)| g.index(x, y)).collect();
        rim.sort_unstable();
        rim.dedup();
        rim
    });
    let (lo, hi) = samples.bounds();
    let c = (lo + hi) / 2.0;
    let rim = crate::check::rim_of(v, on_grid, |i| p[i].distance_squared(c));
    let positive = v.iter().filter(|&&x| x > 0.0).count();
    if crate::check::looks_flipped(rim, positive) {
        return Err(crate::check::flipped(rim));
    }
    Ok(())
}

fn check_separation(samples: &Samples2, max_fraction: f64) -> Result<()> {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    use rayon::prelude::*;
    let (p, v) = (samples.positions(), samples.values());
    let mut severe = 0;
    for negative in [true, false] {
        let other: Vec<usize> = (0..v.len())
            .filter(|&j| (v[j] < 0.0) != negative && v[j] != 0.0)
            .collect();
        if other.is_empty() {
            continue;
        }
        let coords: Vec<[f64; 2]> = other.iter().map(|&j| p[j].to_array()).collect();
        let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(&coords) else {
            continue;
        };
        severe += (0..v.len())
            .into_par_iter()
            .filter(|&i| (v[i] < 0.0) == negative && v[i] != 0.0)
            .filter(|&i| {
                let nn = tree
                    .query(&p[i].to_array())
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                let j = other[nn.item as usize];
                let d = p[i].distance(p[j]);
                v[i].abs() + v[j].abs() > crate::check::SEVERE_RATIO * d
            })
            .count();
    }
    if severe as f64 > max_fraction * v.len() as f64 {
        return Err(Error::NotADistance(format!(
            "{severe} of {} samples overlap their nearest sample of the other sign by more than a quarter of the distance between them, which a signed distance never does (an occupancy image, or values in other units than the positions?); check the PNG's value range or the grid's bounds, or turn the check off (--no-check)",
            v.len()
        )));
    }
    Ok(())
}

/// Samples whose circles a small loop must touch, nearest, for the loop to stay without a sample
/// of its inside sign in it (the 3D pipeline asks for 3; a feature between the grid points of a
/// 2D grid touches fewer circles).
const GAP_WITNESSES_2D: usize = 2;

/// Removes the loops smaller than `min_island` spacings (bounding-box diagonal) that no sample
/// supports: none of their inside's sign lies in them (an outer loop's inside is negative, a
/// hole's positive), and fewer than [`GAP_WITNESSES_2D`] samples touch them (within the
/// consistency margins) while the rest of the curve is farther than the gap margin. Screened
/// Poisson leaves such loops next to isolated points, a fraction of a spacing across; a thin part
/// between grid points touches the circles around it and stays. Returns the curve, without the
/// removed loops' vertices, and the number of loops removed.
fn drop_islands(
    curve: Polylines,
    circles: &[Circle],
    values: &[f64],
    spacing: f64,
    min_island: f64,
) -> (Polylines, usize) {
    use crate::consistency::{ENTER_MARGIN, GAP_MARGIN};
    if min_island <= 0.0 || curve.is_empty() {
        return (curve, 0);
    }
    let (loops, label) = loops_of(&curve);
    let whole = PolylineIndex::new(&curve);
    let mut keep = vec![true; loops.len()];
    for (k, edges) in loops.values().enumerate() {
        let one = Polylines {
            vertices: curve.vertices.clone(),
            edges: edges.clone(),
        };
        if diagonal(&curve.vertices, edges) >= min_island * spacing {
            continue;
        }
        let area: f64 = edges
            .iter()
            .map(|&e| {
                let s = one.segment(e);
                s.a.perp_dot(s.b)
            })
            .sum();
        let inside_negative = area > 0.0;
        let index = PolylineIndex::new(&one);
        // The rest of the curve, built and indexed once per small loop, if a sample needs it.
        let others = std::cell::OnceCell::new();
        let rest_index = std::cell::OnceCell::new();
        let mut witnesses = 0;
        let mut supported = false;
        for (c, &v) in circles.iter().zip(values) {
            if index.winding(c.center) != 0 && (v < 0.0) == inside_negative {
                supported = true;
                break;
            }
            let d = index.closest(c.center).distance;
            if d < c.radius - ENTER_MARGIN * spacing || d > c.radius + GAP_MARGIN * spacing {
                continue;
            }
            // The rest of the curve: the whole curve's nearest edge, unless it is this loop's.
            let nearest = whole.closest(c.center);
            let rest = if label[nearest.edge] == k {
                rest_index
                    .get_or_init(|| {
                        PolylineIndex::new(others.get_or_init(|| {
                            Polylines {
                                vertices: curve.vertices.clone(),
                                edges: (0..curve.edges.len())
                                    .filter(|&e| label[e] != k)
                                    .map(|e| curve.edges[e])
                                    .collect(),
                            }
                        }))
                    })
                    .closest(c.center)
                    .distance
            } else {
                nearest.distance
            };
            if rest > c.radius + GAP_MARGIN * spacing {
                witnesses += 1;
                if witnesses >= GAP_WITNESSES_2D {
                    supported = true;
                    break;
                }
            }
        }
        keep[k] = supported;
    }
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed == 0 || removed == loops.len() {
        return (curve, 0);
    }
    let edges = loops
        .values()
        .zip(&keep)
        .filter(|&(_, &k)| k)
        .flat_map(|(e, _)| e.iter().copied())
        .collect();
    let mut kept = Polylines {
        vertices: curve.vertices,
        edges,
    };
    kept.remove_unreferenced_vertices();
    (kept, removed)
}

/// The loops of `curve` (edges grouped by connected vertices, in the order of their roots) and
/// each edge's loop.
fn loops_of(curve: &Polylines) -> (std::collections::BTreeMap<usize, Vec<[u32; 2]>>, Vec<usize>) {
    let mut sets = rfta_mesh::UnionFind::new(curve.vertices.len());
    for &[a, b] in &curve.edges {
        sets.union(a as usize, b as usize);
    }
    let mut loops: std::collections::BTreeMap<usize, Vec<[u32; 2]>> = Default::default();
    for &e in &curve.edges {
        loops.entry(sets.find(e[0] as usize)).or_default().push(e);
    }
    let number: std::collections::HashMap<usize, usize> = loops
        .keys()
        .enumerate()
        .map(|(k, &root)| (root, k))
        .collect();
    let label = curve
        .edges
        .iter()
        .map(|e| number[&sets.find(e[0] as usize)])
        .collect();
    (loops, label)
}

/// The diagonal of the bounding box of `edges`' vertices.
fn diagonal(vertices: &[DVec2], edges: &[[u32; 2]]) -> f64 {
    let (lo, hi) = edges.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(vertices[v as usize]), hi.max(vertices[v as usize])),
    );
    (hi - lo).length()
}

/// Mean distance from each circle's centre to the nearest other centre (the spacing of scattered
/// samples).
fn mean_nearest(circles: &[Circle]) -> f64 {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    let coords: Vec<[f64; 2]> = circles.iter().map(|c| c.center.to_array()).collect();
    let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(&coords) else {
        return 1.0 / (circles.len() as f64).sqrt();
    };
    let total: f64 = coords
        .iter()
        .map(|p| {
            let near = tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f64>>(
                    std::num::NonZero::<usize>::MIN.saturating_add(1),
                )
                .execute();
            near.get(1).map_or(0.0, |n| n.distance.sqrt())
        })
        .sum();
    (total / circles.len() as f64).max(1e-9)
}
