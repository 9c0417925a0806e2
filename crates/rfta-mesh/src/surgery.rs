//! Topological surgery on a closed, outward-oriented triangle mesh: [`cut_along`] a loop (one
//! handle fewer), [`join`] two faces by a tube (one component fewer).
//!
//! Both keep the mesh closed, manifold along its edges and consistently oriented; they change
//! its geometry only next to the loop or the two faces.

use std::collections::HashMap;

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

/// Cuts `mesh` along `cycle`, a simple closed loop of its edges (as [`crate::ShortLoops::loops`]
/// gives), and closes each side with a fan from the loop's centroid: a non-separating loop makes
/// the genus one lower, a bar cut through or a tunnel filled. The two sides move `gap / 2` apart
/// along the loop's normal (Newell's, turned toward the side the loop's vertices keep), the
/// loop's own vertices and their copies only: a bar's slit is outside, a tunnel's filled slab
/// inside. Returns whether it cut: not when `cycle` is not a simple loop of at least three edges
/// with a face on each side of each edge (the mesh is then unchanged).
pub fn cut_along(mesh: &mut TriMesh, cycle: &[u32], gap: f64) -> bool {
    let k = cycle.len();
    if k < 3 || cycle.iter().any(|&v| v as usize >= mesh.vertices.len()) {
        return false;
    }
    let mut sorted = cycle.to_vec();
    sorted.sort_unstable();
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    let face_of = half_edges(mesh);
    let at = |i: usize| cycle[i % k];
    // The faces right of the loop at each of its vertices: from the face across the edge to the
    // next vertex, turning about the vertex to the face across the edge to the previous one.
    let mut right: Vec<(u32, usize)> = Vec::new();
    for i in 0..k {
        let (c, next, prev) = (at(i), at(i + 1), at(i + k - 1));
        let Some(&start) = face_of.get(&(next, c)) else {
            return false;
        };
        if !face_of.contains_key(&(c, next)) {
            return false;
        }
        let mut f = start;
        let mut turns = 0;
        loop {
            right.push((f, i));
            let t = mesh.faces[f as usize];
            let Some(corner) = t.iter().position(|&v| v == c) else {
                return false;
            };
            let a = t[(corner + 1) % 3];
            if a == prev {
                break;
            }
            // A loop edge reached from the right before `prev`: not a simple cut.
            if a == next || turns > 256 {
                return false;
            }
            let Some(&g) = face_of.get(&(a, c)) else {
                return false;
            };
            f = g;
            turns += 1;
        }
    }
    let positions: Vec<DVec3> = cycle.iter().map(|&v| mesh.vertices[v as usize]).collect();
    let mut normal = DVec3::ZERO;
    for i in 0..k {
        normal += positions[i].cross(positions[(i + 1) % k]);
    }
    let centre = positions.iter().sum::<DVec3>() / k as f64;
    // Newell's normal follows the loop's direction; the sides must part, so it is turned toward
    // the left faces (those the loop's vertices keep): around a bar they lie along it, around a
    // tunnel against it, and moving each side the other way crossed the caps.
    let right_offset: f64 = right
        .iter()
        .map(|&(f, _)| {
            let t = mesh.faces[f as usize];
            (t.iter().map(|&v| mesh.vertices[v as usize]).sum::<DVec3>() / 3.0 - centre).dot(normal)
        })
        .sum();
    let normal = if right_offset > 0.0 { -normal } else { normal }.normalize_or_zero();
    let shift = 0.5 * gap * normal;
    let first_copy = mesh.vertices.len() as u32;
    for p in &positions {
        mesh.vertices.push(*p - shift);
    }
    for (v, p) in cycle.iter().zip(&positions) {
        mesh.vertices[*v as usize] = *p + shift;
    }
    for &(f, i) in &right {
        for v in &mut mesh.faces[f as usize] {
            if *v == cycle[i] {
                *v = first_copy + i as u32;
            }
        }
    }
    let left_centre = mesh.vertices.len() as u32;
    mesh.vertices.push(centre + shift);
    let right_centre = left_centre + 1;
    mesh.vertices.push(centre - shift);
    for i in 0..k {
        let j = (i + 1) % k;
        mesh.faces.push([left_centre, cycle[j], cycle[i]]);
        mesh.faces
            .push([right_centre, first_copy + i as u32, first_copy + j as u32]);
    }
    true
}

/// Joins two faces of different components by a tube: both faces are removed and their
/// boundaries connected by six triangles, each vertex of `a` paired with a vertex of `b` so
/// that the tube's edges are shortest. One component fewer, the genus the sum of the two. Two
/// of the tube's faces take the indices of `a` and `b`, the other four are appended: the other
/// faces keep theirs.
/// Returns whether it joined: not when a face index is out of range or the faces share a vertex.
pub fn join(mesh: &mut TriMesh, a: u32, b: u32) -> bool {
    let n = mesh.faces.len();
    if a as usize >= n || b as usize >= n || a == b {
        return false;
    }
    let (ta, tb) = (mesh.faces[a as usize], mesh.faces[b as usize]);
    if ta.iter().any(|v| tb.contains(v)) {
        return false;
    }
    let p = |v: u32| mesh.vertices[v as usize];
    // Pair a_i with b_(s - i): the two boundaries run opposite ways through the tube.
    let pair = |s: usize, i: usize| tb[(s + 3 - i % 3) % 3];
    let cost = |s: usize| {
        (0..3)
            .map(|i| p(ta[i]).distance(p(pair(s, i))))
            .sum::<f64>()
    };
    let s = (0..3)
        .min_by(|&x, &y| cost(x).total_cmp(&cost(y)))
        .unwrap_or(0);
    let mut tube = Vec::with_capacity(6);
    for i in 0..3 {
        let (a0, a1) = (ta[i], ta[(i + 1) % 3]);
        let (b0, b1) = (pair(s, i), pair(s, i + 1));
        tube.push([a0, a1, b1]);
        tube.push([a0, b1, b0]);
    }
    // The tube's first two faces take the removed faces' places: every other face keeps its
    // index, so several joins can be planned on one mesh.
    mesh.faces[a as usize] = tube[0];
    mesh.faces[b as usize] = tube[1];
    mesh.faces.extend_from_slice(&tube[2..]);
    true
}

/// Each directed edge's face.
fn half_edges(mesh: &TriMesh) -> HashMap<(u32, u32), u32> {
    let mut map = HashMap::with_capacity(3 * mesh.faces.len());
    for (f, t) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            map.insert((t[k], t[(k + 1) % 3]), f as u32);
        }
    }
    map
}

#[cfg(test)]
mod tests {
    use rfta_geom::shapes;

    use super::*;
    use crate::{MeshIndex, Topology, short_loops};

    fn check(mesh: &TriMesh) -> Topology {
        let t = Topology::of(mesh);
        assert!(t.is_watertight() && t.is_manifold(), "{t:?}");
        assert!(t.is_consistently_oriented(), "{t:?}");
        t
    }

    /// Volume by the divergence theorem: positive for an outward-oriented closed mesh.
    fn volume(mesh: &TriMesh) -> f64 {
        mesh.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| mesh.vertices[v as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// The mean of a loop's vertices.
    fn centroid(mesh: &TriMesh, cycle: &[u32]) -> DVec3 {
        cycle
            .iter()
            .map(|&v| mesh.vertices[v as usize])
            .sum::<DVec3>()
            / cycle.len() as f64
    }

    #[test]
    fn cutting_a_tube_leaves_a_sphere_of_the_same_volume() {
        let mut torus = shapes::torus(1.0, 0.2, 48, 12);
        let before = volume(&torus);
        let loops = short_loops(&torus, 2.0).expect("closed");
        assert_eq!(loops.loops.len(), 1);
        // The loop's centre before the cut: midway between the two caps after it (the loop's
        // own vertices move to one cap, so their centre afterwards lies on it).
        let cycle = &loops.loops[0];
        let centre = centroid(&torus, cycle);
        assert!(cut_along(&mut torus, cycle, 0.01));
        let t = check(&torus);
        assert_eq!((t.genus(), t.components), (Some(0), 1));
        // The slit is 0.01 wide across a tube of area pi 0.2^2 (the caps' sag is below it).
        let cut = (volume(&torus) - before).abs();
        assert!(
            cut < 0.01 * 0.2 * 0.2 * std::f64::consts::PI * 1.05,
            "{cut}"
        );
        // Both caps face outward: a point in the slit is outside, points beside it inside (the
        // tube's direction at the loop is horizontal, across the loop's plane through the axis).
        let index = MeshIndex::new(&torus).expect("index");
        assert!(index.winding_number(centre) < 0.1);
        let along = DVec3::new(-centre.y, centre.x, 0.0).normalize();
        for side in [-0.05, 0.05] {
            assert!(index.winding_number(centre + side * along) > 0.9);
        }
    }

    #[test]
    fn filling_a_hole_leaves_a_sphere() {
        // The loop around the hole of a fat torus is shorter than around its tube.
        let mut torus = shapes::torus(0.5, 0.4, 48, 24);
        let loops = short_loops(&torus, 1.0).expect("closed");
        assert_eq!(loops.loops.len(), 1, "{:?}", loops.lengths);
        let cycle = &loops.loops[0];
        let centre = centroid(&torus, cycle);
        let before = volume(&torus);
        assert!(cut_along(&mut torus, cycle, 0.1));
        let t = check(&torus);
        assert_eq!((t.genus(), t.components), (Some(0), 1));
        // The hole's throat is a circle of radius 0.1: a slab 0.1 thick across it is filled, the
        // hole above and below it stays empty. The throat widens away from its waist, so the
        // faces beside the moved loop add a little more (14% here); crossed caps took it away.
        let filled = volume(&torus) - before;
        let slab = 0.1 * std::f64::consts::PI * 0.1 * 0.1;
        assert!(
            filled > 0.9 * slab && filled < 1.25 * slab,
            "{filled} against {slab}"
        );
        let index = MeshIndex::new(&torus).expect("index");
        assert!(index.winding_number(centre) > 0.9);
        for side in [-0.2, 0.2] {
            assert!(index.winding_number(centre + side * DVec3::Z) < 0.1);
        }
    }

    #[test]
    fn a_loop_that_is_not_simple_or_not_made_of_edges_is_refused() {
        let mut torus = shapes::torus(1.0, 0.2, 16, 8);
        let copy = torus.clone();
        assert!(!cut_along(&mut torus, &[0, 1], 0.01));
        assert!(!cut_along(&mut torus, &[0, 1, 0, 2], 0.01));
        assert!(!cut_along(&mut torus, &[0, 17, 40], 0.01));
        assert_eq!(torus, copy);
    }

    #[test]
    fn joining_two_spheres_makes_one() {
        let mut mesh = shapes::icosphere(0.5, 2);
        let mut other = shapes::icosphere(0.3, 2);
        other.map_vertices(|v| v + DVec3::new(1.0, 0.0, 0.0));
        let offset = mesh.n_faces() as u32;
        mesh.append(&other);
        let before = volume(&mesh);
        // The faces nearest each other: on the +x side of the first, the -x side of the second.
        let nearest = |range: std::ops::Range<u32>, x: f64| {
            range
                .min_by(|&f, &g| {
                    let d = |f: u32| {
                        let c = mesh.faces[f as usize]
                            .iter()
                            .map(|&v| mesh.vertices[v as usize])
                            .sum::<DVec3>()
                            / 3.0;
                        c.distance(DVec3::new(x, 0.0, 0.0))
                    };
                    d(f).total_cmp(&d(g))
                })
                .expect("faces")
        };
        let (a, b) = (
            nearest(0..offset, 0.5),
            nearest(offset..mesh.n_faces() as u32, 0.7),
        );
        assert!(join(&mut mesh, a, b));
        let t = check(&mesh);
        assert_eq!((t.genus(), t.components), (Some(0), 1));
        // The tube adds a thin prism's volume, a little more than the two faces' cones lose.
        assert!(
            (volume(&mesh) - before).abs() < 0.01,
            "{}",
            volume(&mesh) - before
        );
        assert!(!join(&mut mesh, 0, 0));
    }
}
