//! Steps 2 and 3: empty space next to the spheres of each sign (rasterization), and one feasible
//! tangency point per sphere from it.

use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::glam::DVec3;
use rfta_sphere_tree::SphereTree;

use crate::normalize::UnitBox;
use crate::params::Seeds;
use crate::report::{InitialReport, Journal, counted};
use crate::{Error, Params, Result, Stage};

/// The initial tangency points, one sign set at a time: rasterize the set's spheres, take the
/// nearest empty-space sample to each centre, make it feasible against a batch of the same set.
pub(crate) fn initial_points(
    unit: &UnitBox,
    params: &Params,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<(TangentPoints, InitialReport)> {
    // Only spheres near the surface shape the empty space an owner starts from (RASTER_REACH).
    drawing(unit, params, unit.raster_radius(params), journal, progress)
}

/// [`initial_points`] rasterizing the spheres smaller than `reach`.
fn drawing(
    unit: &UnitBox,
    params: &Params,
    reach: f64,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<(TangentPoints, InitialReport)> {
    progress(Stage::Initial);
    let t = Instant::now();
    let n = unit.len();
    let res = params.raster_resolution_for(n);
    let mut report = InitialReport {
        raster_resolution: res,
        ..InitialReport::default()
    };
    let backend = if params.gpu {
        rfta_raster::Backend::Gpu
    } else {
        rfta_raster::Backend::Cpu
    };
    let fparams = params.feasible_params(n, unit.owner_radius(params), unit.owner_scale());
    let values = &unit.values;
    let neg: Vec<u32> = (0..n as u32)
        .filter(|&i| values[i as usize] < 0.0)
        .collect();
    let pos: Vec<u32> = (0..n as u32)
        .filter(|&i| values[i as usize] >= 0.0)
        .collect();
    report.negative = neg.len();
    report.non_negative = pos.len();
    let mut parts = Vec::new();
    let mut raster_time = std::time::Duration::ZERO;
    let drawn = |i: usize| unit.spheres[i].radius < reach;
    for (negative, set) in [(false, &pos), (true, &neg)] {
        if set.is_empty() {
            continue;
        }
        let draw: Vec<usize> = set
            .iter()
            .map(|&i| i as usize)
            .filter(|&i| drawn(i))
            .collect();
        let c: Vec<DVec3> = draw.iter().map(|&i| unit.centers[i]).collect();
        let r: Vec<f64> = draw.iter().map(|&i| unit.spheres[i].radius).collect();
        let raster = params.raster_params(res, negative);
        crate::pool::waiters_back();
        let t_raster = Instant::now();
        let mut empty = rfta_raster::rasterize(&c, &r, &raster, backend)?;
        if draw.len() < set.len() {
            // Where the drawn spheres end and the larger ones would begin.
            empty
                .points
                .retain(|&w| unit.nearest_sample(w).is_none_or(drawn));
        }
        raster_time += t_raster.elapsed();
        report.empty_space_points += empty.points.len();
        let batch = draw_batch(
            set,
            params.batch_size,
            Seeds(params.seed).initial_batch(negative),
        );
        let tree = SphereTree::with_indices(&unit.spheres, &batch);
        crate::pool::waiters_back();
        parts.push(counted(set.len(), progress, |done| {
            rfta_feasible::initial_points(
                &unit.spheres,
                values,
                set,
                &empty.points,
                &tree,
                &fparams,
                Some(done),
            )
        }));
    }
    let cloud = merge_by_owner(parts);
    report.feasible_initial = cloud.len();
    journal.timings.push((crate::Step::Rasterize, raster_time));
    journal
        .timings
        .push((crate::Step::InitialPoints, t.elapsed() - raster_time));
    if cloud.len() < 3 && (neg.is_empty() || pos.is_empty()) {
        return Err(Error::NoSurface {
            samples: n,
            sign: if neg.is_empty() {
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

/// `b` indices drawn with replacement from `set` (all of it when `b` is 0 or at least its size).
fn draw_batch(set: &[u32], b: usize, seed: u64) -> Vec<u32> {
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
    use rfta_geom::{Grid, SdfSamples};

    /// A torus (radii 0.5 and 0.2) on a 41^3 grid over [-1, 1]^3: spacing 0.05, so spheres from
    /// 0.45 on (9 spacings, 3 owner radii) are not drawn, a third of the samples. The initial
    /// points are the same as with every sphere drawn, and with spheres up to 1 owner radius
    /// drawn they are not.
    #[test]
    fn drawing_the_near_spheres_gives_the_points_of_drawing_all() {
        let grid = Grid::cube(40, -1.0, 1.0).expect("grid");
        let torus = rfta_testkit::Analytic::Torus {
            major: 0.5,
            minor: 0.2,
        };
        let values: Vec<f64> = (0..grid.len())
            .map(|i| torus.sdf(grid.position(i)))
            .collect();
        let samples = SdfSamples::grid(grid, values).expect("samples");
        let params = Params::default();
        let unit = UnitBox::new(&samples, None, None);
        let reach = unit.raster_radius(&params);
        let undrawn = unit.spheres.iter().filter(|s| s.radius >= reach).count();
        assert!(undrawn * 4 > unit.len(), "{undrawn} of {}", unit.len());
        let run = |reach: f64| {
            drawing(&unit, &params, reach, &mut Journal::default(), &mut |_| {})
                .expect("points")
                .0
        };
        let all = run(f64::INFINITY);
        let near = run(reach);
        assert!(all.len() > 1000, "{}", all.len());
        assert_eq!(near.owners, all.owners);
        assert_eq!(near.points, all.points);
        assert_ne!(run(unit.owner_radius(&params)).points, all.points);
    }
}
