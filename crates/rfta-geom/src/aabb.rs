//! Axis-aligned bounding boxes.

use glam::DVec3;

/// An axis-aligned box `[min, max]`.
///
/// The empty box ([`Aabb::EMPTY`]) has `min = +inf`, `max = -inf`, so that growing it by any
/// point gives that point's box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box, the identity of [`Aabb::union`].
    pub const EMPTY: Self = Self {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// A box from its corners.
    pub const fn new(min: DVec3, max: DVec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding every point (the empty box for no points).
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(*p))
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// This box grown to hold `p`.
    pub fn grow(self, p: DVec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box holding both boxes.
    pub fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The box grown by `pad` on every side.
    pub fn padded(self, pad: f64) -> Self {
        Self {
            min: self.min - DVec3::splat(pad),
            max: self.max + DVec3::splat(pad),
        }
    }

    /// Side lengths (zero for the empty box).
    pub fn extent(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The longest side length.
    pub fn longest_side(&self) -> f64 {
        self.extent().max_element()
    }

    /// The centre.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Whether `p` is in the closed box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Squared distance from `p` to the box (zero inside).
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }
}
