//! Building the tree: obvhs over the spheres' boxes, flattened into `f64` nodes.

use std::time::Duration;

use obvhs::{BvhBuildParams, aabb::Aabb as ObAabb, bvh2::Bvh2, bvh2::builder::build_bvh2};
use rfta_geom::{Aabb, Sphere, glam::DVec3, glam::Vec3A};

/// A node: the box of its spheres' centres, their largest radius, the union of their boxes
/// (for the reference-order traversal), and either two children or a range of spheres.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub(crate) centers: Aabb,
    pub(crate) max_radius: f64,
    pub(crate) bounds: Aabb,
    /// Leaf: first sphere; inner: left child.
    pub(crate) a: u32,
    /// Leaf: sphere count; inner: right child.
    pub(crate) b: u32,
    pub(crate) leaf: bool,
}

/// A static bounding volume hierarchy over spheres, answering containment queries.
///
/// Built over all spheres ([`SphereTree::new`]), a subset ([`SphereTree::with_indices`]) or a
/// seeded random batch ([`SphereTree::batch`]); queries report the caller's sphere indices.
///
/// # Complexity
/// Building is `O(n log n)`. A query costs `O(log n)` node visits when few spheres come near the
/// point, and grows with the number of spheres whose centre box and radius cannot be told apart
/// from a containing one; see the crate documentation for why this is tighter than a box test.
/// Memory is about 150 bytes per sphere.
#[derive(Debug, Clone, Default)]
pub struct SphereTree {
    pub(crate) nodes: Vec<Node>,
    pub(crate) centers: Vec<DVec3>,
    pub(crate) radii: Vec<f64>,
    pub(crate) ids: Vec<u32>,
}

struct SphereBox(ObAabb);

impl obvhs::Boundable for SphereBox {
    fn aabb(&self) -> ObAabb {
        self.0
    }
}

impl SphereTree {
    /// A tree over all `spheres`, reporting indices into `spheres`.
    pub fn new(spheres: &[Sphere]) -> Self {
        let ids: Vec<u32> = (0..spheres.len() as u32).collect();
        Self::with_indices(spheres, &ids)
    }

    /// A tree over `spheres[i]` for each `i` in `indices` (duplicates are kept once), reporting
    /// those indices. Indices out of range are skipped.
    pub fn with_indices(spheres: &[Sphere], indices: &[u32]) -> Self {
        let mut ids: Vec<u32> = indices
            .iter()
            .copied()
            .filter(|&i| (i as usize) < spheres.len())
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let chosen: Vec<Sphere> = ids.iter().map(|&i| spheres[i as usize]).collect();
        if chosen.is_empty() {
            return Self::default();
        }
        let boxes: Vec<SphereBox> = chosen
            .iter()
            .map(|s| SphereBox(to_obvhs(&s.aabb())))
            .collect();
        // PLOC without reinsertion, leaves collapsed to at most 8 spheres. Reinsertion optimises the
        // tree for ray traversal; for these containment queries it measured slower on 10^6 SDF
        // spheres (fast_build: 5.0 s build, 37k inside_any queries/s; this: 1.0 s, 75k/s).
        let params = BvhBuildParams {
            max_prims_per_leaf: 8,
            collapse_traversal_cost: 3.0,
            ..BvhBuildParams::fastest_build()
        };
        let ob = build_bvh2(&boxes, params, &mut Duration::default());
        let mut tree = Self::default();
        let mut order = Vec::with_capacity(chosen.len());
        flatten(&mut tree.nodes, &ob, 0, &chosen, &mut order);
        tree.centers = order.iter().map(|&p| chosen[p as usize].center).collect();
        tree.radii = order.iter().map(|&p| chosen[p as usize].radius).collect();
        tree.ids = order.iter().map(|&p| ids[p as usize]).collect();
        tree
    }

    /// A tree over a random batch: `batch_size` indices drawn uniformly *with replacement* from
    /// `0..spheres.len()` with `seed` ([`rfta_geom::rng::batch_with_replacement`]). A batch size
    /// of 0, or one of at least `n`, takes all.
    pub fn batch(spheres: &[Sphere], batch_size: usize, seed: u64) -> Self {
        match rfta_geom::rng::batch_with_replacement(spheres.len(), batch_size, seed) {
            Some(ids) => Self::with_indices(spheres, &ids),
            None => Self::new(spheres),
        }
    }

    /// Number of (distinct) spheres in the tree.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Whether the tree holds no sphere.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The indices of the spheres in the tree, ascending.
    pub fn indices(&self) -> Vec<u32> {
        let mut ids = self.ids.clone();
        ids.sort_unstable();
        ids
    }
}

fn flatten(
    nodes: &mut Vec<Node>,
    ob: &Bvh2,
    ob_idx: usize,
    spheres: &[Sphere],
    order: &mut Vec<u32>,
) -> u32 {
    let node = &ob.nodes[ob_idx];
    let my = nodes.len() as u32;
    let empty = Node {
        centers: Aabb::EMPTY,
        max_radius: 0.0,
        bounds: Aabb::EMPTY,
        a: 0,
        b: 0,
        leaf: false,
    };
    nodes.push(empty);
    let filled = if node.is_leaf() {
        let first = order.len() as u32;
        let range = node.first_index as usize..(node.first_index + node.prim_count) as usize;
        let mut out = Node {
            leaf: true,
            a: first,
            b: node.prim_count,
            ..empty
        };
        for &p in &ob.primitive_indices[range] {
            let s = spheres[p as usize];
            order.push(p);
            out.centers = out.centers.grow(s.center);
            out.max_radius = out.max_radius.max(s.radius);
            out.bounds = out.bounds.union(s.aabb());
        }
        out
    } else {
        let left = flatten(nodes, ob, node.first_index as usize, spheres, order);
        let right = flatten(nodes, ob, node.first_index as usize + 1, spheres, order);
        let (l, r) = (nodes[left as usize], nodes[right as usize]);
        Node {
            centers: l.centers.union(r.centers),
            max_radius: l.max_radius.max(r.max_radius),
            bounds: l.bounds.union(r.bounds),
            a: left,
            b: right,
            leaf: false,
        }
    };
    nodes[my as usize] = filled;
    my
}

/// The obvhs box holding an `f64` box.
fn to_obvhs(b: &Aabb) -> ObAabb {
    let (lo, hi) = b.to_f32_outward();
    ObAabb::new(Vec3A::from(lo), Vec3A::from(hi))
}
