//! [`CubicField`]: a smooth function through a grid's values (tricubic Catmull-Rom), its gradient,
//! and the nearest point of its zero set along the gradient (Newton's method).
//!
//! ```
//! use rfta_geom::glam::DVec3;
//! use rfta_geom::{CubicField, Grid};
//!
//! // A sphere's signed distance on a 17^3 grid; the field's zero set lies on the sphere.
//! let grid = Grid::cube(16, -1.0, 1.0).unwrap();
//! let values: Vec<f64> = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let field = CubicField::new(&grid, &values).unwrap();
//! let (point, normal) = field.zero_near(DVec3::new(0.3, 0.1, 0.0), 0.5).unwrap();
//! assert!((point.length() - 0.5).abs() < 1e-3);
//! assert!(normal.dot(point.normalize()) > 0.999);
//! ```

use glam::DVec3;

use crate::Grid;

/// Newton steps [`CubicField::zero_near`] takes at most.
const NEWTON_STEPS: usize = 12;

/// A step longer than this many grid spacings is cut to it: far from the zero set the linear
/// model the step trusts is poor.
const MAX_STEP: f64 = 0.5;

/// [`CubicField::zero_near`] stops once the value is below this many grid spacings.
const ZERO: f64 = 1e-6;

/// The tricubic Catmull-Rom interpolant of values on a [`Grid`]: it passes through every value,
/// is continuous with a continuous gradient, and reproduces polynomials of degree two in each
/// axis (Catmull and Rom, "A class of local interpolating splines", 1974; Keys, "Cubic
/// convolution interpolation for digital image processing", IEEE TASSP 29, 1981). Beyond the
/// outermost points each line is continued linearly, so linear functions are reproduced up to
/// the box's faces.
#[derive(Debug, Clone, Copy)]
pub struct CubicField<'a> {
    grid: &'a Grid,
    values: &'a [f64],
}

impl<'a> CubicField<'a> {
    /// The field through `values` on `grid` (`values[grid.index(i, j, k)]` at point `(i, j, k)`);
    /// `None` unless there is one value per point and at least two points along every axis.
    pub fn new(grid: &'a Grid, values: &'a [f64]) -> Option<Self> {
        (values.len() == grid.len() && grid.dims().iter().all(|&n| n >= 2))
            .then_some(Self { grid, values })
    }

    /// The grid the field is defined on.
    pub fn grid(&self) -> &Grid {
        self.grid
    }

    /// The value at `p` and its gradient; `p` outside the grid's box is taken at the nearest
    /// point of the box.
    pub fn value_gradient(&self, p: DVec3) -> (f64, DVec3) {
        let dims = self.grid.dims();
        let u = ((p - self.grid.origin()) / self.grid.spacing()).to_array();
        let mut base = [0i64; 3];
        let mut w = [[0.0; 4]; 3];
        let mut dw = [[0.0; 4]; 3];
        for a in 0..3 {
            let last = (dims[a] - 1) as f64;
            let x = u[a].clamp(0.0, last);
            let cell = x.floor().min(last - 1.0);
            base[a] = cell as i64 - 1;
            (w[a], dw[a]) = weights(x - cell);
        }
        let spacing = self.grid.spacing();
        let (mut value, mut grad) = (0.0, DVec3::ZERO);
        for (a, (wa, da)) in w[0].iter().zip(&dw[0]).enumerate() {
            for (b, (wb, db)) in w[1].iter().zip(&dw[1]).enumerate() {
                for (c, (wc, dc)) in w[2].iter().zip(&dw[2]).enumerate() {
                    let v = self.at([base[0] + a as i64, base[1] + b as i64, base[2] + c as i64]);
                    value += wa * wb * wc * v;
                    grad += DVec3::new(da * wb * wc, wa * db * wc, wa * wb * dc) * v;
                }
            }
        }
        (value, grad / spacing)
    }

    /// The point of the zero set that Newton's method along the gradient reaches from `p`, and
    /// the unit gradient there (the outward normal when values are negative inside), if it gets
    /// within `reach` of `p` and stays in the grid's box. Each step `-f grad f / |grad f|^2` is
    /// cut to half a grid spacing.
    pub fn zero_near(&self, p: DVec3, reach: f64) -> Option<(DVec3, DVec3)> {
        let h = self.grid.spacing().min_element();
        let bounds = self.grid.bounds();
        let mut q = p;
        for _ in 0..NEWTON_STEPS {
            let (f, g) = self.value_gradient(q);
            let g2 = g.length_squared();
            if !(g2 > 0.0 && f.is_finite()) {
                return None;
            }
            if f.abs() < ZERO * h {
                let inside = q.cmpge(bounds.min).all() && q.cmple(bounds.max).all();
                return (inside && q.distance(p) <= reach).then(|| (q, g / g2.sqrt()));
            }
            let step = g * (-f / g2);
            q += step * (MAX_STEP * h / step.length()).min(1.0);
        }
        None
    }

    /// The value at grid point `ijk`, each index continued linearly one point beyond each end.
    fn at(&self, ijk: [i64; 3]) -> f64 {
        let dims = self.grid.dims();
        for a in 0..3 {
            let n = dims[a] as i64;
            let (inner, next) = match ijk[a] {
                -1 => (0, 1),
                i if i == n => (n - 1, n - 2),
                _ => continue,
            };
            let (mut near, mut far) = (ijk, ijk);
            near[a] = inner;
            far[a] = next;
            return 2.0 * self.at(near) - self.at(far);
        }
        let [i, j, k] = ijk.map(|i| i as usize);
        self.values[self.grid.index(i, j, k)]
    }
}

/// The Catmull-Rom weights of the four points around `t` in `[0, 1]` (points at `-1, 0, 1, 2`)
/// and their derivatives in `t`.
fn weights(t: f64) -> ([f64; 4], [f64; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    (
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ],
        [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn field_of(grid: &Grid, f: impl Fn(DVec3) -> f64) -> Vec<f64> {
        (0..grid.len()).map(|i| f(grid.position(i))).collect()
    }

    fn grid() -> Grid {
        Grid::new(
            [7, 8, 9],
            DVec3::new(-0.3, 0.2, -1.0),
            DVec3::new(0.2, 0.25, 0.3),
        )
        .expect("test")
    }

    #[test]
    fn passes_through_every_value() {
        let grid = grid();
        let values = field_of(&grid, |p| (3.0 * p.x).sin() * p.y + p.z * p.z * p.x);
        let field = CubicField::new(&grid, &values).expect("test");
        for (i, &value) in values.iter().enumerate() {
            let (v, _) = field.value_gradient(grid.position(i));
            assert!((v - value).abs() < 1e-12, "{v} against {value}");
        }
    }

    #[test]
    fn rejects_a_mismatch_and_a_flat_axis() {
        let grid = grid();
        assert!(CubicField::new(&grid, &[0.0; 3]).is_none());
        let flat = Grid::new([4, 1, 4], DVec3::ZERO, DVec3::ONE).expect("test");
        assert!(CubicField::new(&flat, &[0.0; 16]).is_none());
    }

    proptest! {
        /// Catmull-Rom reproduces each axis' quadratics inside (products of them too): value
        /// and gradient of `q(x) q(y) q(z)` at any point at least a cell from the faces, and
        /// linear functions everywhere (the continuation beyond the faces is linear).
        #[test]
        fn reproduces_quadratics_inside_and_linear_functions_everywhere(
            c in prop::array::uniform3(-2.0f64..2.0),
            t in prop::array::uniform3(0.0f64..1.0),
        ) {
            let grid = grid();
            let b = grid.bounds();
            let quad = |p: DVec3| (1.0 + c[0] * p.x * p.x) * (c[1] + p.y) * (p.z * p.z - c[2]);
            let quad_grad = |p: DVec3| DVec3::new(
                2.0 * c[0] * p.x * (c[1] + p.y) * (p.z * p.z - c[2]),
                (1.0 + c[0] * p.x * p.x) * (p.z * p.z - c[2]),
                (1.0 + c[0] * p.x * p.x) * (c[1] + p.y) * 2.0 * p.z,
            );
            let values = field_of(&grid, quad);
            let field = CubicField::new(&grid, &values).expect("test");
            let inner = DVec3::from(t) * (b.max - b.min - 2.0 * grid.spacing()) + b.min + grid.spacing();
            let (v, g) = field.value_gradient(inner);
            prop_assert!((v - quad(inner)).abs() < 1e-9);
            prop_assert!((g - quad_grad(inner)).length() < 1e-8);
            let lin = |p: DVec3| c[0] * p.x - c[1] * p.y + c[2] * p.z + 0.5;
            let values = field_of(&grid, lin);
            let field = CubicField::new(&grid, &values).expect("test");
            let anywhere = DVec3::from(t) * (b.max - b.min) + b.min;
            let (v, g) = field.value_gradient(anywhere);
            prop_assert!((v - lin(anywhere)).abs() < 1e-9);
            prop_assert!((g - DVec3::new(c[0], -c[1], c[2])).length() < 1e-9);
        }

        /// The gradient is the value's derivative: central differences agree.
        #[test]
        fn gradient_is_the_derivative(t in prop::array::uniform3(0.0f64..1.0)) {
            let grid = grid();
            let values = field_of(&grid, |p| (2.0 * p.x + p.y).sin() * (p.z - 0.3).cos() + p.x * p.y);
            let field = CubicField::new(&grid, &values).expect("test");
            let b = grid.bounds();
            let p = DVec3::from(t) * (b.max - b.min) * 0.98 + b.min + 0.01 * (b.max - b.min);
            let (_, g) = field.value_gradient(p);
            let e = 1e-6;
            for a in 0..3 {
                let mut d = DVec3::ZERO;
                d[a] = e;
                let fd = (field.value_gradient(p + d).0 - field.value_gradient(p - d).0) / (2.0 * e);
                prop_assert!((fd - g[a]).abs() < 1e-5, "axis {a}: {fd} against {}", g[a]);
            }
        }

        /// Newton reaches a plane's zero set at the foot of the perpendicular (the field is
        /// linear, so one step lands exactly, cut steps walk straight to it).
        #[test]
        fn zero_near_finds_a_planes_foot(
            n in prop::array::uniform3(-1.0f64..1.0),
            t in prop::array::uniform3(0.3f64..0.7),
        ) {
            let n = DVec3::from(n);
            prop_assume!(n.length() > 0.1);
            let n = n.normalize();
            let grid = Grid::cube(10, -1.0, 1.0).expect("test");
            let values = field_of(&grid, |p| n.dot(p) - 0.05);
            let field = CubicField::new(&grid, &values).expect("test");
            let p = DVec3::from(t) * 1.2 - 0.6;
            let foot = p - n * (n.dot(p) - 0.05);
            let (q, normal) = field.zero_near(p, 2.0).expect("test");
            prop_assert!(q.distance(foot) < 1e-5, "{q} against {foot}");
            prop_assert!(normal.distance(n) < 1e-9);
            let far = (p.distance(foot) > 0.01).then(|| field.zero_near(p, 0.5 * p.distance(foot)));
            prop_assert!(far.is_none_or(|found| found.is_none()), "beyond reach");
        }
    }
}
