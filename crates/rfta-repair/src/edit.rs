//! Edits of a mesh that keep it a surface, given the faces around each vertex
//! ([`rfta_mesh::Incidence`]): vertex moves taken without turning a face over ([`apply_moves`]),
//! and new vertices on faces or edges ([`Splitter`]).

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_mesh::Incidence;

/// How many times [`apply_moves`] goes over the vertices.
pub(crate) const MOVE_SWEEPS: usize = 8;

/// Moves each vertex towards its `moved_to` position where it has one without folding the
/// surface: in index order, each takes the largest of its whole remaining move, half, a quarter
/// or an eighth of it that turns none of its faces over (a face's normal against the one it had),
/// given where its neighbours are by then; `MOVE_SWEEPS` (8) sweeps, so that a vertex held back by
/// a neighbour (at sharp features the faces can be a fiftieth of a spacing across) follows it.
/// `incident` holds the mesh's faces around each vertex. Returns the vertices that moved.
pub fn apply_moves(
    mesh: &mut TriMesh,
    incident: &Incidence,
    moved_to: &[Option<DVec3>],
) -> Vec<u32> {
    let targets: Vec<(u32, DVec3)> = (0..mesh.vertices.len() as u32)
        .filter_map(|v| moved_to[v as usize].map(|t| (v, t)))
        .collect();
    if targets.is_empty() {
        return Vec::new();
    }
    let normals: Vec<DVec3> = (0..mesh.faces.len())
        .map(|f| mesh.face_normal_scaled(f))
        .collect();
    let turned = |mesh: &TriMesh, v: u32| {
        incident
            .faces(v)
            .iter()
            .any(|&f| normals[f as usize].dot(mesh.face_normal_scaled(f as usize)) <= 0.0)
    };
    let original: Vec<DVec3> = targets
        .iter()
        .map(|&(v, _)| mesh.vertices[v as usize])
        .collect();
    let mut arrived = vec![false; targets.len()];
    for _ in 0..MOVE_SWEEPS {
        for (k, &(v, target)) in targets.iter().enumerate() {
            if arrived[k] {
                continue;
            }
            let from = mesh.vertices[v as usize];
            for fraction in [1.0, 0.5, 0.25, 0.125] {
                mesh.vertices[v as usize] = from + (target - from) * fraction;
                if !turned(mesh, v) {
                    arrived[k] = fraction == 1.0;
                    break;
                }
                mesh.vertices[v as usize] = from;
            }
        }
    }
    targets
        .iter()
        .zip(&original)
        .filter(|&(&(v, _), o)| mesh.vertices[v as usize] != *o)
        .map(|(&(v, _), _)| v)
        .collect()
}

/// Puts new vertices on a mesh's faces or edges, each face at most once (faces a split has made
/// or changed are left alone until the next [`Splitter`]), given the faces around each vertex
/// before the first split.
pub struct Splitter<'a> {
    incident: &'a Incidence,
    pub(crate) touched: Vec<bool>,
}

impl<'a> Splitter<'a> {
    /// A splitter for `mesh`, whose faces around each vertex `incident` holds.
    pub fn new(incident: &'a Incidence, mesh: &TriMesh) -> Self {
        Self {
            incident,
            touched: vec![false; mesh.faces.len()],
        }
    }

    /// Adds a vertex at `at` for the point of face `f` with barycentric coordinates `b`: the
    /// face splits in three, or, within a fiftieth of its barycentric range of an edge, it and
    /// the face beside that edge split in two each. Not made (`None`) near a vertex, where a face
    /// was split already, or where a new face would turn against the face it is part of (`at`
    /// off the face). Returns the new vertex.
    pub fn split(&mut self, mesh: &mut TriMesh, f: usize, b: [f64; 3], at: DVec3) -> Option<u32> {
        if self.touched.get(f).is_none_or(|&t| t) {
            return None;
        }
        let face = mesh.faces[f];
        let k = mesh.vertices.len() as u32;
        let on_edge: Vec<usize> = (0..3).filter(|&j| b[j] < 0.02).collect();
        let pieces: Vec<(Option<usize>, [u32; 3])> = match on_edge.as_slice() {
            [] => vec![
                (Some(f), [face[0], face[1], k]),
                (None, [face[1], face[2], k]),
                (None, [face[2], face[0], k]),
            ],
            &[j] => {
                // The edge opposite vertex j, u -> v in this face, v -> u in the one beside it.
                let (w, u, v) = (face[j], face[(j + 1) % 3], face[(j + 2) % 3]);
                let g = self
                    .incident
                    .faces(u)
                    .iter()
                    .map(|&g| g as usize)
                    .find(|&g| g != f && mesh.faces[g].contains(&v))?;
                if self.touched[g] {
                    return None;
                }
                let x = mesh.faces[g].into_iter().find(|&x| x != u && x != v)?;
                vec![
                    (Some(f), [u, k, w]),
                    (None, [k, v, w]),
                    (Some(g), [v, k, x]),
                    (None, [k, u, x]),
                ]
            }
            _ => return None,
        };
        // Each piece against the face it is cut from: `f` (its slot and the new face after it)
        // or the one beside the edge.
        let mut from = f;
        for &(slot, t) in &pieces {
            from = slot.unwrap_or(from);
            let [a, b, c] = t.map(|x| {
                if x == k {
                    at
                } else {
                    mesh.vertices[x as usize]
                }
            });
            if (b - a).cross(c - a).dot(mesh.face_normal_scaled(from)) <= 0.0 {
                return None;
            }
        }
        mesh.vertices.push(at);
        for (slot, piece) in pieces {
            match slot {
                Some(g) => {
                    self.touched[g] = true;
                    mesh.faces[g] = piece;
                }
                None => mesh.faces.push(piece),
            }
        }
        Some(k)
    }

    /// Moves vertex `v` to `to`, unless a face around it was split already or would turn over,
    /// or `v` is a vertex a split made (its faces are split ones).
    pub fn move_vertex(&mut self, mesh: &mut TriMesh, v: u32, to: DVec3) -> bool {
        if v as usize >= self.incident.n_vertices() {
            return false;
        }
        let around = self.incident.faces(v);
        if around.iter().any(|&f| self.touched[f as usize]) {
            return false;
        }
        let normals: Vec<DVec3> = around
            .iter()
            .map(|&f| mesh.face_normal_scaled(f as usize))
            .collect();
        let from = std::mem::replace(&mut mesh.vertices[v as usize], to);
        let turned = around
            .iter()
            .zip(&normals)
            .any(|(&f, n)| mesh.face_normal_scaled(f as usize).dot(*n) <= 0.0);
        if turned {
            mesh.vertices[v as usize] = from;
            return false;
        }
        for &f in around {
            self.touched[f as usize] = true;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex a split made is left where it is (its faces are split ones): no move, no panic.
    /// Found by an adaptive run whose dents first split a face and then asked to move a vertex of
    /// the same, changed face.
    #[test]
    fn a_vertex_a_split_made_is_not_moved() {
        let mut mesh = rfta_geom::shapes::icosphere(1.0, 1);
        let incident = Incidence::of(&mesh);
        let mut splitter = Splitter::new(&incident, &mesh);
        let [a, b, c] = mesh.triangle(0);
        let centre = (a + b + c) / 3.0;
        let k = splitter
            .split(&mut mesh, 0, [1.0 / 3.0; 3], centre)
            .expect("split");
        assert!(!splitter.move_vertex(&mut mesh, k, centre * 1.1));
        assert_eq!(mesh.vertices[k as usize], centre);
    }
}
