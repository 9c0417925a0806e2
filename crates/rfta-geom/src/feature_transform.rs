//! The exact Euclidean feature transform on a grid: for every point, a nearest marked point.

use crate::Grid;

/// No marked point (in [`Grid::nearest_marked`]'s answer).
pub const NONE: u32 = u32::MAX;

impl Grid {
    /// For every point of the grid (flat order), the index of a marked point nearest to it in
    /// Euclidean distance (the grid's spacing per axis counted), or [`NONE`] when nothing is
    /// marked. Among equally near marked points the answer is one of them, always the same one.
    ///
    /// Exact, in `O(len)` time: the squared distance separates by axis, so three passes of the
    /// one-dimensional transform (the lower envelope of the parabolas `w^2 (q - p)^2 + f(p)`),
    /// each carrying the nearest point's index, give the nearest point in 3D (Felzenszwalb and
    /// Huttenlocher, "Distance transforms of sampled functions", Theory of Computing 8, 2012).
    ///
    /// # Panics
    /// If `marked.len() != self.len()` (a caller bug).
    pub fn nearest_marked(&self, marked: &[bool]) -> Vec<u32> {
        assert_eq!(marked.len(), self.len(), "one mark per grid point");
        let dims = self.dims();
        // The nearest point does not change with the unit of length: measured in the largest
        // spacing, no squared distance overflows (spacings of 1e155) or underflows (1e-200).
        let spacing = (self.spacing() / self.spacing().max_element()).to_array();
        let mut dist: Vec<f64> = marked
            .iter()
            .map(|&m| if m { 0.0 } else { f64::INFINITY })
            .collect();
        let mut feature: Vec<u32> = (0..marked.len())
            .map(|i| if marked[i] { i as u32 } else { NONE })
            .collect();
        // Flat index = (i * ny + j) * nz + k: the stride of each axis.
        let strides = [dims[1] * dims[2], dims[2], 1];
        let mut line = Envelope::default();
        for axis in 0..3 {
            let n = dims[axis];
            let stride = strides[axis];
            let w2 = (spacing[axis] * spacing[axis]).max(f64::MIN_POSITIVE);
            // Every line along `axis`: its first point runs over the other two axes.
            let (a, b) = match axis {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            for u in 0..dims[a] {
                for v in 0..dims[b] {
                    let start = u * strides[a] + v * strides[b];
                    line.run(&mut dist, &mut feature, start, stride, n, w2);
                }
            }
        }
        feature
    }
}

/// Scratch space of the one-dimensional transform.
#[derive(Default)]
struct Envelope {
    /// Positions of the parabolas of the lower envelope.
    v: Vec<usize>,
    /// Where each parabola of the envelope starts to be the lowest.
    z: Vec<f64>,
    f: Vec<f64>,
    feat: Vec<u32>,
}

impl Envelope {
    /// Transforms the `n` points `start + q stride` of `dist` and `feature` in place.
    fn run(
        &mut self,
        dist: &mut [f64],
        feature: &mut [u32],
        start: usize,
        stride: usize,
        n: usize,
        w2: f64,
    ) {
        self.f.clear();
        self.feat.clear();
        for q in 0..n {
            self.f.push(dist[start + q * stride]);
            self.feat.push(feature[start + q * stride]);
        }
        self.v.clear();
        self.z.clear();
        let f = &self.f;
        // Where the parabola at q starts to lie below the one at p (p < q).
        let cross = |p: usize, q: usize| {
            let (pf, qf) = (p as f64, q as f64);
            ((f[q] + w2 * qf * qf) - (f[p] + w2 * pf * pf)) / (2.0 * w2 * (qf - pf))
        };
        for q in (0..n).filter(|&q| f[q].is_finite()) {
            loop {
                let Some(&last) = self.v.last() else {
                    self.v.push(q);
                    self.z.push(f64::NEG_INFINITY);
                    break;
                };
                let s = cross(last, q);
                if s <= *self.z.last().unwrap_or(&f64::NEG_INFINITY) {
                    self.v.pop();
                    self.z.pop();
                } else {
                    self.v.push(q);
                    self.z.push(s);
                    break;
                }
            }
        }
        if self.v.is_empty() {
            return;
        }
        let mut k = 0;
        for q in 0..n {
            while k + 1 < self.v.len() && self.z[k + 1] < q as f64 {
                k += 1;
            }
            let p = self.v[k];
            let d = q as f64 - p as f64;
            dist[start + q * stride] = w2 * d * d + f[p];
            feature[start + q * stride] = self.feat[p];
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn the_nearest_marked_point_is_as_near_as_brute_force_finds(
            nx in 1usize..9, ny in 1usize..9, nz in 1usize..9,
            hx in 0.1f64..2.0, hy in 0.1f64..2.0, hz in 0.1f64..2.0,
            seed in 0u64..1000, density in 0.0f64..0.6,
        ) {
            let grid = Grid::new([nx, ny, nz], DVec3::ZERO, DVec3::new(hx, hy, hz)).expect("grid");
            let mut rng = crate::rng::Rng::new(seed);
            let marked: Vec<bool> = (0..grid.len()).map(|_| rng.next_f64() < density).collect();
            let nearest = grid.nearest_marked(&marked);
            for (i, &found) in nearest.iter().enumerate() {
                let p = grid.position(i);
                let brute = (0..grid.len())
                    .filter(|&j| marked[j])
                    .map(|j| p.distance_squared(grid.position(j)))
                    .fold(f64::INFINITY, f64::min);
                if brute.is_infinite() {
                    prop_assert_eq!(found, NONE);
                } else {
                    let j = found as usize;
                    prop_assert!(marked[j]);
                    let d = p.distance_squared(grid.position(j));
                    prop_assert!((d - brute).abs() <= 1e-9 * brute.max(1.0), "{} vs {}", d, brute);
                }
            }
        }
    }

    /// Spacings whose squares overflow or underflow give the answers of the same grid at unit
    /// spacing (D3 of the hostile test: a grid over 1e155 wide panicked the input check).
    #[test]
    fn the_answer_does_not_depend_on_the_scale() {
        let marks = |n: usize| {
            (0..n)
                .map(|i| i % 7 == 3 || i % 11 == 0)
                .collect::<Vec<_>>()
        };
        let unit = Grid::new([5, 6, 7], DVec3::ZERO, DVec3::new(1.0, 0.5, 0.75)).expect("grid");
        let expected = unit.nearest_marked(&marks(unit.len()));
        for scale in [1e155, 1e300, 1e-200, 1e-310] {
            let grid = Grid::new([5, 6, 7], DVec3::ZERO, unit.spacing() * scale).expect("grid");
            assert_eq!(
                grid.nearest_marked(&marks(grid.len())),
                expected,
                "scale {scale}"
            );
        }
    }

    #[test]
    fn a_single_mark_is_everyones_nearest_and_none_marked_is_none() {
        let grid = Grid::cube(4, -1.0, 1.0).expect("grid");
        let mut marked = vec![false; grid.len()];
        assert!(grid.nearest_marked(&marked).iter().all(|&j| j == NONE));
        marked[37] = true;
        assert!(grid.nearest_marked(&marked).iter().all(|&j| j == 37));
    }
}
