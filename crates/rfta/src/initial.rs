//! Steps 2 and 3: empty space next to the spheres of each sign, and one feasible tangency point
//! per sphere from it. On grids the empty space is the closest surface point each sample's
//! gradient points to, where it lies outside the sign's other spheres
//! ([`crate::InitialPoints::Gradient`]); otherwise the rasterization of the paper.

use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::SphereSet;
use rfta_geom::glam::DVec3;
use rfta_sphere_tree::SphereTree;

use crate::normalize::UnitBox;
use crate::params::Seeds;
use crate::plan::Plan;
use crate::report::{InitialReport, Journal, counted};
use crate::{Error, Reading, Result, Stage};

/// With [`crate::InitialPoints::Gradient`], a sign set is rasterized all the same when none or
/// fewer than one in this many of its drawn spheres gives an empty-space point.
const GRADIENT_FLOOR: usize = 100;

/// The initial tangency points, one sign set at a time: rasterize the set's spheres, take the
/// nearest empty-space sample to each centre, make it feasible against a batch of the same set.
/// `seeds` (an earlier run's points, in the caller's coordinates) start the spheres they still
/// fit.
pub(crate) fn initial_points(
    plan: &Plan<'_>,
    seeds: Option<&TangentPoints>,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<(TangentPoints, InitialReport)> {
    match plan.field.read_as {
        Reading::LevelSet => Ok(on_zero_set(plan, seeds, progress)),
        Reading::Distances => {
            let seeds = seeds.map(|s| feasible_seeds(plan, &plan.scaled(s)));
            // Only spheres near the surface shape the empty space an owner starts from
            // (RASTER_REACH).
            drawing(plan, seeds, plan.raster_radius, journal, progress)
        }
        Reading::Bounds => {
            let (cloud, mut report) = drawing(plan, None, plan.raster_radius, journal, progress)?;
            let (cloud, moved) = crate::field::onto_zero_set(cloud, &plan.samples, &plan.unit);
            report.moved_onto_zero_set = moved;
            report.feasible_initial = cloud.len();
            Ok((cloud, report))
        }
    }
}

/// The initial points of samples read as a level set: on its zero set ([`crate::field`]), or
/// `seeds` (points on it an adaptive run put there, in the caller's coordinates).
fn on_zero_set(
    plan: &Plan<'_>,
    seeds: Option<&TangentPoints>,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> (TangentPoints, InitialReport) {
    progress(Stage::Initial);
    let mut cloud = match seeds {
        Some(seeds) => plan.scaled(seeds),
        None => crate::field::zero_set_points(&plan.samples, None),
    };
    for p in &mut cloud.points {
        *p = plan.unit.to_unit(*p);
    }
    let values = &plan.unit.values;
    let negative = values.iter().filter(|&&v| v < 0.0).count();
    let report = InitialReport {
        negative,
        non_negative: values.len() - negative,
        feasible_initial: cloud.len(),
        ..InitialReport::default()
    };
    (cloud, report)
}

/// The seeds (at the working scale) that can start this run, in the unit box: those whose
/// owner is a sample here and that no other sphere holds by more than the feasibility tolerance
/// (an earlier run's points, before the samples added since).
fn feasible_seeds(plan: &Plan<'_>, seeds: &TangentPoints) -> TangentPoints {
    use rayon::prelude::*;
    let unit = &plan.unit;
    let all = SphereTree::new(unit);
    let kept: Vec<usize> = (0..seeds.len())
        .into_par_iter()
        .filter(|&k| {
            let owner = seeds.owners[k];
            (owner as usize) < unit.len()
                && !all.inside_any(
                    unit.to_unit(seeds.points[k]),
                    -plan.params.tolerance,
                    Some(owner),
                )
        })
        .collect();
    TangentPoints {
        points: kept
            .iter()
            .map(|&k| unit.to_unit(seeds.points[k]))
            .collect(),
        normals: kept.iter().map(|&k| seeds.normals[k]).collect(),
        owners: kept.iter().map(|&k| seeds.owners[k]).collect(),
    }
}

/// [`initial_points`] rasterizing the spheres smaller than `reach`.
fn drawing(
    plan: &Plan<'_>,
    seeds: Option<TangentPoints>,
    reach: f64,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<(TangentPoints, InitialReport)> {
    progress(Stage::Initial);
    let t = Instant::now();
    let (unit, params) = (&plan.unit, &plan.params);
    let n = unit.len();
    let mut report = InitialReport {
        raster_resolution: params.raster_resolution_for(n),
        ..InitialReport::default()
    };
    let values = &unit.values;
    let neg: Vec<u32> = (0..n as u32)
        .filter(|&i| values[i as usize] < 0.0)
        .collect();
    let pos: Vec<u32> = (0..n as u32)
        .filter(|&i| values[i as usize] >= 0.0)
        .collect();
    report.negative = neg.len();
    report.non_negative = pos.len();
    // Spheres with a seed keep it; the others get points of their own (no copy of the sets
    // without seeds: on a 513^3 grid they are 135 million indices).
    let seeded: Option<Vec<bool>> = seeds.as_ref().map(|s| owned(&s.owners, n));
    report.seeded = seeds.as_ref().map_or(0, TangentPoints::len);
    let mut parts: Vec<TangentPoints> = seeds.into_iter().collect();
    let mut raster_time = std::time::Duration::ZERO;
    let drawn = |i: usize| unit.radius(i) < reach;
    for (negative, set) in [(false, &pos), (true, &neg)] {
        let unseeded: std::borrow::Cow<[u32]> = match &seeded {
            None => set.as_slice().into(),
            Some(seeded) => set
                .iter()
                .copied()
                .filter(|&i| !seeded[i as usize])
                .collect::<Vec<u32>>()
                .into(),
        };
        if unseeded.is_empty() {
            continue;
        }
        let draw: Vec<usize> = set
            .iter()
            .map(|&i| i as usize)
            .filter(|&i| drawn(i))
            .collect();
        crate::pool::waiters_back();
        let t_raster = Instant::now();
        let empty_points = empty_space(plan, set, &draw, reach, negative, &mut report)?;
        raster_time += t_raster.elapsed();
        report.empty_space_points += empty_points.len();
        // Bounds are tested against every sphere drawn, not a batch: a bound's point a batch
        // passes can lie on a part's face buried in spheres the batch left out.
        let batch = match plan.field.read_as {
            Reading::Bounds => draw.iter().map(|&i| i as u32).collect(),
            _ => draw_batch(
                set,
                params.batch_size,
                Seeds(params.seed).initial_batch(negative),
            ),
        };
        let tree = SphereTree::with_indices(unit, &batch);
        crate::pool::waiters_back();
        parts.push(counted(unseeded.len(), progress, |done| {
            rfta_feasible::initial_points(
                unit,
                values,
                &unseeded,
                &empty_points,
                &tree,
                &plan.feasible,
                Some(done),
            )
        }));
    }
    let mut cloud = merge_by_owner(parts);
    // Samples of one sign show a surface only where their spheres leave room inside the box
    // they were taken in (a thin shape between grid points). Beyond it every sphere's outer
    // side is free, and points there would put a surface where no sample looked (hostile
    // test E8: a ramp of positive values gave a mesh reaching three times past its box).
    if neg.is_empty() || pos.is_empty() {
        cloud = within_samples_box(unit, cloud);
    }
    report.feasible_initial = cloud.len();
    journal.timings.push((crate::Step::Rasterize, raster_time));
    journal
        .timings
        .push((crate::Step::InitialPoints, t.elapsed() - raster_time));
    enough(cloud, report, n, [neg.is_empty(), pos.is_empty()])
}

/// The cloud and its report when it has at least 3 points; otherwise the error that says why:
/// samples of one sign (`no_sign` says which set is empty) that show no surface, or too few
/// feasible points among `n` spheres.
fn enough(
    cloud: TangentPoints,
    report: InitialReport,
    n: usize,
    [no_negative, no_positive]: [bool; 2],
) -> Result<(TangentPoints, InitialReport)> {
    if cloud.len() < 3 && (no_negative || no_positive) {
        return Err(Error::NoSurface {
            samples: n,
            sign: if no_negative {
                "positive (outside)"
            } else {
                "negative (inside)"
            },
        });
    }
    if cloud.len() < 3 {
        return Err(Error::TooFewPoints {
            feasible: cloud.len(),
            spheres: n,
        });
    }
    Ok((cloud, report))
}

/// Which of `n` spheres own one of `owners`.
fn owned(owners: &[u32], n: usize) -> Vec<bool> {
    let mut seeded = vec![false; n];
    for &o in owners {
        seeded[o as usize] = true;
    }
    seeded
}

/// Empty space next to the spheres of the sign set `set` (the `draw`n ones among them): on a grid
/// the points their gradients point to outside them ([`crate::InitialPoints::Gradient`]), else
/// the rasterization's samples (`report.raster_resolution` 0 when no set was rasterized).
fn empty_space(
    plan: &Plan<'_>,
    set: &[u32],
    draw: &[usize],
    reach: f64,
    negative: bool,
    report: &mut InitialReport,
) -> Result<Vec<DVec3>> {
    let (unit, params) = (&plan.unit, &plan.params);
    let drawn = |i: usize| unit.radius(i) < reach;
    let from_gradient = match params.initial {
        crate::InitialPoints::Gradient => unit
            .gradient_points(set, |i| drawn(i) && unit.radius(i) < unit.clamp)
            .map(|points| {
                // Empty space: the points outside every drawn sphere of the set.
                let all = SphereTree::with_indices(
                    unit,
                    &draw.iter().map(|&i| i as u32).collect::<Vec<_>>(),
                );
                let tol = params.tolerance;
                use rayon::prelude::*;
                points
                    .into_par_iter()
                    .filter(|&q| !all.inside_any(q, -tol, None))
                    .collect::<Vec<_>>()
            })
            // Values that are not a distance near the surface (a lone sample of one sign
            // among the other's) leave the gradients little empty space: rasterize then.
            .filter(|p| !p.is_empty() && p.len() * GRADIENT_FLOOR >= draw.len()),
        crate::InitialPoints::Raster => None,
    };
    if let Some(points) = from_gradient {
        report.raster_resolution = 0;
        return Ok(points);
    }
    let c: Vec<DVec3> = draw.iter().map(|&i| unit.center(i)).collect();
    let r: Vec<f64> = draw.iter().map(|&i| unit.radius(i)).collect();
    let raster = params.raster_params(params.raster_resolution_for(unit.len()), negative);
    let backend = if params.gpu {
        rfta_raster::Backend::Gpu
    } else {
        rfta_raster::Backend::Cpu
    };
    let mut empty = rfta_raster::rasterize(&c, &r, &raster, backend)?;
    if draw.len() < set.len() {
        // Where the drawn spheres end and the larger ones would begin.
        empty
            .points
            .retain(|&w| unit.nearest_sample(w).is_none_or(drawn));
    }
    Ok(empty.points)
}

/// The points of `cloud` (in the unit box) that lie in the box of the samples.
fn within_samples_box(unit: &UnitBox, cloud: TangentPoints) -> TangentPoints {
    let b = unit.samples_box();
    let (lo, hi) = (unit.to_unit(b.min), unit.to_unit(b.max));
    let eps = 1e-9;
    let mut out = TangentPoints::default();
    for ((p, n), o) in cloud
        .points
        .into_iter()
        .zip(cloud.normals)
        .zip(cloud.owners)
    {
        if p.cmpge(lo - eps).all() && p.cmple(hi + eps).all() {
            out.points.push(p);
            out.normals.push(n);
            out.owners.push(o);
        }
    }
    out
}

/// `b` indices drawn with replacement from `set` (all of it when `b` is 0 or at least its size).
pub(crate) fn draw_batch(set: &[u32], b: usize, seed: u64) -> Vec<u32> {
    match rfta_geom::rng::batch_with_replacement(set.len(), b, seed) {
        Some(at) => at.iter().map(|&k| set[k as usize]).collect(),
        None => set.to_vec(),
    }
}

fn merge_by_owner(parts: Vec<TangentPoints>) -> TangentPoints {
    let mut all: Vec<(u32, DVec3, DVec3)> = parts
        .into_iter()
        .flat_map(|p| {
            p.owners
                .into_iter()
                .zip(p.points)
                .zip(p.normals)
                .map(|((o, x), n)| (o, x, n))
        })
        .collect();
    all.sort_by_key(|e| e.0);
    TangentPoints {
        owners: all.iter().map(|e| e.0).collect(),
        points: all.iter().map(|e| e.1).collect(),
        normals: all.iter().map(|e| e.2).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Params;
    use rfta_geom::{Grid, SdfSamples};

    const TORUS: rfta_testkit::Analytic = rfta_testkit::Analytic::Torus {
        major: 0.5,
        minor: 0.2,
    };

    /// The plan of a run that rasterizes, on samples taken as they are (no input check).
    fn raster_plan(samples: &SdfSamples) -> Plan<'_> {
        let params = Params {
            initial: crate::InitialPoints::Raster,
            check: false,
            ..Params::default()
        };
        Plan::new(samples, &params, &mut Journal::default()).expect("plan")
    }

    /// [`TORUS`]'s exact SDF on the 41^3 grid over [-1, 1]^3 (spacing 0.05).
    fn torus_values() -> Vec<f64> {
        let grid = Grid::cube(40, -1.0, 1.0).expect("grid");
        (0..grid.len())
            .map(|i| TORUS.sdf(grid.position(i)))
            .collect()
    }

    /// A torus (radii 0.5 and 0.2) on a 41^3 grid over [-1, 1]^3: spacing 0.05, so spheres from
    /// 0.45 on (9 spacings, 3 owner radii) are not drawn, a third of the samples. The initial
    /// points are the same as with every sphere drawn, and with spheres up to 1 owner radius
    /// drawn they are not.
    #[test]
    fn drawing_the_near_spheres_gives_the_points_of_drawing_all() {
        let samples = SdfSamples::grid(Grid::cube(40, -1.0, 1.0).expect("grid"), torus_values())
            .expect("samples");
        let plan = raster_plan(&samples);
        let unit = &plan.unit;
        let reach = plan.raster_radius;
        let undrawn = unit.spheres().filter(|s| s.radius >= reach).count();
        assert!(undrawn * 4 > unit.len(), "{undrawn} of {}", unit.len());
        let run = |reach: f64| {
            drawing(&plan, None, reach, &mut Journal::default(), &mut |_| {})
                .expect("points")
                .0
        };
        let all = run(f64::INFINITY);
        let near = run(reach);
        assert!(all.len() > 1000, "{}", all.len());
        assert_eq!(near.owners, all.owners);
        assert_eq!(near.points, all.points);
        assert_ne!(run(plan.owner_radius).points, all.points);
    }

    /// On a grid of a torus's exact SDF (41^3, spacing 0.05), the point each sample near the
    /// surface's gradient points to is the closest surface point up to the central difference's
    /// error: on the torus within 2% of a spacing, for every sample within 2 spacings.
    #[test]
    fn the_gradient_points_lie_on_the_surface() {
        let h = 0.05;
        let grid = Grid::cube(40, -1.0, 1.0).expect("grid");
        let values = torus_values();
        let near: Vec<u32> = (0..grid.len() as u32)
            .filter(|&i| values[i as usize].abs() < 2.0 * h)
            .collect();
        let samples = SdfSamples::grid(grid, values).expect("samples");
        let unit = UnitBox::new(&samples, None, None);
        let points = unit.gradient_points(&near, |_| true).expect("a grid");
        assert_eq!(points.len(), near.len());
        let worst = points
            .iter()
            .map(|&q| TORUS.sdf(unit.to_input(q)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.02 * h, "{worst}");
        // Scattered samples have no grid to take differences on.
        let scattered =
            SdfSamples::scattered(samples.positions(), samples.values().to_vec()).expect("ok");
        assert!(
            UnitBox::new(&scattered, None, None)
                .gradient_points(&near, |_| true)
                .is_none()
        );
    }

    /// Seeds that are the run's own initial points (in the input's coordinates) come back as
    /// they are: each feasible, each sphere with one getting no other. A seed moved into another
    /// sphere is dropped and its sphere gets the point it gets without seeds; a seed whose owner
    /// is not a sample is dropped.
    #[test]
    fn seeds_are_kept_where_feasible_and_only_the_rest_get_points() {
        let samples = SdfSamples::grid(Grid::cube(20, -1.0, 1.0).expect("grid"), {
            let grid = Grid::cube(20, -1.0, 1.0).expect("grid");
            (0..grid.len())
                .map(|i| TORUS.sdf(grid.position(i)))
                .collect()
        })
        .expect("samples");
        let plan = raster_plan(&samples);
        let unit = &plan.unit;
        let run = |seeds: Option<&TangentPoints>| {
            initial_points(&plan, seeds, &mut Journal::default(), &mut |_| {}).expect("points")
        };
        let (own, report) = run(None);
        assert!(own.len() > 300, "{}", own.len());
        assert_eq!(report.seeded, 0);
        let seeds = unit.points_to_input(own.clone());
        let (again, report) = run(Some(&seeds));
        assert_eq!(report.seeded, own.len());
        assert_eq!(again.owners, own.owners);
        for (a, b) in again.points.iter().zip(&own.points) {
            assert!((*a - *b).length() < 1e-12, "{a} {b}");
        }
        // The first seed moved to the centre of the largest sphere (inside it), and a seed
        // whose owner is past the samples.
        let k = 0;
        let other = (0..unit.len())
            .max_by(|&a, &b| unit.radius(a).total_cmp(&unit.radius(b)))
            .expect("samples");
        assert!(unit.radius(other) > 0.1);
        let mut bad = seeds.clone();
        bad.points[k] = unit.to_input(unit.center(other));
        bad.owners.push(unit.len() as u32);
        bad.points.push(seeds.points[1]);
        bad.normals.push(seeds.normals[1]);
        let (mended, report) = run(Some(&bad));
        assert_eq!(report.seeded, own.len() - 1);
        assert_eq!(mended.owners, own.owners);
        for (a, b) in mended.points.iter().zip(&own.points) {
            assert!((*a - *b).length() < 1e-12, "{a} {b}");
        }
    }
}
