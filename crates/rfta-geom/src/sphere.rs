//! Spheres.

use glam::DVec3;

use crate::Aabb;

/// A sphere with centre `center` and radius `radius >= 0`.
///
/// An SDF sample `(p, s)` is the sphere `Sphere::new(p, s.abs())`: the surface touches it
/// without entering it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// The centre.
    pub center: DVec3,
    /// The radius (non-negative).
    pub radius: f64,
}

impl Sphere {
    /// A sphere from its centre and radius.
    pub const fn new(center: DVec3, radius: f64) -> Self {
        Self { center, radius }
    }

    /// Signed distance from `x` to the sphere's surface: negative inside, positive outside.
    pub fn signed_distance(&self, x: DVec3) -> f64 {
        (x - self.center).length() - self.radius
    }

    /// Whether `x` lies strictly deeper than `tol` inside the sphere (`|x - c| - r < -tol`).
    pub fn contains(&self, x: DVec3, tol: f64) -> bool {
        self.signed_distance(x) < -tol
    }

    /// The sphere's bounding box.
    pub fn aabb(&self) -> Aabb {
        let r = DVec3::splat(self.radius);
        Aabb::new(self.center - r, self.center + r)
    }
}
