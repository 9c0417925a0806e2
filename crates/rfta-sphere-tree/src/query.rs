//! The queries: nearest-first traversals pruned by a signed-distance lower bound.

use rfta_geom::glam::DVec3;

use crate::build::{Node, SphereTree};

/// Lower bound of `|x - p_j| - r_j` over the node's spheres: the larger of two bounds.
///
/// - `dist(x, centre box) - max radius`, tight for spheres of similar radii;
/// - the signed distance from `x` to the union of the spheres' boxes (negative inside): outside it
///   every sphere is at least that far, and inside it no sphere can hold `x` deeper than `x`'s
///   distance to the box's boundary, since the ball of that depth around `x` lies in the sphere
///   and so in the box. Tight where one large sphere shares a node with small ones.
///
/// The second is lowered by a relative `1e-12` so that rounding never prunes a sphere the exact
/// test would report.
fn lower_bound(node: &Node, x: DVec3) -> f64 {
    let by_centres = node.centers.distance_squared(x).sqrt() - node.max_radius;
    let b = &node.bounds;
    let d = (b.min - x).max(x - b.max);
    let by_box = d.max(DVec3::ZERO).length() + d.max_element().min(0.0);
    let slack = 1e-12 * (1.0 + x.abs().max_element() + (b.max - b.min).max_element());
    by_centres.max(by_box - slack)
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
            Visit::Leaf(node) => {
                hit = self.leaf_hit(node, x, threshold, ignore);
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
            Visit::Leaf(node) => {
                for s in node.a as usize..(node.a + node.b) as usize {
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
            Visit::Leaf(node) => {
                out.extend(
                    (node.a as usize..(node.a + node.b) as usize)
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
        if self.nodes.is_empty() {
            return false;
        }
        let pad = threshold.max(0.0);
        let mut stack: Vec<u32> = vec![0];
        while let Some(idx) = stack.pop() {
            let node = &self.nodes[idx as usize];
            if !node.bounds.padded(pad).contains(x) {
                continue;
            }
            if node.leaf {
                if self.leaf_hit(node, x, threshold, ignore) {
                    return true;
                }
            } else {
                stack.push(node.b);
                stack.push(node.a);
            }
        }
        false
    }
}

/// What [`SphereTree::traverse`] asks its visitor about.
enum Visit<'a> {
    /// A node whose spheres all have signed distance at least this: descend into it?
    Bound(f64),
    /// A leaf to examine: go on?
    Leaf(&'a Node),
}

impl SphereTree {
    /// Nearest-first traversal from `x`: `visit` decides, from each node's lower bound, whether
    /// to enter it, and examines each leaf entered; the traversal ends when it says to stop.
    fn traverse<'a>(&'a self, x: DVec3, mut visit: impl FnMut(Visit<'a>) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        stack.push((0, lower_bound(&self.nodes[0], x)));
        while let Some((idx, lb)) = stack.pop() {
            if !visit(Visit::Bound(lb)) {
                continue;
            }
            let node = &self.nodes[idx as usize];
            if !node.leaf {
                push_ordered(&mut stack, &self.nodes, node, x);
            } else if !visit(Visit::Leaf(node)) {
                return;
            }
        }
    }

    /// Whether a sphere of leaf `node`, other than `ignore`, has signed distance below `threshold` at `x`.
    fn leaf_hit(&self, node: &Node, x: DVec3, threshold: f64, ignore: Option<u32>) -> bool {
        (node.a as usize..(node.a + node.b) as usize).any(|s| {
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
fn push_ordered(stack: &mut Vec<(u32, f64)>, nodes: &[Node], node: &Node, x: DVec3) {
    let (l, r) = (node.a, node.b);
    let (lb_l, lb_r) = (
        lower_bound(&nodes[l as usize], x),
        lower_bound(&nodes[r as usize], x),
    );
    if lb_l <= lb_r {
        stack.push((r, lb_r));
        stack.push((l, lb_l));
    } else {
        stack.push((l, lb_l));
        stack.push((r, lb_r));
    }
}
