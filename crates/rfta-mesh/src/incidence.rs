//! The faces around each vertex of a mesh, in one array (compressed rows).

use rfta_geom::TriMesh;

/// The faces around each vertex of a mesh, each vertex's in face order.
#[derive(Debug, Clone)]
pub struct Incidence {
    /// Where each vertex's faces start in `faces` (one more entry than vertices).
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl Incidence {
    /// The faces around each vertex of `mesh`.
    pub fn of(mesh: &TriMesh) -> Self {
        let mut start = vec![0u32; mesh.vertices.len() + 1];
        for face in &mesh.faces {
            for &v in face {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..mesh.vertices.len() {
            start[v + 1] += start[v];
        }
        let mut at = start.clone();
        let mut faces = vec![0u32; start[mesh.vertices.len()] as usize];
        for (f, face) in mesh.faces.iter().enumerate() {
            for &v in face {
                faces[at[v as usize] as usize] = f as u32;
                at[v as usize] += 1;
            }
        }
        Self { start, faces }
    }

    /// The vertices it has faces for (the mesh's, used or not).
    pub fn n_vertices(&self) -> usize {
        self.start.len() - 1
    }

    /// The faces around vertex `v`.
    pub fn faces(&self, v: u32) -> &[u32] {
        &self.faces[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// Each vertex's faces are exactly the faces that name it, in face order, by a scan of
    /// every face.
    #[test]
    fn each_vertex_has_the_faces_that_name_it() {
        let mut mesh = shapes::torus(1.0, 0.3, 9, 5);
        mesh.vertices.push(rfta_geom::glam::DVec3::ZERO); // a vertex no face uses
        let incidence = Incidence::of(&mesh);
        assert_eq!(incidence.n_vertices(), mesh.vertices.len());
        for v in 0..mesh.vertices.len() as u32 {
            let scan: Vec<u32> = (0..mesh.faces.len() as u32)
                .filter(|&f| mesh.faces[f as usize].contains(&v))
                .collect();
            assert_eq!(incidence.faces(v), scan.as_slice(), "vertex {v}");
        }
    }
}
