//! The queries: nearest-first traversals pruned by a signed-distance lower bound.

use rfta_geom::glam::{DVec3, Vec3A};

use crate::build::{Bound, Next, SLACK, SphereTree};

/// Lower bound of `|x - p_j| - r_j` over the node's spheres: the larger of two bounds.
///
/// - `dist(x, centre box) - max radius`, tight for spheres of similar radii;
/// - the signed distance from `x` to the union of the spheres' boxes (negative inside): outside it
///   every sphere is at least that far, and inside it no sphere can hold `x` deeper than `x`'s
///   distance to the box's boundary, since the ball of that depth around `x` lies in the sphere
///   and so in the box. Tight where one large sphere shares a node with small ones.
///
/// Computed in `f32` from the node's outward-rounded record ([`Bound`]) and lowered by the node's
/// and the query's slack (`at.slack`), so that rounding never prunes a sphere the exact test
/// would report; a bound that is not a number (coordinates beyond `f32`) is `-inf`.
fn lower_bound(node: &Bound, at: &Query) -> f32 {
    let x = at.x;
    let c = (node.centers_min() - x).max(x - node.centers_max());
    let by_centres = c.max(Vec3A::ZERO).length() - node.max_radius();
    let d = (node.bounds_min() - x).max(x - node.bounds_max());
    let by_box = d.max(Vec3A::ZERO).length() + d.max_element().min(0.0);
    let lb = by_centres.max(by_box) - (node.slack() + at.slack);
    if lb.is_nan() { f32::NEG_INFINITY } else { lb }
}

/// A query point as the bounds read it: rounded to `f32`, with its share of the slack.
struct Query {
    x: Vec3A,
    slack: f32,
}

impl Query {
    fn new(x: DVec3) -> Self {
        let x = x.as_vec3a();
        Self {
            x,
            slack: SLACK * x.abs().max_element(),
        }
    }
}

impl SphereTree {
    /// Whether some sphere `j != ignore` has signed distance `|x - p_j| - r_j < threshold`.
    ///
    /// `threshold = -tol` asks "is `x` inside another sphere by more than `tol`" (the reference's
    /// feasibility test, `tol = 1e-4` in unit-box coordinates).
    pub fn inside_any(&self, x: DVec3, threshold: f64, ignore: Option<u32>) -> bool {
        let mut hit = false;
        self.traverse(x, |visit| match visit {
            Visit::Bound(lb) => lb < threshold,
            Visit::Leaf(spheres) => {
                hit = self.leaf_hit(spheres, x, threshold, ignore);
                !hit
            }
        });
        hit
    }

    /// Up to `k` spheres `j != ignore` with `|x - p_j| - r_j < threshold`, deepest first (ties by
    /// index): the `k` smallest signed distances.
    pub fn spheres_containing(
        &self,
        x: DVec3,
        k: usize,
        threshold: f64,
        ignore: Option<u32>,
    ) -> Vec<u32> {
        let mut hits = Vec::new();
        self.spheres_containing_into(x, k, threshold, ignore, &mut hits);
        hits.into_iter().map(|(_, j)| j).collect()
    }

    /// [`SphereTree::spheres_containing`] into a reused buffer of `(signed distance, index)`,
    /// sorted ascending; avoids allocating in hot loops.
    pub fn spheres_containing_into(
        &self,
        x: DVec3,
        k: usize,
        threshold: f64,
        ignore: Option<u32>,
        hits: &mut Vec<(f64, u32)>,
    ) {
        hits.clear();
        if k == 0 {
            return;
        }
        self.traverse(x, |visit| match visit {
            // Once k hits are held, only spheres at least as deep as the k-th can still enter.
            Visit::Bound(lb) => lb < threshold && !(hits.len() == k && lb > hits[k - 1].0),
            Visit::Leaf(spheres) => {
                for s in spheres {
                    let id = self.ids[s];
                    if Some(id) == ignore {
                        continue;
                    }
                    let d = (x - self.centers[s]).length() - self.radii[s];
                    if d >= threshold {
                        continue;
                    }
                    let key = (d, id);
                    if hits.len() == k && !less(key, hits[k - 1]) {
                        continue;
                    }
                    let at = hits.partition_point(|h| less(*h, key));
                    hits.insert(at, key);
                    hits.truncate(k);
                }
                true
            }
        });
    }

    /// Every sphere `j != ignore` with `|x - p_j| - r_j < threshold`, into `out` in ascending
    /// index order: the short list a caller tests many nearby points against (a point within
    /// `e` of `x` is inside a sphere by more than `m` only if that sphere is in the list for
    /// `threshold = e - m`).
    pub fn spheres_within_into(
        &self,
        x: DVec3,
        threshold: f64,
        ignore: Option<u32>,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.traverse(x, |visit| match visit {
            Visit::Bound(lb) => lb < threshold,
            Visit::Leaf(spheres) => {
                out.extend(
                    spheres
                        .filter(|&s| {
                            Some(self.ids[s]) != ignore
                                && (x - self.centers[s]).length() - self.radii[s] < threshold
                        })
                        .map(|s| self.ids[s]),
                );
                true
            }
        });
        out.sort_unstable();
    }

    /// [`SphereTree::inside_any`] with the reference implementation's traversal: descend into every
    /// node whose box of spheres (padded by the threshold, when positive) holds `x`, left before
    /// right, with no distance bound. Same answers; kept as the baseline for benchmarks.
    pub fn inside_any_reference_order(
        &self,
        x: DVec3,
        threshold: f64,
        ignore: Option<u32>,
    ) -> bool {
        if self.bounds.is_empty() {
            return false;
        }
        let pad = threshold.max(0.0);
        let mut stack: Vec<u32> = vec![0];
        while let Some(idx) = stack.pop() {
            if !self.bounds[idx as usize].bounds().padded(pad).contains(x) {
                continue;
            }
            match self.links[idx as usize].next() {
                Next::Children(first) => stack.extend([first + 1, first]),
                Next::Spheres(spheres) => {
                    if self.leaf_hit(spheres, x, threshold, ignore) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// What [`SphereTree::traverse`] asks its visitor about.
enum Visit {
    /// A node whose spheres all have signed distance at least this: descend into it?
    Bound(f64),
    /// A leaf to examine: go on?
    Leaf(std::ops::Range<usize>),
}

impl SphereTree {
    /// Nearest-first traversal from `x`: `visit` decides, from each node's lower bound, whether
    /// to enter it, and examines each leaf entered; the traversal ends when it says to stop.
    fn traverse(&self, x: DVec3, mut visit: impl FnMut(Visit) -> bool) {
        // A point that is not finite is in no sphere (every exact test is false for it).
        if self.bounds.is_empty() || !x.is_finite() {
            return;
        }
        let at = Query::new(x);
        let mut stack: Vec<(u32, f32)> = Vec::with_capacity(64);
        stack.push((0, lower_bound(&self.bounds[0], &at)));
        while let Some((idx, lb)) = stack.pop() {
            if !visit(Visit::Bound(lb as f64)) {
                continue;
            }
            match self.links[idx as usize].next() {
                Next::Children(first) => push_ordered(&mut stack, &self.bounds, first, &at),
                Next::Spheres(spheres) => {
                    if !visit(Visit::Leaf(spheres)) {
                        return;
                    }
                }
            }
        }
    }

    /// Whether a sphere of a leaf's `spheres`, other than `ignore`, has signed distance below
    /// `threshold` at `x`.
    fn leaf_hit(
        &self,
        spheres: std::ops::Range<usize>,
        x: DVec3,
        threshold: f64,
        ignore: Option<u32>,
    ) -> bool {
        spheres.into_iter().any(|s| {
            Some(self.ids[s]) != ignore
                && (x - self.centers[s]).length() - self.radii[s] < threshold
        })
    }
}

/// `(d, id)` ordering: by signed distance, then index.
fn less(a: (f64, u32), b: (f64, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// Pushes both children, the one with the smaller bound last so that it is visited first.
fn push_ordered(stack: &mut Vec<(u32, f32)>, bounds: &[Bound], first: u32, at: &Query) {
    let (l, r) = (first, first + 1);
    let (lb_l, lb_r) = (
        lower_bound(&bounds[l as usize], at),
        lower_bound(&bounds[r as usize], at),
    );
    if lb_l <= lb_r {
        stack.push((r, lb_r));
        stack.push((l, lb_l));
    } else {
        stack.push((l, lb_l));
        stack.push((r, lb_r));
    }
}
