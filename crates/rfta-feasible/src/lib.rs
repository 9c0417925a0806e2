//! Tangency points of Reach for the Arcs (Sellán, Ren, Batty and Stein, SIGGRAPH 2024, §4): every
//! SDF sample `(p_i, s_i)` is a sphere of radius `|s_i|` that the surface must touch without
//! entering; this crate finds one point on each sphere that no other sphere covers, moves those
//! points toward a reconstructed mesh, and orients them. It never calls the surface
//! reconstruction itself: the pipeline crate `rfta` alternates the two.
//!
//! - [`initial_points`]: the nearest empty-space sample to each sphere, projected onto it and made
//!   feasible by [`local_search`] (at most `local_search_iters` moves to circle and triple points
//!   with the spheres that cover it).
//! - [`fine_tune`]: one fine-tuning round against a mesh: the cut / miss / tangent cases with the
//!   tolerance band, up to `n_max` points per sphere with the severe rule, a second chance for
//!   spheres without a point, then feasibility again.
//! - [`transport`]: geodesic transport by arc length `tau` with halving until feasible.
//!
//! Coordinates are the pipeline's normalized unit box (the tolerances are in those units).
//! Every sphere is processed independently from immutable shared state, and outputs are
//! concatenated in sphere order, so results do not depend on the thread count.
//!
//! # Example
//! ```
//! use rfta_geom::{Sphere, glam::DVec3};
//! use rfta_sphere_tree::SphereTree;
//! use rfta_feasible::{Params, local_search};
//!
//! // Two overlapping spheres; a point on sphere 0 that lies inside sphere 1 moves to their
//! // intersection circle, where it is feasible.
//! let spheres = [Sphere::new(DVec3::ZERO, 1.0), Sphere::new(DVec3::new(1.5, 0.0, 0.0), 1.0)];
//! let tree = SphereTree::new(&spheres);
//! let params = Params { k_search: 4, ..Params::default() };
//! let x = local_search(&spheres, &tree, 0, DVec3::new(1.0, 0.0, 0.0), &params).expect("feasible");
//! assert!(((x - spheres[0].center).length() - 1.0).abs() < 1e-12);
//! assert!((x - spheres[1].center).length() >= 1.0 - 1e-9);
//! ```

use std::sync::atomic::{AtomicUsize, Ordering};

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::kernels::{
    SphereSphere, closest_point_on_circle, fallback_perpendicular, project_onto_sphere,
    sphere_sphere_circle, transport_on_sphere, trilaterate,
};
use rfta_geom::{Sphere, SphereSet, TriMesh};
use rfta_mesh::MeshIndex;
use rfta_sphere_tree::SphereTree;

/// Most spheres a parallel task of the initial points or the fine-tuning takes: the owners' work
/// varies a hundredfold (a sphere the surface cuts searches, one it touches does not), and
/// rayon's default split leaves whole quarters of the range to one thread at the end of a
/// round. Results are collected in sphere order, so this changes nothing but the balance.
const SPHERES_PER_TASK: usize = 32;

/// Parameters, in normalized unit-box units. Defaults are the reference implementation's.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Tolerance of the inside tests (`1e-4`).
    pub tol: f64,
    /// Moves of the feasibility local search (20).
    pub local_search_iters: usize,
    /// Spheres considered per move: the reference uses `ceil(2 n^(1/3))` over all `n` samples
    /// (see [`Params::k_search_for`]).
    pub k_search: usize,
    /// Arc length of one transport step (`0.01`).
    pub tau: f64,
    /// Maximum points per sphere (3; the paper's Table 2 used 30).
    pub n_max: usize,
    /// Spheres at least this large (as given, before [`Params::owner_scale`]) get no point: those
    /// of a clamped SDF, and any the caller keeps as constraints only (the pipeline's owner band
    /// on a grid); `+inf` for none. Nor do spheres the set says it does not let own points
    /// ([`SphereSet::owns`]).
    pub owner_radius: f64,
    /// A cut is severe when the mesh comes within `severe * r` of the centre (0.8).
    pub severe: f64,
    /// Halvings of the transport step before giving up (20).
    pub halvings: usize,
    /// A sphere's own points lie on it at `owner_scale` times its radius (1), while every other
    /// sphere constrains them at its radius: with noisy values the caller shrinks the spheres
    /// by the noise and scales them back for their own points, so that a point counts as inside
    /// another sphere only when it is deeper than that sphere's noise.
    pub owner_scale: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            tol: 1e-4,
            local_search_iters: 20,
            k_search: 22,
            tau: 0.01,
            n_max: 3,
            owner_radius: f64::INFINITY,
            severe: 0.8,
            halvings: 20,
            owner_scale: 1.0,
        }
    }
}

impl Params {
    /// The reference's `k_search = ceil(2 n^(1/3))` for `n` samples.
    pub fn k_search_for(n: usize) -> usize {
        (2.0 * rfta_geom::math::cbrt(n as f64)).ceil().max(1.0) as usize
    }

    /// Sphere `s` as its own points see it ([`Params::owner_scale`]).
    pub fn owner(&self, s: Sphere) -> Sphere {
        Sphere {
            radius: s.radius * self.owner_scale,
            ..s
        }
    }
}

/// Oriented tangency points, each owned by a sphere, sorted by owner.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TangentPoints {
    /// Positions.
    pub points: Vec<DVec3>,
    /// Unit normals (outward from the surface, eq. (2) of the paper).
    pub normals: Vec<DVec3>,
    /// Index of the sphere each point lies on.
    pub owners: Vec<u32>,
}

impl TangentPoints {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    fn from_per_sphere(items: Vec<Vec<(DVec3, DVec3)>>, owners: impl Iterator<Item = u32>) -> Self {
        let mut out = Self::default();
        for (list, owner) in items.into_iter().zip(owners) {
            for (p, n) in list {
                out.points.push(p);
                out.normals.push(n);
                out.owners.push(owner);
            }
        }
        out
    }
}

/// Outward surface normal at a tangency point `x` of sphere `i` with SDF value `s` (eq. (2)):
/// away from the centre of an inside sphere, toward the centre of an outside one.
pub fn normal_at(center: DVec3, s: f64, x: DVec3) -> DVec3 {
    let d = x - center;
    let len = d.length();
    let dir = if len > f64::EPSILON {
        d / len
    } else {
        DVec3::X
    };
    if s < 0.0 { dir } else { -dir }
}

/// Whether `y` lies strictly inside sphere `s` (the reference's `|y - c|^2 + eps <= r^2`).
fn collides(y: DVec3, s: &Sphere) -> bool {
    (y - s.center).length_squared() + f64::EPSILON <= s.radius * s.radius
}

fn in_unit_box(y: DVec3) -> bool {
    y.cmpge(DVec3::ZERO).all() && y.cmple(DVec3::ONE).all()
}

/// Closest point to `x` on the circle where sphere `s` meets `other`; when they do not meet, the
/// point of `s` facing `other`'s centre; when they coincide, `x` projected onto `s`.
fn circle_point(s: &Sphere, other: &Sphere, x: DVec3) -> DVec3 {
    match sphere_sphere_circle(s, other) {
        SphereSphere::Circle(c) => closest_point_on_circle(&c, x),
        SphereSphere::Coincident => project_onto_sphere(s, x),
        SphereSphere::Separate | SphereSphere::Nested => {
            let d = other.center - s.center;
            let len = d.length();
            let dir = if len > 0.0 {
                d / len
            } else {
                fallback_perpendicular(DVec3::Z)
            };
            s.center + s.radius * dir
        }
    }
}

/// One collision-resolution move (the reference's `resolve_collisions_on_sphere`, 3D): a point on
/// sphere `s` outside the candidate spheres (sorted by radius, ascending), found at triple points
/// of `s` with pairs of candidates (inside the unit box) or on circles with one candidate; `x`
/// unchanged when none qualifies. The first acceptable point in pair order is returned.
pub fn resolve(s: &Sphere, x: DVec3, cands: &[Sphere]) -> DVec3 {
    let free_of = |y: DVec3, skip: &[usize]| {
        cands
            .iter()
            .enumerate()
            .all(|(k, c)| skip.contains(&k) || !collides(y, c))
    };
    let out = match cands.len() {
        0 => x,
        1 => circle_point(s, &cands[0], x),
        _ => {
            let mut found = None;
            'pairs: for i in 0..cands.len() {
                for j in 0..i {
                    match trilaterate(s, &cands[i], &cands[j]) {
                        Some(pts) => {
                            if let Some(best) = pts
                                .into_iter()
                                .filter(|&y| in_unit_box(y) && free_of(y, &[i, j]))
                                .min_by(|a, b| {
                                    (*a - x)
                                        .length_squared()
                                        .total_cmp(&(*b - x).length_squared())
                                })
                            {
                                found = Some(best);
                                break 'pairs;
                            }
                        }
                        None => {
                            for k in [i, j] {
                                let y = circle_point(s, &cands[k], x);
                                if free_of(y, &[k]) {
                                    found = Some(y);
                                    break 'pairs;
                                }
                            }
                        }
                    }
                }
            }
            found.unwrap_or(x)
        }
    };
    if out.is_finite() { out } else { x }
}

/// Make point `x` on sphere `i` feasible against the spheres in `tree`: at most
/// `local_search_iters` moves, each resolving the up to `k_search` spheres that (nearly) contain
/// it. `None` when it is still inside another sphere by more than `tol` after the last move.
pub fn local_search(
    spheres: &(impl SphereSet + ?Sized),
    tree: &SphereTree,
    i: u32,
    mut x: DVec3,
    params: &Params,
) -> Option<DVec3> {
    let s = params.owner(spheres.sphere(i as usize));
    let mut buf = Vec::new();
    let mut cands: Vec<(f64, u32)> = Vec::new();
    let mut list: Vec<Sphere> = Vec::new();
    for it in 0..=params.local_search_iters {
        // One query answers both questions: the deepest sphere within `tol` decides feasibility
        // (inside by more than `tol`), and the `k_search` deepest are the ones to resolve.
        tree.spheres_containing_into(x, params.k_search.max(1), params.tol, Some(i), &mut buf);
        if buf.first().is_none_or(|&(d, _)| d >= -params.tol) {
            return Some(x);
        }
        if it == params.local_search_iters {
            break;
        }
        buf.truncate(params.k_search);
        // Candidates by radius, ascending (ties by index), as the reference sorts them.
        cands.clear();
        cands.extend(buf.iter().map(|&(_, j)| (spheres.radius(j as usize), j)));
        cands.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        list.clear();
        list.extend(cands.iter().map(|&(_, j)| spheres.sphere(j as usize)));
        x = resolve(&s, x, &list);
    }
    None
}

/// Where [`transport`] put a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transported {
    /// A step that passed the feasibility test against the tree.
    Feasible(DVec3),
    /// Not known to be feasible: the target after every halving failed, or the start untouched
    /// (for the feasibility pass to handle, the reference's behaviour).
    Unchecked(DVec3),
}

impl Transported {
    /// The point, whichever it is.
    pub fn point(self) -> DVec3 {
        match self {
            Self::Feasible(x) | Self::Unchecked(x) => x,
        }
    }
}

/// Geodesic transport of `a` toward `q` on sphere `i` by arc length `tau`, halved until the
/// result lies inside no other sphere of `tree` (at most `halvings` times); `q` if none works.
/// `near` is scratch (a caller transporting many points passes the same one).
pub fn transport(
    spheres: &(impl SphereSet + ?Sized),
    tree: &SphereTree,
    i: u32,
    a: DVec3,
    q: DVec3,
    params: &Params,
    near: &mut Vec<u32>,
) -> Transported {
    let s = params.owner(spheres.sphere(i as usize));
    let tol = params.tol;
    if (a - q).length() < tol || s.radius < tol || (a - s.center).length() < tol {
        return Transported::Unchecked(a);
    }
    let chord = ((a - q).length() / (2.0 * s.radius)).min(1.0);
    let mut arc = (params.tau / s.radius).min(2.0 * rfta_geom::math::asin(chord)) * s.radius;
    // Every step lands within `arc` of `a`'s projection (a chord is shorter than its arc), so the
    // spheres that can hold a step by more than `tol` are among those within `arc - tol` of it
    // (padded for rounding): one tree query for all the halvings, then the tree's own test
    // against that short list.
    let start = project_onto_sphere(&s, a);
    let reach = arc * (1.0 + 1e-9) + 1e-12 * (1.0 + start.abs().max_element()) - tol;
    tree.spheres_within_into(start, reach, Some(i), near);
    for _ in 0..params.halvings {
        let y = transport_on_sphere(&s, a, q, arc);
        if !near
            .iter()
            .any(|&j| spheres.sphere(j as usize).signed_distance(y) < -tol)
        {
            return Transported::Feasible(y);
        }
        arc *= 0.5;
    }
    Transported::Unchecked(q)
}

/// Initial tangency points of one sign set (`set`: indices into `spheres` / `values`): for each
/// sphere, the empty-space sample nearest its centre projected onto it, then [`local_search`]
/// against `tree` (a batch of the same sign set). Spheres that end infeasible, reach
/// [`Params::owner_radius`], are not owners ([`SphereSet::owns`]) or have zero radius (a sample
/// exactly on the surface gives no normal) get no point. With `done`, 1 is added to it as each
/// sphere of `set` is finished (for progress reports from another thread; the result does not
/// depend on it).
pub fn initial_points(
    spheres: &(impl SphereSet + ?Sized),
    values: &[f64],
    set: &[u32],
    empty_space: &[DVec3],
    tree: &SphereTree,
    params: &Params,
    done: Option<&AtomicUsize>,
) -> TangentPoints {
    if empty_space.is_empty() || set.is_empty() {
        return TangentPoints::default();
    }
    let pts: Vec<[f64; 3]> = empty_space.iter().map(|p| p.to_array()).collect();
    let Ok(kd) = ImmutableKdTree::<f64, 3>::new_from_slice(&pts) else {
        return TangentPoints::default();
    };
    let per: Vec<Vec<(DVec3, DVec3)>> = set
        .par_iter()
        .with_max_len(SPHERES_PER_TASK)
        .map(|&i| {
            let s = params.owner(spheres.sphere(i as usize));
            let v = values[i as usize];
            // Owners are chosen by their radius as constraints, the caller's measure, and by
            // the set.
            let owner =
                spheres.owns(i as usize) && spheres.radius(i as usize) < params.owner_radius;
            if !owner || s.radius <= 0.0 {
                return Vec::new();
            }
            let nn = kd
                .query(&s.center.to_array())
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute();
            let w = empty_space[nn.item as usize];
            let d = w - s.center;
            let len = d.length();
            let dir = if len > f64::EPSILON {
                d / len
            } else {
                DVec3::X
            };
            let x0 = s.center + s.radius * dir;
            match local_search(spheres, tree, i, x0, params) {
                Some(x) => vec![(x, normal_at(s.center, v, x))],
                None => Vec::new(),
            }
        })
        .inspect(|_| {
            if let Some(done) = done {
                done.fetch_add(1, Ordering::Relaxed);
            }
        })
        .collect();
    TangentPoints::from_per_sphere(per, set.iter().copied())
}

/// Whether every point of a cloud passed the feasibility test against the tree a round tests
/// against ([`fine_tune`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tested {
    /// Not known: every point is tested.
    No,
    /// Every point passed against this same tree (the previous round's output, when every round's
    /// tree holds all spheres): points kept unchanged are not tested again. The result is the
    /// same either way.
    AgainstThisTree,
}

/// One fine-tuning round (the reference's `fine_tune_point_cloud_iter`): every sphere is compared
/// with `mesh` (the reconstruction of `cloud`), its points are moved, added or dropped by the
/// cut / miss / tangent rule, and every resulting point is made feasible against `tree` (a batch
/// of all spheres). Spheres without a point get a second chance from their projection. `tested`
/// says what `cloud`'s points passed already; with `done`, 1 is added to it as each sphere is
/// finished (for progress reports from another thread; the result does not depend on it).
#[allow(clippy::too_many_arguments)]
pub fn fine_tune(
    spheres: &(impl SphereSet + ?Sized),
    values: &[f64],
    mesh: &TriMesh,
    cloud: &TangentPoints,
    tested: Tested,
    tree: &SphereTree,
    params: &Params,
    done: Option<&AtomicUsize>,
) -> TangentPoints {
    let cloud_feasible = tested == Tested::AgainstThisTree;
    let Ok(index) = MeshIndex::new(mesh) else {
        return cloud.clone();
    };
    // Only spheres below the owner radius can own a point: the others are skipped before any
    // work (on a 257^3 grid 99% of the spheres), without a slot each.
    let owners: Vec<u32> = (0..spheres.len() as u32)
        .filter(|&i| {
            let r = spheres.radius(i as usize);
            r < params.owner_radius && r * params.owner_scale > 0.0 && spheres.owns(i as usize)
        })
        .collect();
    if let Some(done) = done {
        done.fetch_add(spheres.len() - owners.len(), Ordering::Relaxed);
    }
    let round = Round {
        spheres,
        values,
        index: &index,
        cloud,
        tree,
        params,
        cloud_feasible,
    };
    let per: Vec<Vec<(DVec3, DVec3)>> = owners
        .par_iter()
        .with_max_len(SPHERES_PER_TASK)
        .map(|&i| round.sphere(i))
        .inspect(|_| {
            if let Some(done) = done {
                done.fetch_add(1, Ordering::Relaxed);
            }
        })
        .collect();
    TangentPoints::from_per_sphere(per, owners.into_iter())
}

/// The index in `range` of the point of `points` nearest `q` (the lowest on a tie; the range's
/// start when it is empty).
fn nearest(points: &[DVec3], range: std::ops::Range<usize>, q: DVec3) -> usize {
    let start = range.start;
    range
        .min_by(|&a, &b| {
            (points[a] - q)
                .length_squared()
                .total_cmp(&(points[b] - q).length_squared())
                .then(a.cmp(&b))
        })
        .unwrap_or(start)
}

/// What one fine-tuning round reads, shared by every sphere's rule.
#[derive(Clone, Copy)]
struct Round<'a, S: SphereSet + ?Sized> {
    spheres: &'a S,
    values: &'a [f64],
    index: &'a MeshIndex,
    /// Sorted by owner.
    cloud: &'a TangentPoints,
    tree: &'a SphereTree,
    params: &'a Params,
    cloud_feasible: bool,
}

impl<S: SphereSet + ?Sized> Round<'_, S> {
    /// Owner `i`'s points after the round, with their normals: the cut / miss / tangent rule.
    fn sphere(&self, i: u32) -> Vec<(DVec3, DVec3)> {
        let Round {
            spheres,
            values,
            index,
            cloud,
            tree,
            params,
            cloud_feasible,
        } = *self;
        let tol = params.tol;
        let s = params.owner(spheres.sphere(i as usize));
        let v = values[i as usize];
        // An owner (`fine_tune` passes no other): below the owner radius, of positive radius.
        let r = s.radius;
        let cp = index.closest_point(s.center);
        let di = cp.distance_squared.sqrt();
        // The cloud's points of sphere `i`.
        let owned =
            cloud.owners.partition_point(|&o| o < i)..cloud.owners.partition_point(|&o| o <= i);
        let k = owned.len();
        let cut = di < r - tol && r > tol;
        let miss = di > r + tol && r > tol;
        let search = |x: DVec3| local_search(spheres, tree, i, x, params);
        let oriented = |x: DVec3| (x, normal_at(s.center, v, x));
        if k > 0 && !cut && !miss {
            // Touched within the tolerance: the points stay. A point that passed the test against
            // this tree would pass the local search's first test and come back unchanged.
            return owned
                .filter_map(|a| {
                    let x = cloud.points[a];
                    if cloud_feasible { Some(x) } else { search(x) }
                })
                .map(oriented)
                .collect();
        }
        let inside_mesh = index.winding_number(s.center) > 0.5;
        let sigma = if v < 0.0 { -1.0 } else { 1.0 } * if inside_mesh { -1.0 } else { 1.0 };
        let proj = |x: DVec3| {
            let d = x - s.center;
            let len = d.length();
            let dir = if len > f64::EPSILON {
                d / len
            } else {
                DVec3::X
            };
            s.center + r * sigma * dir
        };
        let qi = proj(cp.point);
        // Each emitted point, and whether it is already known to be feasible.
        let mut emitted: Vec<Transported> = Vec::new();
        let mut near = Vec::new();
        if k == 0 {
            emitted.push(Transported::Unchecked(qi));
        } else {
            let closest = nearest(&cloud.points, owned.clone(), qi);
            emitted.push(transport(
                spheres,
                tree,
                i,
                cloud.points[closest],
                qi,
                params,
                &mut near,
            ));
            if cut && params.n_max > 1 {
                // Each point's own closest point on the mesh, nearest first.
                let mut by_distance: Vec<(usize, DVec3, f64)> = owned
                    .map(|a| {
                        let c = index.closest_point(cloud.points[a]);
                        (a, c.point, c.distance_squared.sqrt())
                    })
                    .collect();
                by_distance.sort_by(|x, y| x.2.total_cmp(&y.2).then(x.0.cmp(&y.0)));
                let severe = di <= params.severe * r;
                let limit = if severe { k } else { k - 1 };
                for &(a, c, _) in by_distance.iter().take(limit.min(params.n_max - 1)) {
                    emitted.push(transport(
                        spheres,
                        tree,
                        i,
                        cloud.points[a],
                        proj(c),
                        params,
                        &mut near,
                    ));
                }
            }
        }
        emitted
            .into_iter()
            .filter_map(|t| match t {
                Transported::Feasible(x) => Some(x),
                Transported::Unchecked(x) => search(x),
            })
            .map(oriented)
            .collect()
    }
}
