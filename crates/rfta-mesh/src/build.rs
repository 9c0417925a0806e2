//! Building the tree: the faces split top-down by the surface area heuristic over binned
//! centroids (Wald, "On fast construction of SAH-based bounding volume hierarchies", 2007), the
//! two halves of a large range built side by side. Every choice depends only on the faces (exact
//! minima, maxima and counts, ties to the first bin), so the tree, and which of two equidistant
//! faces a query finds, is the same on any number of threads.

use rayon::prelude::*;
use rfta_geom::{Aabb, glam::DVec3};

use crate::node::Node;

/// Centroid bins along the axis a range is split across.
const BINS: usize = 16;

/// Ranges of at most this many faces become leaves.
const LEAF_FACES: usize = 4;

/// Ranges of at least this many faces are binned in parallel and build their halves side by
/// side; smaller ones are built on one thread.
const PARALLEL_FROM: usize = 4096;

/// A face as the build sees it.
struct Face {
    bounds: Aabb,
    centroid: DVec3,
}

/// The tree over triangles `corners`: nodes in depth-first order (a node's children after it,
/// leaves indexing positions of the returned face order, oriented boxes not yet filled) and the
/// faces in leaf order.
pub(crate) fn build(corners: &[[DVec3; 3]]) -> (Vec<Node>, Vec<u32>) {
    let faces: Vec<Face> = corners
        .par_iter()
        .map(|t| Face {
            bounds: Aabb::from_points(t.iter()),
            centroid: (t[0] + t[1] + t[2]) / 3.0,
        })
        .collect();
    let mut order: Vec<u32> = (0..corners.len() as u32).collect();
    let part = subtree(&faces, &mut order, 0);
    let mut nodes = Vec::with_capacity(part.len());
    part.flatten(&mut nodes);
    (nodes, order)
}

/// A subtree as built: one thread's nodes (children indexed from the first of them), or two
/// subtrees built side by side under a node of their own. Flattened once at the end, so that each
/// node is copied once however many levels were built in parallel.
enum Part {
    Serial(Vec<Node>),
    Join {
        left: Box<Part>,
        right: Box<Part>,
        len: usize,
    },
}

impl Part {
    /// Nodes in the subtree.
    fn len(&self) -> usize {
        match self {
            Part::Serial(nodes) => nodes.len(),
            Part::Join { len, .. } => *len,
        }
    }

    /// Appends the subtree to `out` depth first (a node, its left subtree, its right subtree);
    /// returns its root's index there.
    fn flatten(self, out: &mut Vec<Node>) -> u32 {
        match self {
            Part::Serial(nodes) => {
                let offset = out.len() as u32;
                out.extend(nodes.into_iter().map(|n| {
                    if n.leaf {
                        n
                    } else {
                        Node {
                            a: n.a + offset,
                            b: n.b + offset,
                            ..n
                        }
                    }
                }));
                offset
            }
            Part::Join { left, right, .. } => {
                let my = out.len();
                out.push(Node::PENDING);
                let l = left.flatten(out);
                let r = right.flatten(out);
                out[my] = Node::inner(out, l, r);
                my as u32
            }
        }
    }
}

/// The subtree over `order` (positions `first..` of the final face order).
fn subtree(faces: &[Face], order: &mut [u32], first: u32) -> Part {
    if order.len() < PARALLEL_FROM {
        let mut nodes = Vec::with_capacity(order.len());
        grow(faces, order, first, &mut nodes);
        return Part::Serial(nodes);
    }
    let mid = split(faces, order);
    let (lo, hi) = order.split_at_mut(mid);
    let (left, right) = rayon::join(
        || subtree(faces, lo, first),
        || subtree(faces, hi, first + mid as u32),
    );
    Part::Join {
        len: 1 + left.len() + right.len(),
        left: Box::new(left),
        right: Box::new(right),
    }
}

/// Appends the subtree over `order` (positions `first..` of the final face order) to `nodes`;
/// returns its root's index.
fn grow(faces: &[Face], order: &mut [u32], first: u32, nodes: &mut Vec<Node>) -> u32 {
    let my = nodes.len() as u32;
    if order.len() <= LEAF_FACES {
        let bounds = order
            .iter()
            .fold(Aabb::EMPTY, |b, &f| b.union(faces[f as usize].bounds));
        nodes.push(Node {
            bounds,
            a: first,
            b: order.len() as u32,
            leaf: true,
            ..Node::PENDING
        });
        return my;
    }
    nodes.push(Node::PENDING);
    let mid = split(faces, order);
    let (lo, hi) = order.split_at_mut(mid);
    let left = grow(faces, lo, first, nodes);
    let right = grow(faces, hi, first + mid as u32, nodes);
    nodes[my as usize] = Node::inner(nodes, left, right);
    my
}

/// Face counts and bounds per bin.
#[derive(Clone, Copy)]
struct Bins {
    count: [u32; BINS],
    bounds: [Aabb; BINS],
}

impl Bins {
    const EMPTY: Bins = Bins {
        count: [0; BINS],
        bounds: [Aabb::EMPTY; BINS],
    };

    fn merge(mut self, other: Bins) -> Bins {
        for b in 0..BINS {
            self.count[b] += other.count[b];
            self.bounds[b] = self.bounds[b].union(other.bounds[b]);
        }
        self
    }
}

/// Half the surface area of a box (0 for an empty one).
fn half_area(b: &Aabb) -> f64 {
    let e = (b.max - b.min).max(DVec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// `of` over the faces `order`, in chunks side by side from [`PARALLEL_FROM`] faces on, the
/// chunks' results joined by `merge` (exact minima, maxima and counts, so the result does not
/// depend on how the chunks fall).
fn gather<T: Copy + Send + Sync>(
    order: &[u32],
    empty: T,
    of: impl Fn(&[u32]) -> T + Sync + Send,
    merge: impl Fn(T, T) -> T + Sync + Send,
) -> T {
    if order.len() < PARALLEL_FROM {
        return of(order);
    }
    order
        .par_chunks(PARALLEL_FROM / 4)
        .map(of)
        .reduce(|| empty, merge)
}

/// Reorders `order` so that the faces on the cheap side of a split come first; returns how many
/// they are (both sides hold at least one face). The split is across the axis along which the
/// centroids spread most, at the bin boundary of least cost `A_left n_left + A_right n_right`
/// by the surface area heuristic. Faces whose centroids all coincide are split in the middle.
fn split(faces: &[Face], order: &mut [u32]) -> usize {
    let centroid_bounds = |ids: &[u32]| {
        ids.iter().fold(Aabb::EMPTY, |b, &f| {
            let c = faces[f as usize].centroid;
            Aabb {
                min: b.min.min(c),
                max: b.max.max(c),
            }
        })
    };
    let cb = gather(order, Aabb::EMPTY, centroid_bounds, Aabb::union);
    let extent = cb.max - cb.min;
    let axis = extent.max_position();
    if extent[axis] <= 0.0 {
        return order.len() / 2;
    }
    let (min, scale) = (cb.min[axis], BINS as f64 / extent[axis]);
    let bin = |f: u32| (((faces[f as usize].centroid[axis] - min) * scale) as usize).min(BINS - 1);
    let fill = |ids: &[u32]| {
        let mut bins = Bins::EMPTY;
        for &f in ids {
            let b = bin(f);
            bins.count[b] += 1;
            bins.bounds[b] = bins.bounds[b].union(faces[f as usize].bounds);
        }
        bins
    };
    let bins = gather(order, Bins::EMPTY, fill, Bins::merge);
    // The cost of everything after bin `k`, then the cheapest boundary (the first of equals).
    let mut right_cost = [0.0; BINS];
    let (mut n, mut b) = (0u32, Aabb::EMPTY);
    for k in (1..BINS).rev() {
        n += bins.count[k];
        b = b.union(bins.bounds[k]);
        right_cost[k] = f64::from(n) * half_area(&b);
    }
    let mut best: Option<(f64, usize)> = None;
    let (mut n, mut b) = (0u32, Aabb::EMPTY);
    for k in 0..BINS - 1 {
        n += bins.count[k];
        b = b.union(bins.bounds[k]);
        let cost = f64::from(n) * half_area(&b) + right_cost[k + 1];
        if n > 0 && (n as usize) < order.len() && best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, k));
        }
    }
    let Some((_, k)) = best else {
        return order.len() / 2;
    };
    // In place: the faces of bins `..=k` to the front.
    let mut mid = 0;
    for i in 0..order.len() {
        if bin(order[i]) <= k {
            order.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// The corners of every face of `mesh`.
    fn corners(mesh: &rfta_geom::TriMesh) -> Vec<[DVec3; 3]> {
        (0..mesh.n_faces()).map(|f| mesh.triangle(f)).collect()
    }

    /// Checks the tree against its definition: leaves of 1 to `LEAF_FACES` faces covering the
    /// face order in depth-first order, every face once, each inside its leaf's box, children
    /// after their parent, inner boxes the union of their children's.
    fn check(nodes: &[Node], order: &[u32], corners: &[[DVec3; 3]]) {
        let mut seen = vec![false; corners.len()];
        let mut next = 0u32;
        // Depth first from the root: leaves come in the order of their ranges, without gaps.
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &nodes[i as usize];
            let range = if node.leaf {
                assert!(
                    node.b >= 1 && node.b as usize <= LEAF_FACES,
                    "leaf of {}",
                    node.b
                );
                assert_eq!(node.a, next, "leaves out of order");
                next += node.b;
                node.a..node.a + node.b
            } else {
                assert!(node.a > i && node.b > node.a, "children after their parent");
                stack.push(node.b);
                stack.push(node.a);
                continue;
            };
            for t in range {
                let f = order[t as usize] as usize;
                assert!(!seen[f], "face {f} twice");
                seen[f] = true;
                let b = Aabb::from_points(corners[f].iter());
                assert!(node.bounds.min.cmple(b.min).all() && node.bounds.max.cmpge(b.max).all());
            }
        }
        assert!(seen.iter().all(|&s| s), "a face is missing");
        // Inner boxes are exactly their children's union.
        for node in nodes.iter().filter(|n| !n.leaf) {
            let (l, r) = (&nodes[node.a as usize], &nodes[node.b as usize]);
            assert_eq!(node.bounds, l.bounds.union(r.bounds));
        }
    }

    /// A small mesh (one thread's build) and a large one (halves side by side) hold every face
    /// once, in leaves of at most `LEAF_FACES` in depth-first order, inside their nodes' boxes.
    #[test]
    fn every_face_once_inside_its_boxes() {
        for mesh in [shapes::icosphere(1.0, 2), shapes::torus(0.6, 0.25, 120, 60)] {
            let c = corners(&mesh);
            let (nodes, order) = build(&c);
            check(&nodes, &order, &c);
        }
    }

    /// The large mesh's tree is the same, node for node, on 1 and 3 threads.
    #[test]
    fn the_tree_does_not_depend_on_the_thread_count() -> Result<(), rayon::ThreadPoolBuildError> {
        let mesh = shapes::torus(0.6, 0.25, 120, 60);
        assert!(mesh.n_faces() >= 3 * PARALLEL_FROM);
        let c = corners(&mesh);
        let on = |threads: usize| -> Result<_, rayon::ThreadPoolBuildError> {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()?;
            Ok(pool.install(|| build(&c)))
        };
        let ((a, order_a), (b, order_b)) = (on(1)?, on(3)?);
        assert_eq!(order_a, order_b);
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!((x.bounds, x.a, x.b, x.leaf), (y.bounds, y.a, y.b, y.leaf));
        }
        Ok(())
    }

    /// Faces whose centroids coincide (the same triangle many times) cannot be told apart by
    /// any split: they are halved until the leaves are small enough.
    #[test]
    fn coincident_faces_are_halved() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let c = vec![t; 5000];
        let (nodes, order) = build(&c);
        check(&nodes, &order, &c);
    }
}
