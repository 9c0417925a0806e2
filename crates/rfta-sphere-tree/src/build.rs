//! Building the tree: obvhs over the spheres' boxes, flattened into exact nodes, then laid out
//! for the queries (`f32` bounds of a cache line each, children side by side).

use std::time::Duration;

use obvhs::{BvhBuildParams, aabb::Aabb as ObAabb, bvh2::Bvh2, bvh2::builder::build_bvh2};
use rfta_geom::{Aabb, Sphere, SphereSet, glam::DVec3, glam::Vec3A, glam::Vec4};

/// A node's bound as the queries read it: one 64-byte record (a cache line; 120 bytes in
/// `f64`) in `f32`, rounded so that every bound it gives is at most the exact one (boxes outward,
/// the radius up, and [`Bound::slack`] for the arithmetic's rounding). The leaves' tests stay
/// exact in `f64`, so the answers are those of an `f64` tree; only nodes within a few millionths
/// of the coordinates' size of the threshold are entered in addition.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(crate) struct Bound {
    /// The box of the spheres' centres; `w` of the low corner is the largest radius (rounded
    /// up), `w` of the high corner the slack.
    centers_min: Vec4,
    centers_max: Vec4,
    /// The union of the spheres' boxes (`w` unused).
    bounds_min: Vec4,
    bounds_max: Vec4,
}

/// The relative error allowed for the `f32` bounds: the rounding of the query point (`2^-24` per
/// coordinate), of the subtractions, squares, sums and square roots (a few `2^-24` of the
/// distance), with a margin of four.
pub(crate) const SLACK: f32 = 4e-6;

impl Bound {
    fn new(w: &Wide) -> Self {
        let (centers_min, centers_max) = w.centers.to_f32_outward();
        let (bounds_min, bounds_max) = w.bounds.to_f32_outward();
        let max_radius = rfta_geom::math::f32_at_least(w.max_radius);
        let scale = [centers_min, centers_max, bounds_min, bounds_max]
            .iter()
            .map(|v| v.abs().max_element())
            .fold(max_radius.abs(), f32::max);
        // A scale beyond f32 (or NaN) makes the slack infinite: the node is always entered.
        let slack = if scale.is_finite() {
            SLACK * (1.0 + scale)
        } else {
            f32::INFINITY
        };
        Self {
            centers_min: centers_min.extend(max_radius),
            centers_max: centers_max.extend(slack),
            bounds_min: bounds_min.extend(0.0),
            bounds_max: bounds_max.extend(0.0),
        }
    }

    pub(crate) fn centers_min(&self) -> Vec3A {
        Vec3A::from_vec4(self.centers_min)
    }

    pub(crate) fn centers_max(&self) -> Vec3A {
        Vec3A::from_vec4(self.centers_max)
    }

    pub(crate) fn bounds_min(&self) -> Vec3A {
        Vec3A::from_vec4(self.bounds_min)
    }

    pub(crate) fn bounds_max(&self) -> Vec3A {
        Vec3A::from_vec4(self.bounds_max)
    }

    /// The largest radius of the node's spheres, rounded up.
    pub(crate) fn max_radius(&self) -> f32 {
        self.centers_min.w
    }

    /// What a bound computed in `f32` from this node may exceed the exact one by, but for the
    /// query point's own share: [`SLACK`] times the node's largest coordinate and radius;
    /// infinite when they do not fit in `f32` (the node is then always entered).
    pub(crate) fn slack(&self) -> f32 {
        self.centers_max.w
    }

    /// The box of the spheres' boxes, in `f64` (outward of the exact one).
    pub(crate) fn bounds(&self) -> Aabb {
        Aabb::new(self.bounds_min().as_dvec3(), self.bounds_max().as_dvec3())
    }
}

/// Where a node leads ([`Link::next`]): an inner node's two children sit side by side (their
/// bounds, read together, are two adjacent cache lines); a leaf holds a range of spheres.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Link {
    /// Inner: the first child; leaf: the first sphere.
    a: u32,
    /// Inner: 0; leaf: the sphere count with [`LEAF`] set.
    b: u32,
}

/// The bit of [`Link`]'s `b` that marks a leaf.
const LEAF: u32 = 1 << 31;

/// What is below a node.
pub(crate) enum Next {
    /// The first of the two children (the second follows it).
    Children(u32),
    /// A leaf's spheres, as positions in the tree's arrays.
    Spheres(std::ops::Range<usize>),
}

impl Link {
    pub(crate) fn next(self) -> Next {
        if self.b & LEAF == 0 {
            Next::Children(self.a)
        } else {
            Next::Spheres(self.a as usize..(self.a + (self.b & !LEAF)) as usize)
        }
    }
}

/// A node while it is built, exact: the box of its spheres' centres, their largest radius, the
/// union of their boxes, and either two children or a range of spheres.
#[derive(Debug, Clone, Copy)]
struct Wide {
    centers: Aabb,
    max_radius: f64,
    bounds: Aabb,
    a: u32,
    b: u32,
    leaf: bool,
}

/// The built tree (`wide`, depth first from its root at 0) laid out for the queries: breadth
/// first, each node's two children next to each other.
fn narrow(wide: &[Wide]) -> (Vec<Bound>, Vec<Link>) {
    let mut bounds = vec![Bound::new(&wide[0])];
    let mut links = vec![Link::default()];
    // `origin[n]`: the built node that node `n` of the layout is.
    let mut origin = vec![0usize];
    let mut n = 0;
    while n < origin.len() {
        let w = &wide[origin[n]];
        links[n] = if w.leaf {
            Link {
                a: w.a,
                b: w.b | LEAF,
            }
        } else {
            let first = origin.len() as u32;
            for child in [w.a as usize, w.b as usize] {
                bounds.push(Bound::new(&wide[child]));
                links.push(Link::default());
                origin.push(child);
            }
            Link { a: first, b: 0 }
        };
        n += 1;
    }
    (bounds, links)
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
/// Memory is about 40 bytes per sphere once built: its centre, radius and index, and a 72-byte
/// node per 16 spheres or so (an SDF grid's spheres).
#[derive(Debug, Clone, Default)]
pub struct SphereTree {
    pub(crate) bounds: Vec<Bound>,
    pub(crate) links: Vec<Link>,
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
    pub fn new(spheres: &(impl SphereSet + ?Sized)) -> Self {
        let ids: Vec<u32> = (0..spheres.len() as u32).collect();
        Self::with_indices(spheres, &ids)
    }

    /// A tree over `spheres[i]` for each `i` in `indices` (duplicates are kept once), reporting
    /// those indices. Indices out of range are skipped.
    pub fn with_indices(spheres: &(impl SphereSet + ?Sized), indices: &[u32]) -> Self {
        let mut ids: Vec<u32> = indices
            .iter()
            .copied()
            .filter(|&i| (i as usize) < spheres.len())
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let chosen: Vec<Sphere> = ids.iter().map(|&i| spheres.sphere(i as usize)).collect();
        if chosen.is_empty() {
            return Self::default();
        }
        let boxes: Vec<SphereBox> = chosen
            .iter()
            .map(|s| SphereBox(to_obvhs(&s.aabb())))
            .collect();
        // PLOC without reinsertion. Reinsertion optimises the tree for ray traversal; for these
        // containment queries it measured slower on 10^6 SDF spheres (fast_build: 5.0 s build,
        // 37k inside_any queries/s; this: 1.0 s, 75k/s). Leaves of up to 64 spheres, collapsed
        // at a traversal cost of 20 (against 8 and 3): a query near the surface, where every
        // sphere nearly touches it, enters most nodes its bound cannot rule out, and a leaf's
        // spheres in a row cost less than the nodes above them. The sphere queries' share of a
        // run fell by a third to a half (adaptive bunny at 30,000 evaluations, the dev grids at
        // N = 20 and 50, the 129^3 bunny; docs/speed.md, item 37).
        let params = BvhBuildParams {
            max_prims_per_leaf: 64,
            collapse_traversal_cost: 20.0,
            ..BvhBuildParams::fastest_build()
        };
        let ob = build_bvh2(&boxes, params, &mut Duration::default());
        let mut tree = Self::default();
        let mut order = Vec::with_capacity(chosen.len());
        let mut wide = Vec::with_capacity(ob.nodes.len());
        flatten(&mut wide, &ob, 0, &chosen, &mut order);
        (tree.bounds, tree.links) = narrow(&wide);
        tree.centers = order.iter().map(|&p| chosen[p as usize].center).collect();
        tree.radii = order.iter().map(|&p| chosen[p as usize].radius).collect();
        tree.ids = order.iter().map(|&p| ids[p as usize]).collect();
        tree
    }

    /// A tree over a random batch: `batch_size` indices drawn uniformly *with replacement* from
    /// `0..spheres.len()` with `seed` ([`rfta_geom::rng::batch_with_replacement`]). A batch size
    /// of 0, or one of at least `n`, takes all.
    pub fn batch(spheres: &(impl SphereSet + ?Sized), batch_size: usize, seed: u64) -> Self {
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
    nodes: &mut Vec<Wide>,
    ob: &Bvh2,
    ob_idx: usize,
    spheres: &[Sphere],
    order: &mut Vec<u32>,
) -> u32 {
    let node = &ob.nodes[ob_idx];
    let my = nodes.len() as u32;
    let empty = Wide {
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
        let mut out = Wide {
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
        Wide {
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
