//! Handles cut: those narrower than the solve's finest cell ([`cut_sub_cell_handles`]), and,
//! for a known genus, every component joined to the largest, then the shortest loops around
//! handles cut until the genus is reached ([`to_genus`]); [`cut_disjoint`] is the pass both
//! make.

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

use rfta_mesh::face_components;

/// How far apart the two sides of a cut handle move, in sample spacings.
pub const CUT_GAP: f64 = 0.05;

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
        let this_pass =
            cut_disjoint(mesh, &loops.loops, CUT_GAP * h, |_, cut| cut < excess, None).len();
        if this_pass == 0 {
            break;
        }
        cut += this_pass;
    }
    (joined, cut)
}

/// A test of one cut of [`cut_disjoint`]: the mesh before, the mesh after, the loop's index.
pub type CutTest<'a> = dyn FnMut(&TriMesh, &TriMesh, usize) -> bool + 'a;

/// Cuts, in one pass, the loops of `cycles` (as [`rfta_mesh::ShortLoops::loops`] gives them,
/// shortest first) for which `wanted(k, cut)` holds (`k` the loop's index, `cut` the number cut
/// so far) and that share no vertex with one cut before it in the pass, the two sides `gap`
/// apart ([`rfta_mesh::cut_along`]); with `keeps`, each cut is made on a copy and kept only if
/// `keeps(before, after, k)` approves the mesh it makes (without, in place). Loops of one basis that share no vertex are disjoint and independent: no
/// set of them separates the surface, so each cut takes one handle. Returns the indices of the
/// loops cut, ascending.
///
/// # Example
/// ```
/// use rfta_geom::shapes;
///
/// // A torus whose tube is 0.63 around: its one short loop cut, genus 1 to 0.
/// let mut torus = shapes::torus(1.0, 0.1, 64, 16);
/// let loops = rfta_mesh::short_loops(&torus, 1.0).expect("closed");
/// let cut = rfta_repair::cut_disjoint(&mut torus, &loops.loops, 0.01, |_, _| true, None);
/// assert_eq!(cut, [0]);
/// assert_eq!(rfta_mesh::Topology::of(&torus).genus(), Some(0));
/// ```
pub fn cut_disjoint(
    mesh: &mut TriMesh,
    cycles: &[Vec<u32>],
    gap: f64,
    mut wanted: impl FnMut(usize, usize) -> bool,
    mut keeps: Option<&mut CutTest<'_>>,
) -> Vec<usize> {
    let mut touched = vec![false; mesh.vertices.len()];
    let mut cut = Vec::new();
    for (k, cycle) in cycles.iter().enumerate() {
        if !wanted(k, cut.len()) {
            continue;
        }
        if cycle
            .iter()
            .any(|&v| touched.get(v as usize).is_none_or(|&t| t))
        {
            continue;
        }
        let made = match keeps.as_mut() {
            None => rfta_mesh::cut_along(mesh, cycle, gap),
            Some(keeps) => {
                let mut after = mesh.clone();
                let kept = rfta_mesh::cut_along(&mut after, cycle, gap) && keeps(mesh, &after, k);
                if kept {
                    *mesh = after;
                }
                kept
            }
        };
        if made {
            for &v in cycle {
                touched[v as usize] = true;
            }
            cut.push(k);
        }
    }
    cut
}

/// Cuts every handle of `mesh` whose loop is shorter than `cells` times `finest_cell`, the side
/// of the finest cells of the solve the mesh was extracted from, the two sides `gap` apart; on
/// meshes of genus up to `max_genus`. Returns the handles cut.
///
/// Such a handle is not a feature of the function the mesh is an iso-surface of: where the
/// function has a saddle within a cell whose value is near the iso-value, the extraction joins
/// or separates the two sides by the signs at the cell's corners, and a corner a hair inside
/// (or outside) leaves a thread of material through it, or a pinhole through a wall, a fraction
/// of a cell across. The cut is the other choice at that saddle.
pub fn cut_sub_cell_handles(
    mesh: &mut TriMesh,
    finest_cell: f64,
    cells: f64,
    gap: f64,
    max_genus: i64,
) -> usize {
    let mut cut = 0;
    loop {
        let genus = rfta_mesh::Topology::of(mesh).genus();
        if genus.is_none_or(|g| g <= 0 || g > max_genus) {
            break;
        }
        let Some(loops) = rfta_mesh::short_loops(mesh, cells * finest_cell) else {
            break;
        };
        let this_pass = cut_disjoint(mesh, &loops.loops, gap, |_, _| true, None).len();
        if this_pass == 0 {
            break;
        }
        cut += this_pass;
    }
    cut
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
