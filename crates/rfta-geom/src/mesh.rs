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

    /// Adds `other`'s vertices and faces (its faces renumbered after this mesh's vertices): the
    /// union of the two as one mesh with separate components.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.faces
            .extend(other.faces.iter().map(|f| f.map(|v| v + base)));
    }
}
