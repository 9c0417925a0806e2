//! Indexed triangle meshes.

use glam::DVec3;

use crate::{Aabb, Error, Result};

/// An indexed triangle mesh: vertex positions and triangles as vertex-index triples.
///
/// Faces are oriented counter-clockwise seen from outside (normals `(b - a) x (c - a)` point out).
/// [`TriMesh::new`] checks that every index is in range and every vertex finite; the fields stay
/// public for cheap access, and [`TriMesh::validate`] re-checks them after edits.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Triangles, as indices into `vertices`.
    pub faces: Vec<[u32; 3]>,
}

impl TriMesh {
    /// A mesh from vertices and faces, validated.
    ///
    /// # Errors
    /// [`Error::NonFinitePosition`] for a vertex with a NaN or infinite coordinate,
    /// [`Error::FaceIndexOutOfRange`] for a face naming a missing vertex.
    pub fn new(vertices: Vec<DVec3>, faces: Vec<[u32; 3]>) -> Result<Self> {
        let mesh = Self { vertices, faces };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks the invariants [`TriMesh::new`] establishes.
    ///
    /// # Errors
    /// As [`TriMesh::new`].
    pub fn validate(&self) -> Result<()> {
        for (index, v) in self.vertices.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::NonFinitePosition {
                    what: "vertex",
                    index,
                    x: v.x,
                    y: v.y,
                    z: v.z,
                });
            }
        }
        let n_vertices = self.vertices.len();
        for (face, f) in self.faces.iter().enumerate() {
            if let Some(&vertex) = f.iter().find(|&&i| i as usize >= n_vertices) {
                return Err(Error::FaceIndexOutOfRange {
                    face,
                    vertex,
                    n_vertices,
                });
            }
        }
        Ok(())
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of triangles.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The corners of triangle `face`.
    ///
    /// # Panics
    /// If `face` is out of range (an indexing bug of the caller, not a data error).
    pub fn triangle(&self, face: usize) -> [DVec3; 3] {
        self.faces[face].map(|i| self.vertices[i as usize])
    }

    /// The (unnormalised) normal `(b - a) x (c - a)` of triangle `face`: its length is twice the area.
    pub fn face_normal_scaled(&self, face: usize) -> DVec3 {
        let [a, b, c] = self.triangle(face);
        (b - a).cross(c - a)
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.n_faces())
            .map(|f| 0.5 * self.face_normal_scaled(f).length())
            .sum()
    }

    /// Signed enclosed volume (positive for a closed, outward-oriented mesh), by the divergence theorem.
    pub fn signed_volume(&self) -> f64 {
        (0..self.n_faces())
            .map(|f| {
                let [a, b, c] = self.triangle(f);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Bounding box of the vertices that faces use (of all vertices if there are no faces).
    pub fn bounds(&self) -> Aabb {
        if self.faces.is_empty() {
            return Aabb::from_points(&self.vertices);
        }
        self.faces
            .iter()
            .flatten()
            .fold(Aabb::EMPTY, |b, &i| b.grow(self.vertices[i as usize]))
    }

    /// Applies `f` to every vertex.
    pub fn map_vertices(&mut self, f: impl Fn(DVec3) -> DVec3) {
        for v in &mut self.vertices {
            *v = f(*v);
        }
    }

    /// Reverses the orientation of every face.
    pub fn flip(&mut self) {
        for f in &mut self.faces {
            f.swap(1, 2);
        }
    }

    /// The number of vertices that no face uses. Every mesh rfta returns or writes has none.
    pub fn unreferenced_vertices(&self) -> usize {
        unreferenced(self.vertices.len(), &self.faces)
    }

    /// Removes the vertices that no face uses, keeping the others in their order (so a mesh
    /// without any is left exactly as it was); faces are renumbered. Returns how many went.
    pub fn remove_unreferenced_vertices(&mut self) -> usize {
        remove_unreferenced(&mut self.vertices, &mut self.faces)
    }

    /// The faces named by `faces` (indices into [`TriMesh::faces`], kept in that order) as a mesh
    /// of their own, with only the vertices they use, in their order here.
    /// Costs what the part holds, not what the whole mesh does.
    pub fn part(&self, faces: &[usize]) -> TriMesh {
        let mut used: Vec<u32> = faces.iter().flat_map(|&f| self.faces[f]).collect();
        used.sort_unstable();
        used.dedup();
        let renumber = |v: u32| used.binary_search(&v).map_or(u32::MAX, |i| i as u32);
        TriMesh {
            vertices: used.iter().map(|&v| self.vertices[v as usize]).collect(),
            faces: faces.iter().map(|&f| self.faces[f].map(renumber)).collect(),
        }
    }

    /// Adds `other`'s vertices and faces (its faces renumbered after this mesh's vertices): the
    /// union of the two as one mesh with separate components.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.faces
            .extend(other.faces.iter().map(|f| f.map(|v| v + base)));
    }
}

/// How many of `n` vertices no element of `elements` names (every index must be below `n`).
pub(crate) fn unreferenced<const K: usize>(n: usize, elements: &[[u32; K]]) -> usize {
    let mut used = vec![false; n];
    for &v in elements.iter().flatten() {
        used[v as usize] = true;
    }
    used.iter().filter(|&&u| !u).count()
}

/// Drops the vertices that no element names, keeping the rest in order, and renumbers the
/// elements; the one compaction behind [`TriMesh`] and [`crate::plane::Polylines`]. Returns the
/// number dropped.
pub(crate) fn remove_unreferenced<T: Copy, const K: usize>(
    vertices: &mut Vec<T>,
    elements: &mut [[u32; K]],
) -> usize {
    let mut new_index = vec![u32::MAX; vertices.len()];
    for &v in elements.iter().flatten() {
        new_index[v as usize] = 0;
    }
    let mut kept = 0u32;
    for slot in &mut new_index {
        if *slot == 0 {
            *slot = kept;
            kept += 1;
        }
    }
    let removed = vertices.len() - kept as usize;
    if removed == 0 {
        return 0;
    }
    let mut k = 0;
    vertices.retain(|_| {
        k += 1;
        new_index[k - 1] != u32::MAX
    });
    for v in elements.iter_mut().flatten() {
        *v = new_index[*v as usize];
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Against brute force: the vertices kept are exactly the used ones, in their order, and
        /// every face has the corners it had.
        #[test]
        fn removing_unreferenced_vertices_keeps_every_face_and_the_order(
            n in 0usize..40,
            raw in proptest::collection::vec([0u32..1000, 0u32..1000, 0u32..1000], 0..30),
        ) {
            let vertices: Vec<DVec3> = (0..n).map(|i| DVec3::new(i as f64, 0.5, -1.0)).collect();
            let faces: Vec<[u32; 3]> = if n == 0 {
                Vec::new()
            } else {
                raw.iter().map(|f| f.map(|v| v % n as u32)).collect()
            };
            let mesh = TriMesh::new(vertices.clone(), faces.clone()).expect("indices in range");
            let used: Vec<DVec3> = (0..n)
                .filter(|&i| faces.iter().flatten().any(|&v| v as usize == i))
                .map(|i| vertices[i])
                .collect();
            prop_assert_eq!(mesh.unreferenced_vertices(), n - used.len());
            let mut compact = mesh.clone();
            prop_assert_eq!(compact.remove_unreferenced_vertices(), n - used.len());
            prop_assert_eq!(compact.unreferenced_vertices(), 0);
            prop_assert_eq!(&compact.vertices, &used);
            prop_assert_eq!(compact.faces.len(), faces.len());
            for f in 0..faces.len() {
                prop_assert_eq!(compact.triangle(f), mesh.triangle(f));
            }
            prop_assert!(compact.validate().is_ok());
        }

        /// Against brute force: a part is the chosen faces, in the order chosen, over exactly
        /// the vertices they use, in the whole mesh's order.
        #[test]
        fn a_part_is_its_faces_over_their_own_vertices(
            n in 1usize..40,
            raw in proptest::collection::vec([0u32..1000, 0u32..1000, 0u32..1000], 1..30),
            pick in proptest::collection::vec(0usize..1000, 0..20),
        ) {
            let vertices: Vec<DVec3> = (0..n).map(|i| DVec3::new(i as f64, 0.5, -1.0)).collect();
            let faces: Vec<[u32; 3]> = raw.iter().map(|f| f.map(|v| v % n as u32)).collect();
            let mesh = TriMesh::new(vertices.clone(), faces.clone()).expect("indices in range");
            let chosen: Vec<usize> = pick.iter().map(|&f| f % faces.len()).collect();
            let part = mesh.part(&chosen);
            let used: Vec<DVec3> = (0..n)
                .filter(|&i| chosen.iter().any(|&f| faces[f].contains(&(i as u32))))
                .map(|i| vertices[i])
                .collect();
            prop_assert_eq!(&part.vertices, &used);
            prop_assert_eq!(part.faces.len(), chosen.len());
            for (k, &f) in chosen.iter().enumerate() {
                prop_assert_eq!(part.triangle(k), mesh.triangle(f));
            }
            prop_assert!(part.validate().is_ok());
        }
    }

    #[test]
    fn a_mesh_without_unreferenced_vertices_is_left_as_it_was() {
        let mut mesh = crate::shapes::icosphere(1.0, 2);
        let before = mesh.clone();
        assert_eq!(mesh.remove_unreferenced_vertices(), 0);
        assert_eq!(mesh, before);
    }
}
