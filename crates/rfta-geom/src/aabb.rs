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

    /// Whether the two closed boxes share a point.
    pub fn overlaps(&self, other: &Self) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// Whether `p` is in the closed box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The smallest `f32` box that holds this box: corners rounded outwards, for `f32`
    /// structures (GPU buffers, obvhs) that must stay conservative.
    pub fn to_f32_outward(&self) -> (glam::Vec3, glam::Vec3) {
        use crate::math::{f32_at_least as up, f32_at_most as down};
        (
            glam::Vec3::new(down(self.min.x), down(self.min.y), down(self.min.z)),
            glam::Vec3::new(up(self.max.x), up(self.max.y), up(self.max.z)),
        )
    }

    /// Squared distance from `p` to the box (zero inside).
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_boxes_hold_their_f64_boxes() {
        for (lo, hi) in [
            (0.1, 0.7),
            (-1e-9, 1e-9),
            (-3.3, -1.1),
            (1e20, 1.000001e20),
            (0.0, 0.0),
        ] {
            let b = Aabb::new(DVec3::splat(lo), DVec3::splat(hi));
            let (flo, fhi) = b.to_f32_outward();
            assert!(
                (flo.x as f64) <= lo && (fhi.x as f64) >= hi,
                "{lo} {hi} -> {flo} {fhi}"
            );
        }
    }
}
