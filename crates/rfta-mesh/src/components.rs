//! Connected components of a mesh (faces sharing a vertex) and their volumes: a closed component
//! that faces inward encloses a cavity.

use rfta_geom::TriMesh;

use crate::UnionFind;

/// The faces of each connected component (faces sharing a vertex), components in the order of
/// their first face.
pub fn face_components(mesh: &TriMesh) -> Vec<Vec<usize>> {
    let mut sets = UnionFind::new(mesh.vertices.len());
    for f in &mesh.faces {
        sets.union(f[0] as usize, f[1] as usize);
        sets.union(f[0] as usize, f[2] as usize);
    }
    let mut index_of = std::collections::HashMap::new();
    let mut parts: Vec<Vec<usize>> = Vec::new();
    for (i, f) in mesh.faces.iter().enumerate() {
        let root = sets.find(f[0] as usize);
        let k = *index_of.entry(root).or_insert_with(|| {
            parts.push(Vec::new());
            parts.len() - 1
        });
        parts[k].push(i);
    }
    parts
}

/// The divergence theorem over some faces (`TriMesh::signed_volume` of a part): negative for a
/// closed component that faces inward, a cavity.
pub fn signed_volume(mesh: &TriMesh, faces: &[usize]) -> f64 {
    faces
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.triangle(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// The components that face inward (negative volume): in a closed, outward-oriented mesh, the
/// walls of its cavities.
pub fn cavities(mesh: &TriMesh) -> Vec<Vec<usize>> {
    face_components(mesh)
        .into_iter()
        .filter(|faces| signed_volume(mesh, faces) < 0.0)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// A hollow ball (a sphere inside a larger one, turned inward) has one cavity; two balls
    /// side by side have none; the faces of each component are counted once.
    #[test]
    fn a_hollow_ball_has_one_cavity_and_two_balls_none() {
        let outer = shapes::icosphere(1.0, 2);
        let mut inner = shapes::icosphere(0.5, 2);
        for f in &mut inner.faces {
            f.swap(1, 2);
        }
        let mut hollow = outer.clone();
        hollow.append(&inner);
        assert_eq!(face_components(&hollow).len(), 2);
        let walls = cavities(&hollow);
        assert_eq!(walls.len(), 1);
        assert_eq!(walls[0].len(), inner.n_faces());
        // The inner sphere's volume, turned inward: -(4/3) pi 0.5^3 within the icosphere's error.
        let v = signed_volume(&hollow, &walls[0]);
        assert!((v + std::f64::consts::PI / 6.0).abs() < 0.03, "{v}");
        let mut two = outer.clone();
        let mut moved = shapes::icosphere(1.0, 2);
        moved.map_vertices(|p| p + rfta_geom::glam::DVec3::new(3.0, 0.0, 0.0));
        two.append(&moved);
        assert_eq!(face_components(&two).len(), 2);
        assert!(cavities(&two).is_empty());
    }
}
