//! A known genus: every component joined to the largest, then the shortest loops around handles
//! cut until the genus is reached.

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

use rfta_mesh::face_components;

/// How far apart the two sides of a cut handle move, in sample spacings.
const CUT_GAP: f64 = 0.05;

/// A known genus: every component joined to the largest, then the shortest loops around handles
/// cut until the genus is `genus`; loops are searched below `first` spacings `h` first, then below
/// twice and four times that, and so on to 64 spacings, on meshes of genus up to `max_genus`
/// (the search's memory grows with it). Returns the components joined and the handles cut.
pub fn to_genus(
    mesh: &mut TriMesh,
    genus: usize,
    h: f64,
    first: f64,
    max_genus: i64,
) -> (usize, usize) {
    let mut joined = 0;
    for (a, b) in nearest_faces_to_largest(mesh) {
        if rfta_mesh::join(mesh, a, b) {
            joined += 1;
        }
    }
    let mut cut = 0;
    let mut bound = first;
    while bound <= 64.0 {
        let Some(excess) = rfta_mesh::Topology::of(mesh)
            .genus()
            .filter(|&g| g <= max_genus)
            .and_then(|g| usize::try_from(g).ok())
            .and_then(|g| g.checked_sub(genus))
            .filter(|&e| e > 0)
        else {
            break;
        };
        let Some(loops) = rfta_mesh::short_loops(mesh, bound * h) else {
            break;
        };
        if loops.loops.is_empty() {
            bound *= 2.0;
            continue;
        }
        // Shortest first; loops of one basis that share no vertex are cut in one pass (disjoint
        // and independent, they do not separate the surface: each takes one handle).
        let mut touched = vec![false; mesh.vertices.len()];
        let mut this_pass = 0;
        for cycle in &loops.loops {
            if this_pass == excess {
                break;
            }
            if cycle.iter().any(|&v| touched[v as usize]) {
                continue;
            }
            if rfta_mesh::cut_along(mesh, cycle, CUT_GAP * h) {
                for &v in cycle {
                    touched[v as usize] = true;
                }
                this_pass += 1;
            }
        }
        if this_pass == 0 {
            break;
        }
        cut += this_pass;
    }
    (joined, cut)
}

/// For each component but the largest (in face order), a face of it and the face of the largest
/// nearest to it: at its vertex nearest the largest, the face whose centre is nearest the
/// largest's closest point, and the face that point lies on. Faces of different components, so
/// the joins can be made one after another ([`rfta_mesh::join`] keeps the other faces' indices).
fn nearest_faces_to_largest(mesh: &TriMesh) -> Vec<(u32, u32)> {
    let parts = face_components(mesh);
    let Some(largest) = (0..parts.len()).max_by_key(|&i| (parts[i].len(), std::cmp::Reverse(i)))
    else {
        return Vec::new();
    };
    if parts.len() < 2 {
        return Vec::new();
    }
    let Ok(index) = rfta_mesh::MeshIndex::new(&mesh.part(&parts[largest])) else {
        return Vec::new();
    };
    let centre = |f: u32| {
        mesh.faces[f as usize]
            .iter()
            .map(|&i| mesh.vertices[i as usize])
            .sum::<DVec3>()
            / 3.0
    };
    let mut pairs = Vec::new();
    for (k, part) in parts.iter().enumerate() {
        if k == largest {
            continue;
        }
        let mut best: Option<(u32, rfta_mesh::ClosestPoint)> = None;
        for &f in part {
            for &v in &mesh.faces[f] {
                let q = index.closest_point(mesh.vertices[v as usize]);
                if best
                    .as_ref()
                    .is_none_or(|b| q.distance_squared < b.1.distance_squared)
                {
                    best = Some((v, q));
                }
            }
        }
        let Some((v, q)) = best else { continue };
        let a = part
            .iter()
            .map(|&f| f as u32)
            .filter(|&f| mesh.faces[f as usize].contains(&v))
            .min_by(|&f, &g| {
                centre(f)
                    .distance_squared(q.point)
                    .total_cmp(&centre(g).distance_squared(q.point))
            });
        if let Some(a) = a {
            pairs.push((a, parts[largest][q.face as usize] as u32));
        }
    }
    pairs
}
