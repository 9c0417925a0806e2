//! Holes the curve closes around outside samples, opened: the 2D case of the 3D pipeline's
//! cavity opening (`rfta_repair::cavity_openings`).
//!
//! A hole of the curve (a clockwise loop: outside lies within it) whose outside samples are grid
//! neighbours of outside samples beyond the curve is walled off by less than a spacing that no
//! inside sample shows: the samples do not tell a wall from a gap, and the curve closed it. Such
//! a hole is opened by a channel through that wall along the grid edge where the wall is
//! thinnest, joining the hole's loop and the loop beyond into one. A hole whose every grid edge
//! out meets an inside sample (a wall a spacing thick or more all round: a ring, a frame) is
//! the samples' and stays.

use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Grid2, Polylines};
use rfta_mesh::PolylineIndex;

use crate::arcs::Circle;

/// What [`open_holes`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Opened {
    /// Holes opened.
    pub opened: usize,
    /// Holes around outside samples left closed: walled in by inside samples, or no channel
    /// found that enters no circle.
    pub kept: usize,
}

/// A channel's half width in spacings, at most (half the way to the ends of the edges it cuts,
/// if less).
pub(crate) const CHANNEL_HALF_WIDTH: f64 = 0.05;

/// Opens the holes of the closed curve `curve` that enclose outside samples of `grid` walled off
/// by less than a spacing (module documentation). `values[i]` is the sample at
/// `grid.position(i)` (positive outside) and `circles[i]` its circle, in the curve's coordinates;
/// a channel is kept only where its two walls cross no edge of the curve and enter no circle by
/// more than `margin`. The result does not depend on the thread count (there is none).
pub fn open_holes(
    curve: &mut Polylines,
    grid: &Grid2,
    values: &[f64],
    circles: &[Circle],
    margin: f64,
) -> Opened {
    let h = grid.spacing().min_element();
    let mut report = Opened::default();
    // Each pass opens at most one hole (the loops change), at most once per hole there was.
    let holes_at_start = holes(curve).len();
    let mut failed: Vec<Vec<u32>> = Vec::new();
    for _ in 0..holes_at_start {
        let loops = holes(curve);
        let whole = PolylineIndex::new(curve);
        let beyond: Vec<bool> = (0..grid.len())
            .map(|i| values[i] > 0.0 && whole.winding(grid.position(i)) == 0)
            .collect();
        let mut done = false;
        for hole in &loops {
            if failed.contains(&hole.edges) {
                continue;
            }
            let one = hole.alone(curve);
            let index = PolylineIndex::new(&one);
            let inside: Vec<bool> = (0..grid.len())
                .map(|i| beyond[i] && index.winding(grid.position(i)) != 0)
                .collect();
            if !inside.iter().any(|&b| b) {
                // Around no outside sample: not a cavity of the samples.
                failed.push(hole.edges.clone());
                continue;
            }
            let mut walls: Vec<Wall> = grid_edges(grid)
                .filter_map(|(a, b)| {
                    let (i, j) = match (inside[a], inside[b]) {
                        (true, false) => (a, b),
                        (false, true) => (b, a),
                        _ => return None,
                    };
                    if !beyond[j] {
                        return None;
                    }
                    Wall::across(curve, hole, grid.position(i), grid.position(j))
                })
                .collect();
            walls.sort_by(|x, y| x.thickness.total_cmp(&y.thickness));
            let opened = walls
                .iter()
                .any(|wall| wall.cut(curve, CHANNEL_HALF_WIDTH * h, circles, margin));
            if opened {
                report.opened += 1;
                done = true;
                break;
            }
            failed.push(hole.edges.clone());
        }
        if !done {
            break;
        }
    }
    report.kept = enclosing(curve, grid, values);
    report
}

/// The holes of the closed curve `curve` that enclose outside samples of `grid` (`values[i]` at
/// `grid.position(i)`, positive outside).
pub fn enclosing(curve: &Polylines, grid: &Grid2, values: &[f64]) -> usize {
    holes(curve)
        .iter()
        .filter(|hole| {
            let one = hole.alone(curve);
            let index = PolylineIndex::new(&one);
            (0..grid.len()).any(|i| values[i] > 0.0 && index.winding(grid.position(i)) != 0)
        })
        .count()
}

/// A loop of the curve: its edges (indices into `Polylines::edges`) in order.
struct Loop {
    edges: Vec<u32>,
}

impl Loop {
    /// The loop as polylines of its own (the curve's vertices, its edges).
    fn alone(&self, curve: &Polylines) -> Polylines {
        Polylines {
            vertices: curve.vertices.clone(),
            edges: self
                .edges
                .iter()
                .map(|&e| curve.edges[e as usize])
                .collect(),
        }
    }
}

/// The clockwise loops of a closed curve (negative signed area: outside lies within them), each
/// in the order of its edges from its lowest edge index.
fn holes(curve: &Polylines) -> Vec<Loop> {
    let mut from = vec![u32::MAX; curve.vertices.len()];
    for (e, &[a, _]) in curve.edges.iter().enumerate() {
        from[a as usize] = e as u32;
    }
    let mut seen = vec![false; curve.edges.len()];
    let mut out = Vec::new();
    for start in 0..curve.edges.len() {
        if seen[start] {
            continue;
        }
        let mut edges = Vec::new();
        let mut e = start as u32;
        while !seen[e as usize] {
            seen[e as usize] = true;
            edges.push(e);
            let next = from[curve.edges[e as usize][1] as usize];
            if next == u32::MAX {
                break;
            }
            e = next;
        }
        let area: f64 = edges
            .iter()
            .map(|&e| {
                let s = curve.segment(curve.edges[e as usize]);
                s.a.perp_dot(s.b)
            })
            .sum();
        if area < 0.0 {
            out.push(Loop { edges });
        }
    }
    out
}

/// The grid's edges between neighbours along each axis, as sample index pairs.
fn grid_edges(grid: &Grid2) -> impl Iterator<Item = (usize, usize)> + '_ {
    let [nx, ny] = grid.dims();
    (0..nx).flat_map(move |i| {
        (0..ny).flat_map(move |j| {
            let a = grid.index(i, j);
            let right = (i + 1 < nx).then(|| (a, grid.index(i + 1, j)));
            let up = (j + 1 < ny).then(|| (a, grid.index(i, j + 1)));
            right.into_iter().chain(up)
        })
    })
}

/// A wall between a hole and the outside beyond it, crossed by a grid edge from an outside
/// sample in the hole (`from`) to one beyond (`to`): the edge meets the curve exactly twice, the
/// hole's loop first.
struct Wall {
    from: DVec2,
    to: DVec2,
    /// The hole's edge crossed and where.
    near: (usize, DVec2),
    /// The other loop's edge crossed and where.
    far: (usize, DVec2),
    thickness: f64,
}

impl Wall {
    fn across(curve: &Polylines, hole: &Loop, from: DVec2, to: DVec2) -> Option<Wall> {
        let mut hits: Vec<(f64, usize, DVec2)> = Vec::new();
        for (e, &edge) in curve.edges.iter().enumerate() {
            let s = curve.segment(edge);
            if let Some((t, x)) = crossing(from, to, s.a, s.b) {
                hits.push((t, e, x));
                if hits.len() > 2 {
                    return None;
                }
            }
        }
        if hits.len() != 2 {
            return None;
        }
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (near, far) = ((hits[0].1, hits[0].2), (hits[1].1, hits[1].2));
        if !hole.edges.contains(&(near.0 as u32)) || hole.edges.contains(&(far.0 as u32)) {
            return None;
        }
        Some(Wall {
            from,
            to,
            near,
            far,
            thickness: near.1.distance(far.1),
        })
    }

    /// Cuts the channel: the hole's edge `p -> q` and the far edge `r -> t` split `half` (or
    /// half the way to their ends) either side of their crossings, `p -> y_p -> z_t -> t` and `r -> z_r -> y_q -> q`, joining the
    /// two loops into one. Refused (the curve unchanged) where the walls `y_p z_t` and
    /// `z_r y_q` would not lie on their own sides of the grid edge, would cross the curve, or
    /// would enter a circle by more than `margin`.
    fn cut(&self, curve: &mut Polylines, half: f64, circles: &[Circle], margin: f64) -> bool {
        let [p, q] = curve.edges[self.near.0];
        let [r, t] = curve.edges[self.far.0];
        // Each split point stays on its edge, at most half way to either end.
        let split = |e: [u32; 2], x: DVec2| {
            let s = curve.segment(e);
            let u = (s.b - s.a).normalize_or_zero();
            let room = half.min(0.5 * x.distance(s.a)).min(0.5 * x.distance(s.b));
            (x - room * u, x + room * u)
        };
        let (y_p, y_q) = split([p, q], self.near.1);
        let (z_r, z_t) = split([r, t], self.far.1);
        let d = self.to - self.from;
        let side = |x: DVec2| d.perp_dot(x - self.from).signum();
        if side(y_p) != side(z_t) || side(z_r) != side(y_q) || side(y_p) == side(y_q) {
            return false;
        }
        let clear = |a: DVec2, b: DVec2| {
            // No edge crossed but the two being cut (whose crossings are the walls' ends).
            let crossed = curve.edges.iter().enumerate().any(|(e, &edge)| {
                e != self.near.0 && e != self.far.0 && {
                    let s = curve.segment(edge);
                    crossing(a, b, s.a, s.b).is_some()
                }
            });
            !crossed
                && circles.iter().all(|c| {
                    let s = rfta_geom::plane::Segment { a, b };
                    s.closest_point(c.center).distance(c.center) >= c.radius - margin
                })
        };
        if !clear(y_p, z_t) || !clear(z_r, y_q) {
            return false;
        }
        let first = curve.vertices.len() as u32;
        curve.vertices.extend([y_p, y_q, z_r, z_t]);
        let (yp, yq, zr, zt) = (first, first + 1, first + 2, first + 3);
        curve.edges[self.near.0] = [p, yp];
        curve.edges[self.far.0] = [r, zr];
        curve.edges.extend([[yp, zt], [zt, t], [zr, yq], [yq, q]]);
        true
    }
}

/// Where segment `a -> b` properly crosses segment `c -> d`: the parameter along `a -> b` in
/// `(0, 1)` and the point.
fn crossing(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Option<(f64, DVec2)> {
    let (r, s) = (b - a, d - c);
    let denom = r.perp_dot(s);
    if denom == 0.0 {
        return None;
    }
    let t = (c - a).perp_dot(s) / denom;
    let u = (c - a).perp_dot(r) / denom;
    ((0.0..1.0).contains(&t) && t > 0.0 && (0.0..=1.0).contains(&u)).then(|| (t, a + t * r))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circle of radius `r` about `c` as a closed polygon of `n` vertices, counter-clockwise
    /// (`ccw`) or clockwise, appended to `curve`.
    fn polygon(curve: &mut Polylines, c: DVec2, r: f64, n: usize, ccw: bool) {
        let first = curve.vertices.len() as u32;
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            let a = if ccw { a } else { -a };
            curve.vertices.push(c + r * DVec2::new(a.cos(), a.sin()));
        }
        for k in 0..n as u32 {
            curve.edges.push([first + k, first + (k + 1) % n as u32]);
        }
    }

    /// The ring `r0 <= |p - c| <= r1` about the unit square's centre: its two loops, and its SDF
    /// on a 17 x 17 grid over the unit square (h = 1/16) with the circles.
    fn ring(r0: f64, r1: f64) -> (Polylines, Grid2, Vec<f64>, Vec<Circle>) {
        let c = DVec2::splat(0.5);
        let mut curve = Polylines::default();
        polygon(&mut curve, c, r1, 128, true);
        polygon(&mut curve, c, r0, 128, false);
        let grid = Grid2::from_bounds([17, 17], DVec2::ZERO, DVec2::ONE).expect("grid");
        let (mid, half) = ((r0 + r1) / 2.0, (r1 - r0) / 2.0);
        let values: Vec<f64> = (0..grid.len())
            .map(|i| ((grid.position(i) - c).length() - mid).abs() - half)
            .collect();
        let circles = (0..grid.len())
            .map(|i| Circle {
                center: grid.position(i),
                radius: values[i].abs(),
            })
            .collect();
        (curve, grid, values, circles)
    }

    /// Every sample on its own side of the curve (winding number), away from it.
    fn sides_kept(curve: &Polylines, grid: &Grid2, values: &[f64]) -> bool {
        let index = PolylineIndex::new(curve);
        (0..grid.len()).all(|i| {
            values[i].abs() < 1e-9 || (index.winding(grid.position(i)) != 0) == (values[i] < 0.0)
        })
    }

    /// A ring whose wall (0.03) is thinner than a spacing (0.0625) holds no sample: every grid
    /// edge across it joins an outside sample in the hole to one beyond, so the samples cannot
    /// tell the wall from a gap. The hole is opened: one loop, closed, every sample on its side,
    /// the channel entering no circle.
    #[test]
    fn a_hole_behind_a_wall_no_sample_shows_is_opened() {
        let (mut curve, grid, values, circles) = ring(0.30, 0.33);
        assert_eq!(curve.loops(), 2);
        let margin = 0.1 / 16.0;
        let opened = open_holes(&mut curve, &grid, &values, &circles, margin);
        assert_eq!(opened, Opened { opened: 1, kept: 0 });
        assert_eq!(curve.loops(), 1);
        assert!(curve.is_closed());
        assert!(sides_kept(&curve, &grid, &values));
        let index = PolylineIndex::new(&curve);
        for c in &circles {
            assert!(index.closest(c.center).distance >= c.radius - margin);
        }
    }

    /// A ring whose wall (0.15) holds inside samples all round is the samples' own: kept.
    #[test]
    fn a_hole_walled_in_by_inside_samples_is_kept() {
        let (mut curve, grid, values, circles) = ring(0.25, 0.40);
        let before = curve.clone();
        let opened = open_holes(&mut curve, &grid, &values, &circles, 0.1 / 16.0);
        assert_eq!(opened, Opened { opened: 0, kept: 1 });
        assert_eq!(curve, before);
    }

    /// A hole around no sample (between grid points) is no cavity of the samples: neither opened
    /// nor counted.
    #[test]
    fn a_hole_around_no_outside_sample_is_left_alone() {
        let (_, grid, values, circles) = ring(0.25, 0.40);
        let mut curve = Polylines::default();
        polygon(&mut curve, DVec2::splat(0.5), 0.45, 64, true);
        polygon(&mut curve, DVec2::new(0.53, 0.53), 0.02, 16, false);
        let before = curve.clone();
        let opened = open_holes(&mut curve, &grid, &values, &circles, 0.1 / 16.0);
        assert_eq!(opened, Opened::default());
        assert_eq!(curve, before);
    }
}
