//! The surface out of every sample sphere it enters: vertices pushed radially out of the spheres
//! that own points, then every sphere cleared (faces split where they cut a sphere no vertex is
//! in, vertices moved along the normal or radially).

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_sphere_tree::SphereTree;

use crate::Spheres;
use crate::edit::{Splitter, apply_moves};
use rfta_mesh::Incidence;

/// Passes of [`push_out_of_spheres`] per vertex: leaving the deepest sphere can land a vertex in
/// a neighbour, which the next pass leaves in turn.
pub(crate) const PUSH_PASSES: usize = 8;

/// The surface may not enter a sample sphere (Sellán et al. 2024, §3), yet the final screened
/// Poisson surface is smooth and cuts into the spheres where the shape is not (edges, corners, thin
/// parts). Each vertex inside some sphere by more than `depth` (in the spheres' frame) moves
/// radially onto the boundary of the sphere it is deepest in, up to `PUSH_PASSES` (8) times; the
/// connectivity stays, and the moves are taken without folding the surface ([`apply_moves`]). The
/// targets do not depend on one another, so the result does not depend on the thread count.
pub fn push_out_of_spheres(
    mesh: &mut TriMesh,
    spheres: &Spheres<'_>,
    tree: &SphereTree,
    depth: f64,
) {
    use rayon::prelude::*;
    let moved_to: Vec<Option<DVec3>> = mesh
        .vertices
        .par_iter()
        .map_init(Vec::new, |hits, &v| {
            let mut p = spheres.frame.to_frame(v);
            let mut moved = false;
            for _ in 0..PUSH_PASSES {
                tree.spheres_containing_into(p, 1, -depth, None, hits);
                let Some(&(_, j)) = hits.first() else {
                    break;
                };
                let s = spheres.spheres.sphere(j as usize);
                let dir = (p - s.center).normalize_or_zero();
                if dir == DVec3::ZERO {
                    break;
                }
                p = s.center + dir * s.radius;
                moved = true;
            }
            moved.then(|| spheres.frame.to_mesh(p))
        })
        .collect();
    apply_moves(mesh, &Incidence::of(mesh), &moved_to);
}

/// Rounds of [`clear_spheres`] at most: each finds the spheres the mesh still enters and moves the
/// vertices inside them out; they stop sooner when a round moves and adds nothing. A small
/// sphere whose vertices already lie on it is left by hundredths of a spacing a round (a face
/// between points on a sphere dips into it by the sagitta of its chords, and each round splits
/// one face per sphere): six rounds left 3holes at N = 10 and thingi54725 at N = 50 entering one
/// and three spheres, which eighteen clear, with the dev set's mean Chamfer within 0.2% at N = 20
/// to 50 and 129^3 (-0.7% at N = 10) and no run measurably slower (docs/speed.md, 2026-12-07,
/// late night).
pub(crate) const CLEAR_ROUNDS: usize = 18;

/// The farthest a vertex moves in [`clear_spheres`], in sample spacings: an entry deeper than
/// this is not a smooth surface's overshoot but a wrong part, which moving vertices would tear.
pub(crate) const CLEAR_REACH: f64 = 0.5;

/// The mesh in the spheres' frame.
pub(crate) fn in_frame(mesh: &TriMesh, spheres: &Spheres<'_>) -> TriMesh {
    TriMesh {
        vertices: mesh
            .vertices
            .iter()
            .map(|&v| spheres.frame.to_frame(v))
            .collect(),
        faces: mesh.faces.clone(),
    }
}

/// The surface may not enter a sample sphere (Sellán et al. 2024, §3), of any size: the far
/// spheres own no tangency point, so nothing but this keeps the smooth Poisson surface out of
/// them (a bulge at a corner, where many far spheres touch the same point), and the near ones are
/// cut wherever the shape is sharper than the surface (edges, corners, thin parts).
///
/// Each round finds the spheres the mesh enters by more than `depth` (in the spheres' frame): the
/// first round those of `among`, the later ones those entered before. Where no vertex of the
/// cutting face lies in the sphere, a vertex is put at the face's point nearest the centre
/// (`split_where_entered`). Then each vertex inside entered spheres moves along its normal
/// (inward out of positive spheres, outward out of negative ones) or radially away from the
/// deepest sphere's centre, whichever leaves all of them sooner (`leave_along`), as long as that
/// is within `CLEAR_REACH` (0.5) and meets no sphere of the other sign; the moves are taken
/// without folding the surface ([`apply_moves`]). At most `CLEAR_ROUNDS` (18) rounds. Vertices
/// move in index order, so the result does not depend on the thread count. Returns how many
/// vertices were added.
pub fn clear_spheres(
    mesh: &mut TriMesh,
    spheres: &Spheres<'_>,
    among: Among<'_>,
    depth: f64,
) -> usize {
    use rayon::prelude::*;
    let reach = CLEAR_REACH * spheres.spacing;
    let mut added = 0;
    // The spheres entered in the last round, each with the face that came nearest its centre.
    let mut last: Vec<(u32, rfta_mesh::ClosestPoint)> = Vec::new();
    // The faces around each vertex: only splits change them.
    let mut incident = Incidence::of(mesh);
    for round in 0..CLEAR_ROUNDS {
        let part = in_frame(mesh, spheres);
        let previous = (round > 0).then_some(last.as_slice());
        let Some(found) = entered(&part, &incident, spheres, previous, among, depth) else {
            break;
        };
        if found.is_empty() {
            break;
        }
        let splits = split_where_entered(mesh, &part, &incident, spheres, &found, depth);
        added += splits;
        let part = if splits > 0 {
            incident = Incidence::of(mesh);
            in_frame(mesh, spheres)
        } else {
            part
        };
        let entered: Vec<u32> = found.iter().map(|&(i, _)| i).collect();
        let tree = SphereTree::with_indices(spheres.spheres, &entered);
        // The vertices inside entered spheres: each sphere's cap, grown from the face nearest
        // its centre (the face's slot holds a piece of it after a split).
        let mut inside: Vec<u32> = found
            .par_iter()
            .flat_map_iter(|&(i, ref c)| {
                let s = spheres.spheres.sphere(i as usize);
                let holds =
                    |v: u32| (part.vertices[v as usize] - s.center).length() < s.radius - depth;
                cap(&part, &incident, c.face, holds)
            })
            .collect();
        inside.sort_unstable();
        inside.dedup();
        let mut moved_to: Vec<Option<DVec3>> = vec![None; part.vertices.len()];
        let targets: Vec<Option<DVec3>> = inside
            .par_iter()
            .map_init(Vec::new, |hits, &v| {
                let p = part.vertices[v as usize];
                tree.spheres_containing_into(p, usize::MAX, -depth, None, hits);
                let &(_, deepest) = hits.first()?;
                let positive = spheres.values[deepest as usize] > 0.0;
                let n: DVec3 = incident
                    .faces(v)
                    .iter()
                    .map(|&f| part.face_normal_scaled(f as usize))
                    .sum();
                let along = n.normalize_or_zero() * if positive { -1.0 } else { 1.0 };
                let radial =
                    (p - spheres.spheres.sphere(deepest as usize).center).normalize_or_zero();
                let start = std::mem::take(hits);
                [along, radial]
                    .into_iter()
                    .filter(|d| *d != DVec3::ZERO)
                    .filter_map(|dir| {
                        hits.clone_from(&start);
                        leave_along(spheres, &tree, p, dir, positive, depth, reach, hits)
                            .map(|t| (t, dir))
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(t, dir)| spheres.frame.to_mesh(p + dir * t))
            })
            .collect();
        for (&v, t) in inside.iter().zip(targets) {
            moved_to[v as usize] = t;
        }
        let moved = apply_moves(mesh, &incident, &moved_to);
        if moved.is_empty() && splits == 0 {
            break;
        }
        last = found;
    }
    added
}

/// Which spheres [`clear_spheres`] looks at in its first round; the later rounds look again at
/// those it found entered.
#[derive(Debug, Clone, Copy)]
pub enum Among<'a> {
    /// Every sphere whose radius (in the spheres' frame) is below this.
    SmallerThan(f64),
    /// These spheres, by index (a check's findings); indices past the set are ignored.
    These(&'a [u32]),
}

/// The spheres that `part` enters by more than `depth`, each with the point of `part` nearest its
/// centre: those of `among` the first round (`previous` none), the later ones only those entered
/// before, around where they were entered (a vertex moves by at most `CLEAR_REACH`). `None` when
/// `part` cannot be indexed.
fn entered(
    part: &TriMesh,
    incident: &Incidence,
    spheres: &Spheres<'_>,
    previous: Option<&[(u32, rfta_mesh::ClosestPoint)]>,
    among: Among<'_>,
    depth: f64,
) -> Option<Vec<(u32, rfta_mesh::ClosestPoint)>> {
    use rayon::prelude::*;
    let entry = |i: u32| {
        let s = spheres.spheres.sphere(i as usize);
        let lo = s.radius - depth;
        (lo > 0.0).then_some((s.center, lo))
    };
    Some(match previous {
        None => {
            let index = rfta_mesh::MeshIndex::new(part).ok()?;
            let nearest = |i: u32| {
                let (c, lo) = entry(i)?;
                Some((i, index.closest_point_within(c, lo * lo)?))
            };
            match among {
                Among::SmallerThan(below) => (0..spheres.spheres.len() as u32)
                    .into_par_iter()
                    .filter(|&i| spheres.spheres.radius(i as usize) < below)
                    .filter_map(nearest)
                    .collect(),
                Among::These(these) => {
                    let mut these = these.to_vec();
                    these.sort_unstable();
                    these.dedup();
                    these.retain(|&i| (i as usize) < spheres.spheres.len());
                    these.into_par_iter().filter_map(nearest).collect()
                }
            }
        }
        Some(last) => last
            .par_iter()
            .filter_map(|&(i, ref seed)| {
                let (c, lo) = entry(i)?;
                Some((i, nearest_around(part, incident, seed.face, c, lo)?))
            })
            .collect(),
    })
}

/// The vertices `holds` takes that connect to face `face`'s through such vertices: a sphere's
/// cap, grown from the face nearest its centre.
fn cap(part: &TriMesh, incident: &Incidence, face: u32, holds: impl Fn(u32) -> bool) -> Vec<u32> {
    let mut cap: Vec<u32> = part.faces[face as usize]
        .into_iter()
        .filter(|&v| holds(v))
        .collect();
    let mut next = 0;
    while next < cap.len() {
        let v = cap[next];
        next += 1;
        for &f in incident.faces(v) {
            for w in part.faces[f as usize] {
                if !cap.contains(&w) && holds(w) {
                    cap.push(w);
                }
            }
        }
    }
    cap
}

/// The nearest point to `center` of the faces of `part` within `lo` of it that connect to the
/// face `seed` or its neighbours through such faces, if there are any: where a sphere was entered
/// before a round of [`clear_spheres`], the part still inside it after the round surrounds the
/// face that was nearest its centre.
fn nearest_around(
    part: &TriMesh,
    incident: &Incidence,
    seed: u32,
    center: DVec3,
    lo: f64,
) -> Option<rfta_mesh::ClosestPoint> {
    let mut queue = vec![seed];
    let mut seen = std::collections::HashSet::from([seed]);
    let mut next = 0;
    let mut best: Option<rfta_mesh::ClosestPoint> = None;
    while next < queue.len() {
        let f = queue[next];
        next += 1;
        let [a, b, c] = part.triangle(f as usize);
        let (point, barycentric) = rfta_geom::kernels::closest_point_on_triangle(center, a, b, c);
        let d2 = (point - center).length_squared();
        if d2 < lo * lo && best.as_ref().is_none_or(|b| d2 < b.distance_squared) {
            best = Some(rfta_mesh::ClosestPoint {
                point,
                distance_squared: d2,
                face: f,
                barycentric,
            });
        }
        if d2 < lo * lo || f == seed {
            for v in part.faces[f as usize] {
                for &g in incident.faces(v) {
                    if seen.insert(g) {
                        queue.push(g);
                    }
                }
            }
        }
    }
    best
}

/// Where no vertex of the nearest face lies inside an entered sphere (`found`: the sphere and the
/// mesh's nearest point to its centre, on `part`, the mesh in the spheres' frame, whose faces
/// around each vertex `incident` holds), a vertex is put at that nearest point
/// ([`Splitter::split`]; the new faces lie in the old ones' planes). Returns how many vertices were
/// added.
fn split_where_entered(
    mesh: &mut TriMesh,
    part: &TriMesh,
    incident: &Incidence,
    spheres: &Spheres<'_>,
    found: &[(u32, rfta_mesh::ClosestPoint)],
    depth: f64,
) -> usize {
    let mut splitter = Splitter::new(incident, mesh);
    let mut added = 0;
    for &(i, ref c) in found {
        let f = c.face as usize;
        let s = spheres.spheres.sphere(i as usize);
        // A face split in this call holds a new vertex, which `part` does not have.
        let holds = |v: u32| {
            part.vertices
                .get(v as usize)
                .is_some_and(|&p| (p - s.center).length() < s.radius - depth)
        };
        if splitter.touched[f] || mesh.faces[f].iter().any(|&v| holds(v)) {
            continue;
        }
        let at = mesh.faces[f]
            .iter()
            .zip(c.barycentric)
            .map(|(&v, b)| mesh.vertices[v as usize] * b)
            .sum();
        added += usize::from(splitter.split(mesh, f, c.barycentric, at).is_some());
    }
    added
}

/// How far along `dir` from `p` the line leaves every sphere of `tree` that holds it by more
/// than `depth` (`hits` holds those at `p`), if it does within `reach` and meets only spheres of
/// the sign `positive`.
#[allow(clippy::too_many_arguments)]
fn leave_along(
    spheres: &Spheres<'_>,
    tree: &SphereTree,
    p: DVec3,
    dir: DVec3,
    positive: bool,
    depth: f64,
    reach: f64,
    hits: &mut Vec<(f64, u32)>,
) -> Option<f64> {
    let mut t = 0.0f64;
    for _ in 0..8 {
        for &(_, j) in hits.iter() {
            if (spheres.values[j as usize] > 0.0) != positive {
                return None;
            }
            let s = spheres.spheres.sphere(j as usize);
            let o = p - s.center;
            let b = o.dot(dir);
            let disc = b * b - (o.length_squared() - s.radius * s.radius);
            t = t.max(-b + disc.max(0.0).sqrt());
        }
        if t > reach {
            return None;
        }
        tree.spheres_containing_into(p + dir * t, usize::MAX, -depth, None, hits);
        if hits.is_empty() {
            return Some(t);
        }
    }
    None
}
