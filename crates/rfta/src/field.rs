//! Fields that are not distances: how far a grid's values can be read as distances
//! (`measure`), and, where they cannot, the initial points on the field's zero set
//! (`zero_set_points`) instead of on the spheres.
//!
//! Reach for the Arcs reads every `|s_i|` as the distance to the surface: the sphere of that
//! radius touches it. Trained networks, CSG bounds and re-distanced level sets give values that
//! fall short of it (a sphere that touches nothing: its tangency point floats in empty space) or
//! go beyond it (a sphere the surface crosses). A distance reaches its zero set: a sample `d`
//! from the nearest sample next to a sign change is within `d - sqrt(3) h` of the zero set, so a
//! value shorter than `d - 2h` is not a distance. [`FieldReport::reach`] is the median of
//! `|s| / d` over the samples at least `FAR` spacings from the zero set: 0.8 to 1.06 on every exact
//! dev grid (thin parts the grid misses lower it at 11^3), 0.14 to 0.18 on the networks fitted
//! DeepSDF-style (their values flatten at the training's clamp).
//!
//! Values that reach their zero set can still fail to touch it: a CSG tree's min and max, or a
//! smooth blend, give a bound, not a distance. A sphere of a distance touches the surface where
//! no other sphere reaches, so the paper's local search finds a point on it that no other sphere
//! covers; a bound's sphere may stop short inside the union of others (a part's face buried in
//! another part), and none is found. [`FieldReport::covered`] is the fraction of the spheres that
//! own points on which that search fails (`cover_check`, about a thousand of them tested): at
//! most 0.1% on every exact dev grid and on OpenVDB's mesh-to-volume level sets of the dev shapes,
//! 1.6% to 5.5% on three of the four CSG fields of `cargo xtask eval inexact` (the fourth, a cube
//! intersected with a ball, has its cut-away faces less than `COVER_DEPTH` deep and reads as
//! distances, which suit it).
//!
//! Below `REACH_FLOOR` the samples are read as a level set ([`Reading::LevelSet`]): each sample
//! within a spacing and a half of the zero set is moved to it by Newton's method on the grid's
//! tricubic interpolant ([`rfta_geom::CubicField`]), its normal the interpolant's gradient there;
//! the screened Poisson solve of those points is the mesh, with no fine-tuning against the
//! spheres (they do not touch the surface). The input check, the repair and the verdict are the
//! same.
//!
//! Above `COVERED_CEILING` they are read as bounds ([`Reading::Bounds`]): each sphere is empty
//! space (a bound's value never exceeds the distance), but not every one touches the surface. The
//! initial points are the paper's, found against every sphere near the surface (not a random
//! batch: a point a batch misses can lie inside a sphere it left out, on a part's buried face),
//! and each one off the zero set of the grid's tricubic interpolant by more than `ON_ZERO_SET`
//! spacings (a short sphere's, floating in the gap it leaves) is moved onto it by Newton's
//! method (`onto_zero_set`); no fine-tuning rounds (they would pull the surface back to short
//! spheres). Spheres keep creases the interpolant rounds: on the CSG fields of `cargo xtask eval
//! inexact` the mean Chamfer is 0.54x marching cubes' at 64^3 where the level-set reading gives
//! 0.71x (docs/eval/inexact.md).

use rayon::prelude::*;
use rfta_feasible::TangentPoints;
use rfta_geom::glam::DVec3;
use rfta_geom::{CubicField, SdfSamples, SphereSet};
use rfta_sphere_tree::SphereTree;
use serde::{Deserialize, Serialize};

use crate::normalize::UnitBox;

/// How the samples are read ([`crate::Params::field`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Field {
    /// As distances when they behave like distances, else as a level set or as bounds: on a
    /// grid, a [`FieldReport::reach`] below 0.5 reads them as a level set, a
    /// [`FieldReport::covered`] above 0.5% as bounds; scattered samples are read as distances.
    #[default]
    Auto,
    /// As distances: the paper's spheres, each touching the surface.
    Distance,
    /// As a level set whose zero set is the surface (grids only): points on it by Newton's
    /// method on the tricubic interpolant, no fine-tuning.
    LevelSet,
    /// As bounds on the distance (grids only; CSG trees, smooth blends): each sphere empty
    /// space, its tangency point moved onto the tricubic interpolant's zero set where it lies
    /// off it, no fine-tuning.
    Bound,
}

/// How the samples were read ([`FieldReport::read_as`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reading {
    /// As distances ([`Field::Distance`]).
    #[default]
    Distances,
    /// As a level set ([`Field::LevelSet`]).
    LevelSet,
    /// As bounds on the distance ([`Field::Bound`]).
    Bounds,
}

/// As the report's sentences name it.
impl std::fmt::Display for Reading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Distances => "distances",
            Self::LevelSet => "a level set",
            Self::Bounds => "bounds on the distance",
        })
    }
}

impl Reading {
    /// Whether fine-tuning rounds run: only for distances (a level set's and a bound's spheres
    /// need not touch the surface).
    pub(crate) fn fine_tunes(self) -> bool {
        self == Self::Distances
    }

    /// Whether every sphere is empty space the mesh may not enter: not a level set's.
    pub(crate) fn spheres_bind(self) -> bool {
        self != Self::LevelSet
    }
}

/// What the field's measure found, and how the samples were read.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FieldReport {
    /// How the samples were read: as distances, a level set or bounds.
    pub read_as: Reading,
    /// Median of `|s| / d` over the grid's samples at least 4 spacings from the nearest sample
    /// next to a sign change (`d` the distance to it): about 1 for a distance, lower where the
    /// values fall short of their zero set. `None`: scattered samples, or fewer than 100 such.
    pub reach: Option<f64>,
    /// Samples whose value falls short of that distance by more than two spacings (a distance
    /// never does), as a fraction of all.
    #[serde(rename = "short_of_zero_set")]
    pub short: f64,
    /// The 10th, 50th and 90th percentiles of the gradient norm (central differences, one-sided
    /// on the grid's faces, [`rfta_geom::Grid::central_difference`]) at the samples next to a
    /// sign change: 1 for a distance sampled finely, lower at coarse grids.
    #[serde(rename = "slope_at_zero_set")]
    pub slope: Option<[f64; 3]>,
    /// The fraction of the spheres that own points (every k-th, about a thousand) that other
    /// spheres cover: the local search finds no point on them outside every other sphere (by a
    /// quarter spacing, `COVER_DEPTH`). About 0 for a distance; a bound's (a CSG tree's)
    /// spheres stop short inside others. `None`: scattered samples, values already read as a
    /// level set, a reading asked for, or fewer than 100 such spheres.
    #[serde(rename = "spheres_covered")]
    pub covered: Option<f64>,
}

/// Samples this many spacings or more from the zero set give [`FieldReport::reach`].
const FAR: f64 = 4.0;

/// A [`FieldReport::reach`] below this reads the samples as a level set.
const REACH_FLOOR: f64 = 0.5;

/// Fewer far samples than this give no [`FieldReport::reach`], fewer owners no
/// [`FieldReport::covered`].
const MIN_FAR: usize = 100;

/// A [`FieldReport::covered`] above this reads the samples as bounds: 5 times the most an exact
/// dev grid or OpenVDB level set gives (0.1%), a third of the least a CSG field does (1.6%,
/// csg-drilled at 65^3 and 129^3).
const COVERED_CEILING: f64 = 0.005;

/// The spheres each local-search move resolves in [`cover_check`] and in the initial points of
/// bounds, whose trees hold every sphere near the surface, not a batch: the reference's
/// `2 n^(1/3)` of all `n` samples (130 at 64^3) made the bounds' covered spheres, which use
/// every move, cost six times as long for the same points (csg-drilled at 64^3: 12.6 s against
/// 2.1 s, Chamfer 0.00172 both).
pub(crate) const NEAR_K_SEARCH: usize = 22;

/// [`cover_check`] counts a sphere covered only where other spheres hold every point it tries by
/// more than this many spacings: distances that are close but not exact (OpenVDB's
/// mesh-to-volume level sets of the dev shapes: up to 0.8% covered without it, 0.1% with it)
/// overlap by less, a CSG tree's buried faces lie deeper (1.6% to 5.5% with it).
const COVER_DEPTH: f64 = 0.25;

/// [`cover_check`] tests at most about this many spheres ...
const COVER_TESTS: usize = 1000;

/// ... this many at a time.
const COVER_CHUNK: usize = 128;

/// Where [`cover_check`]'s local search starts on a sphere when it fails from the gradient's side:
/// the axes and the diagonals.
const STARTS: [[f64; 3]; 14] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [-1.0, -1.0, -1.0],
];

/// Samples within this many spacings of the zero set (by value, or next to a sign change) start
/// a zero-set point.
const BAND: f64 = 1.5;

/// A zero-set point this many spacings or more from its sample is dropped (Newton went astray).
const REACH: f64 = 2.5;

/// Read as bounds, a tangency point where the interpolant's magnitude exceeds this many spacings
/// is moved onto its zero set: of 0.03, 0.05, 0.1 and 0.3 the mean Chamfer of the CSG fields
/// at 32^3 and 64^3 was least at 0.05 (0.56x and 0.54x marching cubes'; 0.1: 0.54x and 0.58x;
/// 0.3: 0.64x and 0.62x).
const ON_ZERO_SET: f64 = 0.05;

/// How the grid's values behave as distances (the module docs), and whether `field` reads them as
/// a level set. Samples at or beyond `clamp` (a clamp given or detected: its plateaus fall short
/// by design, and the spheres handle them), or at the largest magnitude of their sign (a clamp's
/// plateau when the check is off), give no reach. Scattered samples are read as
/// distances ([`crate::plan::Plan::new`] refuses [`Field::LevelSet`] for them).
pub(crate) fn measure(samples: &SdfSamples, field: Field, clamp: Option<f64>) -> FieldReport {
    let Some(grid) = samples.as_grid() else {
        return FieldReport::default();
    };
    let values = samples.values();
    let h = grid.spacing().min_element();
    let below_clamp = clamp.map_or(f64::INFINITY, |c| c * (1.0 - 1e-9));
    let (most_negative, most_positive) = values
        .iter()
        .fold((0.0f64, 0.0f64), |(n, p), &v| (n.min(v), p.max(v)));
    let on_plateau = |v: f64| v == most_negative || v == most_positive;
    let marked = next_to_sign_change(samples);
    let nearest = grid.nearest_marked(&marked);
    let (ratios, short): (Vec<f64>, usize) = (0..values.len())
        .into_par_iter()
        .filter(|&i| {
            nearest[i] != rfta_geom::feature_transform::NONE
                && values[i].abs() < below_clamp
                && !on_plateau(values[i])
        })
        .map(|i| {
            let d = grid
                .position(i)
                .distance(grid.position(nearest[i] as usize));
            let s = values[i].abs();
            let ratio = (d >= FAR * h).then(|| s / d);
            (ratio, usize::from(s < d - 2.0 * h))
        })
        .fold(
            || (Vec::new(), 0),
            |(mut r, n), (ratio, short)| {
                r.extend(ratio);
                (r, n + short)
            },
        )
        .reduce(
            || (Vec::new(), 0),
            |(mut a, n), (b, m)| {
                a.extend(b);
                (a, n + m)
            },
        );
    let reach = (ratios.len() >= MIN_FAR).then(|| percentiles(ratios, &[0.5])[0]);
    let slopes: Vec<f64> = (0..values.len())
        .into_par_iter()
        .filter(|&i| marked[i])
        .map(|i| grid.central_difference(values, i).length())
        .collect();
    let slope = (!slopes.is_empty()).then(|| {
        let p = percentiles(slopes, &[0.1, 0.5, 0.9]);
        [p[0], p[1], p[2]]
    });
    let read_as = match field {
        Field::Auto if reach.is_some_and(|r| r < REACH_FLOOR) => Reading::LevelSet,
        Field::Auto | Field::Distance => Reading::Distances,
        Field::LevelSet => Reading::LevelSet,
        Field::Bound => Reading::Bounds,
    };
    FieldReport {
        read_as,
        reach,
        short: short as f64 / values.len().max(1) as f64,
        slope,
        covered: None,
    }
}

/// With [`Field::Auto`], on a grid whose values were not read as a level set by their reach:
/// [`FieldReport::covered`] measured, and the samples read as bounds above `COVERED_CEILING`.
/// Of the spheres that own points (radius below `owner_radius`, every k-th of them, about
/// `COVER_TESTS`), each starts on the side its value's gradient points to the zero
/// set and is moved by the paper's local search (`params`, as the initial points') against every
/// sphere smaller than `reach_radius`; those that end inside another are covered. With `asked`,
/// only the spheres of the samples it marks (an adaptive run's dense grid, whose other values are
/// interpolated and bound nothing).
pub(crate) fn cover_check(
    report: &mut FieldReport,
    field: Field,
    samples: &SdfSamples,
    unit: &UnitBox,
    (owner_radius, reach_radius): (f64, f64),
    params: &rfta_feasible::Params,
    asked: Option<&[bool]>,
) {
    let Some(grid) = samples.as_grid() else {
        return;
    };
    if field != Field::Auto || report.read_as != Reading::Distances {
        return;
    }
    let values = samples.values();
    let spheres = unit;
    let asked = |i: u32| asked.is_none_or(|a| a[i as usize]);
    let owners: Vec<u32> = (0..spheres.len() as u32)
        .filter(|&i| {
            let r = spheres.radius(i as usize);
            r > 0.0 && r < owner_radius && asked(i)
        })
        .collect();
    if owners.len() < MIN_FAR {
        return;
    }
    let near: Vec<u32> = (0..spheres.len() as u32)
        .filter(|&i| spheres.radius(i as usize) < reach_radius && asked(i))
        .collect();
    let tree = SphereTree::with_indices(spheres, &near);
    let params = &rfta_feasible::Params {
        k_search: params.k_search.min(NEAR_K_SEARCH),
        tol: params.tol.max(COVER_DEPTH * unit.spacing()),
        ..params.clone()
    };
    let planned: Vec<u32> = owners
        .iter()
        .step_by(owners.len().div_ceil(COVER_TESTS))
        .copied()
        .collect();
    // In chunks, stopping once the spheres found covered put the fraction over the ceiling
    // whatever the rest give (a bound's: it is an estimate of a few hundred then).
    let (mut tested, mut stuck) = (0usize, 0usize);
    for chunk in planned.chunks(COVER_CHUNK) {
        let (t, s) = chunk
            .par_iter()
            .filter_map(|&i| {
                let g = grid.central_difference(values, i as usize);
                let len = g.length();
                (len > 0.0 && len.is_finite()).then(|| {
                    (
                        1usize,
                        usize::from(!uncovered_point(
                            spheres,
                            &tree,
                            i,
                            -values[i as usize].signum() * g / len,
                            params,
                        )),
                    )
                })
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        (tested, stuck) = (tested + t, stuck + s);
        if stuck as f64 > COVERED_CEILING * planned.len() as f64 {
            break;
        }
    }
    if tested < MIN_FAR {
        return;
    }
    let covered = stuck as f64 / tested as f64;
    report.covered = Some(covered);
    if covered > COVERED_CEILING {
        report.read_as = Reading::Bounds;
    }
}

/// Whether the paper's local search finds a point on sphere `i` outside every sphere of `tree`:
/// from the side `toward` first, then from each of `STARTS`.
fn uncovered_point(
    spheres: &UnitBox,
    tree: &SphereTree,
    i: u32,
    toward: DVec3,
    params: &rfta_feasible::Params,
) -> bool {
    let s = params.owner(spheres.sphere(i as usize));
    std::iter::once(toward)
        .chain(STARTS.iter().map(|d| DVec3::from_array(*d).normalize()))
        .any(|d| {
            rfta_feasible::local_search(spheres, tree, i, s.center + s.radius * d, params).is_some()
        })
}

/// Tangency points (in the unit box of `unit`) on the zero set of the grid's tricubic
/// interpolant: each where the interpolant's magnitude is below `ON_ZERO_SET` spacings, the
/// others moved onto it by Newton's method (the unit gradient there their normal) or, where it
/// does not converge within `REACH` spacings, dropped. Also returns how many were moved.
pub(crate) fn onto_zero_set(
    cloud: TangentPoints,
    samples: &SdfSamples,
    unit: &UnitBox,
) -> (TangentPoints, usize) {
    let Some(grid) = samples.as_grid() else {
        return (cloud, 0);
    };
    let Some(field) = CubicField::new(grid, samples.values()) else {
        return (cloud, 0);
    };
    let h = grid.spacing().min_element();
    let moved: Vec<Option<(DVec3, DVec3, bool)>> = (0..cloud.len())
        .into_par_iter()
        .map(|k| {
            let p = unit.to_input(cloud.points[k]);
            if field.value_gradient(p).0.abs() <= ON_ZERO_SET * h {
                return Some((cloud.points[k], cloud.normals[k], false));
            }
            let (q, normal) = field.zero_near(p, REACH * h)?;
            Some((unit.to_unit(q), normal, true))
        })
        .collect();
    let mut out = TangentPoints::default();
    let mut count = 0;
    for (k, m) in moved.into_iter().enumerate() {
        if let Some((p, n, was_moved)) = m {
            out.points.push(p);
            out.normals.push(n);
            out.owners.push(cloud.owners[k]);
            count += usize::from(was_moved);
        }
    }
    (out, count)
}

/// A level-set reading's mesh vertex moves onto the interpolant's zero set when Newton's method
/// reaches it within this many spacings.
const SNAP_REACH: f64 = 0.25;

/// A level-set reading's mesh with each vertex moved onto the zero set of the grid's tricubic
/// interpolant where Newton's method reaches it within [`SNAP_REACH`] spacings (in the samples'
/// coordinates); how many moved. The screened Poisson surface through the zero-set points sits
/// off them by a few hundredths of a spacing where the surface is flat (its iso-value is a
/// mean over the whole surface), which no fine-tuning corrects in this reading: on the rounded
/// cube's 129^3 grid its faces lay 0.02 spacings outside the cube's, and the mesh's Chamfer to
/// the field's zero set was 1.05x marching cubes' before and 0.51x after (docs/eval/inexact.md).
/// The repair calls it before its dents, which then dent past any sample a move left on the wrong
/// side (moved after them, one of thingi54725's network's samples at 33^3 was).
pub(crate) fn vertices_onto_zero_set(mesh: &mut rfta_geom::TriMesh, samples: &SdfSamples) -> usize {
    let Some(grid) = samples.as_grid() else {
        return 0;
    };
    let Some(field) = CubicField::new(grid, samples.values()) else {
        return 0;
    };
    let reach = SNAP_REACH * grid.spacing().min_element();
    mesh.vertices
        .par_iter_mut()
        .map(|v| match field.zero_near(*v, reach) {
            Some((q, _)) if q != *v => {
                *v = q;
                1
            }
            _ => 0,
        })
        .sum()
}

/// One point per sample within `BAND` spacings of the zero set (by value, or next to a sign
/// change), of those `asked` marks when given (the others' values are interpolated: an adaptive
/// run's): Newton's method from the sample on the grid's tricubic interpolant, the unit gradient
/// there its normal, the sample its owner; in the samples' coordinates. Empty for scattered
/// samples.
pub(crate) fn zero_set_points(samples: &SdfSamples, asked: Option<&[bool]>) -> TangentPoints {
    let Some(grid) = samples.as_grid() else {
        return TangentPoints::default();
    };
    let values = samples.values();
    let Some(field) = CubicField::new(grid, values) else {
        return TangentPoints::default();
    };
    let h = grid.spacing().min_element();
    let marked = next_to_sign_change(samples);
    let found: Vec<_> = (0..values.len())
        .into_par_iter()
        .filter(|&i| asked.is_none_or(|a| a[i]) && (marked[i] || values[i].abs() < BAND * h))
        .filter_map(|i| {
            let (q, normal) = field.zero_near(grid.position(i), REACH * h)?;
            Some((q, normal, i as u32))
        })
        .collect();
    let mut cloud = TangentPoints::default();
    for (p, n, owner) in found {
        cloud.points.push(p);
        cloud.normals.push(n);
        cloud.owners.push(owner);
    }
    cloud
}

/// For each grid sample, whether an axis neighbour has the other sign (negative against the
/// rest).
fn next_to_sign_change(samples: &SdfSamples) -> Vec<bool> {
    let Some(grid) = samples.as_grid() else {
        return vec![false; samples.len()];
    };
    let values = samples.values();
    let dims = grid.dims();
    (0..values.len())
        .into_par_iter()
        .map(|i| {
            let ijk = grid.ijk(i);
            let inside = values[i] < 0.0;
            (0..3).any(|a| {
                [-1i64, 1].iter().any(|&step| {
                    let mut n = ijk;
                    let k = ijk[a] as i64 + step;
                    if k < 0 || k >= dims[a] as i64 {
                        return false;
                    }
                    n[a] = k as usize;
                    (values[grid.index(n[0], n[1], n[2])] < 0.0) != inside
                })
            })
        })
        .collect()
}

/// The values at fractions `at` of the sorted `values` (nearest rank), each found by selection
/// (linear) instead of a sort: on the 513^3 bunny the field's step took 20.8 s with the sort of
/// its reaches, 13.9 s with selection (docs/speed.md, item 44).
fn percentiles(mut values: Vec<f64>, at: &[f64]) -> Vec<f64> {
    let last = values.len().saturating_sub(1) as f64;
    at.iter()
        .map(|&q| {
            *values
                .select_nth_unstable_by((q * last).round() as usize, f64::total_cmp)
                .1
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::Grid;
    use rfta_geom::glam::DVec3;

    fn sphere_grid(n: usize, value: impl Fn(f64) -> f64) -> SdfSamples {
        let grid = Grid::cube(n, -1.0, 1.0).expect("test");
        let values = (0..grid.len())
            .map(|i| value(grid.position(i).length() - 0.5))
            .collect();
        SdfSamples::grid(grid, values).expect("test")
    }

    /// A level set whose zero set is the ball of radius 0.5 (`|p|^2 - 0.25`, not a distance): the
    /// reading's vertices on it to a thousandth of a spacing (the screened Poisson surface alone
    /// lies a few hundredths of a spacing off).
    #[test]
    fn a_level_set_readings_vertices_lie_on_the_zero_set() {
        let grid = Grid::cube(32, -1.0, 1.0).expect("test");
        let values = (0..grid.len())
            .map(|i| grid.position(i).length_squared() - 0.25)
            .collect();
        let samples = SdfSamples::grid(grid, values).expect("test");
        let params = crate::Params {
            field: Field::LevelSet,
            simplify: false,
            // Its values overstate the distance away from the zero set: the input check would
            // refuse it as a distance.
            check: false,
            ..crate::Params::default()
        };
        let mesh = crate::reconstruct(&samples, &params).expect("a mesh").mesh;
        let h = 2.0 / 32.0;
        let worst = mesh
            .vertices
            .iter()
            .map(|v| (v.length() - 0.5).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-3 * h, "{} spacings", worst / h);
        let mut off = mesh.clone();
        off.vertices.iter_mut().for_each(|v| *v *= 1.0 + 0.1 * h);
        assert!(vertices_onto_zero_set(&mut off, &samples) == off.n_vertices());
        let back = off.vertices.iter().zip(&mesh.vertices);
        assert!(back.map(|(a, b)| a.distance(*b)).fold(0.0, f64::max) <= 1e-3 * h);
    }

    #[test]
    fn a_distance_reaches_its_zero_set() {
        let r = measure(&sphere_grid(32, |d| d), Field::Auto, None);
        let reach = r.reach.expect("test");
        // The nearest sample next to a sign change may lie beyond the surface: slightly over 1.
        assert!((0.9..=1.1).contains(&reach), "{reach}");
        assert_eq!(r.short, 0.0);
        let [lo, mid, hi] = r.slope.expect("test");
        assert!(lo > 0.95 && mid > 0.98 && hi < 1.01, "{:?}", r.slope);
        assert_eq!(r.read_as, Reading::Distances);
    }

    /// A distance clamped at 0.1, softly (a trained network's far field): the spheres stop short
    /// of the surface by up to 0.5 - 0.1, the median ratio is far below the floor.
    #[test]
    fn a_flattened_field_is_read_as_a_level_set() {
        let r = measure(
            &sphere_grid(32, |d| 0.1 * (d / 0.1).tanh()),
            Field::Auto,
            None,
        );
        assert!(r.reach.expect("test") < 0.3, "{:?}", r.reach);
        assert!(r.short > 0.5, "{}", r.short);
        assert_eq!(r.read_as, Reading::LevelSet);
        let forced = measure(
            &sphere_grid(32, |d| 0.1 * (d / 0.1).tanh()),
            Field::Distance,
            None,
        );
        assert_eq!(forced.read_as, Reading::Distances);
    }

    /// A distance clamped exactly at 0.1 (a narrow band), the clamp not given: its plateau is
    /// left out, and what is left reaches its zero set.
    #[test]
    fn a_hard_clamps_plateau_is_no_shortfall() {
        let r = measure(&sphere_grid(32, |d| d.clamp(-0.1, 0.1)), Field::Auto, None);
        assert_eq!(r.read_as, Reading::Distances, "{r:?}");
        assert!(r.reach.is_none_or(|x| x > 0.9), "{r:?}");
    }

    #[test]
    fn scattered_samples_are_distances() {
        let p: Vec<DVec3> = (0..50).map(|i| DVec3::splat(i as f64 / 50.0)).collect();
        let v = p.iter().map(|p| p.x - 0.5).collect();
        let r = measure(
            &SdfSamples::scattered(p, v).expect("test"),
            Field::Auto,
            None,
        );
        assert_eq!(r, FieldReport::default());
    }

    /// A point on the zero set stays as it is; one a third of a spacing off it (a short sphere's)
    /// moves onto it with the radial normal; one three spacings off (beyond Newton's reach) is
    /// dropped.
    #[test]
    fn points_off_the_zero_set_move_onto_it() {
        let samples = sphere_grid(24, |d| d);
        let unit = UnitBox::new(&samples, None, None);
        let h = 2.0 / 24.0;
        let dir = DVec3::new(1.0, 2.0, 2.0) / 3.0;
        let on = dir * 0.5;
        let cloud = TangentPoints {
            points: [on, dir * (0.5 + h / 3.0), dir * (0.5 + 3.0 * h)]
                .map(|p| unit.to_unit(p))
                .to_vec(),
            normals: vec![dir; 3],
            owners: vec![0, 1, 2],
        };
        let (out, moved) = onto_zero_set(cloud.clone(), &samples, &unit);
        assert_eq!((out.owners.as_slice(), moved), ([0, 1].as_slice(), 1));
        assert_eq!(out.points[0], cloud.points[0]);
        let q = unit.to_input(out.points[1]);
        assert!((q.length() - 0.5).abs() < 0.01 * h, "{q}");
        assert!(out.normals[1].dot(dir) > 0.999);
    }

    /// Half the slope of a distance (a field that under-states by 2): the zero-set points lie on
    /// the sphere within a hundredth of a spacing, normals outward.
    #[test]
    fn zero_set_points_lie_on_the_zero_set() {
        let samples = sphere_grid(24, |d| 0.5 * d);
        let cloud = zero_set_points(&samples, None);
        let h = 2.0 / 24.0;
        assert!(cloud.len() > 500, "{}", cloud.len());
        for (&q, n) in cloud.points.iter().zip(&cloud.normals) {
            assert!((q.length() - 0.5).abs() < 0.01 * h, "{q}");
            assert!(n.dot(q.normalize()) > 0.999);
        }
    }

    /// Selection finds the nearest-rank values a sort finds, ties, zeros of both signs and
    /// repeated fractions included.
    #[test]
    fn percentiles_are_the_sorted_values_at_their_ranks() {
        let mut rng = rfta_geom::rng::Rng::new(21);
        for n in [1usize, 2, 3, 10, 101, 1000] {
            let values: Vec<f64> = (0..n)
                .map(|k| match k % 5 {
                    0 => -0.0,
                    1 => 0.0,
                    _ => (rng.next_f64() * 8.0).floor() - 3.0,
                })
                .collect();
            let at = [0.0, 0.1, 0.5, 0.5, 0.9, 1.0];
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            let want: Vec<u64> = (at.iter())
                .map(|&q| sorted[(q * (n - 1) as f64).round() as usize].to_bits())
                .collect();
            let got: Vec<u64> = percentiles(values, &at)
                .iter()
                .map(|v| v.to_bits())
                .collect();
            assert_eq!(got, want, "n = {n}");
        }
    }
}
