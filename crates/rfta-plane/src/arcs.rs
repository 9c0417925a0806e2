//! Tangency points on circles (the paper's §4 in 2D): each sample is a circle the curve touches
//! without entering, and a point may lie only on the part of its circle that no other circle
//! covers.
//!
//! In the plane that part is a handful of arcs, computed exactly once per circle from the circles
//! that cross it (the paper's 2D rule: pairs of circles meet in at most two points). The 3D
//! pipeline searches for feasible points with a local search against batches of spheres; here
//! every point is feasible against every circle by construction, and a move along the circle
//! stops where its free arc ends instead of halving until it lands somewhere free.

use std::f64::consts::{PI, TAU};

use rayon::prelude::*;
use rfta_geom::glam::DVec2;
use rfta_mesh::{Closest, PolylineIndex};

/// A circle: a sample's position and `|s|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// Centre (the sample's position).
    pub center: DVec2,
    /// Radius (the sample's `|s|`).
    pub radius: f64,
}

impl Circle {
    /// The point at angle `theta`.
    pub fn point(&self, theta: f64) -> DVec2 {
        self.center
            + DVec2::new(rfta_geom::math::cos(theta), rfta_geom::math::sin(theta)) * self.radius
    }

    /// The angle of the direction from the centre to `p` (0 when `p` is the centre).
    pub fn angle_of(&self, p: DVec2) -> f64 {
        let d = p - self.center;
        if d == DVec2::ZERO {
            0.0
        } else {
            rfta_geom::math::atan2(d.y, d.x).rem_euclid(TAU)
        }
    }
}

/// The arcs of one circle that no other circle covers by more than a tolerance: disjoint closed
/// angle intervals `[a, b]`, `0 <= a < 2 pi`, `a < b <= a + 2 pi`, in increasing `a`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FreeArcs {
    arcs: Vec<(f64, f64)>,
}

impl FreeArcs {
    /// The free arcs of `circles[i]` among `neighbours` (indices into `circles`; others are
    /// ignored, so pass every circle that may cross it). A point is covered by circle `j` when it
    /// lies more than `tol` inside it.
    pub fn of(circles: &[Circle], i: usize, neighbours: &[usize], tol: f64) -> Self {
        let c = circles[i];
        let mut covered: Vec<(f64, f64)> = Vec::new();
        for &j in neighbours {
            if j == i {
                continue;
            }
            let o = circles[j];
            let rho = o.radius - tol;
            let d = (o.center - c.center).length();
            if rho <= 0.0 || d >= c.radius + rho || d + rho <= c.radius {
                continue; // apart, or inside this circle without reaching it
            }
            if d + c.radius <= rho {
                return Self::default(); // this circle lies inside the other
            }
            // Law of cosines: the half-angle of the arc inside `o`.
            let cos = (c.radius * c.radius + d * d - rho * rho) / (2.0 * c.radius * d);
            let half = rfta_geom::math::acos(cos.clamp(-1.0, 1.0));
            let mid = c.angle_of(o.center);
            let (a, b) = ((mid - half).rem_euclid(TAU), 2.0 * half);
            if a + b > TAU {
                covered.push((a, TAU));
                covered.push((0.0, a + b - TAU));
            } else {
                covered.push((a, a + b));
            }
        }
        if covered.is_empty() {
            return Self {
                arcs: vec![(0.0, TAU)],
            };
        }
        covered.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for (a, b) in covered {
            match merged.last_mut() {
                Some(last) if a <= last.1 => last.1 = last.1.max(b),
                _ => merged.push((a, b)),
            }
        }
        let mut arcs = Vec::new();
        for k in 0..merged.len() {
            let start = merged[k].1;
            let end = if k + 1 < merged.len() {
                merged[k + 1].0
            } else {
                merged[0].0 + TAU
            };
            if end > start {
                let a = start.rem_euclid(TAU);
                arcs.push((a, a + (end - start)));
            }
        }
        arcs.sort_by(|x, y| x.0.total_cmp(&y.0));
        Self { arcs }
    }

    /// No free point at all.
    pub fn is_empty(&self) -> bool {
        self.arcs.is_empty()
    }

    /// The arcs, as angle intervals.
    pub fn arcs(&self) -> &[(f64, f64)] {
        &self.arcs
    }

    /// The arc that holds angle `theta`, if any.
    fn holding(&self, theta: f64) -> Option<(f64, f64)> {
        let t = theta.rem_euclid(TAU);
        self.arcs
            .iter()
            .copied()
            .find(|&(a, b)| (a <= t && t <= b) || (a <= t + TAU && t + TAU <= b))
    }

    /// The free angle nearest to `theta` (along the circle), if there is one.
    pub fn nearest(&self, theta: f64) -> Option<f64> {
        if self.holding(theta).is_some() {
            return Some(theta.rem_euclid(TAU));
        }
        let gap = |x: f64| {
            let d = (x - theta).rem_euclid(TAU);
            d.min(TAU - d)
        };
        self.arcs
            .iter()
            .flat_map(|&(a, b)| [a, b.rem_euclid(TAU)])
            .min_by(|x, y| gap(*x).total_cmp(&gap(*y)).then(x.total_cmp(y)))
    }

    /// Move from the free angle `from` toward `to` by at most `step` radians, stopping where the
    /// free arc that holds `from` ends.
    pub fn transport(&self, from: f64, to: f64, step: f64) -> f64 {
        let Some((a, b)) = self.holding(from) else {
            return from;
        };
        let delta = (to - from + PI).rem_euclid(TAU) - PI;
        let theta = delta.abs().min(step).copysign(delta);
        // `from` in the arc's own unwrapped range.
        let f = if from.rem_euclid(TAU) >= a {
            from.rem_euclid(TAU)
        } else {
            from.rem_euclid(TAU) + TAU
        };
        (f + theta).clamp(a, b).rem_euclid(TAU)
    }
}

/// Settings of the fine-tuning rounds (the paper's names in brackets).
#[derive(Debug, Clone, PartialEq)]
pub struct TuneParams {
    /// Maximum points per circle (`n_max`).
    pub max_points: usize,
    /// Arc length of one move (`tau`).
    pub step: f64,
    /// Width of the tangent band and of the inside tests (`tol`).
    pub tolerance: f64,
    /// A cut is severe when the curve comes nearer to the centre than this fraction of the radius
    /// (the reference's 4/5).
    pub severe: f64,
}

/// The circles that own points, with their free arcs and their points' angles.
#[derive(Debug, Clone)]
pub struct Owners {
    /// Indices of the owning circles.
    pub circle: Vec<usize>,
    /// Their free arcs.
    pub free: Vec<FreeArcs>,
    /// Their points, as angles.
    pub angles: Vec<Vec<f64>>,
}

impl Owners {
    /// Number of points.
    pub fn points(&self) -> usize {
        self.angles.iter().map(Vec::len).sum()
    }

    /// Every point with its outward normal (from the sign of its circle's sample: the curve is
    /// outside an inside circle, so the normal points away from a negative sample's centre).
    pub fn oriented(&self, circles: &[Circle], values: &[f64]) -> (Vec<DVec2>, Vec<DVec2>) {
        let mut points = Vec::with_capacity(self.points());
        let mut normals = Vec::with_capacity(self.points());
        for (k, angles) in self.angles.iter().enumerate() {
            let i = self.circle[k];
            let sign = if values[i] < 0.0 { 1.0 } else { -1.0 };
            for &t in angles {
                points.push(circles[i].point(t));
                normals.push(DVec2::new(rfta_geom::math::cos(t), rfta_geom::math::sin(t)) * sign);
            }
        }
        (points, normals)
    }

    /// One fine-tuning round against the current curve (the paper's Algorithm 3 as the reference
    /// runs it: cut, missed and tangent circles, up to `max_points` per circle, the severe rule,
    /// a second chance for circles without a point).
    pub fn fine_tune(
        &mut self,
        circles: &[Circle],
        values: &[f64],
        curve: &PolylineIndex<'_>,
        params: &TuneParams,
    ) {
        let new: Vec<Vec<f64>> = (0..self.circle.len())
            .into_par_iter()
            .with_min_len(32)
            .map(|k| {
                let i = self.circle[k];
                tune_one(
                    circles[i],
                    values[i],
                    &self.free[k],
                    &self.angles[k],
                    curve,
                    params,
                )
            })
            .collect();
        self.angles = new;
    }
}

fn tune_one(
    c: Circle,
    value: f64,
    free: &FreeArcs,
    owned: &[f64],
    curve: &PolylineIndex<'_>,
    params: &TuneParams,
) -> Vec<f64> {
    let tol = params.tolerance;
    let Closest {
        distance, point, ..
    } = curve.closest(c.center);
    if !distance.is_finite() {
        return owned.to_vec();
    }
    // Where the curve says the centre is: the target is the radial projection of the closest
    // curve point, flipped when the centre is on the side its sign contradicts.
    let inside = curve.winding(c.center) != 0;
    let flip = (value < 0.0) != inside;
    let project = |p: DVec2| {
        let t = c.angle_of(p);
        if flip { t + PI } else { t }
    };
    let target = project(point);
    let step = params.step / c.radius.max(1e-300);
    let second_chance = || free.nearest(target).into_iter().collect::<Vec<_>>();
    let cut = distance < c.radius - tol && c.radius > tol;
    let missed = distance > c.radius + tol && c.radius > tol;
    if owned.is_empty() {
        return second_chance();
    }
    let nearest_owned = |to: f64| {
        owned
            .iter()
            .copied()
            .min_by(|&a, &b| {
                (c.point(a) - c.point(to))
                    .length_squared()
                    .total_cmp(&(c.point(b) - c.point(to)).length_squared())
            })
            .unwrap_or(to)
    };
    if missed {
        return vec![free.transport(nearest_owned(target), target, step)];
    }
    if !cut {
        return owned.to_vec();
    }
    let mut out = vec![free.transport(nearest_owned(target), target, step)];
    if params.max_points > 1 {
        // The other points move toward the projection of their own closest curve point, nearest
        // to the curve first; a cut that is not severe drops the farthest.
        let mut by_distance: Vec<(f64, f64, f64)> = owned
            .iter()
            .map(|&a| {
                let q = curve.closest(c.point(a));
                (q.distance, a, project(q.point))
            })
            .collect();
        by_distance.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
        let severe = distance <= params.severe * c.radius;
        let keep = if severe { owned.len() } else { owned.len() - 1 };
        for &(_, a, to) in by_distance.iter().take(keep.min(params.max_points - 1)) {
            out.push(free.transport(a, to, step));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_crossing_circles_leave_the_outer_arc_free() {
        let circles = [
            Circle {
                center: DVec2::ZERO,
                radius: 1.0,
            },
            Circle {
                center: DVec2::new(1.0, 0.0),
                radius: 1.0,
            },
        ];
        let free = FreeArcs::of(&circles, 0, &[1], 0.0);
        // The circles meet at angles +-60 degrees on circle 0: the free arc runs from 60 to 300.
        assert_eq!(free.arcs().len(), 1);
        let (a, b) = free.arcs()[0];
        assert!((a - PI / 3.0).abs() < 1e-12 && (b - 5.0 * PI / 3.0).abs() < 1e-12);
        // Every free point is outside circle 1; every covered one inside.
        for k in 0..360 {
            let t = (k as f64 + 0.5) / 360.0 * TAU;
            let outside = (circles[0].point(t) - circles[1].center).length() >= 1.0 - 1e-12;
            assert_eq!(free.holding(t).is_some(), outside, "at {t}");
        }
        assert!((free.nearest(0.1).expect("free") - PI / 3.0).abs() < 1e-12);
        assert!((free.nearest(-0.1).expect("free") - 5.0 * PI / 3.0).abs() < 1e-12);
        // Transport stops at the arc's end.
        assert!((free.transport(PI / 2.0, 0.0, 1.0) - PI / 3.0).abs() < 1e-12);
        assert!((free.transport(PI / 2.0, 0.0, 0.1) - (PI / 2.0 - 0.1)).abs() < 1e-12);
    }

    #[test]
    fn a_circle_inside_another_has_no_free_arc_and_a_lone_one_is_all_free() {
        let circles = [
            Circle {
                center: DVec2::ZERO,
                radius: 0.2,
            },
            Circle {
                center: DVec2::new(0.1, 0.0),
                radius: 1.0,
            },
        ];
        assert!(FreeArcs::of(&circles, 0, &[1], 1e-4).is_empty());
        let whole = FreeArcs::of(&circles, 1, &[0], 1e-4);
        assert_eq!(whole.arcs(), &[(0.0, TAU)]);
    }

    #[test]
    fn free_arcs_match_brute_force_on_random_circles() {
        let mut rng = rfta_geom::rng::Rng::new(11);
        let circles: Vec<Circle> = (0..40)
            .map(|_| Circle {
                center: DVec2::new(rng.next_f64(), rng.next_f64()),
                radius: 0.05 + 0.2 * rng.next_f64(),
            })
            .collect();
        let all: Vec<usize> = (0..circles.len()).collect();
        let tol = 1e-4;
        for i in 0..circles.len() {
            let free = FreeArcs::of(&circles, i, &all, tol);
            for k in 0..720 {
                let t = (k as f64 + 0.5) / 720.0 * TAU;
                let p = circles[i].point(t);
                let covered = circles
                    .iter()
                    .enumerate()
                    .any(|(j, o)| j != i && (p - o.center).length() < o.radius - tol);
                // Exact up to rounding at the arcs' ends.
                let margin = circles.iter().enumerate().all(|(j, o)| {
                    j == i || ((p - o.center).length() - (o.radius - tol)).abs() > 1e-9
                });
                if margin {
                    assert_eq!(free.holding(t).is_none(), covered, "circle {i} at {t}");
                }
            }
        }
    }
}
