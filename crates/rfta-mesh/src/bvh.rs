//! The bounding volume hierarchy over triangles and the distance queries.

use rayon::prelude::*;
use rfta_geom::{Aabb, TriMesh, glam::DVec3, kernels};

use crate::moments::Moments;
use crate::node::{Node, OrientedBox};
use crate::{Error, Result};

/// Nodes of up to this many triangles get their [`OrientedBox`] from the triangles themselves, larger ones
/// from their children's.
const EXACT_BOX: usize = 8192;

/// An acceleration structure over a triangle mesh for distance and winding-number queries.
///
/// # Complexity
/// Building is `O(F log F)` for `F` triangles; a closest-point query visits `O(log F)` nodes
/// on well-shaped meshes; a winding-number query visits `O(log F)` nodes for points away from
/// the surface and more near it. Memory is about 280 bytes per triangle.
#[derive(Debug, Clone)]
pub struct MeshIndex {
    pub(crate) nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    pub(crate) tris: Vec<[DVec3; 3]>,
    /// Original face index of each entry of `tris`.
    pub(crate) face_ids: Vec<u32>,
    /// Far-field moments of each node, for the winding number.
    pub(crate) moments: Vec<Moments>,
}

/// The answer of [`MeshIndex::closest_point`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// The closest point on the mesh.
    pub point: DVec3,
    /// Squared distance from the query to it.
    pub distance_squared: f64,
    /// Index of the triangle it lies on (in the mesh's face order).
    pub face: u32,
    /// Its barycentric coordinates in that triangle.
    pub barycentric: [f64; 3],
}

/// The answer of [`MeshIndex::shell`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shell {
    /// Some point of the mesh is closer than the shell's inner radius; the closest one.
    Closer(ClosestPoint),
    /// The nearest point of the mesh lies in the shell.
    Within,
    /// No point of the mesh is within the shell's outer radius.
    Beyond,
}

/// What a nearest-first traversal ([`MeshIndex::nearest_first`]) looks for.
trait Search {
    /// Whether a node at squared distance `d2` (a lower bound) cannot change the answer.
    fn skips(&self, d2: f64) -> bool;
    /// A triangle's point closest to the query, at squared distance `dq` (`c` makes it in full).
    fn offer(&mut self, dq: f64, c: impl FnOnce() -> ClosestPoint);
    /// Whether the answer is the same whatever order equally near triangles are found in, so
    /// that children may be visited in the order of their tighter bounds (the shell queries of
    /// the check of every sample: 10.6 to 9.3 s on the 257^3 bunny, docs/speed.md item 46).
    const ANY_ORDER: bool = false;
}

/// The closest point within a squared distance (the last of equally near triangles found).
struct Nearest {
    best: Option<ClosestPoint>,
    bound: f64,
}

impl Search for Nearest {
    fn skips(&self, d2: f64) -> bool {
        d2 > self.bound
    }

    fn offer(&mut self, dq: f64, c: impl FnOnce() -> ClosestPoint) {
        if dq <= self.bound {
            self.bound = dq;
            self.best = Some(c());
        }
    }
}

/// [`MeshIndex::shell`]'s search: the closest point if one is closer than `lo`, else whether one
/// lies within `hi`.
struct InShell {
    lo2: f64,
    hi2: f64,
    best: Option<ClosestPoint>,
    within: bool,
    /// Boxes at this squared distance or farther cannot change the answer (`lo2` and the nearest
    /// point found so far stay strict: a point at exactly `lo` is in the shell).
    bound: f64,
    strict: bool,
}

impl Search for InShell {
    // The answer is a class and, when closer, the least distance: no triangle's identity.
    const ANY_ORDER: bool = true;

    fn skips(&self, d2: f64) -> bool {
        d2 > self.bound || (self.strict && d2 >= self.bound)
    }

    fn offer(&mut self, dq: f64, c: impl FnOnce() -> ClosestPoint) {
        if dq < self.lo2 {
            if self.best.is_none_or(|b| dq <= b.distance_squared) {
                self.best = Some(c());
                self.bound = dq;
                self.strict = false;
            }
        } else if dq <= self.hi2 && self.best.is_none() && !self.within {
            self.within = true;
            self.bound = self.lo2;
            self.strict = true;
        }
    }
}

impl MeshIndex {
    /// Builds the index over `mesh`.
    ///
    /// # Errors
    /// [`Error::EmptyMesh`] for a mesh without triangles; [`Error::Geom`] if the mesh is invalid
    /// (a face index out of range or a non-finite vertex).
    pub fn new(mesh: &TriMesh) -> Result<Self> {
        mesh.validate()?;
        if mesh.is_empty() {
            return Err(Error::EmptyMesh);
        }
        let corners: Vec<[DVec3; 3]> = (0..mesh.n_faces())
            .into_par_iter()
            .map(|f| mesh.triangle(f))
            .collect();
        let (nodes, order) = crate::build::build(&corners);
        let mut index = MeshIndex {
            nodes,
            tris: order.par_iter().map(|&f| corners[f as usize]).collect(),
            face_ids: order,
            moments: Vec::new(),
        };
        index.moments = crate::moments::node_moments(&index.nodes, &index.tris);
        index.fill_oriented_boxes();
        Ok(index)
    }

    /// Every node's [`OrientedBox`]: the direction of its area-weighted normal sum (from its winding
    /// moments); the extents from its triangles (a contiguous range of `tris`, the tree being
    /// flattened depth first) for nodes of up to [`EXACT_BOX`] triangles, from the corners of its
    /// children's boxes above (each triangle is projected a few times rather than once per level:
    /// the extents above that size bound far-off queries, which the children's corners do about
    /// as well).
    fn fill_oriented_boxes(&mut self) {
        let range = self.ranges();
        let tris = &self.tris;
        let small: Vec<Option<OrientedBox>> = range
            .par_iter()
            .zip(&self.moments)
            .map(|(&(first, count), m)| {
                (count as usize <= EXACT_BOX).then(|| {
                    let corners = tris[first as usize..(first + count) as usize]
                        .iter()
                        .flatten()
                        .copied();
                    OrientedBox::around(m.normal.normalize_or_zero(), corners)
                })
            })
            .collect();
        for (node, exact) in self.nodes.iter_mut().zip(&small) {
            if let Some(exact) = exact {
                node.oriented = *exact;
            }
        }
        for i in (0..self.nodes.len()).rev() {
            if small[i].is_none() {
                let node = self.nodes[i];
                let (l, r) = (&self.nodes[node.a as usize], &self.nodes[node.b as usize]);
                let corners = l.box_corners().into_iter().chain(r.box_corners());
                self.nodes[i].oriented =
                    OrientedBox::around(self.moments[i].normal.normalize_or_zero(), corners);
            }
        }
    }

    /// Each node's triangles, a contiguous range of `tris` (first, count): computed bottom-up,
    /// children coming after their parent.
    fn ranges(&self) -> Vec<(u32, u32)> {
        let mut range = vec![(0u32, 0u32); self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            range[i] = if node.leaf {
                (node.a, node.b)
            } else {
                let (l, r) = (range[node.a as usize], range[node.b as usize]);
                (l.0.min(r.0), l.1 + r.1)
            };
        }
        range
    }

    /// Number of triangles.
    pub fn n_faces(&self) -> usize {
        self.tris.len()
    }

    /// Bounding box of the mesh.
    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bounds
    }

    /// The point of the mesh closest to `p`.
    pub fn closest_point(&self, p: DVec3) -> ClosestPoint {
        self.closest_point_within(p, f64::INFINITY)
            .unwrap_or(ClosestPoint {
                point: p,
                distance_squared: f64::INFINITY,
                face: 0,
                barycentric: [1.0, 0.0, 0.0],
            })
    }

    /// The point of the mesh closest to `p` if it is within squared distance `max_distance_squared`
    /// (inclusive); `None` otherwise. A finite bound prunes the search.
    pub fn closest_point_within(
        &self,
        p: DVec3,
        max_distance_squared: f64,
    ) -> Option<ClosestPoint> {
        let mut search = Nearest {
            best: None,
            bound: max_distance_squared,
        };
        self.nearest_first(p, &mut search);
        search.best
    }

    /// The one traversal behind [`MeshIndex::closest_point_within`] and [`MeshIndex::shell`]:
    /// nodes nearest first (the nearer child next), each skipped when `search` says its lower
    /// bound cannot change the answer, every triangle of a visited leaf offered with its point
    /// closest to `p`.
    fn nearest_first<S: Search>(&self, p: DVec3, search: &mut S) {
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        stack.push((0, self.nodes[0].bounds.distance_squared(p)));
        while let Some((idx, d2)) = stack.pop() {
            if search.skips(d2) {
                continue;
            }
            let node = &self.nodes[idx as usize];
            if node.leaf {
                for t in node.a..node.a + node.b {
                    let [a, b, c] = self.tris[t as usize];
                    let (q, bary) = kernels::closest_point_on_triangle(p, a, b, c);
                    let dq = p.distance_squared(q);
                    search.offer(dq, || ClosestPoint {
                        point: q,
                        distance_squared: dq,
                        face: self.face_ids[t as usize],
                        barycentric: bary,
                    });
                }
            } else {
                self.push_children::<S>(node, p, &mut stack);
            }
        }
    }

    /// Pushes an inner node's children with their squared distances to `p`, the farther first so
    /// that the nearer one is visited next.
    ///
    /// The order is the boxes' (as it always was: among triangles at exactly the same distance
    /// the same one is found), or the pushed bounds' where the answer does not depend on it
    /// (`Search::ANY_ORDER`); the distance pushed, that prunes, is the larger bound of box and
    /// [`OrientedBox`].
    fn push_children<S: Search>(&self, node: &Node, p: DVec3, stack: &mut Vec<(u32, f64)>) {
        let (l, r) = (&self.nodes[node.a as usize], &self.nodes[node.b as usize]);
        let (bl, br) = (l.lower_bound_squared(p), r.lower_bound_squared(p));
        let left_first = if S::ANY_ORDER {
            bl <= br
        } else {
            l.bounds.distance_squared(p) <= r.bounds.distance_squared(p)
        };
        if left_first {
            stack.push((node.b, br));
            stack.push((node.a, bl));
        } else {
            stack.push((node.a, bl));
            stack.push((node.b, br));
        }
    }

    /// Where the mesh lies relative to the spherical shell `lo <= |x - p| <= hi` around `p`
    /// (`lo <= hi`): closer than `lo` (with the exact closest point), within the shell, or
    /// beyond it. Cheaper than [`MeshIndex::closest_point`] when the answer is "within": the
    /// search stops looking for nearer points once it has one in the shell, and only proves that
    /// none is closer than `lo`.
    pub fn shell(&self, p: DVec3, lo: f64, hi: f64) -> Shell {
        let lo2 = if lo > 0.0 { lo * lo } else { 0.0 };
        // A negative outer radius holds no point: every box is pruned.
        let hi2 = if hi >= 0.0 { hi * hi } else { -1.0 };
        let mut search = InShell {
            lo2,
            hi2,
            best: None,
            within: false,
            bound: hi2,
            strict: false,
        };
        self.nearest_first(p, &mut search);
        match search.best {
            Some(c) => Shell::Closer(c),
            None if search.within => Shell::Within,
            None => Shell::Beyond,
        }
    }

    /// Whether the segment from `a` to `b` crosses the mesh (a triangle, its edges included; see
    /// [`kernels::segment_triangle`]): a collision query, as a moving point's path from one time
    /// step to the next.
    pub fn segment_hits(&self, a: DVec3, b: DVec3) -> bool {
        let mut hit = false;
        self.along_segment(a, b, |_, _| {
            hit = true;
            false
        });
        hit
    }

    /// Every crossing of the segment from `a` to `b` with the mesh (as [`MeshIndex::segment_hits`]
    /// counts them), as the segment's parameter in `[0, 1]` and the face crossed, in order along
    /// the segment (ties by face).
    pub fn segment_crossings(&self, a: DVec3, b: DVec3) -> Vec<(f64, u32)> {
        let mut crossings = Vec::new();
        self.along_segment(a, b, |t, face| {
            crossings.push((t, face));
            true
        });
        crossings.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        crossings
    }

    /// The traversal behind the segment queries: `visit(t, face)` for each crossing, in no
    /// particular order, until it returns false.
    fn along_segment(&self, a: DVec3, b: DVec3, mut visit: impl FnMut(f64, u32) -> bool) {
        let dir = b - a;
        // Slab test of the segment against a box, with the reciprocal direction precomputed.
        let inv = DVec3::ONE / dir;
        let crosses = |bounds: &Aabb| {
            let (mut near, mut far) = (0.0_f64, 1.0_f64);
            for k in 0..3 {
                if dir[k] == 0.0 {
                    if a[k] < bounds.min[k] || a[k] > bounds.max[k] {
                        return false;
                    }
                } else {
                    let t0 = (bounds.min[k] - a[k]) * inv[k];
                    let t1 = (bounds.max[k] - a[k]) * inv[k];
                    near = near.max(t0.min(t1));
                    far = far.min(t0.max(t1));
                }
            }
            near <= far
        };
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(idx) = stack.pop() {
            let node = &self.nodes[idx as usize];
            if !crosses(&node.bounds) {
                continue;
            }
            if node.leaf {
                for t in node.a..node.a + node.b {
                    let [p0, p1, p2] = self.tris[t as usize];
                    if let Some(s) = kernels::segment_triangle(a, b, p0, p1, p2)
                        && !visit(s, self.face_ids[t as usize])
                    {
                        return;
                    }
                }
            } else {
                stack.push(node.a);
                stack.push(node.b);
            }
        }
    }

    /// Distance from `p` to the mesh.
    pub fn unsigned_distance(&self, p: DVec3) -> f64 {
        self.closest_point(p).distance_squared.sqrt()
    }

    /// Signed distance from `p` to the mesh: the unsigned distance, negated where the winding
    /// number is above 1/2 (inside), zero where it is exactly 1/2.
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        let d = self.unsigned_distance(p);
        let w = self.winding_number(p);
        // sign(1 - 2w), as libigl's signed distance with the winding-number sign.
        d * (1.0 - 2.0 * w).signum() * if w == 0.5 { 0.0 } else { 1.0 }
    }

    /// [`MeshIndex::signed_distance`] at every point, in parallel; the result does not depend on the thread count.
    pub fn signed_distances(&self, points: &[DVec3]) -> Vec<f64> {
        points
            .par_iter()
            .map(|&p| self.signed_distance(p))
            .collect()
    }

    /// [`MeshIndex::unsigned_distance`] at every point, in parallel.
    pub fn unsigned_distances(&self, points: &[DVec3]) -> Vec<f64> {
        points
            .par_iter()
            .map(|&p| self.unsigned_distance(p))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every node's bound (both boxes) is at most the squared distance from the query to
        /// each of the node's triangles (brute force), on a torus seen from anywhere around it.
        #[test]
        fn node_bounds_never_exceed_the_distance(
            x in -2.0f64..2.0, y in -2.0f64..2.0, z in -1.0f64..1.0
        ) {
            let mesh = rfta_geom::shapes::torus(1.0, 0.3, 24, 12);
            let index = MeshIndex::new(&mesh).map_err(|e| TestCaseError::fail(e.to_string()))?;
            let p = DVec3::new(x, y, z);
            for (node, (first, count)) in index.nodes.iter().zip(index.ranges()) {
                let end = first + count;
                let nearest = index.tris[first as usize..end as usize]
                    .iter()
                    .map(|&[a, b, c]| p.distance_squared(kernels::closest_point_on_triangle(p, a, b, c).0))
                    .fold(f64::INFINITY, f64::min);
                prop_assert!(node.lower_bound_squared(p) <= nearest, "{} > {nearest}", node.lower_bound_squared(p));
            }
        }
    }

    /// Near the surface the oriented boxes are what prunes: from points just off a sphere, along
    /// its normal, some node's oriented bound exceeds its box bound.
    #[test]
    fn oriented_boxes_are_tighter_than_boxes_facing_the_surface() -> Result<()> {
        let mesh = rfta_geom::shapes::icosphere(1.0, 4);
        let index = MeshIndex::new(&mesh)?;
        let p = DVec3::new(0.6, 0.7, 0.5).normalize() * 1.05;
        let tighter = index
            .nodes
            .iter()
            .filter(|n| n.lower_bound_squared(p) > n.bounds.distance_squared(p))
            .count();
        assert!(tighter > 10, "{tighter}");
        Ok(())
    }

    /// Every node's oriented box holds every corner of its triangles, in an orthonormal frame,
    /// on a mesh large enough that the upper nodes' boxes come from their children's corners
    /// (20,480 triangles, above [`EXACT_BOX`]).
    #[test]
    fn oriented_boxes_hold_their_triangles_above_the_exact_size_too() -> Result<()> {
        let mesh = rfta_geom::shapes::icosphere(1.0, 5);
        let index = MeshIndex::new(&mesh)?;
        let mut from_children = 0;
        for (node, (first, count)) in index.nodes.iter().zip(index.ranges()) {
            let end = first + count;
            let b = &node.oriented;
            if (end - first) as usize > EXACT_BOX {
                from_children += 1;
            }
            for j in 0..3 {
                for k in 0..3 {
                    let dot = b.axes[j].dot(b.axes[k]);
                    let want = if j == k { 1.0 } else { 0.0 };
                    assert!((dot - want).abs() < 1e-12, "axes {j} {k}: {dot}");
                }
            }
            for corner in index.tris[first as usize..end as usize].iter().flatten() {
                for k in 0..3 {
                    let t = b.axes[k].dot(*corner);
                    assert!(
                        b.lo[k] <= t && t <= b.hi[k],
                        "{} not in [{}, {}]",
                        t,
                        b.lo[k],
                        b.hi[k]
                    );
                }
            }
        }
        assert!(from_children >= 3, "{from_children}");
        Ok(())
    }

    /// Beside the tangency of a large sphere resting on a convex surface, the patches' planes
    /// pass nearer than its radius and only their extent along the surface keeps them out: from
    /// 3 above the unit sphere, of the nodes a slab along the normal alone (with the box) cannot
    /// rule out of the ball of radius 2.99, the oriented boxes rule out more than half.
    #[test]
    fn oriented_boxes_rule_out_the_patches_beside_a_tangency() -> Result<()> {
        let mesh = rfta_geom::shapes::icosphere(1.0, 5);
        let index = MeshIndex::new(&mesh)?;
        let p = DVec3::new(0.3, -0.2, 1.0).normalize() * 4.0;
        let lo2 = 2.99f64 * 2.99;
        let slab_only = |node: &Node| {
            let b = &node.oriented;
            let t = b.axes[0].dot(p);
            let e = (t - b.hi[0]).max(b.lo[0] - t).max(0.0);
            node.bounds.distance_squared(p).max(e * e)
        };
        let by_slab = index.nodes.iter().filter(|n| slab_only(n) < lo2).count();
        let by_box = index
            .nodes
            .iter()
            .filter(|n| n.lower_bound_squared(p) < lo2)
            .count();
        assert!(by_slab > 0 && 2 * by_box < by_slab, "{by_box} of {by_slab}");
        Ok(())
    }
}
