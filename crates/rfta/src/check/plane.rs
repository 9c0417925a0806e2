//! The input check of 2D samples (`rfta::plane` runs it before `rfta_plane::reconstruct`): the
//! 3D check's rules for distances and the sign convention, on circles.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use rfta_geom::plane::SdfSamples2;

use crate::{Error, Result};

/// Refuses 2D samples that are not a signed distance ([`separation`]) or look inside-positive
/// ([`sign_convention`]).
pub(crate) fn samples2(samples: &SdfSamples2, max_fraction: f64) -> Result<()> {
    separation(samples, max_fraction)?;
    sign_convention(samples)
}

/// Refuses values that are not a signed distance, by the 3D check's rule
/// (`SEVERE_RATIO`): the curve crosses the segment between two samples of
/// opposite signs, so their circles can at most touch (`|s_i| + |s_j| <= |p_i - p_j|`); more than
/// `max_fraction` of the samples overlapping their nearest sample of the other sign by a quarter
/// of the distance is an occupancy image or a field in other units than the positions, and
/// reconstructing from it gives a wrong curve or none. (The 3D check also detects clamps and
/// measures noise; in 2D this is the whole check.)
fn separation(samples: &SdfSamples2, max_fraction: f64) -> Result<()> {
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
                v[i].abs() + v[j].abs() > super::SEVERE_RATIO * d
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

/// Refuses an inside-positive field as the 3D check does (`looks_flipped`): the
/// samples around the set (a grid's outer rows and columns; otherwise the twentieth farthest from
/// the centre of their box) nearly all negative, around positive ones.
fn sign_convention(samples: &SdfSamples2) -> Result<()> {
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
    let rim = super::rim_of(v, on_grid, |i| p[i].distance_squared(c));
    let positive = v.iter().filter(|&&x| x > 0.0).count();
    if super::looks_flipped(rim, positive) {
        return Err(super::flipped(rim));
    }
    Ok(())
}
