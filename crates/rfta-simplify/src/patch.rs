//! The part of the surface one collapse changes, as a judge sees it.

use rfta_geom::glam::DVec3;
use rfta_geom::kernels::{closest_point_on_triangle, solid_angle};

/// The faces a collapse replaces and the faces that replace them, consistently oriented: both
/// fans span the same boundary loop, so together (`after` turned over) they bound the region the
/// surface sweeps through.
#[derive(Debug, Clone, Copy)]
pub struct Patch<'a> {
    /// The faces before the collapse.
    pub before: &'a [[DVec3; 3]],
    /// The faces after it (two fewer).
    pub after: &'a [[DVec3; 3]],
}

impl Patch<'_> {
    /// Whether `p` lies in the region between `before` and `after`, i.e. whether the collapse
    /// moves the surface across `p` (so that `p` changes side): the winding number of the closed
    /// surface `before` + reversed `after` at `p` (van Oosterom and Strackee's solid angles) is
    /// nonzero. Points on either fan have no defined answer.
    pub fn sweeps(&self, p: DVec3) -> bool {
        let omega = |faces: &[[DVec3; 3]]| -> f64 {
            faces.iter().map(|t| solid_angle(p, t[0], t[1], t[2])).sum()
        };
        let winding = (omega(self.before) - omega(self.after)) / (4.0 * std::f64::consts::PI);
        winding.abs() > 0.5
    }

    /// The distance from `p` to the faces before.
    pub fn distance_before(&self, p: DVec3) -> f64 {
        distance(self.before, p)
    }

    /// The distance from `p` to the faces after.
    pub fn distance_after(&self, p: DVec3) -> f64 {
        distance(self.after, p)
    }

    /// Whether some face after comes closer to `p` than `d` (cheaper than
    /// [`Patch::distance_after`] where most faces are far: each face's bounding box first).
    pub fn after_within(&self, p: DVec3, d: f64) -> bool {
        let d2 = d * d;
        self.after.iter().any(|t| {
            let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
            p.distance_squared(p.clamp(lo, hi)) < d2
                && p.distance_squared(closest_point_on_triangle(p, t[0], t[1], t[2]).0) < d2
        })
    }

    /// The centre and radius of a ball holding both fans.
    pub fn bounding_ball(&self) -> (DVec3, f64) {
        let corners = || self.before.iter().chain(self.after).flatten();
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &c in corners() {
            lo = lo.min(c);
            hi = hi.max(c);
        }
        let centre = 0.5 * (lo + hi);
        let radius = corners()
            .map(|c| c.distance_squared(centre))
            .fold(0.0, f64::max)
            .sqrt();
        (centre, radius)
    }
}

fn distance(faces: &[[DVec3; 3]], p: DVec3) -> f64 {
    faces
        .iter()
        .map(|t| p.distance_squared(closest_point_on_triangle(p, t[0], t[1], t[2]).0))
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square pyramid's four sides (apex up) against its base's two triangles.
    fn pyramid() -> (Vec<[DVec3; 3]>, Vec<[DVec3; 3]>) {
        let c = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
        ];
        let apex = DVec3::new(0.0, 0.0, 1.0);
        let before = (0..4).map(|i| [c[i], c[(i + 1) % 4], apex]).collect();
        let after = vec![[c[0], c[1], c[2]], [c[0], c[2], c[3]]];
        (before, after)
    }

    #[test]
    fn a_point_under_the_roof_is_swept_one_outside_is_not() {
        let (before, after) = pyramid();
        let patch = Patch {
            before: &before,
            after: &after,
        };
        assert!(patch.sweeps(DVec3::new(0.1, 0.2, 0.3)));
        assert!(!patch.sweeps(DVec3::new(0.1, 0.2, -0.3)));
        assert!(!patch.sweeps(DVec3::new(0.1, 0.2, 1.3)));
        assert!(!patch.sweeps(DVec3::new(2.0, 0.0, 0.3)));
    }

    #[test]
    fn distances_to_each_fan() {
        let (before, after) = pyramid();
        let patch = Patch {
            before: &before,
            after: &after,
        };
        let p = DVec3::new(0.0, 0.0, 2.0);
        assert!((patch.distance_before(p) - 1.0).abs() < 1e-12);
        assert!((patch.distance_after(p) - 2.0).abs() < 1e-12);
        assert!(patch.after_within(p, 2.0 + 1e-9) && !patch.after_within(p, 2.0 - 1e-9));
        let (centre, radius) = patch.bounding_ball();
        assert!(
            before
                .iter()
                .flatten()
                .all(|c| c.distance(centre) <= radius + 1e-12)
        );
    }
}
