//! Cavities joined to the surface beyond them by a tube: the opening of last resort, for a
//! cavity the re-solve with points kept outside ([`crate::cavity_openings`]) closes again.

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_mesh::{MeshIndex, face_components, join, signed_volume};

/// Joins cavities of the closed, outward-oriented `mesh` to the surface beyond them, one tube per
/// cavity: along the first segment of `paths` (each from an outside sample in a cavity to an
/// outside sample beyond the mesh, as [`crate::Openings::edges`] gives them) that crosses the
/// mesh exactly twice, first the cavity's wall, then another component's surface, the two faces
/// crossed are joined ([`rfta_mesh::join`]): the cavity opens into the outside through the wall
/// between them, and the two components become one of the same genus sum. Returns how many
/// cavities were joined.
pub fn tunnel_cavities(mesh: &mut TriMesh, paths: &[[DVec3; 2]]) -> usize {
    let components = face_components(mesh);
    let mut component = vec![usize::MAX; mesh.faces.len()];
    for (c, faces) in components.iter().enumerate() {
        for &f in faces {
            component[f] = c;
        }
    }
    let inward: Vec<bool> = components
        .iter()
        .map(|faces| signed_volume(mesh, faces) < 0.0)
        .collect();
    // Cavities joined once, and the faces a join replaced (now the tube's).
    let mut used = vec![false; components.len()];
    let mut replaced = vec![false; mesh.faces.len()];
    let mut joined = 0;
    let Ok(index) = MeshIndex::new(mesh) else {
        return 0;
    };
    for &[from, to] in paths {
        // Crossings of the mesh as it was: the index is not rebuilt after a join, whose tube
        // replaces two faces (marked below) and appends four (beyond `component`).
        let hits = index.segment_crossings(from, to);
        if hits.len() != 2 {
            continue;
        }
        let (near, far) = (hits[0].1 as usize, hits[1].1 as usize);
        if replaced[near] || replaced[far] {
            continue;
        }
        let (cn, cf) = (component[near], component[far]);
        if cn == cf || !inward[cn] || used[cn] {
            continue;
        }
        if join(mesh, near as u32, far as u32) {
            used[cn] = true;
            replaced[near] = true;
            replaced[far] = true;
            joined += 1;
        }
    }
    joined
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;
    use rfta_mesh::{Topology, cavities};

    /// A ball of radius 1 with a spherical cavity of radius 0.5 about its centre.
    fn hollow_ball() -> TriMesh {
        let mut mesh = shapes::icosphere(1.0, 3);
        let mut cavity = shapes::icosphere(0.5, 3);
        cavity.flip();
        mesh.append(&cavity);
        mesh
    }

    /// A path from the cavity's centre out through the wall joins the cavity to the outer
    /// surface: one closed, manifold, consistently oriented component of genus 0, no cavity.
    #[test]
    fn a_path_from_a_cavity_out_joins_it_to_the_surface() {
        let mut mesh = hollow_ball();
        assert_eq!(cavities(&mesh).len(), 1);
        let path = [DVec3::new(0.01, 0.02, 0.0), DVec3::new(1.5, 0.3, 0.1)];
        assert_eq!(tunnel_cavities(&mut mesh, &[path]), 1);
        let t = Topology::of(&mesh);
        assert!(t.is_watertight() && t.is_manifold() && t.is_consistently_oriented());
        assert_eq!((face_components(&mesh).len(), t.genus()), (1, Some(0)));
        assert!(cavities(&mesh).is_empty());
    }

    /// Paths that do not leave a cavity through one wall join nothing: one from outside across
    /// the whole ball (four crossings), one that ends inside the wall (one crossing), one across
    /// the outer surface alone.
    #[test]
    fn other_paths_join_nothing() {
        let paths = [
            [DVec3::new(-1.5, 0.1, 0.0), DVec3::new(1.5, 0.1, 0.0)],
            [DVec3::new(0.0, 0.1, 0.0), DVec3::new(0.75, 0.1, 0.0)],
            [DVec3::new(0.75, 0.1, 0.0), DVec3::new(1.5, 0.1, 0.0)],
        ];
        let mut mesh = hollow_ball();
        let before = mesh.clone();
        assert_eq!(tunnel_cavities(&mut mesh, &paths), 0);
        assert_eq!(mesh, before);
    }
}
