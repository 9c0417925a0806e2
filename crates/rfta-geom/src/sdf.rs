//! Samples of a signed distance function: a regular grid or scattered points.

use glam::DVec3;

use crate::{Aabb, Error, Result, Sphere};

/// A regular grid of sample positions: `dims[0] x dims[1] x dims[2]` points, the point `(i, j, k)`
/// at `origin + (i, j, k) * spacing`.
///
/// Values are stored in C order with z fastest: the flat index of `(i, j, k)` is
/// `(i * dims[1] + j) * dims[2] + k`, the layout of a NumPy array of shape `dims` indexed
/// `S[i, j, k]`. A grid with `n` cells per axis has `n + 1` points per axis, like
/// `numpy.linspace(lo, hi, n + 1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    dims: [usize; 3],
    origin: DVec3,
    spacing: DVec3,
}

impl Grid {
    /// A grid from its point counts per axis, the position of point `(0, 0, 0)` and the spacing.
    ///
    /// # Errors
    /// [`Error::InvalidGrid`] if a count is zero, the total overflows, the origin is not finite
    /// or a spacing is not positive and finite.
    pub fn new(dims: [usize; 3], origin: DVec3, spacing: DVec3) -> Result<Self> {
        if dims.contains(&0) {
            return Err(Error::InvalidGrid(format!(
                "dimensions {dims:?} contain a zero"
            )));
        }
        if dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .is_none()
        {
            return Err(Error::InvalidGrid(format!(
                "dimensions {dims:?} overflow the address space"
            )));
        }
        if !origin.is_finite() {
            return Err(Error::InvalidGrid(format!("origin {origin} is not finite")));
        }
        if !(spacing.cmpgt(DVec3::ZERO).all() && spacing.is_finite()) {
            return Err(Error::InvalidGrid(format!(
                "spacing {spacing} must be positive and finite"
            )));
        }
        Ok(Self {
            dims,
            origin,
            spacing,
        })
    }

    /// A grid whose corner points are `min` and `max`: the spacing along an axis with `d > 1`
    /// points is `(max - min) / (d - 1)`, as `numpy.linspace(min, max, d)`.
    ///
    /// # Errors
    /// [`Error::InvalidGrid`] if the bounds are not finite, or `max <= min` along an axis with more
    /// than one point (inverted or zero-size bounds), or as [`Grid::new`].
    pub fn from_bounds(dims: [usize; 3], min: DVec3, max: DVec3) -> Result<Self> {
        if !(min.is_finite() && max.is_finite()) {
            return Err(Error::InvalidGrid(format!(
                "bounds [{min}, {max}] are not finite"
            )));
        }
        let mut spacing = DVec3::ONE;
        for axis in 0..3 {
            if dims[axis] > 1 {
                if max[axis] <= min[axis] {
                    return Err(Error::InvalidGrid(format!(
                        "bounds along axis {axis} are inverted or of zero size: min {} >= max {}",
                        min[axis], max[axis]
                    )));
                }
                spacing[axis] = (max[axis] - min[axis]) / (dims[axis] - 1) as f64;
            }
        }
        Self::new(dims, min, spacing)
    }

    /// The grid `linspace(lo, hi, n_cells + 1)` along each axis: the paper's "`n^3`" grid.
    ///
    /// # Errors
    /// As [`Grid::from_bounds`].
    pub fn cube(n_cells: usize, lo: f64, hi: f64) -> Result<Self> {
        let d = n_cells.saturating_add(1);
        Self::from_bounds([d; 3], DVec3::splat(lo), DVec3::splat(hi))
    }

    /// The grid whose points `positions` are, in any order, with the flat index of each
    /// position in it: how a grid passed as a list of points (numpy's `meshgrid` flattened, in
    /// any axis order) is recognised. `None` unless every position is a grid point (to 10^-6 of
    /// the spacing), each grid point appears exactly once, and every axis has at least 2 points.
    pub fn fit(positions: &[DVec3]) -> Option<(Self, Vec<usize>)> {
        let mut dims = [0; 3];
        let (mut origin, mut spacing) = (DVec3::ZERO, DVec3::ZERO);
        for a in 0..3 {
            let mut c: Vec<f64> = positions.iter().map(|p| p[a]).collect();
            if c.iter().any(|x| !x.is_finite()) {
                return None;
            }
            c.sort_by(f64::total_cmp);
            let (lo, hi) = (*c.first()?, *c.last()?);
            let merge = 1e-9 * (hi - lo).abs().max(f64::MIN_POSITIVE);
            c.dedup_by(|b, a| *b - *a <= merge);
            let n = c.len();
            if n < 2 {
                return None;
            }
            let h = (hi - lo) / (n - 1) as f64;
            if c.iter()
                .enumerate()
                .any(|(j, &x)| (x - (lo + j as f64 * h)).abs() > 1e-6 * h)
            {
                return None;
            }
            (dims[a], origin[a], spacing[a]) = (n, lo, h);
        }
        if dims.iter().try_fold(1usize, |t, &d| t.checked_mul(d)) != Some(positions.len()) {
            return None;
        }
        let grid = Self::new(dims, origin, spacing).ok()?;
        let mut seen = vec![false; positions.len()];
        let mut index = Vec::with_capacity(positions.len());
        for p in positions {
            let t = (*p - origin) / spacing;
            let ijk = t.round();
            if (t - ijk).abs().max_element() > 1e-6 {
                return None;
            }
            let i = grid.index(ijk.x as usize, ijk.y as usize, ijk.z as usize);
            if std::mem::replace(&mut seen[i], true) {
                return None;
            }
            index.push(i);
        }
        Some((grid, index))
    }

    /// Points per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Position of point `(0, 0, 0)`.
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Distance between neighbouring points along each axis.
    pub fn spacing(&self) -> DVec3 {
        self.spacing
    }

    /// Total number of points.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Whether the grid has no points (never true for a constructed grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of point `(i, j, k)` (C order, z fastest).
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (i * self.dims[1] + j) * self.dims[2] + k
    }

    /// The `(i, j, k)` of a flat index.
    pub fn ijk(&self, index: usize) -> [usize; 3] {
        let k = index % self.dims[2];
        let ij = index / self.dims[2];
        [ij / self.dims[1], ij % self.dims[1], k]
    }

    /// Position of the point with flat index `index`.
    pub fn position(&self, index: usize) -> DVec3 {
        let [i, j, k] = self.ijk(index);
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.spacing
    }

    /// The gradient of `values` (one per point, flat order) at point `index` by central
    /// differences, one-sided on the grid's faces; an axis with one point contributes 0.
    ///
    /// # Panics
    /// If `values` is shorter than the grid (a caller bug).
    pub fn central_difference(&self, values: &[f64], index: usize) -> DVec3 {
        let ijk = self.ijk(index);
        let mut grad = DVec3::ZERO;
        for a in 0..3 {
            let (mut lo, mut hi) = (ijk, ijk);
            lo[a] = lo[a].saturating_sub(1);
            hi[a] = (hi[a] + 1).min(self.dims[a] - 1);
            if hi[a] == lo[a] {
                continue;
            }
            let v = |q: [usize; 3]| values[self.index(q[0], q[1], q[2])];
            grad[a] = (v(hi) - v(lo)) / ((hi[a] - lo[a]) as f64 * self.spacing[a]);
        }
        grad
    }

    /// The box from the first to the last point.
    pub fn bounds(&self) -> Aabb {
        let last = DVec3::new(
            (self.dims[0] - 1) as f64,
            (self.dims[1] - 1) as f64,
            (self.dims[2] - 1) as f64,
        );
        Aabb::new(self.origin, self.origin + last * self.spacing)
    }
}

/// Where the samples are.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// On a regular grid.
    Grid(Grid),
    /// At arbitrary positions.
    Scattered(Vec<DVec3>),
}

/// Counts of negative (inside), zero and positive (outside) values.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SignBalance {
    /// Values `< 0`.
    pub negative: usize,
    /// Values `== 0`.
    pub zero: usize,
    /// Values `> 0`.
    pub positive: usize,
    /// Values that are NaN or infinite.
    pub non_finite: usize,
}

impl SignBalance {
    /// Counts the signs of `values`.
    pub fn of(values: &[f64]) -> Self {
        let mut b = Self::default();
        for &v in values {
            if !v.is_finite() {
                b.non_finite += 1;
            } else if v < 0.0 {
                b.negative += 1;
            } else if v > 0.0 {
                b.positive += 1;
            } else {
                b.zero += 1;
            }
        }
        b
    }
}

/// Samples `(p_i, s_i)` of a signed distance function, negative inside, validated on construction.
///
/// Every sample is finite, there are at least two, and the values describe a surface: some are
/// negative (inside) and some positive or exactly zero (outside, or on the surface).
#[derive(Debug, Clone, PartialEq)]
pub struct SdfSamples {
    layout: Layout,
    values: Vec<f64>,
    /// The spacing the caller states ([`SdfSamples::with_spacing`]), in place of the one the
    /// layout gives.
    stated_spacing: Option<f64>,
}

impl SdfSamples {
    /// The smallest number of samples accepted.
    pub(crate) const MIN_SAMPLES: usize = 2;

    /// Samples on a grid; `values[grid.index(i, j, k)]` is the value at point `(i, j, k)`.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] if `values.len() != grid.len()`, then as [`SdfSamples::scattered`].
    pub fn grid(grid: Grid, values: Vec<f64>) -> Result<Self> {
        if values.len() != grid.len() {
            return Err(Error::LengthMismatch {
                expected_what: "grid points",
                expected: grid.len(),
                found_what: "values",
                found: values.len(),
            });
        }
        validate_values(&values)?;
        Ok(Self {
            layout: Layout::Grid(grid),
            values,
            stated_spacing: None,
        })
    }

    /// Samples at scattered positions.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] if the lengths differ, [`Error::TooFewSamples`] for fewer than two,
    /// [`Error::NonFiniteValue`] or [`Error::NonFinitePosition`] naming the first bad sample,
    /// [`Error::NoSignChange`] when every value is zero,
    /// [`Error::ConflictingSamples`] when two samples share a position but not a value (exact
    /// duplicates are accepted).
    pub fn scattered(positions: Vec<DVec3>, values: Vec<f64>) -> Result<Self> {
        if values.len() != positions.len() {
            return Err(Error::LengthMismatch {
                expected_what: "positions",
                expected: positions.len(),
                found_what: "values",
                found: values.len(),
            });
        }
        if let Some((index, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(Error::NonFinitePosition {
                what: "sample",
                index,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        validate_values(&values)?;
        check_coincident(&positions, &values)?;
        Ok(Self {
            layout: Layout::Scattered(positions),
            values,
            stated_spacing: None,
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no samples (never true for constructed samples).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The SDF values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Where the samples are.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The grid, for gridded samples.
    pub fn as_grid(&self) -> Option<&Grid> {
        match &self.layout {
            Layout::Grid(g) => Some(g),
            Layout::Scattered(_) => None,
        }
    }

    /// Position of sample `index`.
    pub fn position(&self, index: usize) -> DVec3 {
        match &self.layout {
            Layout::Grid(g) => g.position(index),
            Layout::Scattered(p) => p[index],
        }
    }

    /// All positions, in sample order.
    pub fn positions(&self) -> Vec<DVec3> {
        match &self.layout {
            Layout::Grid(g) => (0..g.len()).map(|i| g.position(i)).collect(),
            Layout::Scattered(p) => p.clone(),
        }
    }

    /// Sample `index` as a sphere of radius `|s|`.
    pub fn sphere(&self, index: usize) -> Sphere {
        Sphere::new(self.position(index), self.values[index].abs())
    }

    /// Bounding box of the sample positions.
    pub fn bounds(&self) -> Aabb {
        match &self.layout {
            Layout::Grid(g) => g.bounds(),
            Layout::Scattered(p) => Aabb::from_points(p),
        }
    }

    /// These samples with the spacing `h` stated by the caller, for samples whose density varies
    /// by design (an adaptive sampler's: a coarse lattice far from the surface, a fine one near
    /// it), where the average over the box would describe neither.
    ///
    /// # Errors
    /// [`Error::InvalidSpacing`] unless `h` is positive and finite.
    pub fn with_spacing(mut self, h: f64) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::InvalidSpacing(h));
        }
        self.stated_spacing = Some(h);
        Ok(self)
    }

    /// The spacing stated with [`SdfSamples::with_spacing`], if any.
    pub fn stated_spacing(&self) -> Option<f64> {
        self.stated_spacing
    }

    /// The sample spacing `h` every margin and resolution in rfta is stated in: the one stated
    /// with [`SdfSamples::with_spacing`]; otherwise the grid spacing (its largest axis), or for
    /// scattered samples the side of a cube holding one sample on average over their bounding box
    /// (the spacing of a grid with as many samples in that box).
    pub fn spacing(&self) -> f64 {
        if let Some(h) = self.stated_spacing {
            return h;
        }
        match &self.layout {
            Layout::Grid(g) => g.spacing().max_element(),
            Layout::Scattered(_) => {
                let b = self.bounds();
                let e = (b.max - b.min).max(DVec3::splat(1e-300));
                crate::math::cbrt(e.x * e.y * e.z / self.len().max(1) as f64)
            }
        }
    }

    /// Counts of negative, zero and positive values.
    pub fn sign_balance(&self) -> SignBalance {
        SignBalance::of(&self.values)
    }
}

/// Samples at the same position must have the same value: sorts the indices by position (`-0.0`
/// and `0.0` alike) and compares neighbours in that order, naming the first conflict by index.
fn check_coincident(positions: &[DVec3], values: &[f64]) -> Result<()> {
    let key = |p: DVec3| (p + DVec3::ZERO).to_array().map(f64::to_bits);
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    order.sort_unstable_by_key(|&i| (key(positions[i as usize]), i));
    let mut conflict: Option<(usize, usize)> = None;
    for w in order.windows(2) {
        let (a, b) = (w[0] as usize, w[1] as usize);
        if key(positions[a]) == key(positions[b]) && values[a] != values[b] {
            let pair = (a.min(b), a.max(b));
            if conflict.is_none_or(|c| pair < c) {
                conflict = Some(pair);
            }
        }
    }
    match conflict {
        None => Ok(()),
        Some((first, second)) => {
            let p = positions[first];
            Err(Error::ConflictingSamples {
                first,
                second,
                x: p.x,
                y: p.y,
                z: p.z,
                first_value: values[first],
                second_value: values[second],
            })
        }
    }
}

fn validate_values(values: &[f64]) -> Result<()> {
    if values.len() < SdfSamples::MIN_SAMPLES {
        return Err(Error::TooFewSamples {
            found: values.len(),
            needed: SdfSamples::MIN_SAMPLES,
        });
    }
    if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(Error::NonFiniteValue { index, value });
    }
    let b = SignBalance::of(values);
    // Samples of one sign can still describe a surface: a thin shape between grid points has
    // no sample inside it, and its spheres leave the room where it is empty (Sellán et al. 2024
    // reconstruct such inputs). Only values that are all zero say nothing of either side.
    if b.negative == 0 && b.positive == 0 {
        return Err(Error::NoSignChange {
            n: values.len(),
            sign: "zero",
            min: 0.0,
            max: 0.0,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Central differences are exact for linear functions everywhere (one-sided on the
        /// faces too) and for quadratics inside; an axis of one point contributes 0.
        #[test]
        fn central_differences_of_linear_and_quadratic_functions(
            c in prop::array::uniform3(-3.0f64..3.0),
            index in 0usize..1000,
        ) {
            let grid = Grid::new([5, 7, 6], DVec3::new(-1.0, 0.5, 2.0), DVec3::new(0.3, 0.2, 0.7))
                .expect("grid");
            let i = index % grid.len();
            let at = |f: &dyn Fn(DVec3) -> f64| -> Vec<f64> {
                (0..grid.len()).map(|k| f(grid.position(k))).collect()
            };
            let lin = at(&|p| c[0] * p.x + c[1] * p.y + c[2] * p.z - 1.0);
            let g = grid.central_difference(&lin, i);
            prop_assert!((g - DVec3::from(c)).length() < 1e-9, "{g}");
            let quad = at(&|p| c[0] * p.x * p.x + c[1] * p.y * p.z);
            let [a, b, k] = grid.ijk(i);
            if a > 0 && a < 4 && b > 0 && b < 6 && k > 0 && k < 5 {
                let p = grid.position(i);
                let exact = DVec3::new(2.0 * c[0] * p.x, c[1] * p.z, c[1] * p.y);
                prop_assert!((grid.central_difference(&quad, i) - exact).length() < 1e-9);
            }
            let flat = Grid::new([3, 1, 2], DVec3::ZERO, DVec3::ONE).expect("grid");
            let v: Vec<f64> = (0..flat.len()).map(|k| flat.position(k).x * 2.0 + flat.position(k).z).collect();
            prop_assert_eq!(flat.central_difference(&v, 1), DVec3::new(2.0, 0.0, 1.0));
        }
    }

    /// A grid's spacing is its largest axis; scattered samples' that of a grid with as many
    /// samples in their box (three samples spanning a 2 x 3 x 4 box: the cube root of 24 / 3).
    #[test]
    fn the_spacing_of_grids_and_scattered_samples() {
        let g = Grid::new([3, 4, 5], DVec3::ZERO, DVec3::new(0.1, 0.3, 0.2)).expect("grid");
        let grid = SdfSamples::grid(g, vec![1.0; 60]).expect("samples");
        assert_eq!(grid.spacing(), 0.3);
        let positions = vec![
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(1.0, 3.0, 4.0),
        ];
        let scattered = SdfSamples::scattered(positions, vec![1.0, -1.0, 1.0]).expect("samples");
        assert!((scattered.spacing() - 2.0).abs() < 1e-15);
    }

    /// A grid's points, shuffled and in another axis order, are recognised as that grid, each
    /// with its own index; a point off the grid, a missing point or a repeated one is not a grid.
    #[test]
    fn fit_recognises_a_grid_in_any_order() {
        let g = Grid::from_bounds(
            [4, 3, 5],
            DVec3::new(-1.0, 0.0, 2.0),
            DVec3::new(0.5, 1.0, 3.0),
        )
        .expect("valid");
        let mut rng = crate::rng::Rng::new(7);
        let mut order: Vec<usize> = (0..g.len()).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.below(i as u64 + 1) as usize);
        }
        let points: Vec<DVec3> = order.iter().map(|&i| g.position(i)).collect();
        let (fit, index) = Grid::fit(&points).expect("a grid");
        assert_eq!(fit.dims(), g.dims());
        assert!((fit.origin() - g.origin()).abs().max_element() < 1e-12);
        assert!((fit.spacing() - g.spacing()).abs().max_element() < 1e-12);
        assert_eq!(index, order);

        let mut off = points.clone();
        off[5].x += 0.3 * g.spacing().x;
        assert!(Grid::fit(&off).is_none());
        assert!(Grid::fit(&points[1..]).is_none());
        let mut repeated = points.clone();
        repeated[0] = repeated[1];
        assert!(Grid::fit(&repeated).is_none());
        assert!(Grid::fit(&[DVec3::ZERO; 1]).is_none());
    }

    #[test]
    fn grid_layout_is_c_order_z_fastest_like_numpy_linspace() {
        let g = Grid::cube(2, -1.0, 1.0).expect("valid");
        assert_eq!(g.dims(), [3, 3, 3]);
        assert_eq!(g.index(0, 0, 1), 1);
        assert_eq!(g.index(1, 0, 0), 9);
        assert_eq!(g.position(g.index(2, 1, 0)), DVec3::new(1.0, 0.0, -1.0));
        assert_eq!(g.ijk(g.index(2, 1, 0)), [2, 1, 0]);
        assert_eq!(g.bounds(), Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)));
    }

    #[test]
    fn each_bad_input_gets_its_own_error() {
        let g = Grid::cube(1, 0.0, 1.0).expect("valid");
        let ok = vec![-1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        assert!(SdfSamples::grid(g, ok.clone()).is_ok());
        assert!(matches!(
            SdfSamples::grid(g, vec![1.0; 7]),
            Err(Error::LengthMismatch {
                expected: 8,
                found: 7,
                ..
            })
        ));
        let mut nan = ok.clone();
        nan[5] = f64::NAN;
        assert!(matches!(
            SdfSamples::grid(g, nan),
            Err(Error::NonFiniteValue { index: 5, .. })
        ));
        let mut inf = ok.clone();
        inf[3] = f64::INFINITY;
        assert!(matches!(
            SdfSamples::grid(g, inf),
            Err(Error::NonFiniteValue { index: 3, .. })
        ));
        // One sign can still describe a thin shape between the samples; the pipeline decides
        // whether their spheres leave room for one.
        assert!(SdfSamples::grid(g, vec![0.5; 8]).is_ok());
        assert!(SdfSamples::grid(g, vec![-0.5; 8]).is_ok());
        let mut zero = vec![0.5; 8];
        zero[0] = 0.0;
        assert!(SdfSamples::grid(g, zero).is_ok());
        assert!(matches!(
            SdfSamples::grid(g, vec![0.0; 8]),
            Err(Error::NoSignChange { sign: "zero", .. })
        ));
        assert!(matches!(
            SdfSamples::scattered(vec![DVec3::ZERO], vec![-1.0]),
            Err(Error::TooFewSamples {
                found: 1,
                needed: 2
            })
        ));
        assert!(matches!(
            SdfSamples::scattered(
                vec![DVec3::ZERO, DVec3::new(0.0, f64::NAN, 0.0)],
                vec![-1.0, 1.0]
            ),
            Err(Error::NonFinitePosition { index: 1, .. })
        ));
        assert!(matches!(
            SdfSamples::scattered(vec![DVec3::ZERO; 3], vec![-1.0, 1.0]),
            Err(Error::LengthMismatch {
                expected: 3,
                found: 2,
                ..
            })
        ));
    }

    #[test]
    fn coincident_samples_must_agree() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, -0.0, 0.0), DVec3::X];
        // Exact duplicates (also -0.0 against 0.0) are fine.
        assert!(SdfSamples::scattered(p.clone(), vec![-0.5, 0.5, -0.5, 0.5]).is_ok());
        let err = SdfSamples::scattered(p, vec![-0.5, 0.5, -0.5, 0.25]);
        assert!(
            matches!(
                err,
                Err(Error::ConflictingSamples {
                    first: 1,
                    second: 3,
                    ..
                })
            ),
            "{err:?}"
        );
    }

    #[test]
    fn grids_reject_bad_shapes() {
        assert!(Grid::new([0, 2, 2], DVec3::ZERO, DVec3::ONE).is_err());
        assert!(Grid::new([2, 2, 2], DVec3::ZERO, DVec3::new(1.0, 0.0, 1.0)).is_err());
        assert!(Grid::new([2, 2, 2], DVec3::NAN, DVec3::ONE).is_err());
        assert!(Grid::from_bounds([2, 2, 2], DVec3::ONE, DVec3::ZERO).is_err());
        assert!(Grid::from_bounds([2, 2, 2], DVec3::ONE, DVec3::ONE).is_err());
        assert!(Grid::new([usize::MAX, 2, 2], DVec3::ZERO, DVec3::ONE).is_err());
    }
}
