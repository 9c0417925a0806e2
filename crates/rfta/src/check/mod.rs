//! Checks that samples behave like a signed distance before they are trusted as one.
//!
//! Reach for the Arcs takes every `|s_i|` as the exact distance to the surface. Values that are not
//! (an occupancy or random field, an SDF clamped at some band, a sentinel such as `1e30` for
//! "far") give spheres that contradict each other or the surface, and a mesh that is wrong without
//! any error. Two properties of a true signed distance `f` are cheap to test:
//!
//! * **Separation.** A negative sample `i` and a positive sample `j` lie on either side of the
//!   surface, so their empty spheres do not overlap: `|s_i| + |s_j| <= |p_i - p_j|` (the
//!   1-Lipschitz bound across the surface). [`inspect`] measures the ratio
//!   `(|s_i| + |s_j|) / |p_i - p_j|` against each sample's nearest sample of the other sign; a
//!   true SDF keeps it at or below 1, up to rounding.
//! * **Unit gradient.** Almost everywhere `|grad f| = 1`, so on a grid with spacing `h` a sample at
//!   distance at least `h` from the surface has an axis neighbour whose value differs by at least
//!   `h / sqrt(3)`. Samples whose six neighbours all carry exactly their value, at the largest
//!   magnitude of their sign, are the flat plateau of a clamped (truncated) SDF.
//!
//! Neither test needs the surface. Both run in `O(n log n)`; on a grid, the separation test runs
//! in `O(n)` (the exact feature transform, [`rfta_geom::Grid::nearest_marked`]).
//!
//! The pipeline checks at both ends: [`inspect`] and [`Params::check`]'s policy before anything
//! is built, and the mesh (finite vertices, degenerate faces, watertightness, components) before
//! it is returned.

mod plane;
mod separation;

pub(crate) use plane::samples2;

use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{SdfSamples, TriMesh};

use crate::report::{InputReport, Journal};
use crate::{Error, MeshCheck, Params, Result, Warning};

/// A separation ratio above this counts as a violation (1% above the exact bound of 1).
pub(crate) const SEPARATION_TOLERANCE: f64 = 1.01;

/// A separation ratio above this is a severe violation: the spheres overlap by a quarter of the
/// distance between the samples. Noise of 5% of the values, or of 5% of a grid spacing, stays
/// below 1.1; occupancy, random and rescaled fields go far beyond.
pub(crate) const SEVERE_RATIO: f64 = 1.25;

/// What [`inspect`] found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Inspection {
    /// Samples that have a sample of the other sign to compare with (zero values are skipped).
    pub checked: usize,
    /// Samples whose separation ratio exceeds `SEPARATION_TOLERANCE` (1.01).
    pub inconsistent: usize,
    /// Samples whose separation ratio exceeds `SEVERE_RATIO` (1.25).
    pub severe: usize,
    /// The worst pair: `(i, j, ratio)`, `i` the sample with the larger `|s|`.
    pub worst: Option<(usize, usize, f64)>,
    /// Samples whose `|s|` exceeds the diagonal of the samples' bounding box: with a sign change
    /// present no distance function sampled in that box has such a value (a sentinel for "far"?).
    pub beyond_extent: Vec<usize>,
    /// A clamping magnitude, if the values look clamped (see the module docs), with the number of
    /// plateau samples that show it.
    pub clamp: Option<(f64, usize)>,
    /// The largest separation ratio short of `SEVERE_RATIO` (1.25) (1 when no pair exceeds 1):
    /// noise that inflates values by a fraction `e` shows as a ratio up to `1 + e`.
    pub overlap: f64,
    /// On a grid, the largest `(|s_i - s_j| - d) / (|s_i| + |s_j|)` over neighbours `i`, `j` along
    /// an axis (`d` apart), below `MAX_NOISE` (0.25) (0 when none is positive): a distance changes
    /// by at most `d` over `d`, so relative noise of `e` shows as up to `e` where the gradient
    /// follows the axis, far more often than across the surface.
    pub lipschitz_excess: f64,
    /// The samples on the outside of the set (a grid's outer faces; otherwise the twentieth
    /// farthest from the centre of their box): `(negative, all)` of them, zeros left out.
    pub rim: (usize, usize),
    /// Samples above zero.
    pub positive: usize,
}

/// The share of the rim's samples ([`Inspection::rim`]) that must be negative, with positive
/// samples within, for the field to look inside-positive: a shape sampled in a box around it
/// has positive values all around.
const FLIPPED_RIM: f64 = 0.95;

/// Excess over the 1-Lipschitz bound (or the separation bound) beyond this fraction of the values
/// is not counted as noise (the separation test judges such fields).
pub(crate) const MAX_NOISE: f64 = 0.25;

impl Inspection {
    /// Whether the field looks inside-positive: at least 95% of the samples around
    /// the set ([`Inspection::rim`]) are negative, around positive ones.
    pub fn looks_inside_positive(&self) -> bool {
        looks_flipped(self.rim, self.positive)
    }

    /// The fraction of checked samples that are inconsistent.
    pub fn inconsistent_fraction(&self) -> f64 {
        self.inconsistent as f64 / self.checked.max(1) as f64
    }

    /// The separation ratio beyond which a sample counts as [`Inspection::severe`].
    pub fn severe_ratio(&self) -> f64 {
        SEVERE_RATIO
    }

    /// The fraction of checked samples that are severely inconsistent.
    pub fn severe_fraction(&self) -> f64 {
        self.severe as f64 / self.checked.max(1) as f64
    }
}

/// Measures how far `samples` are from a signed distance function (see the module docs).
pub fn inspect(samples: &SdfSamples) -> Inspection {
    // Every figure is a ratio of lengths: measured at a working scale where no square overflows.
    if let Some((scaled, _)) = crate::normalize::working_scale(samples) {
        return inspect(&scaled);
    }
    let values = samples.values();
    let bounds = samples.bounds();
    let diag = (bounds.max - bounds.min).length();
    let mut out = Inspection {
        beyond_extent: (0..values.len())
            .filter(|&i| values[i].abs() > diag)
            .collect(),
        overlap: 1.0,
        ..Inspection::default()
    };
    if let Some(found) = separation::measure(samples) {
        out.checked = found.checked;
        out.overlap = found.overlap;
        out.inconsistent = found.inconsistent;
        out.severe = found.severe;
        out.worst = found.worst.map(|(i, j, r)| {
            if values[i].abs() >= values[j].abs() {
                (i, j, r)
            } else {
                (j, i, r)
            }
        });
    }
    out.clamp = detect_clamp(samples);
    out.lipschitz_excess = lipschitz_excess(samples);
    out.rim = rim(samples);
    out.positive = values.par_iter().filter(|&&v| v > 0.0).count();
    out
}

/// Whether a field whose rim has `(negative, all)` samples (zeros left out) and `positive`
/// samples above zero looks inside-positive (2D and 3D alike).
pub(crate) fn looks_flipped((negative, all): (usize, usize), positive: usize) -> bool {
    positive > 0 && all > 0 && negative as f64 >= FLIPPED_RIM * all as f64
}

/// The refusal of a field that [`looks_flipped`], naming the flag that turns the check off.
pub(crate) fn flipped((negative, all): (usize, usize)) -> Error {
    Error::NotADistance(format!(
        "the field looks inside-positive: {negative} of the {all} samples on the outside of the set are negative (inside), around positive ones; rfta takes negative values as inside (as gpytoolbox and OpenVDB do), so negate the values. If the shape truly fills the box around a void, turn the check off"
    ))
}

/// The rim of scattered samples: the twentieth of the `n` samples farthest from their box's
/// centre (at least 8), by `distance_squared`; then `(negative, all)` of them, zeros left out.
pub(crate) fn rim_of(
    values: &[f64],
    on_rim: Option<Vec<usize>>,
    distance_squared: impl Fn(usize) -> f64,
) -> (usize, usize) {
    let on_rim = on_rim.unwrap_or_else(|| {
        let mut by_distance: Vec<(f64, usize)> = (0..values.len())
            .map(|i| (distance_squared(i), i))
            .collect();
        let take = (values.len() / 20).max(8).min(values.len());
        // The `take` farthest, in no particular order (a selection, not a sort).
        let farther = |a: &(f64, usize), b: &(f64, usize)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
        if take < by_distance.len() {
            by_distance.select_nth_unstable_by(take, farther);
        }
        by_distance[..take].iter().map(|&(_, i)| i).collect()
    });
    let negative = on_rim.iter().filter(|&&i| values[i] < 0.0).count();
    let all = on_rim.iter().filter(|&&i| values[i] != 0.0).count();
    (negative, all)
}

/// [`Inspection::rim`].
fn rim(samples: &SdfSamples) -> (usize, usize) {
    let values = samples.values();
    // A grid's outer faces, walked directly (a 513^3 grid has 1.6 million of its 135 million
    // samples there): whole x slabs at the ends, whole y rows at the ends of the slabs between,
    // and the two end samples along z of the rest.
    let on_grid = samples.as_grid().map(|grid| {
        let [nx, ny, nz] = grid.dims();
        let end = |n: usize, k: usize| k == 0 || k + 1 == n;
        let mut rim = Vec::new();
        for x in 0..nx {
            for y in 0..ny {
                if end(nx, x) || end(ny, y) {
                    rim.extend((0..nz).map(|z| grid.index(x, y, z)));
                } else {
                    rim.push(grid.index(x, y, 0));
                    if nz > 1 {
                        rim.push(grid.index(x, y, nz - 1));
                    }
                }
            }
        }
        rim
    });
    let c = samples.bounds().center();
    rim_of(values, on_grid, |i| samples.position(i).distance_squared(c))
}

/// [`Inspection::lipschitz_excess`] (0 for scattered samples).
fn lipschitz_excess(samples: &SdfSamples) -> f64 {
    let Some(g) = samples.as_grid() else {
        return 0.0;
    };
    let values = samples.values();
    let dims = g.dims();
    let h = g.spacing();
    (0..values.len())
        .into_par_iter()
        .map(|i| {
            let ijk = g.ijk(i);
            let mut worst: f64 = 0.0;
            for a in 0..3 {
                if ijk[a] + 1 >= dims[a] {
                    continue;
                }
                let mut n = ijk;
                n[a] += 1;
                let (si, sj) = (values[i], values[g.index(n[0], n[1], n[2])]);
                let sum = si.abs() + sj.abs();
                if sum > 0.0 {
                    let e = ((si - sj).abs() - h[a]) / sum;
                    if e < MAX_NOISE {
                        worst = worst.max(e);
                    }
                }
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
}

/// Plateau samples at the extreme magnitude of each sign (grids: all six neighbours equal;
/// scattered samples: exact ties at distinct positions), enough of them (8, and 0.1% of a grid
/// or 5% of scattered samples) to rule out the symmetric ties of a true SDF.
fn detect_clamp(samples: &SdfSamples) -> Option<(f64, usize)> {
    let values = samples.values();
    let n = values.len();
    let max_pos = values.iter().copied().fold(0.0f64, f64::max);
    let max_neg = values.iter().copied().fold(0.0f64, f64::min);
    let mut found: Option<(f64, usize)> = None;
    for extreme in [max_pos, max_neg] {
        if extreme == 0.0 {
            continue;
        }
        let (count, needed) = match samples.as_grid() {
            Some(g) => {
                let [nx, ny, nz] = g.dims();
                let flat = |i: usize| {
                    if values[i] != extreme {
                        return false;
                    }
                    let [a, b, c] = g.ijk(i);
                    let mut any = false;
                    for (axis, len) in [(0usize, nx), (1, ny), (2, nz)] {
                        let at = [a, b, c][axis];
                        for step in [-1i64, 1] {
                            let t = at as i64 + step;
                            if t < 0 || t >= len as i64 {
                                continue;
                            }
                            let mut ijk = [a, b, c];
                            ijk[axis] = t as usize;
                            any = true;
                            if values[g.index(ijk[0], ijk[1], ijk[2])] != extreme {
                                return false;
                            }
                        }
                    }
                    any
                };
                let count = (0..n).into_par_iter().filter(|&i| flat(i)).count();
                (count, 8.max(n / 1000))
            }
            None => {
                // Distinct positions only: exact duplicates of one sample are not a plateau.
                let mut at: Vec<[u64; 3]> = (0..n)
                    .filter(|&i| values[i] == extreme)
                    .map(|i| {
                        (samples.position(i) + DVec3::ZERO)
                            .to_array()
                            .map(f64::to_bits)
                    })
                    .collect();
                at.sort_unstable();
                at.dedup();
                (at.len(), 8.max(n / 20))
            }
        };
        if count >= needed {
            let c = extreme.abs();
            found = Some(match found {
                Some((d, k)) => (c.min(d), k + count),
                None => (c, count),
            });
        }
    }
    found
}

/// Positions in the samples' own units, for messages.
pub(crate) fn describe(samples: &SdfSamples, i: usize) -> String {
    let p: DVec3 = samples.position(i);
    format!(
        "sample {i} at ({:.4}, {:.4}, {:.4}), value {}",
        p.x,
        p.y,
        p.z,
        samples.values()[i]
    )
}

/// Noise up to this fraction of the values is rounding: the spheres keep their radii.
pub(crate) const NOISE_FLOOR: f64 = 0.001;

/// Runs [`inspect`] and applies [`Params::check`]'s policy.
///
/// Values that overlap the other sign's by a ratio `q` (short of [`SEVERE_RATIO`]), or that change
/// faster than a distance by a fraction `e` of their magnitude
/// ([`Inspection::lipschitz_excess`]), are taken as noise of up to `n = max(q - 1, e)` of the
/// value when `n` exceeds [`NOISE_FLOOR`]: a sample's own tangency points stay on its sphere of
/// radius `|s|`, but as a constraint on the others' points its sphere shrinks by `1 / (1 + n)^2`
/// ([`InputReport::radius_scale`]), the most an inflated neighbour can exceed a deflated sphere.
/// Without it, 1% noise on a 21^3 grid cost most spheres near the surface every point.
pub(crate) fn samples(
    samples: &SdfSamples,
    params: &Params,
    journal: &mut Journal,
) -> Result<InputReport> {
    let mut report = InputReport {
        samples: samples.len(),
        clamp: params.clamp,
        ..InputReport::default()
    };
    let found = inspect(samples);
    report.inconsistent_samples = found.inconsistent;
    let noise = (found.overlap - 1.0).max(found.lipschitz_excess);
    if noise > NOISE_FLOOR {
        report.radius_scale = Some((1.0 + noise).powi(-2));
        journal.warnings.push(Warning::Noisy { fraction: noise });
    }
    if params.clamp.is_none()
        && let Some((c, count)) = found.clamp
    {
        report.clamp = Some(c);
        journal.warnings.push(Warning::Clamped {
            at: c,
            samples: count,
        });
    }
    // Inside negative is the convention (the paper's, gpytoolbox's, OpenVDB's): a field whose
    // outside is negative all around, with positive samples within, is most likely of the
    // other convention, and reconstructing it as it is turns the mesh inside out and breaks it
    // (hostile test E18: six pieces, 9,121 samples on the wrong side, no word).
    if found.looks_inside_positive() {
        return Err(flipped(found.rim));
    }
    if let Some(&i) = found
        .beyond_extent
        .iter()
        .find(|&&i| report.clamp.is_none_or(|c| samples.values()[i].abs() < c))
    {
        let b = samples.bounds();
        return Err(Error::NotADistance(format!(
            "{} exceeds the diagonal {} of the samples' bounding box, which no distance to a surface crossing them can ({} such samples); if it stands for 'far away', set a clamp below it so such samples count as at least that far",
            describe(samples, i),
            (b.max - b.min).length(),
            found.beyond_extent.len()
        )));
    }
    if found.inconsistent > 0 {
        let worst = found.worst.map(|(i, j, r)| {
            format!(
                "{} and {} are {:.3e} apart, their spheres overlap by a factor {r:.3}",
                describe(samples, i),
                describe(samples, j),
                (samples.position(i) - samples.position(j)).length()
            )
        });
        let what = Warning::Overlap {
            inconsistent: found.inconsistent,
            checked: found.checked,
            worst,
        };
        if found.severe_fraction() > params.max_inconsistent {
            return Err(Error::NotADistance(format!(
                "{what}; {:.1}% overlap by more than a factor {}. Is it an occupancy, density or rescaled field? Turn the check off to reconstruct anyway",
                100.0 * found.severe_fraction(),
                SEVERE_RATIO
            )));
        }
        journal.warnings.push(what);
    }
    Ok(report)
}

/// Refuses non-finite vertices and reports degenerate faces and `topo`, the mesh's topology.
pub(crate) fn mesh(mesh: &TriMesh, topo: &rfta_mesh::Topology) -> Result<MeshCheck> {
    if let Some(i) = mesh.vertices.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFiniteOutput(i));
    }
    let zero_area_faces = (0..mesh.faces.len())
        .filter(|&f| mesh.face_normal_scaled(f).length_squared() == 0.0)
        .count();
    Ok(MeshCheck {
        degenerate_faces: topo.degenerate_faces,
        zero_area_faces,
        watertight: topo.is_watertight(),
        boundary_edges: topo.boundary_edges,
        nonmanifold_edges: topo.nonmanifold_edges,
        components: topo.components,
        genus: topo.genus(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::Grid;

    /// The rim walked face by face is exactly the samples with an index at either end of some
    /// axis (brute force over every sample), each once; and a sign flip is told from the field.
    #[test]
    fn a_grids_rim_is_its_outer_faces() {
        for dims in [[2, 2, 2], [2, 3, 4], [5, 5, 5], [13, 2, 7], [3, 9, 2]] {
            let grid = Grid::new(dims, DVec3::ZERO, DVec3::ONE).expect("grid");
            let [nx, ny, nz] = dims;
            // Negative on the rim, positive inside, by the brute-force rule.
            let values: Vec<f64> = (0..grid.len())
                .map(|i| {
                    let (x, y, z) = (i / (ny * nz), (i / nz) % ny, i % nz);
                    let end = |k: usize, n: usize| k == 0 || k + 1 == n;
                    if end(x, nx) || end(y, ny) || end(z, nz) {
                        -1.0
                    } else {
                        1.0
                    }
                })
                .collect();
            let on_rim = values.iter().filter(|&&v| v < 0.0).count();
            let samples = SdfSamples::grid(grid, values).expect("samples");
            assert_eq!(rim(&samples), (on_rim, on_rim), "{dims:?}");
        }
    }

    /// Scattered samples: the farthest twentieth (at least 8) is the rim, whatever the order.
    #[test]
    fn scattered_samples_rim_is_the_farthest_twentieth() {
        let n = 400;
        let values: Vec<f64> = (0..n)
            .map(|i| if i % 7 == 0 { -1.0 } else { 1.0 })
            .collect();
        let distance = |i: usize| ((i * 37) % n) as f64;
        // The 20 farthest are those whose distance is n - 20 .. n.
        let farthest: Vec<usize> = (0..n).filter(|&i| distance(i) >= (n - 20) as f64).collect();
        let negative = farthest.iter().filter(|&&i| values[i] < 0.0).count();
        assert_eq!(rim_of(&values, None, distance), (negative, 20));
        assert!(looks_flipped((19, 20), 1) && !looks_flipped((18, 20), 1));
        assert!(!looks_flipped((20, 20), 0));
    }
}
