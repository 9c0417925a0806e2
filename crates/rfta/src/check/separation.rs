//! The separation test of [`super::inspect`]: each sample against its nearest sample of the
//! other sign (see the module docs of [`super`]).

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use rfta_geom::SdfSamples;

use super::{SEPARATION_TOLERANCE, SEVERE_RATIO};

/// The separation ratios `(|s_i| + |s_j|) / |p_i - p_j|` of every sample `i` against its
/// nearest sample `j` of the other sign, summed over samples: in any order to the same result,
/// and without a list of them (24 bytes a sample: 3.2 GB at 513^3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Separation {
    /// Samples with a ratio (zero values have none).
    pub(super) checked: usize,
    /// The largest ratio up to [`SEVERE_RATIO`], and 1.
    pub(super) overlap: f64,
    /// Ratios over [`SEPARATION_TOLERANCE`].
    pub(super) inconsistent: usize,
    /// Ratios over [`SEVERE_RATIO`].
    pub(super) severe: usize,
    /// The largest ratio over [`SEPARATION_TOLERANCE`], `(i, j, ratio)`; of equal ratios the
    /// lowest `i` (each sample has one ratio, so the choice is the same in any order).
    pub(super) worst: Option<(usize, usize, f64)>,
}

impl Default for Separation {
    fn default() -> Self {
        Self {
            checked: 0,
            overlap: 1.0,
            inconsistent: 0,
            severe: 0,
            worst: None,
        }
    }
}

impl Separation {
    /// Sample `i`'s ratio against sample `j`.
    fn of(i: usize, j: usize, ratio: f64) -> Self {
        Self {
            checked: 1,
            overlap: if ratio <= SEVERE_RATIO {
                ratio.max(1.0)
            } else {
                1.0
            },
            inconsistent: usize::from(ratio > SEPARATION_TOLERANCE),
            severe: usize::from(ratio > SEVERE_RATIO),
            worst: (ratio > SEPARATION_TOLERANCE).then_some((i, j, ratio)),
        }
    }

    fn add(self, o: Self) -> Self {
        let worst = match (self.worst, o.worst) {
            (Some(a), Some(b)) if b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)).is_gt() => Some(b),
            (a, b) => a.or(b),
        };
        Self {
            checked: self.checked + o.checked,
            overlap: self.overlap.max(o.overlap),
            inconsistent: self.inconsistent + o.inconsistent,
            severe: self.severe + o.severe,
            worst,
        }
    }
}

/// The separation of `samples`, or `None` when one sign is missing. On a grid the nearest
/// sample of the other sign comes from the exact feature transform (linear time; a tree query
/// per sample cost seconds at 129^3, most of them for far samples), otherwise from a k-d tree.
pub(super) fn measure(samples: &SdfSamples) -> Option<Separation> {
    let values = samples.values();
    if !(values.iter().any(|&v| v < 0.0) && values.iter().any(|&v| v > 0.0)) {
        return None;
    }
    let ratio = |i: usize, j: usize| {
        let d = samples.position(i).distance(samples.position(j));
        let gap = values[i].abs() + values[j].abs();
        Separation::of(i, j, if d > 0.0 { gap / d } else { f64::INFINITY })
    };
    let mut found = Separation::default();
    for negative in [true, false] {
        let of_sign = |i: usize| {
            if negative {
                values[i] < 0.0
            } else {
                values[i] > 0.0
            }
        };
        let other = |j: usize| {
            if negative {
                values[j] > 0.0
            } else {
                values[j] < 0.0
            }
        };
        let from = (0..values.len()).into_par_iter().filter(|&i| of_sign(i));
        let here = if let Some(grid) = samples.as_grid() {
            let marked: Vec<bool> = (0..values.len()).map(other).collect();
            let nearest = grid.nearest_marked(&marked);
            from.map(|i| ratio(i, nearest[i] as usize))
                .reduce(Separation::default, Separation::add)
        } else {
            let to: Vec<usize> = (0..values.len()).filter(|&j| other(j)).collect();
            let pts: Vec<[f64; 3]> = to.iter().map(|&j| samples.position(j).to_array()).collect();
            let Ok(kd) = ImmutableKdTree::<f64, 3>::new_from_slice(&pts) else {
                continue;
            };
            from.map(|i| {
                let nn = kd
                    .query(&samples.position(i).to_array())
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                ratio(i, to[nn.item as usize])
            })
            .reduce(Separation::default, Separation::add)
        };
        found = found.add(here);
    }
    Some(found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::Grid;
    use rfta_geom::glam::DVec3;

    /// The figures from a list of `(i, ratio)`, as the list of them all gave them before.
    fn figures(ratios: &[(usize, f64)]) -> (usize, usize, usize, f64, Option<(usize, f64)>) {
        let count = |t: f64| ratios.iter().filter(|r| r.1 > t).count();
        let overlap = (ratios.iter().map(|r| r.1))
            .filter(|&r| r <= SEVERE_RATIO)
            .fold(1.0, f64::max);
        let worst = (ratios.iter())
            .filter(|r| r.1 > SEPARATION_TOLERANCE)
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .copied();
        let (inconsistent, severe) = (count(SEPARATION_TOLERANCE), count(SEVERE_RATIO));
        (ratios.len(), inconsistent, severe, overlap, worst)
    }

    /// `measure(samples)` against [`figures`] of `ratios`, which must hold inconsistent samples
    /// and severe ones.
    fn agree(samples: &SdfSamples, ratios: &[(usize, f64)]) {
        let want = figures(ratios);
        assert!(want.1 > want.2 && want.2 > 5, "{want:?}");
        let found = measure(samples).expect("both signs");
        let worst = found.worst.map(|(i, _, r)| (i, r));
        let got = (
            found.checked,
            found.inconsistent,
            found.severe,
            found.overlap,
            worst,
        );
        assert_eq!(got, want);
    }

    /// Every figure is the one a list of all the ratios gives: a ball's exact distances spoiled
    /// by noise up to 40% (some samples inconsistent, some severe); on a grid against the
    /// feature transform's nearest samples (a grid has ties, each broken one way), scattered
    /// (positions jittered: no ties) against the nearest by a scan.
    #[test]
    fn the_separation_is_that_of_every_ratio() {
        let grid = Grid::new([9, 8, 7], DVec3::splat(-1.0), DVec3::splat(0.25)).expect("grid");
        let mut rng = rfta_geom::rng::Rng::new(3);
        let mut noisy = |p: DVec3| (p.length() - 0.7) * (1.0 + 0.4 * rng.next_f64());
        let values: Vec<f64> = (0..grid.len()).map(|i| noisy(grid.position(i))).collect();
        let ratio = |p: &[DVec3], v: &[f64], i: usize, j: usize| {
            (i, (v[i].abs() + v[j].abs()) / p[i].distance(p[j]))
        };
        let p = (0..grid.len())
            .map(|i| grid.position(i))
            .collect::<Vec<_>>();
        let mut on_grid = Vec::new();
        for negative in [true, false] {
            let marked: Vec<bool> = values
                .iter()
                .map(|&v| if negative { v > 0.0 } else { v < 0.0 })
                .collect();
            let nearest = grid.nearest_marked(&marked);
            on_grid.extend(
                (0..p.len())
                    .filter(|&i| {
                        if negative {
                            values[i] < 0.0
                        } else {
                            values[i] > 0.0
                        }
                    })
                    .map(|i| ratio(&p, &values, i, nearest[i] as usize)),
            );
        }
        agree(
            &SdfSamples::grid(grid, values.clone()).expect("samples"),
            &on_grid,
        );

        let mut jitter = rfta_geom::rng::Rng::new(8);
        let mut r = || jitter.next_f64() - 0.5;
        let q: Vec<DVec3> = p
            .iter()
            .map(|&x| x + 0.05 * DVec3::new(r(), r(), r()))
            .collect();
        let values: Vec<f64> = q.iter().map(|&x| noisy(x)).collect();
        let scan: Vec<(usize, f64)> = (0..q.len())
            .filter_map(|i| {
                let j = (0..q.len())
                    .filter(|&j| values[i] * values[j] < 0.0)
                    .min_by(|&a, &b| q[i].distance(q[a]).total_cmp(&q[i].distance(q[b])))?;
                Some(ratio(&q, &values, i, j))
            })
            .collect();
        agree(&SdfSamples::scattered(q, values).expect("samples"), &scan);

        let positive = SdfSamples::grid(grid, vec![1.0; grid.len()]).expect("samples");
        assert_eq!(measure(&positive), None);
    }
}
