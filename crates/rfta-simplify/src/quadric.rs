//! The quadric error of Garland and Heckbert ("Surface simplification using quadric error
//! metrics", SIGGRAPH 1997): the sum of squared distances to a set of planes, as
//! `x^T A x + 2 b^T x + c`.

use rfta_geom::glam::DVec3;

/// A sum of weighted squared distances to planes: `A` (symmetric, six entries), `b`, `c`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Quadric {
    /// `A`'s entries `xx, xy, xz, yy, yz, zz`.
    a: [f64; 6],
    b: DVec3,
    c: f64,
}

impl Quadric {
    /// `weight` times the squared distance to the plane through `point` with unit `normal`.
    pub(crate) fn plane(point: DVec3, normal: DVec3, weight: f64) -> Self {
        let n = normal;
        let d = -n.dot(point);
        let w = weight;
        Self {
            a: [
                w * n.x * n.x,
                w * n.x * n.y,
                w * n.x * n.z,
                w * n.y * n.y,
                w * n.y * n.z,
                w * n.z * n.z,
            ],
            b: w * d * n,
            c: w * d * d,
        }
    }

    /// The planes' total weight (`A`'s trace: each plane's `n n^T` has trace 1): the error over
    /// it is the weighted mean squared distance to the planes.
    pub(crate) fn weight(&self) -> f64 {
        self.a[0] + self.a[3] + self.a[5]
    }

    /// The quadric of both.
    pub(crate) fn add(&self, o: &Self) -> Self {
        let mut a = self.a;
        for (x, y) in a.iter_mut().zip(o.a) {
            *x += y;
        }
        Self {
            a,
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }

    fn times(&self, x: DVec3) -> DVec3 {
        let a = &self.a;
        DVec3::new(
            a[0] * x.x + a[1] * x.y + a[2] * x.z,
            a[1] * x.x + a[3] * x.y + a[4] * x.z,
            a[2] * x.x + a[4] * x.y + a[5] * x.z,
        )
    }

    /// The error at `x` (never negative).
    pub(crate) fn error(&self, x: DVec3) -> f64 {
        (x.dot(self.times(x)) + 2.0 * self.b.dot(x) + self.c).max(0.0)
    }

    /// The point minimizing the error plus `lambda |x - near|^2`, `lambda` a millionth of `A`'s
    /// mean eigenvalue: the quadric's minimizer where it has one, and along the directions it
    /// leaves free (a plane's two, a crease's one) the point nearest `near` (a Tikhonov-regularized
    /// solve, so that flat regions, where `A` is singular, need no special case). `None` only
    /// when `A` is zero or the solve is not finite.
    pub(crate) fn minimizer(&self, near: DVec3) -> Option<DVec3> {
        let a = &self.a;
        let trace = self.weight();
        if trace <= 0.0 || !trace.is_finite() {
            return None;
        }
        let lambda = 1e-6 * trace / 3.0;
        let m = [
            [a[0] + lambda, a[1], a[2]],
            [a[1], a[3] + lambda, a[4]],
            [a[2], a[4], a[5] + lambda],
        ];
        let rhs = lambda * near - self.b;
        let x = solve3(m, rhs)?;
        x.is_finite().then_some(x)
    }
}

/// `m x = r` by Cramer's rule (`m` symmetric positive definite here).
fn solve3(m: [[f64; 3]; 3], r: DVec3) -> Option<DVec3> {
    let c0 = DVec3::new(m[0][0], m[1][0], m[2][0]);
    let c1 = DVec3::new(m[0][1], m[1][1], m[2][1]);
    let c2 = DVec3::new(m[0][2], m[1][2], m[2][2]);
    let det = c0.dot(c1.cross(c2));
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    Some(DVec3::new(
        r.dot(c1.cross(c2)) / det,
        c0.dot(r.cross(c2)) / det,
        c0.dot(c1.cross(r)) / det,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_error_is_the_squared_distance() {
        let q = Quadric::plane(DVec3::new(0.0, 0.0, 2.0), DVec3::Z, 3.0);
        let e = q.error(DVec3::new(5.0, -1.0, 4.5));
        assert!((e - 3.0 * 2.5 * 2.5).abs() < 1e-12, "{e}");
    }

    #[test]
    fn the_weight_is_the_planes_total_whatever_their_normals() {
        let n = DVec3::new(1.0, -2.0, 0.5).normalize();
        let q = Quadric::plane(DVec3::ONE, n, 2.5).add(&Quadric::plane(DVec3::ZERO, DVec3::Y, 0.5));
        assert!((q.weight() - 3.0).abs() < 1e-12, "{}", q.weight());
    }

    #[test]
    fn three_planes_meet_at_their_corner() {
        let corner = DVec3::new(1.0, -2.0, 0.5);
        let q = Quadric::plane(corner, DVec3::X, 1.0)
            .add(&Quadric::plane(corner, DVec3::Y, 1.0))
            .add(&Quadric::plane(corner, DVec3::Z, 1.0));
        let x = q.minimizer(DVec3::ZERO).expect("a corner");
        assert!(x.distance(corner) < 1e-5, "{x}");
        assert!(q.error(x) < 1e-10);
    }

    #[test]
    fn a_plane_keeps_the_nearest_point_of_its_own() {
        // One plane z = 1: the minimizer is the foot of `near` on it.
        let q = Quadric::plane(DVec3::new(0.0, 0.0, 1.0), DVec3::Z, 1.0);
        let near = DVec3::new(0.3, -0.7, 5.0);
        let x = q.minimizer(near).expect("regularized");
        assert!(x.distance(DVec3::new(0.3, -0.7, 1.0)) < 1e-4, "{x}");
    }

    #[test]
    fn a_crease_keeps_the_nearest_point_on_its_line() {
        // Planes x = 0 and y = 0 meet along the z axis.
        let q = Quadric::plane(DVec3::ZERO, DVec3::X, 1.0).add(&Quadric::plane(
            DVec3::ZERO,
            DVec3::Y,
            1.0,
        ));
        let x = q.minimizer(DVec3::new(0.2, 0.1, 0.8)).expect("regularized");
        assert!(x.distance(DVec3::new(0.0, 0.0, 0.8)) < 1e-5, "{x}");
    }

    #[test]
    fn an_empty_quadric_has_no_minimizer() {
        assert!(Quadric::default().minimizer(DVec3::ONE).is_none());
    }
}
