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

/// Spheres read by index: a slice of them, or a set that works each one out when asked (an SDF
/// grid's spheres from its values, without 32 bytes a sample for a copy).
pub trait SphereSet: Sync {
    /// The number of spheres.
    fn len(&self) -> usize;

    /// Sphere `i`, for `i < self.len()` (a caller bug otherwise: it may panic).
    fn sphere(&self, i: usize) -> Sphere;

    /// The radius of sphere `i` alone (a set that works spheres out may find it sooner).
    fn radius(&self, i: usize) -> f64 {
        self.sphere(i).radius
    }

    /// Whether the set holds no sphere.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether sphere `i` may own tangency points: every sphere, unless the set keeps some as
    /// constraints only (the pipeline's owner band on scattered samples).
    fn owns(&self, i: usize) -> bool {
        let _ = i;
        true
    }
}

impl SphereSet for [Sphere] {
    fn len(&self) -> usize {
        <[Sphere]>::len(self)
    }

    fn sphere(&self, i: usize) -> Sphere {
        self[i]
    }
}

impl SphereSet for Vec<Sphere> {
    fn len(&self) -> usize {
        Vec::len(self)
    }

    fn sphere(&self, i: usize) -> Sphere {
        self[i]
    }
}

impl<const N: usize> SphereSet for [Sphere; N] {
    fn len(&self) -> usize {
        N
    }

    fn sphere(&self, i: usize) -> Sphere {
        self[i]
    }
}
